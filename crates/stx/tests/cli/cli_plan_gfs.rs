//! `stx plan --gfs` and `--sounding`: the plan's forecast rows are ecCodes' reading of the GFS
//! file at the launch site (a grid point, a forecast hour), and bad files exit 2 naming what
//! is missing; `stx serve` with a `[forecast_file]` starts the Plan page from its rows.

use std::path::PathBuf;
use std::process::{Command, Output};

use crate::common::{get_value, serve, sigterm, stx, temp_dir};

pub(crate) fn testdata(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../stx-weather/testdata")
        .join(name)
}

pub(crate) fn stx_plan(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_stx"))
        .arg("plan")
        .args(["--runs", "20"])
        .args(args)
        .output()
        .expect("stx runs")
}

pub(crate) fn path(name: &str) -> String {
    testdata(name).display().to_string()
}

/// ecCodes' values of `short_name` at the file's first point, forecast hour 0, per level
/// (as committed beside the file by make_fixtures.py).
fn eccodes_first_point(file: &str, short_name: &str) -> Vec<f64> {
    let text = std::fs::read_to_string(testdata("eccodes_reads.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["files"][file]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["short_name"] == short_name && m["step_hours"] == 0)
        .map(|m| {
            let p = &m["points"][0];
            assert_eq!((p[0].as_f64(), p[1].as_f64()), (Some(36.0), Some(350.0)));
            p[2].as_f64().unwrap()
        })
        .collect()
}

#[test]
fn gfs_rows_at_a_grid_point_are_eccodes_winds_and_geometric_heights() {
    let file = "gfs_0p50_simple.grib2";
    let out = stx_plan(&[
        "--launch",
        "36.0,-10.0,0",
        "--gfs",
        &path(file),
        "--launch-time",
        "2026-11-30T06:00:00Z",
        "--json",
    ]);
    assert!(out.status.success(), "{out:?}");
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let rows = report["request"]["forecast"].as_array().unwrap();
    let (u, v, gh) = (
        eccodes_first_point(file, "u"),
        eccodes_first_point(file, "v"),
        eccodes_first_point(file, "gh"),
    );
    assert_eq!(rows.len(), 4);
    for (k, row) in rows.iter().enumerate() {
        let speed = row["speed_mps"].as_f64().unwrap();
        let from = row["from_deg"].as_f64().unwrap().to_radians();
        // Back to components: where the air goes is opposite to where it comes from.
        let (east, north) = (-speed * from.sin(), -speed * from.cos());
        assert!(
            (east - u[k]).abs() < 0.01,
            "level {k}: {east} vs ecCodes {}",
            u[k]
        );
        assert!(
            (north - v[k]).abs() < 0.01,
            "level {k}: {north} vs ecCodes {}",
            v[k]
        );
        let h = 6_371_008.8 * gh[k] / (6_371_008.8 - gh[k]);
        assert!(
            (row["alt_msl_m"].as_f64().unwrap() - h).abs() < 0.01,
            "level {k}"
        );
    }
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("GFS run 2026-11-30T06:00:00Z"), "{stderr}");
}

#[test]
fn a_sounding_gives_the_plan_its_winds() {
    let out = stx_plan(&[
        "--launch",
        "40.53,-80.22,360",
        "--sounding",
        &path("72520_sounding.txt"),
        "--json",
    ]);
    assert!(out.status.success(), "{out:?}");
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let rows = report["request"]["forecast"].as_array().unwrap();
    assert_eq!(rows.len(), 16);
    assert_eq!(rows[0]["from_deg"].as_f64().unwrap().round(), 250.0);
    // The jet at 250 hPa, 101 knots from 285°, carries the burst east.
    assert!(report["burst"]["east_m"].as_f64().unwrap() > 50_000.0);
}

#[test]
fn bad_gfs_files_and_times_exit_2_naming_what_is_missing() {
    let subset = path("gfs_0p25_subset.grib2");
    let (no_hgt, sounding) = (path("no_hgt.grib2"), path("72520_sounding.txt"));
    // (launch site, file, launch time, what stderr says)
    let cases = [
        ("38,-8", &no_hgt, None, "no HGT on isobaric levels"),
        (
            "45,-8",
            &subset,
            None,
            "45° N -8° E is outside the file's box (latitudes 36…40°, longitudes -10…-5°)",
        ),
        (
            "38,-8",
            &subset,
            Some("2026-11-30T13:00:00Z"),
            "outside the forecast: its hours cover 2026-11-30T06:00:00Z to 2026-11-30T12:00:00Z",
        ),
        ("38,-8", &sounding, None, "not a readable GRIB2 file"),
        ("38,-8", &subset, Some("tomorrow"), "not an RFC 3339 time"),
    ];
    for (launch, file, time, expected) in cases {
        let mut args = vec!["--launch", launch, "--gfs", file];
        if let Some(t) = time {
            args.extend(["--launch-time", t]);
        }
        let out = stx_plan(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
    }
}

/// The shipped station config with its `[[forecast_wind]]` rows replaced by `table`.
pub(crate) fn station_config(dir: &std::path::Path, table: &str) -> PathBuf {
    let shipped = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../config/station.toml"
    ))
    .expect("shipped config");
    let mut in_rows = false;
    let mut text = String::new();
    for line in shipped.lines() {
        in_rows = line.starts_with("[[forecast_wind]]") || (in_rows && !line.is_empty());
        if !in_rows {
            text.push_str(line);
            text.push('\n');
        }
    }
    let path = dir.join("station.toml");
    std::fs::write(&path, format!("{text}\n{table}")).expect("write");
    path
}

#[test]
fn the_station_plans_from_its_configured_gfs_file_and_refuses_a_bad_one() {
    let dir = temp_dir("plan-gfs", "station");
    // The shipped origin, Évora (38.53° N, 7.89° W), lies in the subset's box.
    let good = station_config(
        &dir,
        &format!(
            "[forecast_file]\ngfs = [\"{}\"]\nvalid_time = \"2026-11-30T09:00:00Z\"\n",
            path("gfs_0p25_subset.grib2")
        ),
    );
    let (child, address, token) = serve(&[
        "--config",
        good.to_str().unwrap(),
        "--listen",
        "127.0.0.1:0",
        "--link",
        "udpin:127.0.0.1:0",
    ]);
    let defaults = get_value(&address, "/api/plan/defaults", &token);
    sigterm(&child);
    let rows = defaults["request"]["forecast"].as_array().expect("rows");
    assert_eq!(rows.len(), 11, "{defaults}");
    let out = stx_plan(&[
        "--launch",
        "38.5333,-7.8889,245",
        "--gfs",
        &path("gfs_0p25_subset.grib2"),
        "--launch-time",
        "2026-11-30T09:00:00Z",
        "--json",
    ]);
    let plan: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(
        &plan["request"]["forecast"],
        &defaults["request"]["forecast"]
    );

    let bad = station_config(
        &dir,
        &format!("[forecast_file]\ngfs = [\"{}\"]\n", path("no_hgt.grib2")),
    );
    let out = stx(&["serve", "--config", bad.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("forecast_file") && stderr.contains("no HGT"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(dir);
}
