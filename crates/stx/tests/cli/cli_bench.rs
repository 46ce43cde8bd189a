//! `stx bench station` from the outside, as a function rather than a measurement: a few
//! bursts and commands, enough to see that the simulated drone's real telemetry drives the
//! station's whole pipeline and that each figure is made of samples. The figures themselves
//! are measured on a quiet machine, not here.

use std::process::Command;

use serde_json::Value;

#[test]
fn the_station_bench_flies_the_simulated_drone_and_times_its_frames_and_commands() {
    let out = Command::new(env!("CARGO_BIN_EXE_stx"))
        .args(["bench", "station", "--json", "--clients", "2"])
        .args(["--frames", "12", "--commands", "5"])
        .env("RUST_LOG", "warn")
        .output()
        .expect("stx runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "stx bench station failed ({}): {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    // It bails unless the estimate, the guidance pattern and both predictions are there.
    let report: Value = serde_json::from_str(&stdout).expect("one JSON report");
    let t = &report["telemetry_to_websocket"];
    let frames = t["frames_sent"].as_u64().unwrap_or(0);
    // Three seconds at 4 Hz, one ATTITUDE per control period (fewer on a busy machine).
    assert!((6..=14).contains(&frames), "{t}");
    assert!(t["latency"]["samples"].as_u64().unwrap_or(0) > 0, "{t}");
    // A state in flight is the size the dashboard receives (kilobytes).
    assert!(t["state_bytes"].as_u64().unwrap_or(0) > 1000, "{t}");
    let c = &report["command_to_mavlink"];
    assert_eq!(c["commands_sent"], 5, "{c}");
    assert!(c["latency"]["samples"].as_u64().unwrap_or(0) >= 4, "{c}");
}
