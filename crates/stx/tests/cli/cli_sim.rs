//! `stx sim` from the outside: what an operator types and what comes back.

use std::process::Command;

fn stx(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_stx"))
        .args(args)
        .output()
        .expect("stx runs")
}

#[test]
fn summary_json_is_one_object_with_the_promised_fields() {
    let out = stx(&["sim", "--scenario", "uncontrolled", "--summary-json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).expect("utf-8");
    assert_eq!(text.trim().lines().count(), 1, "one line of JSON");
    let v: serde_json::Value = serde_json::from_str(text.trim()).expect("JSON");
    for key in [
        "scenario",
        "sim_time_s",
        "wall_time_s",
        "rhs_evals",
        "settle_time_s",
        "steady",
        "min_line_tension_n",
        "max_line_length_error_m",
        "max_total_speed_kmh",
        "min_canopy_pitch_deg",
        "yaw_rate_settle_s",
    ] {
        assert!(v.get(key).is_some(), "missing {key} in {v}");
    }
    for key in ["airspeed_mps", "sink_rate_mps", "glide_ratio", "alpha_deg"] {
        assert!(v["steady"][key].as_f64().is_some(), "steady.{key} in {v}");
    }
    assert_eq!(v["scenario"], "uncontrolled");
    assert!(v["rhs_evals"].as_u64().unwrap_or(0) > 100);
}

#[test]
fn trajectories_are_written_as_csv_or_json() {
    let dir = std::env::temp_dir().join(format!("stx-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let csv = dir.join("run.csv");
    let out = stx(&[
        "sim",
        "--scenario",
        "uncontrolled",
        "--out",
        csv.to_str().unwrap_or(""),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&csv).expect("csv written");
    let header = text.lines().next().unwrap_or("");
    assert!(header.starts_with("time_s,canopy_x_m"), "{header}");
    assert!(text.lines().count() > 100);
    let json = dir.join("run.json");
    let out = stx(&[
        "sim",
        "--scenario",
        "uncontrolled",
        "--out",
        json.to_str().unwrap_or(""),
    ]);
    assert!(out.status.success());
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("json written")).expect("JSON");
    assert!(v["samples"].as_array().map(|a| a.len()).unwrap_or(0) > 100);
    assert!(v["summary"]["settle_time_s"].is_number());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn an_unknown_scenario_is_a_clear_error_with_exit_code_2() {
    let out = stx(&["sim", "--scenario", "spirl-exit"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("unknown scenario `spirl-exit`") && err.contains("spiral-exit"),
        "{err}"
    );
}

#[test]
fn bad_files_are_clear_errors_with_exit_code_2() {
    let dir = std::env::temp_dir().join(format!("stx-cli-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let broken = dir.join("broken.toml");
    std::fs::write(
        &broken,
        "name = \"x\"\ndescription = \"y\"\nduration_s = -5\n",
    )
    .expect("write");
    let out = stx(&["sim", "--scenario", broken.to_str().unwrap_or("")]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("duration_s"));

    let missing = dir.join("missing.toml");
    let out = stx(&["sim", "--scenario", missing.to_str().unwrap_or("")]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read scenario file"));

    let vehicle = dir.join("vehicle.toml");
    std::fs::write(&vehicle, "gravity_mps2 = 9.8\n").expect("write");
    let out = stx(&[
        "sim",
        "--scenario",
        "uncontrolled",
        "--vehicle",
        vehicle.to_str().unwrap_or(""),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing field"));

    let out = stx(&[
        "sim",
        "--scenario",
        "uncontrolled",
        "--out",
        "trajectory.txt",
    ]);
    assert_eq!(out.status.code(), Some(2));
    std::fs::remove_dir_all(&dir).ok();
}
