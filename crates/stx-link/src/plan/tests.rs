//! The ground and vehicle sides together: upload, download, a refused item, for the plan and
//! the fence.

use std::time::Duration;

use mavlink::dialects::common::{MavCmd, MavMessage, MavMissionResult};

use super::mission::mission_count;
use super::*;

fn plan() -> Vec<PlanItem> {
    vec![
        PlanItem::Waypoint {
            lat_deg: 41.1,
            lon_deg: -8.6,
            alt_msl_m: 300.0,
        },
        PlanItem::Waypoint {
            lat_deg: 41.2,
            lon_deg: -8.5,
            alt_msl_m: 200.0,
        },
        PlanItem::Land {
            lat_deg: 41.15,
            lon_deg: -8.55,
            alt_msl_m: 90.0,
            approach_heading_deg: Some(270.0),
        },
    ]
}

fn pump<I: MissionItem>(cl: &mut MissionClient<I>, srv: &mut MissionServer<I>) {
    loop {
        let mut moved = false;
        while let Some(m) = cl.poll_transmit() {
            srv.handle_message(Duration::ZERO, (255, 190), &m);
            moved = true;
        }
        while let Some(m) = srv.poll_transmit() {
            cl.handle_message(Duration::ZERO, 1, &m);
            moved = true;
        }
        if !moved {
            break;
        }
    }
}

#[test]
fn upload_then_download_returns_the_plan() {
    let mut cl = PlanClient::default();
    let mut srv = PlanServer::new(1, 1, PlanConfig::default());
    cl.upload(Duration::ZERO, (1, 1), plan()).expect("started");
    pump(&mut cl, &mut srv);
    assert_eq!(cl.poll_event(), Some(PlanEvent::UploadDone { items: 3 }));
    assert_eq!(srv.poll_plan().map(|p| p.len()), Some(3));
    cl.download(Duration::ZERO, (1, 1)).expect("started");
    pump(&mut cl, &mut srv);
    let Some(PlanEvent::DownloadDone { items }) = cl.poll_event() else {
        panic!("no download")
    };
    assert_eq!(items.len(), 3);
    for (a, b) in items.iter().zip(plan()) {
        let (PlanItem::Waypoint { lat_deg: x, .. } | PlanItem::Land { lat_deg: x, .. }) = *a;
        let (PlanItem::Waypoint { lat_deg: y, .. } | PlanItem::Land { lat_deg: y, .. }) = b;
        assert!((x - y).abs() < 1e-7);
    }
    assert!(matches!(items[2], PlanItem::Land { approach_heading_deg: Some(h), .. } if h == 270.0));
}

#[test]
fn unsupported_item_is_refused() {
    let mut srv = PlanServer::new(1, 1, PlanConfig::default());
    srv.handle_message(
        Duration::ZERO,
        (255, 190),
        &mission_count((1, 1), 1, PlanItem::MISSION_TYPE),
    );
    let _ = srv.poll_transmit();
    let MavMessage::MISSION_ITEM_INT(mut m) = plan()[0].to_mavlink((1, 1), 0) else {
        panic!()
    };
    m.command = MavCmd::MAV_CMD_NAV_TAKEOFF;
    srv.handle_message(Duration::ZERO, (255, 190), &MavMessage::MISSION_ITEM_INT(m));
    let Some(MavMessage::MISSION_ACK(a)) = srv.poll_transmit() else {
        panic!("no ack")
    };
    assert_eq!(a.mavtype, MavMissionResult::MAV_MISSION_UNSUPPORTED);
    assert_eq!(srv.stats().uploads_failed, 1);
}

fn frame() -> stx_types::geo::LocalFrame {
    stx_types::geo::LocalFrame {
        lat_deg: 41.15,
        lon_deg: -8.55,
        alt_msl_m: 90.0,
    }
}

/// Two zones 100 m apart: a square and a triangle, with a hole in the square (not sent).
fn zones() -> stx_types::keep_out::KeepOutZones {
    use stx_types::keep_out::{KeepOutZone, KeepOutZones};
    KeepOutZones {
        zones: vec![
            KeepOutZone {
                name: "pond".into(),
                rings_ne_m: vec![
                    vec![[0.0, 0.0], [50.0, 0.0], [50.0, 50.0], [0.0, 50.0]],
                    vec![[10.0, 10.0], [20.0, 10.0], [20.0, 20.0]],
                ],
            },
            KeepOutZone {
                name: "road".into(),
                rings_ne_m: vec![vec![[150.0, 0.0], [200.0, 0.0], [170.0, 30.0]]],
            },
        ],
    }
}

