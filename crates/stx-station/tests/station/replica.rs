//! The station's guidance replica against the real simulated drone: it must fly the plan the
//! drone flies, wherever the target is, whoever set it.

use crate::common;

use std::time::Duration;

use common::*;
use serde_json::{Value, json};
use stx_gnc::geo::LocalFrame;
use stx_sim::drone::config::{BUILTIN, MissionConfig};

/// The drone's target of `mission-short`, 300 m N and 2,500 m E of the station's origin.
const TARGET_NE_M: [f64; 2] = [300.0, 2500.0];

/// The rehearsal (parafoil out, spiral landing by the onboard plan) moved next to a target far
/// from the station's origin, as `mission-short` flies it.
fn far_rehearsal() -> MissionConfig {
    let (_, text) = BUILTIN
        .iter()
        .find(|(name, _)| *name == "rehearsal")
        .expect("built-in rehearsal");
    let text = text
        .replacen(
            "target_ne_m = [0.0, 0.0]",
            &format!(
                "target_ne_m = [{:.1}, {:.1}]",
                TARGET_NE_M[0], TARGET_NE_M[1]
            ),
            1,
        )
        .replacen(
            "position_ned_m = [-500.0, -500.0, -900.0]",
            "position_ned_m = [-200.0, 2000.0, -900.0]",
            1,
        );
    assert!(
        text.contains("2500.0") && text.contains("2000.0"),
        "patched"
    );
    MissionConfig::from_toml_str("rehearsal-far", &text).expect("mission")
}

/// The drone of [`far_rehearsal`] on the station's link, four times faster than real time.
async fn far_drone(station: &Station) -> SimDrone {
    let link = station.running.link_local.expect("link");
    sim_drone(link, &far_rehearsal(), 4.0).await
}

fn frame() -> LocalFrame {
    config(|_| {}).origin
}

/// North and east of the origin, m, of a `{lat_deg, lon_deg}` object.
fn ne_of(v: &Value) -> Option<[f64; 2]> {
    let p = frame().to_ned(v["lat_deg"].as_f64()?, v["lon_deg"].as_f64()?, 245.0);
    Some([p.x, p.y])
}

fn distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

async fn state(addr: std::net::SocketAddr) -> Value {
    http(addr, "GET", "/api/state", Some(VIEWER), None).await.1
}

