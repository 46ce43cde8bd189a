//! The live flight path's launch profile through the real daemon: a station started with the
//! shipped config (no `[flight_path]`, so no burst altitude of its own) and, separately, the
//! simulated drone of `stx drone --scenario mission-short` (a balloon loaded to burst at
//! 3,000 m) over the MAVLink link. Issue 28: the map said "burst in 1 h 45 min at 35.0 km"
//! while the drone burst at 3,000 m.

use crate::common;

use std::time::Duration;

use common::*;
use serde_json::Value;
use stx_sim::drone::MissionConfig;

/// The state's flight path once it has a burst point, within `secs`.
async fn path_with_burst(station: &Station, secs: f64) -> Option<Value> {
    let deadline = tokio::time::Instant::now() + Duration::from_secs_f64(secs);
    while tokio::time::Instant::now() < deadline {
        let (status, state) = http(station.http(), "GET", "/api/state", Some(VIEWER), None).await;
        if status == 200 && state["flight_path"]["burst"].is_object() {
            return Some(state["flight_path"].clone());
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    None
}

#[tokio::test]
async fn regression_the_burst_altitude_is_the_drones_and_the_path_says_so() {
    let station = start_station(config(|_| {})).await;
    assert_eq!(
        station_unset(),
        vec!["burst_altitude_msl_m", "mean_ascent_rate_mps"],
        "the shipped config gives no launch profile"
    );
    let mission = MissionConfig::builtin("mission-short").expect("built-in mission");
    let _drone = sim_drone(station.running.link_local.expect("link"), &mission, 4.0).await;
    let path = path_with_burst(&station, 30.0)
        .await
        .expect("a flight path with a burst point");
    let burst_alt = path["burst"]["alt_msl_m"].as_f64().expect("altitude");
    assert!((burst_alt - 3000.0).abs() < 1.0, "{path}");
    assert_eq!(path["burst_source"], "drone", "{path}");
    assert_eq!(path["ascent_rate_source"], "drone", "{path}");
}

/// What the shipped config leaves out of `[flight_path]`.
fn station_unset() -> Vec<&'static str> {
    config(|_| {}).flight_path_unset
}
