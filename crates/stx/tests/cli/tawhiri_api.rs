//! The station's Tawhiri-compatible prediction API (issue 31, item 4): `GET /api/v1/` answers
//! in Tawhiri's shape (`metadata`, `prediction` as an ascent and a descent stage of timed
//! points, `request` echoed with `dataset` and `version`, `warnings`), the ascent starts at the
//! launch, the descent starts at the burst altitude and ends on the ground, times increase;
//! bad parameters are Tawhiri's errors with its statuses; a station with a GFS file flies it at
//! the launch site and time and names its run.

use serde_json::Value;

use crate::cli_plan_gfs::{path, station_config};
use crate::common::{exchange, serve, sigterm, temp_dir};

const QUERY: &str = "profile=standard_profile&launch_latitude=38.5333&launch_longitude=352.1111\
&launch_datetime=2026-11-30T08:00:00Z&launch_altitude=245&ascent_rate=5&burst_altitude=30000\
&descent_rate=6";

fn station(extra_config: Option<&str>) -> (std::process::Child, String, String) {
    let dir = temp_dir(
        "tawhiri",
        if extra_config.is_some() {
            "gfs"
        } else {
            "rows"
        },
    );
    let mut args = vec!["--listen", "127.0.0.1:0", "--link", "udpin:127.0.0.1:0"];
    let config;
    if let Some(table) = extra_config {
        config = station_config(&dir, table).display().to_string();
        args.extend(["--config", &config]);
    }
    serve(&args)
}

fn get(address: &str, token: Option<&str>, query: &str) -> (u16, Value) {
    exchange(
        address,
        token,
        "GET",
        &format!("/api/v1/?{query}"),
        "text/plain",
        b"",
    )
}

/// Every point's keys and types, the times increasing, the longitudes 0–360.
fn check_trajectory(points: &[Value]) -> Vec<(f64, String, f64, f64)> {
    let mut out: Vec<(f64, String, f64, f64)> = Vec::new();
    for p in points {
        let o = p.as_object().expect("a point is an object");
        let mut keys: Vec<&str> = o.keys().map(String::as_str).collect();
        keys.sort_unstable();
        assert_eq!(keys, ["altitude", "datetime", "latitude", "longitude"]);
        let t = p["datetime"].as_str().unwrap().to_string();
        let parsed = stx_weather::parse_time(&t).expect("RFC 3339");
        if let Some(before) = out.last() {
            assert!(
                parsed > stx_weather::parse_time(&before.1).unwrap(),
                "{t} after {}",
                before.1
            );
        }
        let lon = p["longitude"].as_f64().unwrap();
        assert!((0.0..360.0).contains(&lon), "{lon}");
        out.push((
            p["altitude"].as_f64().unwrap(),
            t,
            p["latitude"].as_f64().unwrap(),
            lon,
        ));
    }
    out
}

