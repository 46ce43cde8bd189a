//! The drone's plan as it told it in a recording. A live station reads the drone's plan with
//! the MAVLink mission download (it asks, the drone answers MISSION_COUNT and one
//! MISSION_ITEM_INT per item); a re-run has no drone to ask, but the recorded link bytes hold
//! the drone's answers to the live station. This listens for them in the received bytes and
//! hands over each plan the drone finished telling, at the moment it finished — when the live
//! station adopted it — so the re-run's replica flies the drone's exact plan (degE7), not the
//! target worked out from NAV_CONTROLLER_OUTPUT's whole degrees and metres.
//!
//! Only the drone's frames (its system id) of the guidance plan's mission type count; an
//! answer cut short (the live download failed) is dropped by the next MISSION_COUNT.

use std::time::Duration;

use stx_link::MavMessage;
use stx_link::frame::{DecoderPolicy, FrameDecoder};
use stx_link::plan::{MAX_PLAN_ITEMS, MissionItem, PlanItem};

/// Listens to the drone's side of plan downloads.
#[derive(Debug)]
pub struct PlanListener {
    decoder: FrameDecoder,
    vehicle_system: u8,
    /// Items the drone announced, while it is telling them.
    expected: Option<u16>,
    items: Vec<PlanItem>,
}

impl PlanListener {
    /// Listens to the drone of system `vehicle_system`.
    pub fn new(vehicle_system: u8) -> Self {
        Self {
            decoder: FrameDecoder::new(DecoderPolicy::default()),
            vehicle_system,
            expected: None,
            items: Vec::new(),
        }
    }

    /// One datagram the station received; the plan the drone finished telling in it, if any.
    pub fn received(&mut self, datagram: &[u8]) -> Option<Vec<PlanItem>> {
        self.decoder.push(datagram);
        // A datagram holds whole frames: what it leaves unfinished is dropped, as the
        // station's link drops it.
        self.decoder.finish();
        let mut told = None;
        while let Some(frame) = self.decoder.poll(Duration::ZERO) {
            let Ok(frame) = frame else { continue };
            if frame.header.system_id != self.vehicle_system {
                continue;
            }
            if let Some(plan) = self.message(&frame.message) {
                told = Some(plan);
            }
        }
        told
    }

    fn message(&mut self, message: &MavMessage) -> Option<Vec<PlanItem>> {
        match message {
            MavMessage::MISSION_COUNT(c) if c.mission_type == PlanItem::MISSION_TYPE => {
                self.items.clear();
                self.expected = None;
                if c.count == 0 {
                    return Some(Vec::new());
                }
                if c.count <= MAX_PLAN_ITEMS {
                    self.expected = Some(c.count);
                }
                None
            }
            MavMessage::MISSION_ITEM_INT(m) if m.mission_type == PlanItem::MISSION_TYPE => {
                let expected = self.expected?;
                // A repeat (the station asked again) or one out of turn.
                if usize::from(m.seq) != self.items.len() {
                    return None;
                }
                match PlanItem::from_mavlink(m) {
                    Ok(item) => self.items.push(item),
                    // The station refused it, and so adopted nothing.
                    Err(_) => {
                        self.expected = None;
                        self.items.clear();
                        return None;
                    }
                }
                if self.items.len() < usize::from(expected) {
                    return None;
                }
                self.expected = None;
                Some(std::mem::take(&mut self.items))
            }
            _ => None,
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use stx_link::frame::FrameEncoder;
    use stx_link::plan::{PlanClient, PlanConfig, PlanServer};

    use super::*;

    const TARGET: PlanItem = PlanItem::Land {
        lat_deg: 38.536_003_1,
        lon_deg: -7.888_894_8,
        alt_msl_m: 245.0,
        approach_heading_deg: None,
    };
    const WAYPOINT: PlanItem = PlanItem::Waypoint {
        lat_deg: 38.53,
        lon_deg: -7.89,
        alt_msl_m: 600.0,
    };

    /// The datagrams a drone of `system` holding `plan` sends while a station downloads it
    /// (stx-link's own client and server talking), one frame each.
    pub(crate) fn drone_answers(system: u8, plan: Vec<PlanItem>) -> Vec<Vec<u8>> {
        let now = Duration::ZERO;
        let mut drone = PlanServer::new(system, 1, PlanConfig::default());
        drone.set_plan(plan);
        let mut station = PlanClient::new(PlanConfig::default());
        station.download(now, (system, 1)).expect("download starts");
        let mut encoder = FrameEncoder::new(system, 1);
        let mut sent = Vec::new();
        for _ in 0..100 {
            let Some(ask) = station.poll_transmit() else {
                break;
            };
            drone.handle_message(now, (255, 190), &ask);
            while let Some(answer) = drone.poll_transmit() {
                let mut datagram = Vec::new();
                encoder.encode_into(now, &answer, &mut datagram);
                sent.push(datagram);
                station.handle_message(now, system, &answer);
            }
        }
        sent
    }

    #[test]
    fn the_plan_the_drone_told_is_handed_over_when_its_last_item_comes() {
        let answers = drone_answers(1, vec![WAYPOINT, TARGET]);
        assert_eq!(answers.len(), 3, "MISSION_COUNT and two MISSION_ITEM_INT");
        let mut listener = PlanListener::new(1);
        assert_eq!(listener.received(&answers[0]), None);
        assert_eq!(listener.received(&answers[1]), None);
        assert_eq!(listener.received(&answers[1]), None, "a repeat");
        let told = listener.received(&answers[2]);
        assert_eq!(
            told,
            Some(vec![WAYPOINT, TARGET]),
            "exactly as sent (degE7)"
        );
    }

    #[test]
    fn other_systems_cut_answers_and_garbage_adopt_nothing() {
        let mut listener = PlanListener::new(1);
        for datagram in drone_answers(2, vec![TARGET]) {
            assert_eq!(listener.received(&datagram), None, "another system's");
        }
        assert_eq!(listener.received(b"\xfd\x09garbage"), None);
        // A download cut short, then a new one: only the new one's items count.
        let cut = drone_answers(1, vec![WAYPOINT, TARGET]);
        listener.received(&cut[0]);
        listener.received(&cut[1]);
        let again = drone_answers(1, vec![TARGET]);
        assert_eq!(listener.received(&again[0]), None);
        assert_eq!(listener.received(&again[1]), Some(vec![TARGET]));
        let empty = drone_answers(1, Vec::new());
        assert_eq!(listener.received(&empty[0]), Some(Vec::new()), "no plan");
    }
}
