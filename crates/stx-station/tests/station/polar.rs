//! A vehicle's planning polar sent to the drone through the station (`stx polar --json`'s
//! body to `POST /api/lab/gains/send`): the drone's guidance plans with it, and the station's
//! parameter table shows it.

use crate::common;

use std::time::Duration;

use common::*;
use serde_json::{Value, json};
use stx_gnc::performance::GlidePerformance;
use stx_sim::drone::config::MissionConfig;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_polar_sent_from_the_station_is_what_the_drones_guidance_plans_with() {
    let station = start_station(config(|_| {})).await;
    let addr = station.http();
    let link = station.running.link_local.expect("link");
    let mission = MissionConfig::builtin("rehearsal").expect("built-in rehearsal");
    let drone = sim_drone(link, &mission, 4.0).await;

    // A canopy 10 % slower and 12 % more sinking than the shipped table, as `stx polar` gives it.
    let mut slow = GlidePerformance::default();
    for k in 0..slow.brake_points.len() {
        slow.airspeed_mps[k] *= 0.9;
        slow.sink_rate_mps[k] *= 1.12;
    }
    let params: serde_json::Map<String, Value> = stx_gnc::params::polar_params(&slow)
        .into_iter()
        .map(|(n, v)| (n.to_string(), json!(v)))
        .collect();
    let send = |body: Value| {
        let body = body.to_string();
        async move {
            http(
                addr,
                "POST",
                "/api/lab/gains/send",
                Some(OPERATOR),
                Some(&body),
            )
            .await
        }
    };
    // Only gains and the polar go this way; the polar must be a glide.
    let (status, body) = send(json!({"gains": {"SP_MIN_FINAL": 50.0}, "confirm": true})).await;
    assert_eq!(
        (status, body["error"].as_str()),
        (400, Some("invalid_gains")),
        "{body}"
    );
    let (status, body) = send(json!({"gains": {"PL_SINK_0": 9.0}, "confirm": true})).await;
    assert_eq!(status, 400, "{body}");
    let (status, body) = send(json!({"gains": params, "confirm": true})).await;
    assert_eq!(status, 202, "{body}");
    assert_eq!(
        body["request_ids"].as_array().map(Vec::len),
        Some(params.len())
    );

    let mut held = None;
    for _ in 0..200 {
        let perf = drone
            .query(|d| d.drone().onboard().guidance().config().performance)
            .await;
        if (perf.sink_rate_mps[5] - slow.sink_rate_mps[5]).abs() < 1e-5 {
            held = Some(perf);
            break;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let held = held.expect("the drone's guidance never took the polar");
    for k in 0..slow.brake_points.len() {
        assert!((held.airspeed_mps[k] - slow.airspeed_mps[k]).abs() < 1e-5);
        assert!((held.sink_rate_mps[k] - slow.sink_rate_mps[k]).abs() < 1e-5);
    }
    // The station's table reads the drone's values back (the replica plans from that table).
    let mut shown = Value::Null;
    for _ in 0..100 {
        shown = http(addr, "GET", "/api/params", Some(OPERATOR), None)
            .await
            .1;
        let value = |name: &str| {
            shown["params"]
                .as_array()
                .and_then(|ps| ps.iter().find(|p| p["name"] == name))
                .and_then(|p| p["value"].as_f64())
        };
        if value("PL_SINK_5").is_some_and(|v| (v - slow.sink_rate_mps[5]).abs() < 1e-5)
            && value("PL_AS_0").is_some_and(|v| (v - slow.airspeed_mps[0]).abs() < 1e-5)
        {
            return;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    panic!("the station's parameter table does not show the polar: {shown}");
}