#[test]
fn a_prediction_has_tawhiris_shape_and_flies_up_to_the_burst_and_down_to_the_ground() {
    let (child, address, token) = station(None);
    let (status, answer) = get(&address, Some(&token), QUERY);
    assert_eq!(status, 200, "{answer}");
    let mut keys: Vec<&str> = answer
        .as_object()
        .unwrap()
        .keys()
        .map(String::as_str)
        .collect();
    keys.sort_unstable();
    assert_eq!(keys, ["metadata", "prediction", "request", "warnings"]);
    for k in ["start_datetime", "complete_datetime"] {
        stx_weather::parse_time(answer["metadata"][k].as_str().unwrap()).expect(k);
    }
    let request = &answer["request"];
    assert_eq!(request["version"], 1);
    assert_eq!(request["profile"], "standard_profile");
    assert_eq!(request["launch_longitude"], 352.1111);
    assert_eq!(request["burst_altitude"], 30000.0);
    assert!(request["dataset"].is_string());
    // The shipped station flies its forecast rows: said in a warning.
    assert!(
        answer["warnings"]["station_profile"]["count"] == 1,
        "{answer}"
    );
    let stages = answer["prediction"].as_array().unwrap();
    let names: Vec<&str> = stages
        .iter()
        .map(|s| s["stage"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["ascent", "descent"]);
    let up = check_trajectory(stages[0]["trajectory"].as_array().unwrap());
    let down = check_trajectory(stages[1]["trajectory"].as_array().unwrap());
    assert_eq!(
        (up[0].0, up[0].1.as_str(), up[0].2),
        (245.0, "2026-11-30T08:00:00Z", 38.5333)
    );
    let burst = up.last().unwrap();
    assert!((burst.0 - 30_000.0).abs() < 1e-6, "{burst:?}");
    // 29 755 m at 5 m/s.
    assert_eq!(burst.1, "2026-11-30T09:39:11Z");
    assert_eq!(down[0], *burst);
    let landing = down.last().unwrap();
    assert!((landing.0 - 245.0).abs() < 1e-6, "{landing:?}");
    // A point a minute, besides the ends.
    assert!(up.len() >= 99 && up.len() <= 101, "{}", up.len());
    sigterm(&child);
}

#[test]
fn bad_parameters_are_tawhiris_errors_with_its_statuses() {
    let (child, address, token) = station(None);
    let without = |name: &str| {
        QUERY
            .split('&')
            .filter(|p| !p.starts_with(&format!("{name}=")))
            .collect::<Vec<_>>()
            .join("&")
    };
    let cases = [
        (
            without("launch_datetime"),
            400,
            "RequestException",
            "Parameter 'launch_datetime' not provided in request.",
        ),
        (
            QUERY.replace("launch_longitude=352.1111", "launch_longitude=-7.9"),
            400,
            "RequestException",
            "Invalid value for parameter 'launch_longitude': -7.9.",
        ),
        (
            QUERY.replace("ascent_rate=5", "ascent_rate=fast"),
            400,
            "RequestException",
            "Unable to parse parameter 'ascent_rate': fast.",
        ),
        (
            QUERY.replace("burst_altitude=30000", "burst_altitude=100"),
            400,
            "RequestException",
            "Invalid value for parameter 'burst_altitude': 100.",
        ),
        (
            QUERY.replace("standard_profile", "balloon"),
            400,
            "RequestException",
            "Unknown profile 'balloon'.",
        ),
        (
            QUERY.replace("standard_profile", "float_profile"),
            501,
            "NotYetImplementedException",
            "stx flies the standard profile only",
        ),
        (
            format!("{QUERY}&dataset=2026-11-30T00:00:00Z"),
            404,
            "InvalidDatasetException",
            "No matching dataset found",
        ),
    ];
    for (query, status, kind, description) in cases {
        let (got, answer) = get(&address, Some(&token), &query);
        assert_eq!(got, status, "{query}: {answer}");
        assert_eq!(answer["error"]["type"], kind, "{query}: {answer}");
        assert!(
            answer["error"]["description"]
                .as_str()
                .unwrap()
                .starts_with(description),
            "{query}: {answer}"
        );
        assert!(answer["metadata"]["start_datetime"].is_string(), "{answer}");
        assert!(answer.get("prediction").is_none(), "{answer}");
    }
    // The token as on every route: in the address too, and none is the station's 401.
    let (status, _) = get(&address, None, &format!("{QUERY}&token={token}"));
    assert_eq!(status, 200);
    let (status, answer) = get(&address, None, QUERY);
    assert_eq!(
        (status, answer["error"].as_str()),
        (401, Some("unauthorized")),
        "{answer}"
    );
    sigterm(&child);
}

#[test]
fn a_station_with_gfs_files_flies_them_at_the_launch_site_and_time() {
    let table = format!(
        "[forecast_file]\ngfs = [\"{}\"]\n",
        path("gfs_0p25_subset.grib2")
    );
    let (child, address, token) = station(Some(&table));
    let (status, at_8) = get(&address, Some(&token), QUERY);
    assert_eq!(status, 200, "{at_8}");
    assert_eq!(at_8["request"]["dataset"], "2026-11-30T06:00:00Z");
    assert_eq!(at_8["warnings"], serde_json::json!({}), "{at_8}");
    // The subset's winds grow by the hour: another launch time lands elsewhere.
    let (_, at_11) = get(&address, Some(&token), &QUERY.replace("T08:00", "T11:00"));
    let end = |a: &Value| {
        a["prediction"][1]["trajectory"]
            .as_array()
            .unwrap()
            .last()
            .unwrap()["longitude"]
            .as_f64()
            .unwrap()
    };
    assert!(
        (end(&at_8) - end(&at_11)).abs() > 1e-3,
        "{} {}",
        end(&at_8),
        end(&at_11)
    );
    let (status, ok) = get(
        &address,
        Some(&token),
        &format!("{QUERY}&dataset=2026-11-30T06:00:00Z"),
    );
    assert_eq!(status, 200, "{ok}");
    let (status, late) = get(
        &address,
        Some(&token),
        &QUERY.replace("2026-11-30T08", "2026-12-01T08"),
    );
    assert_eq!(
        (status, late["error"]["type"].as_str()),
        (400, Some("RequestException")),
        "{late}"
    );
    assert!(
        late["error"]["description"]
            .as_str()
            .unwrap()
            .contains("outside the forecast"),
        "{late}"
    );
    sigterm(&child);
}
