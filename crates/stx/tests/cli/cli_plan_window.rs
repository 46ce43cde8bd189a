//! Launch windows (issue 31, item 3): `stx plan --gfs … --window FROM..TO --every` plans every
//! launch time as `stx plan --launch-time` does for that one time, marks the best three, and
//! exits 2 for a window outside the files' hours; the station's `POST /api/plan/forecast` reads
//! an uploaded file (or names what it lacks) and `POST /api/plan/window` over that upload or the
//! configured file answers what the command prints.

use serde_json::{Value, json};

use crate::cli_plan_gfs::{path, station_config, stx_plan};
use crate::common::{exchange, serve, sigterm, temp_dir};

const SITE: &str = "38,-8,100";
const TARGET: &str = "38,-7.5";
const FROM: &str = "2026-11-30T06:00:00Z";
const TO: &str = "2026-11-30T12:00:00Z";

fn window(extra: &[&str]) -> std::process::Output {
    let subset = path("gfs_0p25_subset.grib2");
    let window = format!("{FROM}..{TO}");
    let mut args = vec![
        "--launch",
        SITE,
        "--gfs",
        &subset,
        "--window",
        &window,
        "--every",
        "90m",
        "--target",
        TARGET,
        "--burst-alt",
        "20000",
    ];
    args.extend(extra);
    stx_plan(&args)
}

#[test]
fn every_launch_of_a_window_is_the_plan_at_its_time_and_the_best_are_marked() {
    let out = window(&["--json"]);
    assert!(out.status.success(), "{out:?}");
    let report: Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let launches = report["launches"].as_array().expect("launches");
    let times: Vec<&str> = launches
        .iter()
        .map(|l| l["launch_time"].as_str().unwrap())
        .collect();
    assert_eq!(
        times,
        [
            FROM,
            "2026-11-30T07:30:00Z",
            "2026-11-30T09:00:00Z",
            "2026-11-30T10:30:00Z",
            TO
        ]
    );
    for k in [0, 3] {
        let single = stx_plan(&[
            "--launch",
            SITE,
            "--gfs",
            &path("gfs_0p25_subset.grib2"),
            "--launch-time",
            times[k],
            "--target",
            TARGET,
            "--burst-alt",
            "20000",
            "--json",
        ]);
        let plan: Value = serde_json::from_slice(&single.stdout).expect("JSON");
        let l = &launches[k];
        assert_eq!(
            l["landing_unsteered"]["lat_deg"],
            plan["landing_unsteered"]["lat_deg"]
        );
        assert_eq!(
            l["landing_unsteered"]["lon_deg"],
            plan["landing_unsteered"]["lon_deg"]
        );
        assert_eq!(l["burst"]["lon_deg"], plan["burst"]["lon_deg"]);
        assert_eq!(l["reach_share"], plan["target"]["reachable_probability"]);
    }
    let best: Vec<u64> = launches
        .iter()
        .filter(|l| l["best"] == true)
        .map(|l| l["rank"].as_u64().unwrap())
        .collect();
    assert_eq!(best.len(), 3, "{launches:?}");
    assert!(best.iter().all(|&r| r <= 3));
    // Rank 1 has the highest share; among equal shares, the nearer landing.
    let first = launches.iter().find(|l| l["rank"] == 1).unwrap();
    for l in launches {
        let (s, s1) = (
            l["reach_share"].as_f64().unwrap(),
            first["reach_share"].as_f64().unwrap(),
        );
        let (d, d1) = (
            l["target_from_landing_m"].as_f64().unwrap(),
            first["target_from_landing_m"].as_f64().unwrap(),
        );
        assert!(s < s1 || (s == s1 && d >= d1), "{l} ranks above {first}");
    }
    // The table: a line per launch, three marked.
    let table = window(&[]);
    let text = String::from_utf8_lossy(&table.stdout);
    assert!(table.status.success(), "{table:?}");
    assert_eq!(text.matches("★ best").count(), 3, "{text}");
    assert!(text.contains("2026-11-30T10:30:00Z"), "{text}");
}

#[test]
fn a_window_outside_the_forecast_hours_or_without_a_target_exits_2() {
    let subset = path("gfs_0p25_subset.grib2");
    let late = stx_plan(&[
        "--launch",
        SITE,
        "--gfs",
        &subset,
        "--window",
        "2026-11-30T10:00:00Z..2026-11-30T14:00:00Z",
        "--target",
        TARGET,
    ]);
    let stderr = String::from_utf8_lossy(&late.stderr);
    assert_eq!(late.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(
            "outside the GFS files' forecast hours 2026-11-30T06:00:00Z..2026-11-30T12:00:00Z"
        ),
        "{stderr}"
    );
    let untargeted = stx_plan(&[
        "--launch",
        SITE,
        "--gfs",
        &subset,
        "--window",
        "2026-11-30T06:00:00Z..2026-11-30T07:00:00Z",
    ]);
    assert_eq!(untargeted.status.code(), Some(2), "{untargeted:?}");
    assert!(String::from_utf8_lossy(&untargeted.stderr).contains("--target"));
    let every = stx_plan(&[
        "--launch",
        SITE,
        "--gfs",
        &subset,
        "--target",
        TARGET,
        "--window",
        "2026-11-30T06:00:00Z..2026-11-30T07:00:00Z",
        "--every",
        "1d",
    ]);
    assert_eq!(every.status.code(), Some(2), "{every:?}");
}