/// The first state whose target was read from the drone (Null after 15 s).
async fn wait_for_drone_plan(addr: std::net::SocketAddr) -> Value {
    for _ in 0..150 {
        let s = state(addr).await;
        if s["guidance"]["target_source"] == "drone_plan" {
            return s;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    Value::Null
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_station_flies_the_drones_own_target_far_from_the_origin() {
    let station = start_station(config(|_| {})).await;
    let addr = station.http();
    // Before the drone is heard, the target is unknown: never the origin.
    let before = state(addr).await;
    assert!(
        before["guidance"]["target"].is_null(),
        "{}",
        before["guidance"]
    );
    let drone = far_drone(&station).await;
    // The drone's plan is read back from it.
    let adopted = wait_for_drone_plan(addr).await;
    let target = ne_of(&adopted["guidance"]["target"])
        .unwrap_or_else(|| panic!("the drone's plan was not read: {adopted}"));
    assert!(
        distance(target, TARGET_NE_M) < 1.0,
        "replica target {target:?}, drone's {TARGET_NE_M:?}"
    );
    let onboard = drone
        .query(|d| d.drone().onboard().guidance().plan().target_ned_m)
        .await;
    assert!(distance(target, [onboard.x, onboard.y]) < 1.0);

    // Flying it: the pattern, the planned prediction and the drone's own prediction are all
    // about the target, not the origin 2.5 km away.
    let mut last = Value::Null;
    let mut seen = false;
    for _ in 0..300 {
        last = state(addr).await;
        let planned = ne_of(&last["prediction"]["planned"]);
        let onboard = ne_of(&last["vehicle"]["predicted_landing"]);
        let corners = last["guidance"]["pattern"]["corners"].as_array().cloned();
        let parafoil = last["vehicle"]["stage"] == "parafoil";
        if let (true, Some(planned), Some(onboard), Some(corners)) =
            (parafoil, planned, onboard, corners)
        {
            // The drone predicts its plan only once the parafoil flies; the station's
            // replica flies the same plan.
            if distance(onboard, TARGET_NE_M) > 300.0 {
                tokio::time::sleep(Duration::from_millis(100)).await;
                continue;
            }
            assert!(
                distance(planned, TARGET_NE_M) < 300.0,
                "the station's planned landing {planned:?} is far from the target"
            );
            for c in corners {
                let p = frame().to_ned(
                    c[0].as_f64().expect("lat"),
                    c[1].as_f64().expect("lon"),
                    245.0,
                );
                assert!(
                    distance([p.x, p.y], TARGET_NE_M) < 1500.0,
                    "pattern corner {p:?} far from the target"
                );
            }
            seen = true;
            break;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    assert!(seen, "no pattern and predictions in 30 s: {last}");
    assert_eq!(last["vehicle"]["predicted_landing"]["stale"], false);
    // What the spiral learns of the stack is shown as it flies (nothing before).
    assert!(
        before["guidance"]["learned"].is_null(),
        "{}",
        before["guidance"]
    );
    let learned = &last["guidance"]["learned"];
    assert_eq!(
        learned["brake"],
        serde_json::json!([0.0, 0.5, 1.0]),
        "{learned}"
    );
    for key in ["airspeed_scale", "sink_scale"] {
        let scales = learned[key].as_array().expect("three scales");
        assert_eq!(scales.len(), 3, "{learned}");
        assert!(
            scales
                .iter()
                .all(|v| v.as_f64().is_some_and(|v| (0.5..=2.0).contains(&v))),
            "{learned}"
        );
    }
    assert!(
        learned["learned_s"].as_f64().is_some_and(|s| s >= 0.0),
        "{learned}"
    );
    assert!(
        learned["turn_scale"].as_f64().is_some_and(|v| v > 0.0),
        "{learned}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_plan_uploaded_through_the_api_is_flown_alike_by_drone_and_replica() {
    let station = start_station(config(|_| {})).await;
    let addr = station.http();
    let drone = far_drone(&station).await;
    let adopted = wait_for_drone_plan(addr).await;
    assert!(adopted["guidance"]["target"].is_object(), "{adopted}");
    // Two descending waypoints west of a new target: a localizer line east with a glide
    // slope, and the landing.
    let f = frame();
    let geo = |n: f64, e: f64, up: f64| {
        let (lat, lon, alt) = f.to_geodetic(&nalgebra::Vector3::new(n, e, -up));
        (lat, lon, alt)
    };
    let (a_lat, a_lon, a_alt) = geo(100.0, 1200.0, 600.0);
    let (b_lat, b_lon, b_alt) = geo(150.0, 2200.0, 300.0);
    let (t_lat, t_lon, t_alt) = geo(150.0, 2400.0, 0.0);
    let body = json!({"items": [
        {"kind":"waypoint","lat_deg":a_lat,"lon_deg":a_lon,"alt_msl_m":a_alt},
        {"kind":"waypoint","lat_deg":b_lat,"lon_deg":b_lon,"alt_msl_m":b_alt},
        {"kind":"land","lat_deg":t_lat,"lon_deg":t_lon,"alt_msl_m":t_alt,"approach_course_deg":80.0},
    ]})
    .to_string();
    let (status, reply) = http(
        addr,
        "POST",
        "/api/commands/plan",
        Some(OPERATOR),
        Some(&body),
    )
    .await;
    assert_eq!(status, 202, "{reply}");
    let id = reply["request_id"].as_str().expect("id").to_string();
    let mut outcome = Value::Null;
    for _ in 0..100 {
        outcome = http(
            addr,
            "GET",
            &format!("/api/commands/{id}"),
            Some(VIEWER),
            None,
        )
        .await
        .1;
        if outcome["outcome"] != "in_progress" {
            break;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    assert_eq!(outcome["outcome"], "accepted", "{outcome}");
    let onboard = drone
        .query(|d| *d.drone().onboard().guidance().plan())
        .await;
    // The replica, once it has read the drone's plan back.
    tokio::time::sleep(Duration::from_millis(1500)).await;
    let replica = *station
        .running
        .shared
        .core
        .lock()
        .expect("core")
        .replica_plan();
    assert!(
        (onboard.target_ned_m - replica.target_ned_m).xy().norm() < 0.5,
        "target: drone {:?}, replica {:?}",
        onboard.target_ned_m,
        replica.target_ned_m
    );
    assert!((onboard.target_ned_m.xy() - nalgebra::Vector2::new(150.0, 2400.0)).norm() < 0.5);
    let angle = |a: f64, b: f64| stx_dynamics::rotation::wrap_pi(a - b).abs();
    assert!(
        angle(
            onboard.approach_course_rad.expect("drone approach"),
            replica.approach_course_rad.expect("replica approach")
        ) < 1e-3
    );
    // The localizer line from the waypoints, the same on both sides.
    let (l_drone, l_replica) = (onboard.localizer, replica.localizer);
    assert!(
        distance(l_drone.point_ne_m, l_replica.point_ne_m) < 0.5
            && distance(l_drone.point_ne_m, [100.0, 1200.0]) < 0.5,
        "{l_drone:?} vs {l_replica:?}"
    );
    assert!(angle(l_drone.course_rad, l_replica.course_rad) < 1e-3);
    let slope = |p: &stx_gnc::guidance::Plan| p.localizer_glide_slope.expect("a glide slope");
    assert!((slope(&onboard) - slope(&replica)).abs() < 1e-3);
    assert!((slope(&onboard) - 300.0 / 1000.0_f64.hypot(50.0)).abs() < 1e-3);
    // The page sees the line too.
    let s = state(addr).await;
    assert!(
        s["guidance"]["localizer"]["course_deg"].is_f64(),
        "{}",
        s["guidance"]
    );
}
