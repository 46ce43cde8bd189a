//! Identification checked end to end on a stack whose truth is known (issue 35): the simulated
//! drone flies the rehearsal with 20 % less lift slope than the shipped vehicle
//! (`stx serve --sim --sim-vehicle`), the station records it, and `stx identify` fits
//! `cl_alpha` and `cd0` from the recording, starting from the shipped vehicle.
//!
//! The fit is only as good as the wind the replay flies through, the onboard estimator's: on
//! these recordings its airspeed reads about 0.27 m/s (4 %) low, and the missing air speed
//! sits in its wind along the heading. Measured by this test (`-- --nocapture` prints them;
//! also in `results/2026-11-29.md`): plain, `cl_alpha` 1.943 with its 95 % interval
//! 1.908 … 1.977 beside the truth's 1.840, `cd0` 0.200 (0.188 … 0.212) against 0.150; with each
//! flight's air-data scale fitted too (`--fit-air-scale`, +1.85 %), 1.899 (1.823 … 1.974) and
//! 0.189 (0.162 … 0.215): the lift slope's interval holds the truth, the drag's still does not.

use crate::common;

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use common::{stx, temp_dir, vehicle_file};
use serde_json::Value;

const TRUE_CL_ALPHA: f64 = 1.840;

/// Records the rehearsal flown by the shipped vehicle with `cl_alpha = 1.840` to its landing.
fn record_rehearsal(dir: &Path) -> PathBuf {
    let vehicle = vehicle_file(
        dir,
        "less-lift.toml",
        "cl_alpha = 2.300",
        "cl_alpha = 1.840",
    );
    let recordings = dir.join("recordings");
    let mut serve = Command::new(env!("CARGO_BIN_EXE_stx"))
        .args(["serve", "--sim", "--sim-scenario", "rehearsal"])
        // 20×: the rehearsal's five minutes in 15 s, every frame heard on a busy machine.
        .args(["--sim-speed", "20", "--sim-vehicle"])
        .arg(&vehicle)
        .args(["--listen", "127.0.0.1:0", "--link", "udpin:127.0.0.1:0"])
        .arg("--record-dir")
        .arg(&recordings)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("stx serve starts");
    let log = BufReader::new(serve.stderr.take().expect("stderr"));
    let mut landed = false;
    for line in log.lines() {
        let line = line.expect("the station's log");
        if line.contains("stx_sim::runner::flight: landed") {
            landed = true;
            break;
        }
    }
    let pid = serve.id().to_string();
    let interrupted = Command::new("kill").args(["-INT", &pid]).status();
    let stopped = serve.wait().expect("the station stops");
    assert!(landed, "the simulated drone landed");
    assert!(interrupted.is_ok_and(|s| s.success()) && stopped.success());
    std::fs::read_dir(&recordings)
        .expect("recordings")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.extension().is_some_and(|x| x == "mcap"))
        .expect("a recording")
}

/// `stx identify RECORDING --params cl_alpha,cd0 --json` and `extra`: the report.
fn identify(recording: &Path, dir: &Path, extra: &[&str]) -> Value {
    let out_file = dir.join("fitted.toml");
    let mut args = vec![
        "identify",
        recording.to_str().expect("utf-8"),
        "--params",
        "cl_alpha,cd0",
        "--out",
        out_file.to_str().expect("utf-8"),
        "--json",
    ];
    args.extend(extra);
    let out = stx(&args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON report")
}

/// `(fitted, [low, high])` of the report's parameter `i`.
fn fitted(report: &Value, i: usize) -> (f64, [f64; 2]) {
    let p = &report["params"][i];
    let interval = [0, 1].map(|k| p["interval95"][k].as_f64().expect("an interval"));
    (p["estimate"].as_f64().expect("an estimate"), interval)
}

#[test]
fn the_lift_slope_of_a_rehearsed_stack_is_identified_from_its_recording() {
    let dir = temp_dir("identify-rehearsal", "less-lift");
    let recording = record_rehearsal(&dir);

    let plain = identify(&recording, &dir, &[]);
    let (cl_alpha, [low, high]) = fitted(&plain, 0);
    let (cd0, [cd0_low, cd0_high]) = fitted(&plain, 1);
    eprintln!(
        "plain: cl_alpha {cl_alpha:.4} ({low:.4} … {high:.4}), cd0 {cd0:.4} ({cd0_low:.4} … {cd0_high:.4}); truth {TRUE_CL_ALPHA}, 0.150"
    );
    // From 2.300 to within 8 % of the truth (5.6 % measured): the estimator's wind keeps it high.
    assert!(
        (cl_alpha / TRUE_CL_ALPHA - 1.0).abs() < 0.08,
        "cl_alpha {cl_alpha}"
    );
    assert!(low < cl_alpha && cl_alpha < high, "[{low}, {high}]");

    let scaled = identify(&recording, &dir, &["--fit-air-scale"]);
    let (cl_alpha, [low, high]) = fitted(&scaled, 0);
    let (cd0, [cd0_low, cd0_high]) = fitted(&scaled, 1);
    let air = scaled["air_scale_percent"][0]
        .as_f64()
        .expect("one flight's scale");
    eprintln!(
        "air scale fitted: cl_alpha {cl_alpha:.4} ({low:.4} … {high:.4}), cd0 {cd0:.4} ({cd0_low:.4} … {cd0_high:.4}), air {air:+.2} %"
    );
    // The air went faster than the recorded air data say (1.85 % fitted, 4 % against the
    // truth), and the lift slope's interval now holds the truth (within 4 %; 3.2 % measured).
    assert!(air > 0.5 && air < 6.0, "air-data scale {air} %");
    assert!(
        (cl_alpha / TRUE_CL_ALPHA - 1.0).abs() < 0.04,
        "cl_alpha {cl_alpha}"
    );
    assert!(
        low <= TRUE_CL_ALPHA && TRUE_CL_ALPHA <= high,
        "[{low}, {high}] holds {TRUE_CL_ALPHA}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
