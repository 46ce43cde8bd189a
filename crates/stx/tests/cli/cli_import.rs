//! `stx import` on a tlog written with pymavlink's own encoder (as MAVProxy writes them): every
//! message pymavlink reads back is in the recording's raw frames, with its time, and the ones
//! the station decodes are on their telemetry channels, while reports without a GPS fix (at
//! 0°, 0°) never become positions; bad input is refused clearly.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;
use stx_record::{MavlinkFrame, Recording};

fn python() -> PathBuf {
    std::env::var_os("STX_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../.venv/bin/python"))
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("stx-cli-import-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn stx(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_stx"))
        .args(args)
        .output()
        .expect("stx runs")
}

/// The MAVLink message id of a v2 (or v1) frame.
fn message_id(frame: &[u8]) -> u32 {
    match frame[0] {
        0xFD => u32::from(frame[7]) | u32::from(frame[8]) << 8 | u32::from(frame[9]) << 16,
        _ => u32::from(frame[5]),
    }
}

#[test]
fn a_pymavlink_tlog_becomes_a_recording_with_every_message() {
    let dir = temp_dir("pymavlink");
    let tlog = dir.join("flight.tlog");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/peers/write_tlog.py");
    let out = Command::new(python())
        .arg(&script)
        .arg(&tlog)
        .output()
        .expect("python runs (set STX_PYTHON, with pymavlink)");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let theirs: Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let mcap = dir.join("flight.mcap");
    let imported = stx(&[
        "import",
        tlog.to_str().unwrap(),
        "--out",
        mcap.to_str().unwrap(),
    ]);
    assert!(
        imported.status.success(),
        "{}",
        String::from_utf8_lossy(&imported.stderr)
    );

    let mut rec = Recording::open(&mcap).expect("the import reads");
    let mut by_id: HashMap<u32, u64> = HashMap::new();
    let mut first = None;
    for m in rec.messages().expect("messages") {
        let m = m.expect("message");
        if &*m.topic == stx_station::recording::FRAMES {
            let frame: MavlinkFrame = serde_json::from_slice(&m.data).expect("frame");
            *by_id.entry(message_id(&frame.data)).or_default() += 1;
            first.get_or_insert(m.log_time);
        }
    }
    let counts = theirs["counts"].as_object().expect("counts");
    assert_eq!(counts.len(), 6, "{theirs}");
    for (name, n) in counts {
        let id = theirs["ids"][name].as_u64().expect("id") as u32;
        assert_eq!(by_id.get(&id).copied(), n.as_u64(), "{name} (id {id})");
    }
    assert_eq!(
        first,
        theirs["first_time_us"].as_u64().map(|us| us * 1000),
        "the log's times are the recording's"
    );
    // (This HEARTBEAT is a generic autopilot's: its mode is not an stx drone's, so it stays
    // raw, as SYSTEM_TIME does.)
    for (topic, name) in [
        ("/telemetry/GLOBAL_POSITION_INT", "GLOBAL_POSITION_INT"),
        ("/telemetry/ATTITUDE", "ATTITUDE"),
        ("/telemetry/GPS_RAW_INT", "GPS_RAW_INT"),
        ("/telemetry/STATUSTEXT", "STATUSTEXT"),
    ] {
        assert_eq!(
            rec.channel(topic).map(|c| c.message_count),
            counts[name].as_u64(),
            "{topic}"
        );
    }
    // The pad's reports without a fix (at 0°, 0°) are telemetry, never positions: the map's
    // channel and the exported track hold the fixes alone.
    let positions = theirs["gps_positions"].as_u64().expect("gps_positions");
    assert!(
        positions > 0 && positions < counts["GPS_RAW_INT"].as_u64().unwrap(),
        "{theirs}"
    );
    assert_eq!(
        rec.channel(stx_station::recording::VEHICLE_GPS)
            .map(|c| c.message_count),
        Some(positions)
    );
    // It exports as a station's recording does.
    let gpx = dir.join("flight.gpx");
    let exported = stx(&[
        "export",
        mcap.to_str().unwrap(),
        "--gpx",
        gpx.to_str().unwrap(),
    ]);
    assert!(
        exported.status.success(),
        "{}",
        String::from_utf8_lossy(&exported.stderr)
    );
    let text = std::fs::read_to_string(&gpx).expect("gpx");
    assert_eq!(text.matches("<trkpt ").count() as u64, positions);
    assert!(!text.contains(r#"lat="0.0000000""#), "{text}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn what_is_not_a_tlog_or_an_existing_output_is_bad_input() {
    let dir = temp_dir("bad");
    let junk = dir.join("junk.tlog");
    std::fs::write(&junk, b"this is not a telemetry log").expect("file");
    let existing = dir.join("exists.mcap");
    std::fs::write(&existing, b"x").expect("file");
    for args in [
        vec![
            "import",
            junk.to_str().unwrap(),
            "--out",
            dir.join("a.mcap").to_str().unwrap(),
        ],
        vec![
            "import",
            "/nonexistent/x.tlog",
            "--out",
            dir.join("b.mcap").to_str().unwrap(),
        ],
        vec![
            "import",
            junk.to_str().unwrap(),
            "--out",
            existing.to_str().unwrap(),
        ],
    ] {
        let out = stx(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(
            stderr.starts_with("error: ") && !stderr.contains("panicked"),
            "{stderr}"
        );
    }
    assert!(
        !dir.join("a.mcap").exists(),
        "nothing written for a refused import"
    );
    assert_eq!(
        std::fs::read(&existing).unwrap(),
        b"x",
        "an existing file is kept"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
