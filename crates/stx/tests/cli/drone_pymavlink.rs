//! `stx drone` against an independent MAVLink implementation: pymavlink 2.4.50 as the ground
//! station (`tests/peers/test_drone_pymavlink.py`). It reads the telemetry and measures its
//! rates, lists the parameters, sets one and reads it back, changes the mode and times the
//! COMMAND_ACK, has refusals acknowledged as refusals, and asks for AUTOPILOT_VERSION as
//! QGroundControl and MAVProxy do on connecting. The script raises on any failed
//! check; this test runs it and prints what it measured.
//!
//! Python: `$STX_PYTHON`, or `.venv/bin/python` at the workspace root (`tests/run-all`
//! creates it: `python3 -m venv .venv && .venv/bin/pip install pymavlink==2.4.50`).

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn python() -> PathBuf {
    let p = std::env::var_os("STX_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace_root().join(".venv/bin/python"));
    assert!(
        p.exists(),
        "pymavlink peer: no Python at {} (set STX_PYTHON, or create the venv at the workspace \
         root: `python3 -m venv .venv && .venv/bin/pip install pymavlink==2.4.50`)",
        p.display()
    );
    p
}

#[test]
fn pymavlink_reads_telemetry_lists_and_sets_parameters_and_gets_its_commands_acknowledged() {
    let script = workspace_root().join("tests/peers/test_drone_pymavlink.py");
    let out = Command::new(python())
        .env("MAVLINK20", "1")
        .arg(&script)
        .arg(env!("CARGO_BIN_EXE_stx"))
        .arg("rehearsal")
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "{} failed ({}):\n{}",
        script.display(),
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    let report: Value = serde_json::from_str(stdout.lines().last().unwrap_or_default())
        .unwrap_or_else(|e| panic!("report is not JSON ({e}): {stdout}"));
    println!("pymavlink peer measured: {report:#}");
    let rates = &report["rates_hz"];
    for (message, expected) in [
        ("HEARTBEAT", 1.0),
        ("GPS_RAW_INT", 4.0),
        ("ATTITUDE", 4.0),
        ("SCALED_PRESSURE", 4.0),
        ("GLOBAL_POSITION_INT", 4.0),
        ("SYS_STATUS", 1.0),
    ] {
        let rate = rates[message].as_f64().unwrap_or(0.0);
        assert!(
            (rate - expected).abs() <= 0.15 * expected,
            "{message} at {rate} Hz, expected {expected} Hz"
        );
    }
    assert!(
        report["param_count"].as_u64().unwrap_or(0) >= 10,
        "{report}"
    );
    // A set against the drone's rules is answered only with the value in force.
    let refusal = &report["rule_refusal"];
    assert_eq!(refusal["name"], "SP_MIN_FINAL", "{report}");
    assert!(
        refusal["answered"]
            .as_array()
            .is_some_and(|a| !a.is_empty() && a.iter().all(|v| v.as_f64() != Some(1500.0))),
        "{report}"
    );
    assert_eq!(report["mode_after"], 2, "{report}");
    // Acknowledged within a control period even on a loaded machine.
    assert!(
        report["set_mode_ack_ms"].as_f64().unwrap_or(f64::INFINITY) < 250.0,
        "{report}"
    );
    // Read as a generic MAVLink vehicle: MAVLink 2, whole-number parameters cast into the
    // float field (not bytewise), the same answer to either request.
    let version = &report["autopilot_version"];
    let capabilities: Vec<&str> = version["capabilities"]
        .as_array()
        .map(|a| a.iter().filter_map(|c| c.as_str()).collect())
        .unwrap_or_default();
    for expected in [
        "MAVLINK2",
        "PARAM_ENCODE_C_CAST",
        "COMMAND_INT",
        "MISSION_INT",
    ] {
        assert!(
            capabilities.contains(&expected),
            "{expected} missing: {report}"
        );
    }
    assert!(!capabilities.contains(&"PARAM_ENCODE_BYTEWISE"), "{report}");
    assert_eq!(
        version["flight_sw_version"],
        format!("{} type 0", env!("CARGO_PKG_VERSION")),
        "{report}"
    );
    assert_eq!(version["same_answer_twice"], true, "{report}");
    assert_eq!(report["drone_exit_code"], 0, "{report}");
}
