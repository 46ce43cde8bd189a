//! Replays of a real recording: the simulated drone flies the rehearsal against a recording
//! station, and the file is replayed through `serve_replay` (re-run and as recorded). A seek
//! back while paused must show the flight as it was at that moment — the state of that time
//! (mode, stage, position, fresh), the track and the plots' history ending there, every page
//! told to start over — and a re-run must fly the drone's own plan, exactly as live.

use crate::common;

use std::path::{Path, PathBuf};
use std::time::Duration;

use common::*;
use serde_json::{Value, json};
use stx_record::{IndexSource, Recording};
use stx_station::daemon::{PreparedReplay, Running, serve_replay};
use stx_station::recording::{STATE, telemetry_topic};
use stx_station::replay::ReplayMode;
use tokio::sync::oneshot;

/// The rehearsal flown against a recording station `speed` times faster than real time,
/// until the drone has landed; the closed recording.
async fn recorded_flight(name: &str, speed: f64) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("stx-replay-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let live = start_station(config(|c| {
        c.recording.enabled = true;
        c.recording.dir = Some(dir.clone());
    }))
    .await;
    let mission = stx_sim::drone::config::MissionConfig::builtin("rehearsal").expect("rehearsal");
    let _drone = sim_drone(live.running.link_local.expect("link"), &mission, speed).await;
    let mut landed = false;
    for _ in 0..1200 {
        let (_, s) = http(live.http(), "GET", "/api/state", Some(VIEWER), None).await;
        if s["vehicle"]["stage"] == "landed" {
            landed = true;
            break;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    assert!(landed, "the rehearsal did not land in time");
    // One more second of the drone on the ground, then the station closes its file.
    tokio::time::sleep(Duration::from_secs(1)).await;
    drop(live);
    let file = std::fs::read_dir(&dir)
        .expect("recordings")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.extension().is_some_and(|x| x == "mcap"))
        .expect("a recording");
    for _ in 0..100 {
        if Recording::open(&file).is_ok_and(|r| r.index() == IndexSource::Summary) {
            return file;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    panic!("the recording was not closed");
}

/// The recorded messages of `topic` as (log time, JSON).
fn recorded(file: &Path, topic: &str) -> Vec<(u64, Value)> {
    let mut recording = Recording::open(file).expect("recording");
    recording
        .messages()
        .expect("messages")
        .filter_map(Result::ok)
        .filter(|m| &*m.topic == topic)
        .filter_map(|m| Some((m.log_time, serde_json::from_slice(&m.data).ok()?)))
        .collect()
}

/// A replay station of `file`; dropping the sender stops it.
async fn replay_station(file: &Path, mode: ReplayMode) -> (Running, oneshot::Sender<()>) {
    let prepared = PreparedReplay::open(file, mode, 1.0).expect("a replayable recording");
    let (stop_tx, stop_rx) = oneshot::channel::<()>();
    let (started_tx, started_rx) = oneshot::channel();
    tokio::spawn(async move {
        let shutdown = async move {
            let _ = stop_rx.await;
        };
        let started = move |r: &Running| {
            let _ = started_tx.send(r.clone());
        };
        // Configured to share, as the live station is: a replay must share nothing.
        let sharing = config(|c| {
            c.sondehub = toml::from_str(
                "url = \"http://127.0.0.1:9\"\nuploader_callsign = \"STXTEST\"\n\
                 payload_callsign = \"STRAPLEX1\"\n",
            )
            .ok();
            c.chase = toml::from_str("callsign = \"STRAPLEX1\"\naddress = \"127.0.0.1\"").ok();
        });
        serve_replay(sharing, prepared, shutdown, started)
            .await
            .expect("replay station");
    });
    let running = tokio::time::timeout(Duration::from_secs(10), started_rx)
        .await
        .expect("replay started in time")
        .expect("replay started");
    (running, stop_tx)
}

async fn steer(station: &Running, body: Value) -> Value {
    let (status, view) = http(
        station.http,
        "POST",
        "/api/replay",
        Some(OPERATOR),
        Some(&body.to_string()),
    )
    .await;
    assert_eq!(status, 200, "{view}");
    view
}

/// Waits until the replay shows seek `epoch` (its rebuild done); the state then.
async fn shown(station: &Running, epoch: u64) -> Value {
    for _ in 0..300 {
        let (_, s) = http(station.http, "GET", "/api/state", Some(VIEWER), None).await;
        if s["replay"]["epoch"] == epoch && s["replay"]["seeking"] == false {
            return s;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    panic!("the replay never showed seek {epoch}");
}

/// The newest of `messages` logged at or before `t_ns`, and the first after it.
fn around(messages: &[(u64, Value)], t_ns: u64) -> (&Value, &Value) {
    let after = messages.partition_point(|(t, _)| *t <= t_ns);
    assert!(
        after > 0 && after < messages.len(),
        "{t_ns} within the recording"
    );
    (&messages[after - 1].1, &messages[after].1)
}

fn lat_lon(v: &Value) -> [f64; 2] {
    [
        v["lat_deg"].as_f64().expect("lat_deg"),
        v["lon_deg"].as_f64().expect("lon_deg"),
    ]
}

fn same_place(a: [f64; 2], b: [f64; 2]) -> bool {
    (a[0] - b[0]).abs() <= 1e-7 && (a[1] - b[1]).abs() <= 1e-7
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_seek_back_while_paused_shows_the_flight_as_it_was_then() {
    let file = recorded_flight("seek", 16.0).await;
    let states = recorded(&file, STATE);
    let gps = recorded(&file, &telemetry_topic("GPS_RAW_INT"));
    let start_ns = Recording::open(&file).unwrap().time_range().unwrap().0;

    // --- re-run
    let (station, _stop) = replay_station(&file, ReplayMode::Rerun).await;
    let (_, sharing) = http(station.http, "GET", "/api/sharing", Some(VIEWER), None).await;
    assert!(
        sharing["sondehub"].is_null() && sharing["chase"].is_null(),
        "a replay uploads to SondeHub and broadcasts to chase cars nothing: {sharing}"
    );
    let view = steer(&station, json!({"paused": true})).await;
    let duration_ms = view["duration_ms"].as_u64().expect("duration");
    // To the end first (a replay that has played through), then back while paused.
    steer(&station, json!({"position_ms": duration_ms})).await;
    shown(&station, 1).await;
    let mut ws = ws_connect(station.http, VIEWER).await;
    let back_ms = duration_ms * 6 / 10;
    steer(&station, json!({"position_ms": back_ms})).await;
    let s = shown(&station, 2).await;
    let t_ns = start_ns + back_ms * 1_000_000;
    let back_s = back_ms as f64 / 1000.0;

    assert_eq!(
        s["time_s"], back_s,
        "the station's clock is the replay's position"
    );
    assert_eq!(s["replay"]["paused"], true);
    assert_eq!(s["replay"]["position_ms"], back_ms);
    let (before, after) = around(&states, t_ns);
    for field in ["mode", "stage"] {
        assert_eq!(
            before["vehicle"][field], after["vehicle"][field],
            "steady flight at the seek point"
        );
        assert_eq!(s["vehicle"][field], before["vehicle"][field], "{field}");
    }
    assert_eq!(s["vehicle"]["stage"], "parafoil");
    let (gps_before, gps_after) = around(&gps, t_ns);
    let here = lat_lon(&s["vehicle"]["gps"]);
    assert!(
        same_place(here, lat_lon(gps_before)) || same_place(here, lat_lon(gps_after)),
        "the drone's GPS at the seek point: {here:?}, recorded {gps_before} / {gps_after}"
    );
    let estimate = lat_lon(&s["estimate"]);
    assert!(
        (estimate[0] - here[0]).abs() < 3e-4 && (estimate[1] - here[1]).abs() < 3e-4,
        "the estimate {estimate:?} is where the drone was then ({here:?})"
    );
    assert_eq!(s["link"]["stale"], false, "{}", s["link"]);
    assert_eq!(s["link"]["connected"], true);
    assert_eq!(s["estimate"]["stale"], false);

    // The track and the plots' history end at the seek point.
    let (_, track) = http(station.http, "GET", "/api/track", Some(VIEWER), None).await;
    let last = track["points"]
        .as_array()
        .and_then(|p| p.last())
        .expect("a track");
    let last_s = last["time_s"].as_f64().expect("time");
    assert!(
        last_s <= back_s && last_s > back_s - 1.0,
        "the track ends at {last_s} s, the seek point is {back_s} s"
    );
    let history = ws_until(&mut ws, 10.0, |m| {
        m["type"] == "history" && m["replay_epoch"] == 2
    })
    .await
    .expect("every page gets the history of the seek");
    let times = |key: &str| -> Vec<f64> {
        history[key]
            .as_array()
            .expect("a list")
            .iter()
            .filter_map(|p| p["time_s"].as_f64())
            .collect()
    };
    let (track_times, state_times) = (times("track"), times("states"));
    assert!(track_times.len() > 10 && state_times.len() > 10);
    assert!(track_times.iter().chain(&state_times).all(|&t| t <= back_s));
    assert!(track_times.windows(2).all(|w| w[0] < w[1]), "one timeline");

    // Paused, it stays that moment: nothing ages into stale.
    tokio::time::sleep(Duration::from_secs(3)).await;
    let (_, later) = http(station.http, "GET", "/api/state", Some(VIEWER), None).await;
    assert_eq!(later["time_s"], back_s);
    assert_eq!(later["link"]["stale"], false);
    assert_eq!(lat_lon(&later["vehicle"]["gps"]), here);

    // The re-run flies the drone's own plan, as the live station read it.
    let live_target = states
        .iter()
        .find(|(_, s)| s["guidance"]["target_source"] == "drone_plan")
        .map(|(_, s)| lat_lon(&s["guidance"]["target"]))
        .expect("the live station read the drone's plan");
    assert_eq!(s["guidance"]["target_source"], "drone_plan");
    let target = lat_lon(&s["guidance"]["target"]);
    assert!(
        same_place(target, live_target),
        "re-run target {target:?}, live {live_target:?}"
    );

    // --- as recorded
    let (station, _stop) = replay_station(&file, ReplayMode::Recorded).await;
    steer(&station, json!({"paused": true})).await;
    steer(&station, json!({"position_ms": duration_ms})).await;
    shown(&station, 1).await;
    let mut ws = ws_connect(station.http, VIEWER).await;
    steer(&station, json!({"position_ms": back_ms})).await;
    let s = shown(&station, 2).await;
    assert_eq!(s["wall_ms"], before["wall_ms"], "the state recorded then");
    assert_eq!(s["vehicle"]["stage"], "parafoil");
    assert_eq!(s["link"]["stale"], false);
    let history = ws_until(&mut ws, 10.0, |m| {
        m["type"] == "history" && m["replay_epoch"] == 2
    })
    .await
    .expect("every page gets the history of the seek");
    let then_s = before["time_s"].as_f64().expect("time");
    let track = history["track"].as_array().expect("track");
    let states_then = history["states"].as_array().expect("states");
    let recorded_then: Vec<&Value> = states
        .iter()
        .filter(|(t, _)| *t <= t_ns)
        .map(|(_, s)| s)
        .collect();
    assert_eq!(
        states_then.len(),
        recorded_then.len(),
        "every state recorded up to then"
    );
    let fresh = recorded_then
        .iter()
        .filter(|s| s["link"]["stale"] == false && s["estimate"].is_object())
        .count();
    assert_eq!(
        track.len(),
        fresh,
        "a point for each fresh estimate recorded up to then"
    );
    assert!(
        track
            .iter()
            .chain(states_then)
            .all(|p| p["time_s"].as_f64() <= Some(then_s))
    );
    assert_eq!(
        states_then.last().map(|s| &s["time_s"]),
        Some(&before["time_s"])
    );
    tokio::time::sleep(Duration::from_secs(3)).await;
    let (_, later) = http(station.http, "GET", "/api/state", Some(VIEWER), None).await;
    assert_eq!(later["wall_ms"], before["wall_ms"], "paused, it stays");
    let _ = std::fs::remove_dir_all(file.parent().expect("dir"));
}