#[test]
fn the_station_plans_a_window_over_an_upload_or_its_configured_file_as_the_command_does() {
    let dir = temp_dir("plan-window", "station");
    let config = station_config(
        &dir,
        &format!(
            "[forecast_file]\ngfs = [\"{}\"]\n",
            path("gfs_0p25_subset.grib2")
        ),
    );
    let (child, address, token) = serve(&[
        "--config",
        config.to_str().unwrap(),
        "--listen",
        "127.0.0.1:0",
        "--link",
        "udpin:127.0.0.1:0",
    ]);
    let post = |path: &str, content_type: &str, body: &[u8]| {
        exchange(&address, Some(&token), "POST", path, content_type, body)
    };
    let bytes = |name: &str| std::fs::read(path(name)).expect("test file");
    let octets = "application/octet-stream";
    // A file without HGT, an empty body, and a GFS file without the launch site: 400, named.
    let (status, no_hgt) = post(
        "/api/plan/forecast?lat=38&lon=-8",
        octets,
        &bytes("no_hgt.grib2"),
    );
    assert_eq!(status, 400, "{no_hgt}");
    assert!(
        no_hgt["reason"]
            .as_str()
            .unwrap()
            .contains("no HGT on isobaric levels"),
        "{no_hgt}"
    );
    let (status, empty) = post("/api/plan/forecast?lat=38&lon=-8", octets, b"");
    assert_eq!(status, 400, "{empty}");
    let (status, nowhere) = post(
        "/api/plan/forecast",
        octets,
        &bytes("gfs_0p25_subset.grib2"),
    );
    assert_eq!(
        (
            status,
            nowhere["reason"]
                .as_str()
                .map(|r| r.starts_with("lat, lon"))
        ),
        (400, Some(true)),
        "{nowhere}"
    );
    // The subset: its rows over the site at 07:30 are what `stx plan --launch-time` flies.
    let (status, upload) = post(
        "/api/plan/forecast?lat=38&lon=-8&time=2026-11-30T07:30:00Z",
        octets,
        &bytes("gfs_0p25_subset.grib2"),
    );
    assert_eq!(status, 200, "{upload}");
    let single = stx_plan(&[
        "--launch",
        SITE,
        "--gfs",
        &path("gfs_0p25_subset.grib2"),
        "--launch-time",
        "2026-11-30T07:30:00Z",
        "--json",
    ]);
    let plan: Value = serde_json::from_slice(&single.stdout).expect("JSON");
    assert_eq!(upload["rows"], plan["request"]["forecast"]);
    assert_eq!(upload["kind"], "gfs");
    // The window over the upload and over the configured file: the command's answer.
    let command: Value = serde_json::from_slice(&window(&["--json"]).stdout).expect("JSON");
    let mut request = command["request"].clone();
    request["forecast"] = json!([]);
    for forecast in [json!({"upload": upload["id"]}), json!("configured")] {
        let body = json!({
            "request": request,
            "window": {"from": FROM, "to": TO, "every_s": 5400},
            "forecast": forecast,
        });
        let (status, report) = post(
            "/api/plan/window",
            "application/json",
            body.to_string().as_bytes(),
        );
        assert_eq!(status, 200, "{forecast}: {report}");
        assert_eq!(report["launches"], command["launches"], "{forecast}");
    }
    // Beyond the hours, and a sounding: refused, named.
    let refused = |body: Value, expected: &str| {
        let (status, answer) = post(
            "/api/plan/window",
            "application/json",
            body.to_string().as_bytes(),
        );
        let reason = answer["reason"].as_str().unwrap_or_default().to_string();
        assert_eq!(status, 400, "{answer}");
        assert!(reason.contains(expected), "{answer}");
    };
    refused(
        json!({"request": request, "window": {"from": FROM, "to": "2026-11-30T13:00:00Z", "every_s": 3600}, "forecast": "configured"}),
        "outside the GFS files' forecast hours",
    );
    let (_, sounding) = post("/api/plan/forecast", octets, &bytes("72520_sounding.txt"));
    assert_eq!(sounding["kind"], "sounding", "{sounding}");
    refused(
        json!({"request": request, "window": {"from": FROM, "to": TO, "every_s": 3600}, "forecast": {"upload": sounding["id"]}}),
        "a sounding is one instant",
    );
    sigterm(&child);
}
