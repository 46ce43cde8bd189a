//! The station's ascent winds against the simulated drone: `mission-short` (a balloon
//! ascent at about 5 m/s to a burst at 3 km through a light westerly with gusts) flown in
//! process, every frame crossing the MAVLink link into the station's core, and the bands it
//! measures compared with the scenario's mean wind (`config/scenarios/mission-short.toml`);
//! then the same flight as a station running 20 times slower than the drone's clock (an
//! accelerated rehearsal) sees it, live and from its recordings.
//!
//! `cargo test --release -p stx-station --test station ascent_winds:: -- --nocapture` prints the
//! comparison band by band.

use crate::common;

use std::io::Cursor;
use std::time::Duration;

use stx_dynamics::vehicle::Vehicle;
use stx_dynamics::wind::WindField;
use stx_gnc::mission::FlightStage;
use stx_link::endpoint::{GroundConfig, GroundEndpoint, GroundEvent, LinkConfig, LinkStats};
use stx_link::telemetry::Telemetry;
use stx_record::{CoreOptions, RecorderCore, Recording, RecordingInfo};
use stx_sim::drone::link::LinkedDrone;
use stx_sim::drone::{Drone, MissionConfig};
use stx_station::config::{DEFAULT_STATION_TOML, StationConfig};
use stx_station::core::{REFIT_EVERY_S, StationCore};
use stx_station::messages::AscentBandView;
use stx_station::recording::ascent::measured_forecast;
use stx_station::recording::telemetry::TelemetryChannels;

/// mission-short's mean wind (its gusts left out) and the station's origin, m MSL.
fn truth() -> (Box<dyn WindField>, f64) {
    let mission = MissionConfig::builtin("mission-short").expect("built-in mission");
    let mut mean = mission.wind.clone().expect("mission-short has a wind");
    mean.turbulence = None;
    (mean.build().expect("the mean wind"), mission.site.alt_msl_m)
}

/// mission-short flown until the round chute has fallen a while after the burst, into a
/// station core whose clock runs `1/slower` as fast as the drone's; every telemetry message
/// it decoded, with the drone's mission time at its arrival.
fn fly(slower: f64) -> (StationCore, Vec<(f64, Telemetry)>) {
    let mission = MissionConfig::builtin("mission-short").expect("built-in mission");
    let config = StationConfig::from_toml_str(DEFAULT_STATION_TOML).expect("station config");
    // The station's origin is the launch site: band altitudes above it are the scenario's.
    assert_eq!(config.origin.alt_msl_m, mission.site.alt_msl_m);
    let drone = Drone::new(&mission, Vehicle::straplex()).expect("drone");
    let mut drone = LinkedDrone::new(drone, LinkConfig::vehicle(), Duration::ZERO).expect("link");
    let mut ground = GroundEndpoint::new(GroundConfig::default(), Duration::ZERO);
    let mut core = StationCore::new(config, 0);
    let mut heard = Vec::new();
    let mut next_tick = 0.0;
    // Until the round chute has fallen a while after the burst (3 km at ~5 m/s: ~10 min).
    loop {
        let t = drone.drone().time_s();
        let now = Duration::from_secs_f64(t);
        let station_s = t / slower;
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
            if let GroundEvent::Telemetry { telemetry, .. } = &e {
                heard.push((t, telemetry.clone()));
            }
            core.on_link_event(station_s, e);
        }
        // The station ticks four times a second of its own clock.
        if station_s >= next_tick {
            next_tick = station_s + 0.25;
            let stats = LinkStats {
                connected: true,
                ..LinkStats::default()
            };
            core.set_link_stats(station_s, stats);
            core.tick(station_s);
        }
        let stage = drone.drone().stage();
        let fallen = drone
            .drone()
            .stage_log()
            .iter()
            .any(|&(s, at)| s == FlightStage::RoundChute && t > at + 60.0);
        if fallen || stage == FlightStage::Landed || t > 1500.0 {
            core.tick(station_s + REFIT_EVERY_S);
            break;
        }
    }
    (core, heard)
}

