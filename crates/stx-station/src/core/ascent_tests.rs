//! The ascent winds in the core: telemetry of a balloon rising through a known wind becomes
//! bands of that wind, an `ascent_wind` message and the profile the predictions fly in; the
//! drone's restarts keep or start over the measurement as `ascent.rs` says.

use stx_dynamics::wind::WindField;
use stx_link::telemetry::{GlobalPosition, Telemetry};

use super::tests::{core, gps_raw, level_attitude};
use super::*;

/// The air's velocity (north, east), m/s, at `altitude_m` above the origin: 4 m/s east
/// below 1000 m, 3 m/s north and 2 m/s east above.
fn wind_at(altitude_m: f64) -> [f64; 2] {
    if altitude_m < 1000.0 {
        [0.0, 4.0]
    } else {
        [3.0, 2.0]
    }
}

/// A balloon drifting with [`wind_at`] and climbing at `climb_mps`, its telemetry sent at
/// 2 Hz with the drone's clock `boot_offset_s` behind the flight's.
struct Balloon {
    t: f64,
    ned: [f64; 3],
    boot_offset_s: f64,
}

impl Balloon {
    fn new() -> Self {
        Self {
            t: 0.0,
            ned: [0.0, 0.0, 0.0],
            boot_offset_s: 0.0,
        }
    }

    /// Flies until `to_s` of the flight's clock, ticking the core at each message.
    fn fly(&mut self, core: &mut StationCore, to_s: f64, climb_mps: f64) {
        const DT: f64 = 0.5;
        while self.t < to_s {
            let [n, e] = wind_at(-self.ned[2]);
            self.send(core, [n, e], climb_mps);
            self.ned[0] += n * DT;
            self.ned[1] += e * DT;
            self.ned[2] = (self.ned[2] - climb_mps * DT).min(0.0);
            self.t += DT;
        }
    }

    fn send(&self, core: &mut StationCore, [n, e]: [f64; 2], climb_mps: f64) {
        let position = nalgebra::Vector3::new(self.ned[0], self.ned[1], self.ned[2]);
        let (lat, lon, alt) = core.frame.to_geodetic(&position);
        let ms = ((self.t - self.boot_offset_s) * 1000.0) as u32;
        let now = self.t;
        for telemetry in [
            Telemetry::Position(GlobalPosition {
                time_boot_ms: ms,
                lat_deg: lat,
                lon_deg: lon,
                alt_msl_m: alt,
                alt_rel_m: alt - core.frame.alt_msl_m,
                v_north_mps: n,
                v_east_mps: e,
                v_down_mps: -climb_mps,
                heading_deg: None,
            }),
            level_attitude(ms),
            Telemetry::GpsRaw(gps_raw(ms, [lat, lon, alt], [n, e])),
        ] {
            core.on_link_event(
                now,
                GroundEvent::Telemetry {
                    from: (1, 1),
                    telemetry,
                },
            );
        }
        core.tick(now);
    }
}

fn ascent_msgs(core: &mut StationCore) -> Vec<crate::messages::AscentWindMsg> {
    core.drain_outbound()
        .into_iter()
        .filter_map(|o| match o {
            Outbound::AscentWind(m) => Some(m),
            _ => None,
        })
        .collect()
}

#[test]
fn an_ascent_through_a_known_wind_gives_its_bands_a_message_and_the_predictions_profile() {
    let mut core = core();
    let origin_msl = core.frame.alt_msl_m;
    let mut balloon = Balloon::new();
    // 60 s on the pad, then 400 s at 5 m/s: 2000 m, four 500-m bands.
    balloon.fly(&mut core, 60.0, 0.0);
    assert!(core.ascent.bands().is_empty(), "no band on the pad");
    balloon.fly(&mut core, 460.0, 5.0);
    core.tick(balloon.t + REFIT_EVERY_S);
    let msgs = ascent_msgs(&mut core);
    let last = msgs
        .last()
        .expect("ascent_wind messages as the bands filled");
    assert!(msgs.len() >= 4, "{} messages", msgs.len());
    assert_eq!(last.bands.len(), 4, "{:?}", last.bands);
    for b in &last.bands {
        let truth = wind_at(b.alt_msl_m - origin_msl);
        assert!(
            (b.wind_north_mps - truth[0]).abs() < 0.05 && (b.wind_east_mps - truth[1]).abs() < 0.05,
            "band at {:.0} m MSL: {b:?}, truth {truth:?}",
            b.alt_msl_m
        );
        assert!(b.alt_msl_m > origin_msl && b.alt_msl_m < origin_msl + 2000.0);
        assert!(b.sigma_north_mps > 0.0 && b.sigma_north_mps < 0.5, "{b:?}");
        assert!(b.samples >= 150, "{b:?}");
        assert_eq!(b.method, stx_gnc::ascent_wind::BandMethod::GpsVelocity);
    }
    assert!(!last.ascent_over);
    // The profile: the bands where measured, the forecast above (its 11,755-m row above the
    // origin: 20 m/s from 240°).
    let profile = core.wind_profile().expect("a profile");
    let at =
        |altitude_m: f64| profile.wind_ned_mps(0.0, &nalgebra::Vector3::new(0.0, 0.0, -altitude_m));
    let low = at(last.bands[0].alt_msl_m - origin_msl);
    assert!((low.y - 4.0).abs() < 0.05 && low.x.abs() < 0.05, "{low}");
    let high = at(20_000.0);
    let (s, c) = 240_f64.to_radians().sin_cos();
    assert!((high.x + 20.0 * c).abs() < 1e-9 && (high.y + 20.0 * s).abs() < 1e-9);
    // Nothing new, nothing sent.
    core.tick(balloon.t + 3.0 * REFIT_EVERY_S);
    assert!(ascent_msgs(&mut core).is_empty());
}

