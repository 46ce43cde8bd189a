//! The keep-out zones reach the real simulated drone as its MAVLink fence: the configured
//! zones when it is heard, an operator's edit when it is made; the drone's own guidance flies
//! them and the station says so.

use crate::common;

use std::time::Duration;

use common::*;
use serde_json::{Value, json};
use stx_sim::drone::config::MissionConfig;

fn rehearsal() -> MissionConfig {
    MissionConfig::builtin("rehearsal").expect("built-in rehearsal")
}

/// The zones the drone's guidance flies: each as its boundary's (latitude, longitude)
/// vertices, degrees.
async fn drone_zones(drone: &SimDrone) -> Vec<Vec<[f64; 2]>> {
    drone
        .query(|d| {
            let onboard = d.drone().onboard();
            let frame = onboard.frame();
            onboard
                .guidance()
                .keep_out()
                .zones
                .iter()
                .map(|z| z.boundary_lat_lon(frame))
                .collect()
        })
        .await
}

/// Waits up to `secs` for the drone to fly `n` zones; what it flies last.
async fn until_drone_has(drone: &SimDrone, n: usize, secs: f64) -> Vec<Vec<[f64; 2]>> {
    let deadline = tokio::time::Instant::now() + Duration::from_secs_f64(secs);
    loop {
        let zones = drone_zones(drone).await;
        if zones.len() == n || tokio::time::Instant::now() > deadline {
            return zones;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

async fn fence_state(station: &Station) -> Value {
    let (status, body) = http(station.http(), "GET", "/api/keep-out", Some(VIEWER), None).await;
    assert_eq!(status, 200, "{body}");
    body["fence"].clone()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_drone_flies_the_configured_zones_and_an_operators_edit() {
    // A copy of the shipped zones: the edit below is written to the configured file.
    let dir = std::env::temp_dir().join(format!("stx-fence-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file = dir.join("zones.geojson");
    let shipped = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../config/keep-out/sample.geojson");
    std::fs::copy(&shipped, &file).expect("copy of the sample zones");
    let station = start_station(config(|c| c.keep_out = Some(file.clone()))).await;
    let (_, keep_out) = http(station.http(), "GET", "/api/keep-out", Some(VIEWER), None).await;
    let areas = keep_out["areas"].as_u64().expect("areas") as usize;
    assert!(areas >= 2, "the sample has zones: {keep_out}");
    assert_eq!(keep_out["fence"]["state"], "waiting", "no drone yet");

    let drone = sim_drone(station.running.link_local.expect("link"), &rehearsal(), 4.0).await;
    let zones = until_drone_has(&drone, areas, 20.0).await;
    assert_eq!(zones.len(), areas, "the drone flies the configured zones");
    let mut held = Value::Null;
    for _ in 0..50 {
        held = fence_state(&station).await;
        if held["state"] == "held" {
            break;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    assert_eq!(held["state"], "held", "{held}");

    // An operator replaces them with one triangle north-east of the origin.
    let o = config(|_| {}).origin;
    let corner = |dn: f64, de: f64| {
        let (lat, lon, _) = o.to_geodetic(&nalgebra::Vector3::new(dn, de, 0.0));
        [lat, lon]
    };
    let triangle = [
        corner(400.0, 400.0),
        corner(400.0, 600.0),
        corner(600.0, 500.0),
    ];
    let ring: Vec<Value> = triangle
        .iter()
        .chain(std::iter::once(&triangle[0]))
        .map(|[lat, lon]| json!([lon, lat]))
        .collect();
    let body = json!({"type": "FeatureCollection", "features": [{
        "type": "Feature", "properties": {"name": "Test field"},
        "geometry": {"type": "Polygon", "coordinates": [ring]}
    }]});
    let (status, answer) = http(
        station.http(),
        "PUT",
        "/api/keep-out",
        Some(OPERATOR),
        Some(&body.to_string()),
    )
    .await;
    assert_eq!(status, 200, "{answer}");
    let zones = until_drone_has(&drone, 1, 20.0).await;
    assert_eq!(zones.len(), 1, "the drone flies the edit: {zones:?}");
    // The fence carries degrees in 1e-7 steps (about a centimetre): the same vertices.
    let flown = &zones[0];
    assert_eq!(flown.len(), 3, "{flown:?}");
    for (a, b) in flown.iter().zip(&triangle) {
        assert!(
            (a[0] - b[0]).abs() < 2e-7 && (a[1] - b[1]).abs() < 2e-7,
            "vertex {a:?} vs {b:?}"
        );
    }
    let texts = event_texts(station.http()).await;
    assert!(
        texts
            .iter()
            .any(|t| t.contains("drone holds the keep-out zones (1 areas")),
        "{texts:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