/// Prints `bands` against the truth and returns the worst component error, m/s, and how many
/// components lie outside 2σ of it.
fn against_truth(label: &str, bands: &[AscentBandView]) -> (f64, usize) {
    let (truth, origin_msl) = truth();
    println!("{label}");
    println!("band (m above site)  measured N, E ± 2σ (m/s)        simulated mean N, E   error");
    let (mut worst, mut sum_sq, mut outside_2sigma) = (0.0_f64, 0.0, 0);
    for b in bands {
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
    let rms = (sum_sq / (2 * bands.len().max(1)) as f64).sqrt();
    println!(
        "{} bands: RMS component error {rms:.3} m/s, worst {worst:.3} m/s, {outside_2sigma} of {} components outside 2σ",
        bands.len(),
        2 * bands.len()
    );
    (worst, outside_2sigma)
}

/// A recording of `heard` as a station whose clock runs `1/slower` as fast as the drone's
/// writes it (log times in whole milliseconds of that clock), read back for its bands.
fn recorded_bands(heard: &[(f64, Telemetry)], slower: f64) -> Vec<AscentBandView> {
    const T0_NS: u64 = 1_790_000_000_000_000_000;
    let info = RecordingInfo::new("test", "straplex-2", "ascent winds");
    let mut core = RecorderCore::new(CoreOptions::default(), info, Duration::ZERO).unwrap();
    let channels = TelemetryChannels::register(&mut core, Duration::ZERO).unwrap();
    for (t, telemetry) in heard {
        let station = Duration::from_millis((t / slower * 1000.0) as u64);
        let log = T0_NS + station.as_nanos() as u64;
        for (id, data) in channels.records(log, telemetry) {
            core.write(station, id, log, log, &data).unwrap();
        }
    }
    let bytes = common::finished_recording(core);
    let mut recording = Recording::from_reader(Cursor::new(bytes)).expect("readable");
    let measured = measured_forecast(&mut recording, &[]).expect("measured");
    measured
        .bands
        .iter()
        .map(|b| AscentBandView::of(b, measured.origin_msl_m))
        .collect()
}

#[test]
fn mission_short_ascent_bands_agree_with_the_simulated_wind() {
    let (core, heard) = fly(1.0);
    let end_s = heard.last().map_or(0.0, |(t, _)| *t);
    let msg = core.ascent_wind_msg(end_s);
    assert!(msg.ascent_over, "the burst ends the ascent: {msg:?}");
    // 0–3000 m in 500-m bands: six, the top one perhaps cut short by the burst.
    assert!(msg.bands.len() >= 5, "{} bands: {msg:?}", msg.bands.len());
    let (worst, outside_2sigma) = against_truth("live, 1×", &msg.bands);
    // The gusts (σ 0.2 m/s) and the payload's swing are in the telemetry; the bands'
    // means must still be within a few tenths of the mean wind.
    assert!(worst < 0.4, "worst component error {worst:.3} m/s");
    assert!(
        outside_2sigma <= 2,
        "{outside_2sigma} components outside 2σ"
    );
    assert!(msg.bands.iter().all(|b| b.refused.is_none()), "{msg:?}");
}

/// Issue 28: a recording of a 20× rehearsal gave 88–176 m/s on the Plan page, the drift
/// divided by the station's clock. The same flight seen by a station 20 times slower than the
/// drone — live, and read back from its recording — measures the bands the 1× station does,
/// and they agree with the simulated wind.
#[test]
fn regression_measured_winds_are_the_same_at_1x_and_20x_live_and_recorded() {
    let (live_1x, heard) = fly(1.0);
    let (live_20x, heard_20x) = fly(20.0);
    assert_eq!(heard.len(), heard_20x.len(), "the same flight");
    let end_s = heard.last().map_or(0.0, |(t, _)| *t);
    let live = live_1x.ascent_wind_msg(end_s).bands;
    let cases = [
        (
            "live, station 20× slower",
            live_20x.ascent_wind_msg(end_s / 20.0).bands,
        ),
        ("recorded at 1×", recorded_bands(&heard, 1.0)),
        ("recorded at 20×", recorded_bands(&heard, 20.0)),
    ];
    for (label, bands) in &cases {
        let (worst, outside_2sigma) = against_truth(label, bands);
        assert!(worst < 0.4, "{label}: worst component error {worst:.3} m/s");
        assert!(
            outside_2sigma <= 2,
            "{label}: {outside_2sigma} components outside 2σ"
        );
        assert!(
            bands.iter().all(|b| b.refused.is_none()),
            "{label}: {bands:?}"
        );
        // The same bands as the 1× station's, within their σ: the recordings' origin is
        // their first fix, a few metres off the station's, which moves a band's edges.
        assert_eq!(bands.len(), live.len(), "{label}");
        for (b, l) in bands.iter().zip(&live) {
            assert!(
                (b.alt_msl_m - l.alt_msl_m).abs() < 20.0,
                "{label}: {b:?} vs {l:?}"
            );
            assert!(
                (b.wind_north_mps - l.wind_north_mps).abs() < l.sigma_north_mps,
                "{label}: {b:?} vs {l:?}"
            );
            assert!(
                (b.wind_east_mps - l.wind_east_mps).abs() < l.sigma_east_mps,
                "{label}: {b:?} vs {l:?}"
            );
        }
    }
}
