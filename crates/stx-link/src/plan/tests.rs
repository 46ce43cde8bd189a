//! The ground and vehicle sides together: upload, download, a refused item.

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

fn pump(cl: &mut PlanClient, srv: &mut PlanServer) {
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
    srv.handle_message(Duration::ZERO, (255, 190), &mission_count((1, 1), 1));
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