#[test]
fn a_fence_of_two_zones_uploads_downloads_and_comes_back_as_their_boundaries() {
    let fence = zones_to_fence(&zones(), &frame()).unwrap();
    assert_eq!(fence.len(), 7);
    assert!(fence[..4].iter().all(|v| v.vertex_count == 4));
    assert!(fence[4..].iter().all(|v| v.vertex_count == 3));
    let mut cl = FenceClient::default();
    let mut srv = FenceServer::new(1, 1, PlanConfig::default());
    cl.upload(Duration::ZERO, (1, 1), fence.clone()).unwrap();
    pump(&mut cl, &mut srv);
    assert_eq!(cl.poll_event(), Some(FenceEvent::UploadDone { items: 7 }));
    let received = srv.poll_plan().expect("a fence");
    let back = fence_to_zones(&received, &frame()).unwrap();
    assert_eq!(back.zones.len(), 2);
    assert_eq!(back.zones[1].name, "fence polygon 1");
    for (got, sent) in back.zones.iter().zip(zones().zones) {
        assert_eq!(got.rings_ne_m.len(), 1, "holes are not sent");
        for (a, b) in got.rings_ne_m[0].iter().zip(&sent.rings_ne_m[0]) {
            // degE7 is 1.1 cm of latitude.
            assert!(
                (a[0] - b[0]).abs() < 0.02 && (a[1] - b[1]).abs() < 0.02,
                "{a:?} {b:?}"
            );
        }
    }
    cl.download(Duration::ZERO, (1, 1)).unwrap();
    pump(&mut cl, &mut srv);
    let Some(FenceEvent::DownloadDone { items }) = cl.poll_event() else {
        panic!("no download")
    };
    assert_eq!(fence_polygons(&items).unwrap().len(), 2);
}

#[test]
fn the_plan_and_the_fence_servers_answer_only_their_own_mission_type() {
    let mut plan_srv = PlanServer::new(1, 1, PlanConfig::default());
    let mut cl = FenceClient::default();
    cl.upload(
        Duration::ZERO,
        (1, 1),
        zones_to_fence(&zones(), &frame()).unwrap(),
    )
    .unwrap();
    let count = cl.poll_transmit().unwrap();
    assert!(!plan_srv.handle_message(Duration::ZERO, (255, 190), &count));
    assert_eq!(plan_srv.poll_transmit(), None);
}

/// The vehicle's answer to an upload of `items` sent as they are.
fn answer_to(items: &[mavlink::dialects::common::MISSION_ITEM_INT_DATA]) -> MavMissionResult {
    let mut srv = FenceServer::new(1, 1, PlanConfig::default());
    let count = mission_count((1, 1), items.len() as u16, FenceItem::MISSION_TYPE);
    srv.handle_message(Duration::ZERO, (255, 190), &count);
    for m in items {
        while srv.poll_transmit().is_some() {}
        srv.handle_message(
            Duration::ZERO,
            (255, 190),
            &MavMessage::MISSION_ITEM_INT(m.clone()),
        );
    }
    let mut last = None;
    while let Some(m) = srv.poll_transmit() {
        last = Some(m);
    }
    let Some(MavMessage::MISSION_ACK(a)) = last else {
        panic!("no ack: {last:?}")
    };
    assert_eq!(srv.poll_plan(), None);
    assert_eq!(srv.stats().uploads_failed, 1);
    a.mavtype
}

fn vertex_items(counts: &[u16]) -> Vec<mavlink::dialects::common::MISSION_ITEM_INT_DATA> {
    counts
        .iter()
        .enumerate()
        .map(|(seq, &vertex_count)| {
            let v = FenceItem {
                vertex_count,
                lat_deg: 41.15 + seq as f64 * 1e-4,
                lon_deg: -8.55,
            };
            let MavMessage::MISSION_ITEM_INT(m) = v.to_mavlink((1, 1), seq as u16) else {
                panic!()
            };
            m
        })
        .collect()
}

#[test]
fn malformed_fences_are_refused_with_the_reason_s_mission_result() {
    // Counts that do not add up: the fence ends inside a polygon, or a polygon's vertex
    // declares another count.
    assert_eq!(
        answer_to(&vertex_items(&[4, 4, 4])),
        MavMissionResult::MAV_MISSION_INVALID
    );
    assert_eq!(
        answer_to(&vertex_items(&[3, 3, 4, 4])),
        MavMissionResult::MAV_MISSION_INVALID
    );
    // A polygon of two vertices.
    assert_eq!(
        answer_to(&vertex_items(&[2, 2])[..1]),
        MavMissionResult::MAV_MISSION_INVALID_PARAM1
    );
    // An inclusion polygon, a plan's waypoint.
    let mut items = vertex_items(&[3, 3, 3]);
    items[1].command = MavCmd::MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION;
    assert_eq!(
        answer_to(&items[..2]),
        MavMissionResult::MAV_MISSION_UNSUPPORTED
    );
    items[0].command = MavCmd::MAV_CMD_NAV_WAYPOINT;
    assert_eq!(
        answer_to(&items[..1]),
        MavMissionResult::MAV_MISSION_UNSUPPORTED
    );
    // The list check says why.
    let err = fence_polygons(&[FenceItem {
        vertex_count: 4,
        lat_deg: 0.0,
        lon_deg: 0.0,
    }])
    .unwrap_err();
    assert!(err.to_string().contains("ends before them"), "{err}");
}
