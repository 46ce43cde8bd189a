//! The station's ascent winds against the simulated drone: `mission-short` (a balloon
//! ascent at about 5 m/s to a burst at 3 km through a light westerly with gusts) flown in
//! process, every frame crossing the MAVLink link into the station's core, and the bands it
//! measures compared with the scenario's mean wind (`config/scenarios/mission-short.toml`).
//!
//! `cargo test --release -p stx-station --test ascent_winds -- --nocapture` prints the
//! comparison band by band.

use std::time::Duration;

use stx_dynamics::vehicle::Vehicle;
use stx_dynamics::wind::WindField;
use stx_gnc::mission::FlightStage;
use stx_link::endpoint::{GroundConfig, GroundEndpoint, LinkConfig, LinkStats};
use stx_sim::drone::link::LinkedDrone;
use stx_sim::drone::{Drone, MissionConfig};
use stx_station::config::{DEFAULT_STATION_TOML, StationConfig};
use stx_station::core::{REFIT_EVERY_S, StationCore};

#[test]
fn mission_short_ascent_bands_agree_with_the_simulated_wind() {
    let mission = MissionConfig::builtin("mission-short").expect("built-in mission");
    let mut mean = mission.wind.clone().expect("mission-short has a wind");
    mean.turbulence = None;
    let truth = mean.build().expect("the mean wind");
    let config = StationConfig::from_toml_str(DEFAULT_STATION_TOML).expect("station config");
    // The station's origin is the launch site: band altitudes above it are the scenario's.
    assert_eq!(config.origin.alt_msl_m, mission.site.alt_msl_m);
    let origin_msl = config.origin.alt_msl_m;
    let drone = Drone::new(&mission, Vehicle::straplex()).expect("drone");
    let mut drone = LinkedDrone::new(drone, LinkConfig::vehicle(), Duration::ZERO).expect("link");
    let mut ground = GroundEndpoint::new(GroundConfig::default(), Duration::ZERO);
    let mut core = StationCore::new(config, 0);
    let mut next_tick = 0.0;
    // Until the round chute has fallen a while after the burst (3 km at ~5 m/s: ~10 min).
    loop {
        let t = drone.drone().time_s();
        let now = Duration::from_secs_f64(t);
        drone.step(now).expect("step");
        drone.handle_timeout(now);
        ground.handle_timeout(now);
        loop {
            let mut moved = false;
            while let Some(frame) = drone.poll_transmit(now) {
                ground.handle_bytes(now, &frame);
                moved = true;
            }
            while let Some(frame) = ground.poll_transmit(now) {
                drone.handle_bytes(now, &frame);
                moved = true;
            }
            if !moved {
                break;
            }
        }
        while let Some(e) = ground.poll_event() {
            core.on_link_event(t, e);
        }
        if t >= next_tick {
            next_tick = t + 0.25;
            let stats = LinkStats {
                connected: true,
                ..LinkStats::default()
            };
            core.set_link_stats(t, stats);
            core.tick(t);
        }
        let stage = drone.drone().stage();
        let fallen = drone
            .drone()
            .stage_log()
            .iter()
            .any(|&(s, at)| s == FlightStage::RoundChute && t > at + 60.0);
        if fallen || stage == FlightStage::Landed || t > 1500.0 {
            core.tick(t + REFIT_EVERY_S);
            break;
        }
    }
    let msg = core.ascent_wind_msg(drone.drone().time_s());
    assert!(msg.ascent_over, "the burst ends the ascent: {msg:?}");
    // 0–3000 m in 500-m bands: six, the top one perhaps cut short by the burst.
    assert!(msg.bands.len() >= 5, "{} bands: {msg:?}", msg.bands.len());
    println!("band (m above site)  measured N, E ± 2σ (m/s)        simulated mean N, E   error");
    let (mut worst, mut sum_sq, mut outside_2sigma) = (0.0_f64, 0.0, 0);
    for b in &msg.bands {
        let altitude = b.alt_msl_m - origin_msl;
        let w = truth.wind_ned_mps(0.0, &nalgebra::Vector3::new(0.0, 0.0, -altitude));
        let (dn, de) = (b.wind_north_mps - w.x, b.wind_east_mps - w.y);
        println!(
            "{:6.0} ({:4.0}–{:4.0})  {:+5.2} ± {:.2}, {:+5.2} ± {:.2} [{} fixes]   {:+5.2}, {:+5.2}   {:.2}",
            altitude,
            b.alt_min_msl_m - origin_msl,
            b.alt_max_msl_m - origin_msl,
            b.wind_north_mps,
            2.0 * b.sigma_north_mps,
            b.wind_east_mps,
            2.0 * b.sigma_east_mps,
            b.samples,
            w.x,
            w.y,
            dn.hypot(de)
        );
        worst = worst.max(dn.abs()).max(de.abs());
        sum_sq += dn * dn + de * de;
        outside_2sigma += usize::from(dn.abs() > 2.0 * b.sigma_north_mps)
            + usize::from(de.abs() > 2.0 * b.sigma_east_mps);
    }
    let rms = (sum_sq / (2 * msg.bands.len()) as f64).sqrt();
    println!(
        "{} bands: RMS component error {rms:.3} m/s, worst {worst:.3} m/s, {outside_2sigma} of {} components outside 2σ",
        msg.bands.len(),
        2 * msg.bands.len()
    );
    // The gusts (σ 0.2 m/s) and the payload's swing are in the telemetry; the bands'
    // means must still be within a few tenths of the mean wind.
    assert!(worst < 0.4, "worst component error {worst:.3} m/s");
    assert!(
        outside_2sigma <= 2,
        "{outside_2sigma} components outside 2σ"
    );
}
