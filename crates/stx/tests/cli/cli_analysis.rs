//! `stx analyze`, `stx tune` and the `--gains` option from the outside.

use std::path::PathBuf;
use std::process::Command;

fn stx(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_stx"))
        .args(args)
        .output()
        .expect("stx runs")
}

/// `stx` run with `dir` as its working directory.
fn stx_in(dir: &std::path::Path, args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_stx"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("stx runs")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("stx-cli-analysis-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

#[test]
fn analyze_json_has_the_promised_fields_and_writes_report_and_plots() {
    let dir = temp_dir("analyze");
    let out = stx(&["analyze", "--json", "--out-dir", dir.to_str().unwrap_or("")]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).expect("utf-8");
    assert_eq!(text.trim().lines().count(), 1, "one line of JSON");
    let v: serde_json::Value = serde_json::from_str(text.trim()).expect("JSON");
    for key in [
        "trim",
        "eigenvalues",
        "zero_eigenvalues",
        "max_real_part_nonzero",
        "controllability_rank",
        "observability_rank",
        "n_states",
        "seed",
        "controllability",
        "observability",
        "matrices",
    ] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    assert_eq!(v["n_states"], 31);
    assert_eq!(v["eigenvalues"].as_array().map(Vec::len), Some(31));
    assert_eq!(
        v["eigenvalues"][0].as_array().map(Vec::len),
        Some(2),
        "[re, im] pairs"
    );
    assert_eq!(v["zero_eigenvalues"], 4);
    assert_eq!(v["controllability_rank"], 29);
    assert_eq!(v["observability_rank"], 31);
    assert!(v["max_real_part_nonzero"].as_f64().unwrap_or(1.0) < 0.0);
    let airspeed = v["trim"]["airspeed_mps"].as_f64().expect("airspeed");
    assert!((5.0..9.0).contains(&airspeed), "{airspeed}");
    assert!(v["trim"]["state"].as_array().map(Vec::len) == Some(31));
    assert_eq!(v["seed"]["controllability_rank"], 29);
    assert!(
        v["controllability"]["relative_tolerance"]
            .as_f64()
            .is_some()
    );
    for file in [
        "report.json",
        "eigenvalues.svg",
        "step-main-line.svg",
        "step-brake.svg",
    ] {
        let text = std::fs::read_to_string(dir.join(file)).expect(file);
        assert!(text.len() > 1000, "{file} is written");
        if file.ends_with(".svg") {
            assert!(text.starts_with("<svg") && text.trim_end().ends_with("</svg>"));
        }
    }
    // The text form has the side-by-side table.
    let out = stx(&["analyze", "--out-dir", dir.to_str().unwrap_or("")]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("seed Table 6.1") && text.contains("controllability"));
}

#[test]
fn analyze_decides_ranks_alike_at_altitude_and_warns_when_a_decision_is_marginal() {
    let dir = temp_dir("altitude");
    let out_dir = dir.to_str().unwrap_or("");
    // Regression: at 35 km the Hautus rank read 27 against the staircase's 29 and the
    // altitude's mode counted as non-zero, with no warning.
    let out = stx(&[
        "analyze",
        "--altitude",
        "35000",
        "--json",
        "--out-dir",
        out_dir,
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_str(String::from_utf8_lossy(&out.stdout).trim()).expect("JSON");
    assert_eq!(v["zero_eigenvalues"], 4);
    assert_eq!(v["controllability_rank"], 29);
    assert_eq!(v["controllability_staircase"]["rank"], 29);
    assert_eq!(v["observability_rank"], 31);
    assert_eq!(v["observability_staircase"]["rank"], 31);
    assert_eq!(v["warnings"], serde_json::json!([]));
    // At 50 km, above any STRAPLEX flight, the slowest lateral mode comes within a factor 3
    // of the zero threshold: said in the JSON, on stderr, and in the tables.
    let out = stx(&[
        "analyze",
        "--altitude",
        "50000",
        "--json",
        "--out-dir",
        out_dir,
    ]);
    assert!(out.status.success());
    let v: serde_json::Value =
        serde_json::from_str(String::from_utf8_lossy(&out.stdout).trim()).expect("JSON");
    let warnings = v["warnings"].as_array().cloned().unwrap_or_default();
    assert!(
        warnings
            .iter()
            .any(|w| w.as_str().is_some_and(|w| w.contains("zero threshold"))),
        "{warnings:?}"
    );
    assert!(String::from_utf8_lossy(&out.stderr).contains("warning: an eigenvalue"));
    let out = stx(&["analyze", "--altitude", "50000", "--out-dir", out_dir]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("warning: an eigenvalue"));
}

#[test]
fn analyze_refuses_bad_input_with_exit_code_2() {
    let dir = temp_dir("bad");
    let out_dir = dir.to_str().unwrap_or("");
    // An altitude outside the atmosphere: no trim.
    let out = stx(&["analyze", "--altitude", "200000", "--out-dir", out_dir]);
    assert_eq!(
        out.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stderr).contains("altitude"));
    // A vehicle file that is not one.
    let vehicle = dir.join("vehicle.toml");
    std::fs::write(&vehicle, "gravity_mps2 = \"down\"\n").expect("write");
    let out = stx(&[
        "analyze",
        "--vehicle",
        vehicle.to_str().unwrap_or(""),
        "--out-dir",
        out_dir,
    ]);
    assert_eq!(out.status.code(), Some(2));
    // Regression: the TOML parser's report was printed twice (in the error and its cause).
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.matches("TOML parse error").count(), 1, "{stderr}");
    // A vehicle whose only steady state flies backwards has no glide to analyse.
    let backwards = dir.join("backwards.toml");
    let text = stx_dynamics::vehicle::STRAPLEX_TOML
        .replace("cl0 = 0.250", "cl0 = -3.0")
        .replace("cl_alpha = 2.300", "cl_alpha = 0.0");
    std::fs::write(&backwards, text).expect("write");
    let out = stx(&[
        "analyze",
        "--vehicle",
        backwards.to_str().unwrap_or(""),
        "--out-dir",
        out_dir,
    ]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("not a glide") && stderr.contains("backwards"),
        "{stderr}"
    );
    // A missing one.
    let out = stx(&[
        "analyze",
        "--vehicle",
        "/nonexistent/vehicle.toml",
        "--out-dir",
        out_dir,
    ]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn tune_writes_a_gains_file_that_sim_and_montecarlo_read() {
    // Run where a checkout's config/ would be: the default output must not land there.
    let dir = temp_dir("tune");
    std::fs::create_dir_all(dir.join("config")).expect("config dir");
    let out = stx_in(
        &dir,
        &[
            "tune",
            "--controller",
            "localizer",
            "--json",
            "--draws",
            "2",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let gains = dir.join("target/tune/gains.toml");
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("target/tune/gains.toml"),
        "the path written is printed"
    );
    let in_config: Vec<_> = std::fs::read_dir(dir.join("config"))
        .expect("config dir")
        .collect();
    assert!(
        in_config.is_empty(),
        "stx tune wrote into config/: {in_config:?}"
    );
    let dir = dir.join("target/analysis");
    let v: serde_json::Value =
        serde_json::from_str(String::from_utf8_lossy(&out.stdout).trim()).expect("JSON");
    assert_eq!(v["controller"], "localizer");
    for who in ["current", "tuned", "seed"] {
        for step in ["small", "large"] {
            assert!(
                v[who][step]["linear"]["cost"].as_f64().is_some(),
                "{who} {step}"
            );
        }
        assert!(v[who]["nonlinear_cost"].as_f64().is_some(), "{who}");
        // Judged on two realistic stacks flown with the sensors and the estimator.
        assert_eq!(
            v[who]["sensed"]["per_draw"].as_array().map(Vec::len),
            Some(2),
            "{who}"
        );
        assert!(v[who]["sensed"]["mean"].as_f64().is_some(), "{who}");
    }
    assert_eq!(v["sensed_set"]["dispersions"], "realistic");
    assert!(
        v["verdict"]
            .as_str()
            .is_some_and(|t| t.contains("sensed, dispersed cost")),
        "{}",
        v["verdict"]
    );
    // The localizer's large step starts in the approach phase: 40 m off the line.
    assert_eq!(v["current"]["large"]["step"], 40.0);
    let text = std::fs::read_to_string(&gains).expect("gains file");
    assert!(text.starts_with("# "), "header comment");
    assert!(text.contains("stx tune --controller localizer"));
    assert!(dir.join("step-localizer.svg").exists() && dir.join("tune-localizer.json").exists());
    let written = v["gains_out"]["hk3_m_per_m"].as_f64().expect("hk3");
    assert!(text.contains(&format!("hk3_m_per_m = {written}")), "{text}");

    // Guidance flies with it.
    let out = stx(&[
        "sim",
        "--scenario",
        "localizer",
        "--gains",
        gains.to_str().unwrap_or(""),
        "--summary-json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = stx(&[
        "montecarlo",
        "--runs",
        "1",
        "--altitude",
        "100",
        "--json",
        "--gains",
        gains.to_str().unwrap_or(""),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    // A bad gains file is refused, naming the field; so is --gains on an open-loop scenario.
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "vk2_per_m = -0.1\n").expect("write");
    for args in [
        vec![
            "sim",
            "--scenario",
            "localizer",
            "--gains",
            bad.to_str().unwrap_or(""),
        ],
        vec![
            "montecarlo",
            "--runs",
            "1",
            "--gains",
            bad.to_str().unwrap_or(""),
        ],
    ] {
        let out = stx(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(String::from_utf8_lossy(&out.stderr).contains("vk2_per_m"));
    }
    let out = stx(&[
        "sim",
        "--scenario",
        "uncontrolled",
        "--gains",
        gains.to_str().unwrap_or(""),
    ]);
    assert_eq!(out.status.code(), Some(2));
    // An unknown controller is a usage error.
    let out = stx(&["tune", "--controller", "pitch"]);
    assert_eq!(out.status.code(), Some(2));
}
