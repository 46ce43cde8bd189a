use super::feed::{Feed, RelaySettings, RelaySettingsError, snap};
use super::public::{PublicStateMsg, UpstreamNews, read_upstream};

/// A station `state` as the daemon sends it, trimmed to what a relay reads plus fields it must
/// not pass on.
fn station_state(mission_s: f64, lat: f64, lon: f64) -> String {
    serde_json::json!({
        "type": "state", "time_s": mission_s / 5.0, "mission_time_s": mission_s, "wall_ms": 1_700_000_000_000u64,
        "link": {"connected": true, "stale": false, "loss_percent": 3.0, "radios": []},
        "vehicle": {"mode": "auto", "battery_v": 7.4},
        "estimate": {"lat_deg": lat, "lon_deg": lon, "alt_msl_m": 1200.0, "velocity_ned_mps": [3.0, 4.0, 2.5],
                     "ground_speed_mps": 5.0, "course_deg": 53.1},
        "guidance": {"target": {"lat_deg": 49.0, "lon_deg": 16.0, "alt_msl_m": 300.0}, "phase": "spiral"},
        "prediction": {"planned": {"lat_deg": 49.001, "lon_deg": 16.002, "time_to_land_s": 120.0},
                       "uncontrolled": {"lat_deg": 49.2, "lon_deg": 16.3}},
        "mission": {"stage": "parafoil", "cutdown_armed_until_s": null},
        "readiness": {"items": []}, "recording": {"file": "secret.mcap"}
    })
    .to_string()
}

fn state(news: UpstreamNews) -> PublicStateMsg {
    match news {
        UpstreamNews::State(s) => s,
        other => panic!("not a state: {other:?}"),
    }
}

#[test]
fn a_station_state_becomes_the_public_one_and_nothing_else_of_it_passes() {
    let s = state(read_upstream(&station_state(100.0, 49.01, 16.02)).expect("reads"));
    let p = s.position.expect("position");
    assert_eq!((p.lat_deg, p.lon_deg, p.alt_msl_m), (49.01, 16.02, 1200.0));
    assert_eq!(p.climb_mps, -2.5, "NED down 2.5 m/s is a climb of −2.5");
    assert_eq!(s.stage.as_deref(), Some("parafoil"));
    assert_eq!(
        s.landing.map(|l| (l.lat_deg, l.lon_deg)),
        Some((49.001, 16.002))
    );
    assert_eq!(s.target.map(|t| (t.lat_deg, t.lon_deg)), Some((49.0, 16.0)));
    let text = serde_json::to_string(&s).expect("serialises");
    for private in [
        "battery",
        "mode",
        "secret",
        "loss",
        "uncontrolled",
        "readiness",
        "phase",
    ] {
        assert!(!text.contains(private), "{private} leaked: {text}");
    }
    // Another relay reads it back as it is.
    assert_eq!(state(read_upstream(&text).expect("reads")), s);
}

