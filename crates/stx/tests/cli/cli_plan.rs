//! `stx plan`: a forecast file in, the plan out as JSON whose burst point is the closed form
//! of a uniform wind; bad input exits 2 and says where.

use std::process::Command;

fn stx_plan(dir: &std::path::Path, forecast: &str, args: &[&str]) -> std::process::Output {
    let file = dir.join("forecast.csv");
    std::fs::write(&file, forecast).expect("write forecast");
    Command::new(env!("CARGO_BIN_EXE_stx"))
        .args(["plan", "--forecast"])
        .arg(&file)
        .args(args)
        .output()
        .expect("stx runs")
}

fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("stx-cli-plan-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

#[test]
fn a_uniform_forecast_bursts_downwind_by_wind_times_climb_over_rate() {
    let dir = scratch("uniform");
    let out = stx_plan(
        &dir,
        "alt_msl_m,speed_mps,from_deg,sigma_mps\n0,5,270,0\n",
        &[
            "--launch",
            "38.5333,-7.8889,245",
            "--burst-alt",
            "10245",
            "--ascent-rate",
            "4",
            "--ascent-rate-sigma",
            "0",
            "--burst-alt-sigma",
            "0",
            "--runs",
            "5",
            "--json",
        ],
    );
    assert!(out.status.success(), "{out:?}");
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    // 10 000 m at 4 m/s on average: 2500 s, 12.5 km east (0.1 %: the Simpson rule).
    let burst = &report["burst"];
    let east = burst["east_m"].as_f64().unwrap();
    assert!((east - 12_500.0).abs() < 12.5, "{east}");
    assert!((burst["time_s"].as_f64().unwrap() - 2500.0).abs() < 2.5);
    assert!(burst["north_m"].as_f64().unwrap().abs() < 1e-6);
    assert!(report["target"].is_null());
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn bad_input_exits_2_and_says_where() {
    let dir = scratch("bad");
    let out = stx_plan(
        &dir,
        "300,2,270\n200,oops,270\n",
        &["--launch", "38.5,-7.9"],
    );
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("line 2") && err.contains("speed_mps"), "{err}");
    let out = stx_plan(&dir, "300,2,270\n", &["--launch", "north"]);
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    let out = stx_plan(
        &dir,
        "300,2,270\n",
        &["--launch", "38.5,-7.9", "--runs", "0"],
    );
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    let _ = std::fs::remove_dir_all(dir);
}
