//! The wind at the target, from the simulated world's ground anemometer (NMEA MWV over UDP) or
//! an operator, through the station to the drone's guidance.

use crate::common;

use std::time::Duration;

use common::*;
use serde_json::{Value, json};
use stx_sim::drone::config::MissionConfig;

fn rehearsal() -> MissionConfig {
    MissionConfig::builtin("rehearsal").expect("built-in rehearsal")
}

async fn surface_wind(addr: std::net::SocketAddr) -> Value {
    http(addr, "GET", "/api/state", Some(VIEWER), None).await.1["surface_wind"].clone()
}

/// Where a wind of `speed` from `from_deg` sends the air (north, east), m/s.
fn air(speed: f64, from_deg: f64) -> [f64; 2] {
    let r = from_deg.to_radians();
    [-speed * r.cos(), -speed * r.sin()]
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_ground_anemometers_wind_reaches_the_drones_guidance_as_the_station_shows_it() {
    // A free loopback port for the anemometer.
    let port = std::net::UdpSocket::bind("127.0.0.1:0")
        .and_then(|s| s.local_addr())
        .expect("a port")
        .port();
    let station = start_station(config(|c| {
        c.surface_wind.anemometer = Some(format!("udpin:127.0.0.1:{port}"));
    }))
    .await;
    let addr = station.http();
    let before = surface_wind(addr).await;
    assert!(before["wind"].is_null(), "{before}");
    assert_eq!(before["drone"], "none");
    assert_eq!(before["anemometer"]["sentences"], 0);
    // A stranger's noise on the anemometer's port: refused, counted, nothing else.
    let noise = tokio::net::UdpSocket::bind("127.0.0.1:0")
        .await
        .expect("socket");
    let to = format!("127.0.0.1:{port}");
    for bytes in [
        &b"$WIMWV,270.0,T,3.0,M,A*00\r\n"[..],
        &b"\xff\xfe garbage"[..],
        &b"$WIMWV,999.0,T,3.0,M,A\r\n"[..],
    ] {
        noise.send_to(bytes, &to).await.expect("sent");
    }
    let mut refused = Value::Null;
    for _ in 0..50 {
        refused = surface_wind(addr).await;
        if refused["anemometer"]["rejected"].as_u64() >= Some(2) {
            break;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    assert_eq!(refused["anemometer"]["rejected"], 2, "{refused}");
    assert!(refused["wind"].is_null(), "{refused}");

    let link = station.running.link_local.expect("link");
    let mission = rehearsal();
    let drone = sim_drone_with(link, &mission, 4.0, |o| {
        o.anemometer_to = Some(to.parse().expect("address"));
    })
    .await;
    let mut held = Value::Null;
    for _ in 0..300 {
        let v = surface_wind(addr).await;
        if v["drone"] == "held" && v["wind"]["source"] == "anemometer" {
            held = v;
            break;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    assert!(
        held.is_object(),
        "the drone never held the anemometer's wind"
    );
    assert!(
        held["anemometer"]["sentences"].as_u64() >= Some(1),
        "{held}"
    );
    // What the drone's guidance holds is what the station says it sent (to the f32 of
    // COMMAND_LONG). A newer uplink may land between the two reads: read both again then.
    let mut pair = None;
    for _ in 0..20 {
        let copy = surface_wind(addr).await["held"].clone();
        let sent = air(
            copy["speed_mps"].as_f64().expect("speed"),
            copy["from_deg"].as_f64().expect("from"),
        );
        let onboard = drone
            .query(|d| d.drone().onboard().guidance().surface_wind())
            .await
            .expect("the drone's guidance holds a surface wind");
        pair = Some((sent, onboard));
        if (0..2).all(|i| (onboard.ne_mps[i] - sent[i]).abs() < 0.01) {
            break;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    let (sent, onboard) = pair.expect("read");
    assert!(
        (0..2).all(|i| (onboard.ne_mps[i] - sent[i]).abs() < 0.01),
        "onboard {:?}, the station sent {sent:?}",
        onboard.ne_mps
    );
    // And it is the rehearsal's low-level wind (2–3 m/s from about 300°): within the
    // simulated instrument's errors (5 % speed, 5° vane, 3 σ) and a 10-s mean's gusts.
    let speed = onboard.ne_mps[0].hypot(onboard.ne_mps[1]);
    let from = (-onboard.ne_mps[1])
        .atan2(-onboard.ne_mps[0])
        .to_degrees()
        .rem_euclid(360.0);
    assert!((1.3..=4.2).contains(&speed), "{speed} m/s");
    let off = ((from - 300.0 + 540.0).rem_euclid(360.0) - 180.0).abs();
    assert!(off < 30.0, "from {from:.0}°");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_operator_types_the_surface_wind_and_the_drone_takes_it() {
    let station = start_station(config(|_| {})).await;
    let addr = station.http();
    let body = |speed: f64, from: f64| json!({"speed_mps": speed, "from_deg": from}).to_string();
    let (status, _) = http(
        addr,
        "POST",
        "/api/surface_wind",
        Some(VIEWER),
        Some(&body(3.0, 90.0)),
    )
    .await;
    assert_eq!(status, 403, "viewers cannot set it");
    for bad in [
        body(-1.0, 90.0),
        body(61.0, 90.0),
        body(3.0, 400.0),
        "{\"speed_mps\": 3.0}".to_string(),
        "{\"speed_mps\": 3.0, \"from_deg\": 9, \"x\": 1}".to_string(),
        "not json".to_string(),
    ] {
        let (status, reply) = http(
            addr,
            "POST",
            "/api/surface_wind",
            Some(OPERATOR),
            Some(&bad),
        )
        .await;
        assert_eq!(status, 400, "{bad}: {reply}");
        assert!(
            reply["reason"].as_str().is_some_and(|r| !r.is_empty()),
            "{reply}"
        );
    }
    let (status, reply) = http(
        addr,
        "POST",
        "/api/surface_wind",
        Some(OPERATOR),
        Some(&body(4.0, 200.0)),
    )
    .await;
    assert_eq!(status, 200, "{reply}");
    assert_eq!(reply["wind"]["source"], "operator", "{reply}");
    // Nobody to send it to yet.
    assert_eq!(reply["drone"], "none", "{reply}");
    let link = station.running.link_local.expect("link");
    let drone = sim_drone(link, &rehearsal(), 4.0).await;
    let mut held = Value::Null;
    for _ in 0..200 {
        let v = surface_wind(addr).await;
        if v["drone"] == "held" {
            held = v;
            break;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    assert_eq!(held["held"]["source"], "operator", "{held}");
    let onboard = drone
        .query(|d| d.drone().onboard().guidance().surface_wind())
        .await
        .expect("held onboard");
    let want = air(4.0, 200.0);
    assert!(
        (onboard.ne_mps[0] - want[0]).abs() < 0.01 && (onboard.ne_mps[1] - want[1]).abs() < 0.01,
        "{:?} {want:?}",
        onboard.ne_mps
    );
    let (status, reply) = http(addr, "DELETE", "/api/surface_wind", Some(OPERATOR), None).await;
    assert_eq!(status, 200);
    assert!(
        reply["wind"].is_null() && reply["operator"].is_null(),
        "{reply}"
    );
    // Withdrawn from the drone too: its guidance holds it as too old to use.
    let mut withdrawn = None;
    for _ in 0..100 {
        let (held, now) = drone
            .query(|d| {
                let d = d.drone();
                (d.onboard().guidance().surface_wind(), d.time_s())
            })
            .await;
        if held.is_some_and(|w| now - w.time_s > 120.0) {
            withdrawn = Some(now);
            break;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    assert!(
        withdrawn.is_some(),
        "the drone never let the withdrawn wind go"
    );
    // The station says so once the drone's answer is in.
    let mut after = Value::Null;
    for _ in 0..50 {
        after = surface_wind(addr).await;
        if after["held"].is_null() && after["drone"] == "none" {
            break;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    assert!(
        after["held"].is_null() && after["drone"] == "none",
        "{after}"
    );
}
