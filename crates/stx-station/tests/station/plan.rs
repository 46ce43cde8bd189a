//! `POST /api/plan` and `GET /api/plan/defaults` through a real daemon: a uniform wind whose
//! burst and deploy points are known in closed form (offset = wind × time), the measured
//! ascent of a recording in place of the forecast, bad requests refused with the field named,
//! and one plan at a time with the station answering meanwhile.

use crate::common;

use std::path::{Path, PathBuf};
use std::time::Duration;

use common::*;
use serde_json::{Value, json};
use stx_gnc::geo::LocalFrame;
use stx_link::telemetry::{GlobalPosition, GpsFix, GpsRaw, Telemetry};
use stx_record::{CoreOptions, RecorderCore, RecordingInfo};
use stx_station::recording::telemetry::TelemetryChannels;

const T0: u64 = 1_767_225_600_000_000_000;

/// The shipped config's launch site (Évora, 245 m MSL).
fn launch() -> LocalFrame {
    config(|_| {}).origin
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("stx-plan-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// A request from the launch site through `wind_mps` from the west at every height, with no
/// spread: every sample flies the same path.
fn uniform(wind_mps: f64, runs: u32) -> Value {
    let o = launch();
    json!({
        "launch_lat_deg": o.lat_deg,
        "launch_lon_deg": o.lon_deg,
        "launch_alt_msl_m": o.alt_msl_m,
        "forecast": [{"alt_msl_m": 0.0, "speed_mps": wind_mps, "from_deg": 270.0, "sigma_mps": 0.0}],
        "ascent_rate_mps": 5.0,
        "ascent_rate_sigma_mps": 0.0,
        "burst_altitude_msl_m": 20_000.0,
        "burst_altitude_sigma_m": 0.0,
        "runs": runs,
        "seed": 7,
    })
}

async fn post_plan(addr: std::net::SocketAddr, token: &str, body: &Value) -> (u16, Value) {
    http(
        addr,
        "POST",
        "/api/plan",
        Some(token),
        Some(&body.to_string()),
    )
    .await
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

#[tokio::test]
async fn a_uniform_wind_bursts_and_deploys_downwind_by_wind_times_time() {
    let station = start_station(config(|_| {})).await;
    let mut request = uniform(10.0, 20);
    // 20 km east of the launch: whether steering reaches it is counted and answered.
    request["target_lat_lon_deg"] = json!([launch().lat_deg, launch().lon_deg + 0.23]);
    // A viewer may plan: it commands nothing.
    let (status, plan) = post_plan(station.http(), VIEWER, &json!({ "request": request })).await;
    assert_eq!(status, 200, "{plan}");
    let burst = &plan["burst"];
    let climb_s = (20_000.0 - launch().alt_msl_m) / 5.0;
    assert!(
        (num(&burst["time_s"]) - climb_s).abs() < 1e-3 * climb_s,
        "{burst}"
    );
    let east = num(&burst["east_m"]);
    assert!(
        (east - 10.0 * climb_s).abs() < 1e-3 * 10.0 * climb_s,
        "{east}"
    );
    assert!(num(&burst["north_m"]).abs() < 1e-6, "{burst}");
    assert!(num(&burst["ellipse"]["semi_major_m"]) < 1e-6, "{burst}");
    // The round chute drifts with the same wind down to the deploy height: its offset is the
    // wind times its time as well.
    let deploy = &plan["deploy"];
    let deploy_east = num(&deploy["east_m"]);
    let deploy_t = num(&deploy["time_s"]);
    assert!(deploy_t > climb_s + 60.0, "{deploy}");
    assert!(
        (deploy_east - 10.0 * deploy_t).abs() < 1e-3 * deploy_east,
        "{deploy}"
    );
    // Launch east, burst, deploy and landing further east, in that order.
    let landing_east = num(&plan["landing_unsteered"]["east_m"]);
    assert!(landing_east > deploy_east, "{plan}");
    assert_eq!(
        plan["landing_samples_lat_lon_deg"]
            .as_array()
            .unwrap()
            .len(),
        20
    );
    // Every sample alike: the region is their glide disc, traced cell by cell.
    assert!(plan["steered_region_lat_lon_deg"].as_array().unwrap().len() > 100);
    assert_eq!(plan["steered_region_best_probability"], json!(1.0));
    let p = num(&plan["target"]["reachable_probability"]);
    assert!((0.0..=1.0).contains(&p), "{plan}");
    // Defaults filled in and answered with the plan.
    assert_eq!(plan["request"]["deploy_height_m"], json!(2500.0));
}

#[tokio::test]
async fn the_defaults_are_the_stations_launch_site_and_forecast() {
    let station = start_station(config(|_| {})).await;
    let (status, d) = http(
        station.http(),
        "GET",
        "/api/plan/defaults",
        Some(VIEWER),
        None,
    )
    .await;
    assert_eq!(status, 200, "{d}");
    let o = launch();
    assert_eq!(d["request"]["launch_lat_deg"], json!(o.lat_deg));
    assert_eq!(d["request"]["launch_lon_deg"], json!(o.lon_deg));
    assert_eq!(d["request"]["launch_alt_msl_m"], json!(o.alt_msl_m));
    // The shipped config's three rows, lowest first, without sigmas.
    assert_eq!(
        d["request"]["forecast"],
        json!([
            {"alt_msl_m": 300.0, "speed_mps": 2.0, "from_deg": 270.0},
            {"alt_msl_m": 3000.0, "speed_mps": 6.0, "from_deg": 250.0},
            {"alt_msl_m": 12000.0, "speed_mps": 20.0, "from_deg": 240.0},
        ])
    );
    assert_eq!(d["max_runs"], json!(5000));
    // No drone: no target known.
    assert_eq!(d["request"]["target_lat_lon_deg"], Value::Null);
    assert_eq!(d["target_source"], Value::Null);
    // The defaults plan as they are.
    let (status, plan) = post_plan(station.http(), VIEWER, &json!({"request": d["request"]})).await;
    assert_eq!(status, 200, "{plan}");
}

#[tokio::test]
async fn bad_requests_are_refused_with_the_field_named() {
    let dir = temp_dir("bad");
    std::fs::write(dir.join("broken.mcap"), b"not an MCAP file").unwrap();
    let recordings = dir.clone();
    let station = start_station(config(move |c| c.recording.dir = Some(recordings))).await;
    let good = uniform(10.0, 5);
    let with = |key: &str, value: Value| {
        let mut r = good.clone();
        r[key] = value;
        json!({ "request": r })
    };
    let cases = [
        (with("runs", json!(0)), "`runs` = 0"),
        (with("runs", json!(5001)), "`runs` = 5001"),
        (with("launch_lat_deg", json!(95.0)), "launch_lat_deg"),
        (with("ascent_rate_mps", json!(-1.0)), "ascent_rate_mps"),
        (with("deploy_height_m", json!(1e6)), "deploy_height_m"),
        (with("runs", json!("many")), "request.runs"),
        (with("sideways", json!(1)), "unknown field `sideways`"),
        (
            with(
                "forecast",
                json!([
                    {"alt_msl_m": 3000.0, "speed_mps": 5.0, "from_deg": 270.0},
                    {"alt_msl_m": 300.0, "speed_mps": 5.0, "from_deg": 270.0},
                ]),
            ),
            "forecast",
        ),
        (with("forecast", json!([])), "the forecast has no rows"),
        (
            with(
                "forecast",
                json!([{"alt_msl_m": 0.0, "speed_mps": 5.0, "from_deg": 270.0, "sigma_mps": -1.0}]),
            ),
            "sigma_mps",
        ),
        (json!({ "forecast": [] }), "unknown field `forecast`"),
        (json!({}), "missing field `request`"),
        (
            json!({ "request": good, "from_recording": "nowhere.mcap" }),
            "from_recording: the station has no recording named \"nowhere.mcap\"",
        ),
        (
            json!({ "request": good, "from_recording": "../etc/passwd" }),
            "from_recording",
        ),
        (
            json!({ "request": good, "from_recording": "broken.mcap" }),
            "from_recording: \"broken.mcap\" cannot be read",
        ),
    ];
    for (body, expected) in cases {
        let (status, answer) = post_plan(station.http(), VIEWER, &body).await;
        assert_eq!(status, 400, "{body}: {answer}");
        assert_eq!(answer["error"], "bad_request", "{body}: {answer}");
        let reason = answer["reason"].as_str().unwrap_or_default();
        assert!(reason.contains(expected), "{body}: {reason}");
    }
    // JSON has no NaN or infinity: a number too large for a double is refused as it is read.
    let huge = json!({ "request": with("burst_altitude_msl_m", json!(1.5))["request"] })
        .to_string()
        .replace("1.5", "1e999");
    for text in ["{not json", huge.as_str()] {
        let (status, answer) = http(
            station.http(),
            "POST",
            "/api/plan",
            Some(VIEWER),
            Some(text),
        )
        .await;
        assert_eq!(status, 400, "{text}: {answer}");
        assert!(
            answer["reason"]
                .as_str()
                .unwrap()
                .starts_with("malformed request body")
        );
    }
    let (status, _) = post_plan(station.http(), "wrong-token", &json!({"request": good})).await;
    assert_eq!(status, 401);
    // The station plans on after every refusal.
    let (status, plan) = post_plan(station.http(), VIEWER, &json!({"request": good})).await;
    assert_eq!(status, 200, "{plan}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[tokio::test]
async fn one_plan_at_a_time_and_the_station_answers_meanwhile() {
    let station = start_station(config(|_| {})).await;
    let addr = station.http();
    // The largest plan, to 35 km: about a second of a core.
    let mut big = uniform(10.0, 5000);
    big["burst_altitude_msl_m"] = json!(35_000.0);
    let body = json!({ "request": big });
    let first = tokio::spawn({
        let body = body.clone();
        async move { post_plan(addr, OPERATOR, &body).await }
    });
    // The second asks once the first is surely being computed.
    tokio::time::sleep(Duration::from_millis(100)).await;
    let (status, second) = post_plan(addr, VIEWER, &body).await;
    // The state is read while the first is still computed (this test's runtime has one
    // thread: a plan computed on it would hold every answer until it was done).
    let (state_status, _) = http(addr, "GET", "/api/state", Some(VIEWER), None).await;
    assert_eq!(state_status, 200);
    assert!(
        !first.is_finished(),
        "the first plan ended before the state was read"
    );
    assert_eq!(status, 429, "{second}");
    assert_eq!(second["error"], "busy", "{second}");
    assert!(second["reason"].as_str().unwrap().contains("another plan"));
    let (status, plan) = first.await.expect("first plan");
    assert_eq!(status, 200, "{plan}");
    assert_eq!(plan["request"]["runs"], json!(5000));
    // Once it is done, the next one is computed.
    let (status, _) = post_plan(addr, VIEWER, &json!({"request": uniform(10.0, 10)})).await;
    assert_eq!(status, 200);
}

/// A recording whose drone sits 60 s on the pad, rises at `rate_mps` for 600 s (5 m/s: to
/// 3 km above it) while drifting east at `wind_mps`, then falls: GPS_RAW_INT at 1 Hz of the
/// drone's clock, each after a GLOBAL_POSITION_INT that stamps it, recorded by a station whose
/// clock runs `1/speed` as fast (a rehearsal at `speed`×). With `decoded` false, only the
/// `/vehicle/gps` positions, which carry the station's clock alone.
fn write_ascent(path: &Path, wind_mps: f64, rate_mps: f64, speed: u64, decoded: bool) {
    let o = launch();
    let info = RecordingInfo::new("test", "straplex-2", "plan test");
    let mut core = RecorderCore::new(CoreOptions::default(), info, Duration::ZERO).unwrap();
    let channels = TelemetryChannels::register(&mut core, Duration::ZERO).unwrap();
    let (mut east, mut height) = (0.0, 0.0);
    for i in 0..800u64 {
        let t = i as f64;
        let climb = if (60.0..660.0).contains(&t) {
            east += wind_mps;
            height += rate_mps;
            rate_mps
        } else if t >= 660.0 && height > 0.0 {
            height -= 20.0;
            -20.0
        } else {
            0.0
        };
        let (lat, lon, alt) = o.to_geodetic(&nalgebra::Vector3::new(0.0, east, -height));
        let position = GlobalPosition {
            time_boot_ms: (i * 1000) as u32,
            lat_deg: lat,
            lon_deg: lon,
            alt_msl_m: alt,
            alt_rel_m: height,
            v_north_mps: 0.0,
            v_east_mps: wind_mps,
            v_down_mps: -climb,
            heading_deg: None,
        };
        let gps = GpsRaw {
            time_usec: i * 1_000_000,
            fix: GpsFix::Fix3d,
            lat_deg: lat,
            lon_deg: lon,
            alt_msl_m: alt,
            ground_speed_mps: None,
            course_deg: None,
            satellites: Some(12),
            h_acc_m: None,
            v_acc_m: None,
        };
        let station = Duration::from_millis(i * 1000 / speed);
        let log = T0 + station.as_nanos() as u64;
        for telemetry in [Telemetry::Position(position), Telemetry::GpsRaw(gps)] {
            let records = channels.records(log, &telemetry);
            // Without the decoded telemetry: only the LocationFix a GPS_RAW_INT also gives.
            let skip = usize::from(!decoded);
            for (id, data) in records.into_iter().skip(skip) {
                core.write(station, id, log, log, &data).unwrap();
            }
        }
    }
    std::fs::write(path, finished_recording(core)).unwrap();
}

#[tokio::test]
async fn a_recordings_measured_ascent_replaces_the_forecast_where_it_measured() {
    let dir = temp_dir("measured");
    // Recorded at 10×: the drift is timed by the drone's clock, not the recording's.
    write_ascent(&dir.join("ascent-1.mcap"), 10.0, 5.0, 10, true);
    // A track that never rises measures nothing.
    write_ascent(&dir.join("grounded.mcap"), 0.0, 0.0, 1, true);
    // Positions alone have no drone clock.
    write_ascent(&dir.join("positions.mcap"), 10.0, 5.0, 1, false);
    // 80 m/s from the west: faster than any wind near the ground, refused.
    write_ascent(&dir.join("storm.mcap"), 80.0, 5.0, 1, true);
    let recordings = dir.clone();
    let station = start_station(config(move |c| c.recording.dir = Some(recordings))).await;
    // The forecast says calm at 30 km; the recording measured 10 m/s from the west up to 3 km.
    let mut request = uniform(0.0, 10);
    request["forecast"] = json!([{"alt_msl_m": 30_000.0, "speed_mps": 0.0, "from_deg": 270.0}]);
    request["burst_altitude_msl_m"] = json!(3000.0);
    request["deploy_height_m"] = json!(500.0);
    request["default_wind_sigma_mps"] = json!(0.0);
    let (status, calm) = post_plan(station.http(), VIEWER, &json!({"request": request})).await;
    assert_eq!(status, 200, "{calm}");
    assert!(num(&calm["burst"]["east_m"]).abs() < 1e-6, "{calm}");
    let body = json!({"request": request, "from_recording": "ascent-1.mcap"});
    let (status, plan) = post_plan(station.http(), VIEWER, &body).await;
    assert_eq!(status, 200, "{plan}");
    let climb_s = (3000.0 - launch().alt_msl_m) / 5.0;
    let east = num(&plan["burst"]["east_m"]);
    assert!(
        (east - 10.0 * climb_s).abs() < 0.03 * 10.0 * climb_s,
        "{east} vs {climb_s} s"
    );
    assert!(num(&plan["burst"]["north_m"]).abs() < 0.03 * east, "{plan}");
    // The forecast the plan flew: the measured bands, then the forecast's row above them.
    let rows = plan["request"]["forecast"].as_array().unwrap();
    assert!(rows.len() >= 4, "{rows:?}");
    assert_eq!(rows.last().unwrap()["alt_msl_m"], json!(30_000.0));
    for r in &rows[..rows.len() - 1] {
        assert!((num(&r["speed_mps"]) - 10.0).abs() < 0.5, "{r}");
        assert!((num(&r["from_deg"]) - 270.0).abs() < 3.0, "{r}");
    }
    // The page is told which bands were merged: all of them, here.
    let bands = plan["measured_ascent"]["bands"].as_array().unwrap();
    assert_eq!(plan["measured_ascent"]["recording"], json!("ascent-1.mcap"));
    assert_eq!(bands.len(), rows.len() - 1, "{bands:?}");
    assert!(bands.iter().all(|b| b["refused"].is_null()), "{bands:?}");
    assert!(calm["measured_ascent"].is_null(), "{calm}");
    // The storm's bands are listed with the reason, and the plan flies the forecast.
    let body = json!({"request": request, "from_recording": "storm.mcap"});
    let (status, stormy) = post_plan(station.http(), VIEWER, &body).await;
    assert_eq!(status, 200, "{stormy}");
    let bands = stormy["measured_ascent"]["bands"].as_array().unwrap();
    assert!(bands.len() >= 5, "{bands:?}");
    for b in bands {
        let reason = b["refused"].as_str().unwrap_or_default();
        assert!(reason.contains("faster than any wind"), "{b}");
    }
    assert!(num(&stormy["burst"]["east_m"]).abs() < 1e-6, "{stormy}");
    let body = json!({"request": request, "from_recording": "positions.mcap"});
    let (status, answer) = post_plan(station.http(), VIEWER, &body).await;
    assert_eq!(status, 400, "{answer}");
    assert!(
        answer["reason"]
            .as_str()
            .unwrap_or_default()
            .contains("drone's clock"),
        "{answer}"
    );
    let body = json!({"request": request, "from_recording": "grounded.mcap"});
    let (status, answer) = post_plan(station.http(), VIEWER, &body).await;
    assert_eq!(status, 400, "{answer}");
    let reason = answer["reason"].as_str().unwrap_or_default();
    assert!(
        reason.contains("from_recording: \"grounded.mcap\": no ascent wind"),
        "{reason}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