#[test]
fn a_drone_restart_mid_ascent_keeps_the_bands_and_the_measurement_goes_on() {
    let mut core = core();
    let mut balloon = Balloon::new();
    balloon.fly(&mut core, 250.0, 5.0);
    core.tick(balloon.t + REFIT_EVERY_S);
    let before = core.ascent.bands().to_vec();
    assert_eq!(before.len(), 3, "{before:?}");
    // The drone's clock starts again from 0 at 250 s, 1,250 m up.
    balloon.boot_offset_s = balloon.t;
    balloon.fly(&mut core, 450.0, 5.0);
    core.tick(balloon.t + REFIT_EVERY_S);
    let after = core.ascent.bands();
    assert_eq!(after.len(), 5, "2,250 m: {after:?}");
    assert_eq!(
        after[0], before[0],
        "the band finished before the restart is kept"
    );
    for b in after {
        let truth = wind_at(b.altitude_m);
        assert!(
            (b.wind_north_mps - truth[0]).abs() < 0.05 && (b.wind_east_mps - truth[1]).abs() < 0.05,
            "{b:?}"
        );
    }
    assert!(
        core.events_since(0.0)
            .iter()
            .any(|e| e.text.contains("ascent winds") && e.text.contains("kept")),
        "the operators are told"
    );
}

#[test]
fn a_drone_restart_after_the_ascent_ended_starts_a_new_measurement() {
    let mut core = core();
    let mut balloon = Balloon::new();
    balloon.fly(&mut core, 250.0, 5.0);
    // Burst: the stack falls at 15 m/s to the ground.
    balloon.fly(&mut core, 340.0, -15.0);
    core.tick(balloon.t + REFIT_EVERY_S);
    let msg = core.ascent_wind_msg(balloon.t);
    assert!(msg.ascent_over && msg.bands.len() == 3, "{msg:?}");
    // The fixes of the last 10 s before the fall was seen are withdrawn: the last band ends
    // before the burst at 250 s.
    let top = msg.bands.last().map_or(f64::NAN, |b| b.time_end_s);
    assert!(top < 245.0, "{top}");
    ascent_msgs(&mut core);
    // Power-cycled on the ground for the next flight.
    balloon.boot_offset_s = balloon.t;
    balloon.fly(&mut core, 360.0, 0.0);
    core.tick(balloon.t + REFIT_EVERY_S);
    let sent = ascent_msgs(&mut core);
    assert!(
        sent.last()
            .is_some_and(|m| m.bands.is_empty() && !m.ascent_over),
        "the pages learn the old bands are gone: {sent:?}"
    );
    // Only the forecast remains.
    let rows = core.wind_profile().expect("the forecast").rows().len();
    assert_eq!(rows, core.config.forecast_wind.len());
}

#[test]
fn the_prediction_job_carries_the_profile_and_a_bad_ascent_setting_is_refused() {
    let mut core = core();
    assert!(core.wind_profile().is_some(), "the shipped forecast alone");
    let mut balloon = Balloon::new();
    balloon.fly(&mut core, 150.0, 5.0);
    let job = core.prediction_job().expect("navigation has a solution");
    let rows = job.wind_profile().expect("a profile").rows();
    assert!(rows.len() > core.config.forecast_wind.len(), "{rows:?}");
    let text = format!("{DEFAULT_TOML}\n[ascent_wind]\nband_height_m = -1.0\n");
    match StationConfig::from_toml_str(&text) {
        Err(crate::config::ConfigError::Invalid { field, .. }) => {
            assert_eq!(field, "ascent_wind.band_height_m")
        }
        other => panic!("expected a refusal, got {:?}", other.map(|_| ())),
    }
}

use crate::config::DEFAULT_STATION_TOML as DEFAULT_TOML;