#[test]
fn other_messages_are_not_public_and_garbage_is_an_error() {
    let event = r#"{"type":"event","level":"info","text":"cutdown armed"}"#;
    assert_eq!(read_upstream(event).expect("reads"), UpstreamNews::Other);
    assert!(read_upstream("{not json").is_err());
    assert!(read_upstream(r#"{"type":"state","wall_ms":"soon"}"#).is_err());
}

#[test]
fn settings_out_of_range_are_refused() {
    assert_eq!(
        RelaySettings::new(-1.0, 0.0),
        Err(RelaySettingsError::Delay(-1.0))
    );
    assert!(matches!(
        RelaySettings::new(0.0, f64::NAN),
        Err(RelaySettingsError::Coarsen(_))
    ));
    assert!(RelaySettings::new(30.0, 500.0).is_ok());
}

#[test]
fn a_delayed_relay_shows_each_state_that_much_later_and_the_newest_due_only() {
    let mut feed = Feed::new(RelaySettings::new(10.0, 0.0).expect("valid"));
    for k in 0..8 {
        let t = f64::from(k);
        feed.on_upstream(
            t,
            read_upstream(&station_state(100.0 + t, 49.0, 16.0 + t * 1e-4)).expect("reads"),
        );
        if t < 10.0 {
            assert_eq!(feed.due(t), None, "nothing before the delay ({t} s)");
        }
    }
    assert_eq!(feed.due(9.99), None);
    let first = feed.due(10.0).expect("the first is due at 10 s");
    assert_eq!(first.mission_time_s, Some(100.0));
    assert_eq!(first.delay_s, 10.0);
    let newest = feed.due(13.5).expect("due");
    assert_eq!(
        newest.mission_time_s,
        Some(103.0),
        "the newest due, the ones before it skipped"
    );
    assert_eq!(feed.track().len(), 4, "each state shown is on the track");
    assert_eq!(feed.due(13.6), None, "nothing new");
}

#[test]
fn positions_are_rounded_to_the_grid_and_a_coarser_relay_behind_rounds_again() {
    let mut a = Feed::new(RelaySettings::new(0.0, 500.0).expect("valid"));
    a.on_upstream(
        0.0,
        read_upstream(&station_state(100.0, 49.0123, 16.0456)).expect("reads"),
    );
    let s = a.due(0.0).expect("due");
    let p = s.position.expect("position");
    assert_eq!((p.lat_deg, p.lon_deg), snap(49.0123, 16.0456, 500.0));
    let moved_m = ((p.lat_deg - 49.0123) * 111_320.0)
        .hypot((p.lon_deg - 16.0456) * 111_320.0 * 49f64.to_radians().cos());
    assert!(moved_m <= 500.0 * 0.71 + 1.0, "moved {moved_m} m");
    assert!(moved_m > 1.0, "it did round");
    assert_eq!(s.coarsen_m, 500.0);
    let landing = s.landing.expect("landing");
    assert_eq!(
        (landing.lat_deg, landing.lon_deg),
        snap(49.001, 16.002, 500.0)
    );
    // Behind it a relay with a finer grid keeps 500 m; one with a coarser grid takes its own.
    let text = serde_json::to_string(&s).expect("serialises");
    let mut fine = Feed::new(RelaySettings::new(5.0, 100.0).expect("valid"));
    fine.on_upstream(0.0, read_upstream(&text).expect("reads"));
    let f = fine.due(5.0).expect("due");
    assert_eq!((f.coarsen_m, f.delay_s), (500.0, 5.0));
    assert_eq!(f.position, s.position);
    let mut coarse = Feed::new(RelaySettings::new(0.0, 2000.0).expect("valid"));
    coarse.on_upstream(0.0, read_upstream(&text).expect("reads"));
    let c = coarse.due(0.0).expect("due");
    let cp = c.position.expect("position");
    assert_eq!((cp.lat_deg, cp.lon_deg), snap(p.lat_deg, p.lon_deg, 2000.0));
    assert_eq!(c.coarsen_m, 2000.0);
}

#[test]
fn the_history_fills_the_track_up_to_the_state_shown_never_ahead_of_it() {
    let mut feed = Feed::new(RelaySettings::new(30.0, 0.0).expect("valid"));
    let history = serde_json::json!({"type": "history", "replay_epoch": null, "events": [], "states": [],
        "track": (0..60).map(|k| serde_json::json!({"time_s": k, "mission_time_s": 40.0 + f64::from(k), "lat_deg": 49.0, "lon_deg": 16.0 + f64::from(k) * 1e-4, "alt_msl_m": 900.0})).collect::<Vec<_>>()});
    feed.on_upstream(0.0, read_upstream(&history.to_string()).expect("reads"));
    assert!(
        feed.history().track.is_empty(),
        "a delayed relay shows none of it yet"
    );
    feed.on_upstream(
        0.0,
        read_upstream(&station_state(70.0, 49.0, 16.003)).expect("reads"),
    );
    feed.due(30.0).expect("due");
    let track = feed.history().track;
    assert_eq!(
        track.len(),
        31,
        "40 s … 70 s of the history; the state at 70 s adds nothing within 1 s"
    );
    assert!(track.iter().all(|p| p.mission_time_s <= 70.0));
}
