//! The recordings directory through a real daemon: the list (what it shows of good and bad
//! files), and replays opened from it — each a station of its own, at most
//! `MAX_SESSIONS` at once, refused with a reason past that or for a file that is no recording.

use crate::common;

use std::path::{Path, PathBuf};
use std::time::Duration;

use common::*;
use serde_json::json;
use stx_record::{CoreOptions, RecorderCore, RecordingInfo, foxglove};
use stx_station::daemon::MAX_SESSIONS;

const T0: u64 = 1_767_225_600_000_000_000;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("stx-recordings-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// A closed recording of 50 log lines over 5 s.
fn write_recording(path: &Path) {
    let info = RecordingInfo::new("test", "straplex-2", "api test");
    let mut core = RecorderCore::new(CoreOptions::default(), info, Duration::ZERO).unwrap();
    let ch = core
        .add_channel(Duration::ZERO, foxglove::log_channel("/events").unwrap())
        .unwrap();
    for i in 0..50u64 {
        let t = T0 + i * 100_000_000;
        core.write(Duration::from_millis(100 * i), ch, t, t, br#"{"i":1}"#)
            .unwrap();
    }
    std::fs::write(path, finished_recording(core)).unwrap();
}

fn with_dir(dir: &Path) -> stx_station::config::StationConfig {
    let dir = dir.to_owned();
    config(move |c| c.recording.dir = Some(dir))
}

#[tokio::test]
async fn the_list_shows_recordings_and_says_which_files_are_not() {
    let dir = temp_dir("list");
    write_recording(&dir.join("flight-1.mcap"));
    std::fs::write(dir.join("broken.mcap"), b"not an MCAP file at all").unwrap();
    std::fs::write(dir.join("notes.txt"), b"the field was wet").unwrap();
    let station = start_station(with_dir(&dir)).await;
    let (status, body) = http(station.http(), "GET", "/api/recordings", Some(VIEWER), None).await;
    assert_eq!(status, 200, "{body}");
    assert_eq!(body["directory"], json!(dir.display().to_string()));
    let list = body["recordings"].as_array().expect("recordings");
    assert_eq!(list.len(), 1, "{body}");
    let r = &list[0];
    assert_eq!(r["name"], "flight-1.mcap");
    assert_eq!(r["messages"], 50);
    assert_eq!(r["duration_ms"], 4900);
    assert_eq!(r["start_ms"], T0 / 1_000_000);
    assert_eq!(r["mission"], "api test");
    assert_eq!(r["complete"], true);
    assert_eq!(r["recording_now"], false);
    let size = std::fs::metadata(dir.join("flight-1.mcap")).unwrap().len();
    assert_eq!(r["size_bytes"], size);
    let bad = body["unreadable"].as_array().expect("unreadable");
    assert_eq!(bad.len(), 1, "{body}");
    assert_eq!(bad[0]["name"], "broken.mcap");
    // A name outside the directory, or not a recording's, is not found.
    for path in [
        "/api/recordings/notes.txt",
        "/api/recordings/..%2Fnotes.mcap",
        "/api/recordings/missing.mcap",
    ] {
        let (status, _) = http(station.http(), "GET", path, Some(VIEWER), None).await;
        assert_eq!(status, 404, "{path}");
    }
}

#[tokio::test]
async fn without_a_directory_the_list_is_empty_and_says_so() {
    let station = start_station(config(|c| c.recording.dir = None)).await;
    let (status, body) = http(station.http(), "GET", "/api/recordings", Some(VIEWER), None).await;
    assert_eq!(status, 200);
    assert_eq!(body["directory"], json!(null));
    assert_eq!(body["recordings"], json!([]));
}

#[tokio::test]
async fn replays_open_beside_the_live_station_up_to_the_limit() {
    let dir = temp_dir("replays");
    write_recording(&dir.join("flight-1.mcap"));
    std::fs::write(dir.join("broken.mcap"), b"garbage").unwrap();
    let station = start_station(with_dir(&dir)).await;
    let open = |name: &str, token: &'static str| {
        let path = format!("/api/recordings/{name}/replay");
        let addr = station.http();
        async move { http(addr, "POST", &path, Some(token), Some("{}")).await }
    };
    let (status, body) = open("flight-1.mcap", VIEWER).await;
    assert_eq!((status, body["error"].as_str()), (403, Some("forbidden")));
    let (status, body) = open("broken.mcap", OPERATOR).await;
    assert_eq!(status, 422, "{body}");
    assert_eq!(body["error"], "unreadable");
    let mut ports = Vec::new();
    for _ in 0..MAX_SESSIONS {
        let (status, body) = open("flight-1.mcap", OPERATOR).await;
        assert_eq!(status, 201, "{body}");
        assert_eq!(body["name"], "flight-1.mcap");
        ports.push(body["port"].as_u64().expect("port") as u16);
    }
    let (status, body) = open("flight-1.mcap", OPERATOR).await;
    assert_eq!(
        (status, body["error"].as_str()),
        (409, Some("busy")),
        "{body}"
    );
    // Each is a station replaying the file; the live one stays live.
    for port in ports {
        let addr = std::net::SocketAddr::from(([127, 0, 0, 1], port));
        let (status, state) = http(addr, "GET", "/api/state", Some(VIEWER), None).await;
        assert_eq!(status, 200);
        let file = state["replay"]["file"].as_str().unwrap_or_default();
        assert!(file.ends_with("flight-1.mcap"), "{state}");
        // A replay does not open replays of its own.
        let (status, body) = http(
            addr,
            "POST",
            "/api/recordings/flight-1.mcap/replay",
            Some(OPERATOR),
            Some("{}"),
        )
        .await;
        assert_eq!((status, body["error"].as_str()), (409, Some("replay")));
    }
    let (_, live) = http(station.http(), "GET", "/api/state", Some(VIEWER), None).await;
    assert_eq!(live["replay"], json!(null));
}
