use std::time::Duration;

use stx_record::{CoreOptions, RecordingInfo};

use super::*;
use crate::config::DEFAULT_STATION_TOML;
use crate::core::StationCore;

fn config() -> StationConfig {
    StationConfig::from_toml_str(DEFAULT_STATION_TOML).expect("shipped config")
}

fn channels() -> StationChannels {
    let mut core = RecorderCore::new(
        CoreOptions::default(),
        RecordingInfo::new("test", "v", "m"),
        Duration::ZERO,
    )
    .expect("core");
    StationChannels::register(&mut core, Duration::ZERO).expect("channels")
}

fn parse(payload: &[u8]) -> Value {
    serde_json::from_slice(payload).expect("JSON")
}

#[test]
fn the_configuration_is_kept_without_a_token() {
    let c = config();
    let (_, payload) = channels().config(&c);
    let text = String::from_utf8(payload).expect("utf-8");
    for t in &c.tokens {
        assert!(!text.contains(&t.token), "token of {} in {text}", t.name);
        assert!(text.contains(&t.name), "name {} missing", t.name);
    }
    let v: Value = serde_json::from_str(&text).expect("JSON");
    assert_eq!(v["tokens"][0]["role"], "operator");
    assert_eq!(v["origin"]["lat_deg"], c.origin.lat_deg);
}

#[test]
fn an_event_goes_to_the_station_channel_and_foxglove_s_log() {
    let ch = channels();
    let event = EventMsg {
        kind: "event",
        time_s: 2.0,
        mission_time_s: Some(12.0),
        wall_ms: 1_700_000_000_250,
        level: Level::Warning,
        source: "link",
        text: "link lost".into(),
    };
    let out = ch.event(&event);
    assert_eq!(out.len(), 2);
    assert_eq!(parse(&out[0].1)["text"], "link lost");
    let log = parse(&out[1].1);
    assert_eq!(log["level"], LogLevel::Warning as u8);
    assert_eq!(log["name"], "link");
    assert_eq!(log["timestamp"]["sec"], 1_700_000_000u64);
    assert_eq!(log["timestamp"]["nsec"], 250_000_000u64);
}

#[test]
fn a_predicted_ellipse_becomes_its_east_north_covariance() {
    let ts = Timestamp::from_nanos(0);
    let t = |axis: f64| TouchdownView {
        lat_deg: 38.5,
        lon_deg: -7.9,
        time_to_land_s: 60.0,
        semi_major_m: 30.0,
        semi_minor_m: 10.0,
        major_axis_deg: axis,
    };
    // Major axis north: 900 m² along N, 100 m² along E.
    let north = touchdown_fix(ts, &t(0.0), 245.0).position_covariance;
    assert!((north[0] - 100.0).abs() < 1e-9 && (north[4] - 900.0).abs() < 1e-9);
    assert!(north[1].abs() < 1e-9);
    // Major axis east.
    let east = touchdown_fix(ts, &t(90.0), 245.0).position_covariance;
    assert!((east[0] - 900.0).abs() < 1e-9 && (east[4] - 100.0).abs() < 1e-9);
    // North-east: E and N vary together (positive correlation), trace preserved.
    let ne = touchdown_fix(ts, &t(45.0), 245.0);
    assert!((ne.position_covariance[1] - 400.0).abs() < 1e-9);
    assert!((ne.position_covariance[0] + ne.position_covariance[4] - 1000.0).abs() < 1e-9);
    assert_eq!(ne.altitude, 245.0);
}

#[test]
fn a_state_without_estimate_records_only_itself_and_with_one_its_position_too() {
    let ch = channels();
    let core = StationCore::new(config(), 1_700_000_000_000);
    let state = core.state_msg_now(1.0);
    let out = ch.state(&state, 245.0);
    assert_eq!(out.len(), 1, "no estimate, no prediction yet");
    assert_eq!(parse(&out[0].1)["type"], "state");
}
