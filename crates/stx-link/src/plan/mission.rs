//! What both sides of the transfer share: the largest plan, the timing, and the
//! mission-protocol messages each sends (MISSION_COUNT, MISSION_REQUEST_INT, MISSION_ACK),
//! all of mission type `MAV_MISSION_TYPE_MISSION`.

use std::time::Duration;

use mavlink::dialects::common as mc;
use mavlink::dialects::common::{MavMessage, MavMissionResult};

/// Largest plan accepted, items.
pub const MAX_PLAN_ITEMS: u16 = 512;

/// Timing of either side.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PlanConfig {
    /// Quiet time before re-sending.
    pub timeout: Duration,
    /// Re-sends without progress before giving up.
    pub retries: u8,
}

impl Default for PlanConfig {
    fn default() -> Self {
        Self {
            timeout: Duration::from_millis(1500),
            retries: 4,
        }
    }
}

pub(super) fn mission_ack(target: (u8, u8), result: MavMissionResult) -> MavMessage {
    MavMessage::MISSION_ACK(mc::MISSION_ACK_DATA {
        target_system: target.0,
        target_component: target.1,
        mavtype: result,
        mission_type: mc::MavMissionType::MAV_MISSION_TYPE_MISSION,
        opaque_id: 0,
    })
}

pub(super) fn mission_request(target: (u8, u8), seq: u16) -> MavMessage {
    MavMessage::MISSION_REQUEST_INT(mc::MISSION_REQUEST_INT_DATA {
        seq,
        target_system: target.0,
        target_component: target.1,
        mission_type: mc::MavMissionType::MAV_MISSION_TYPE_MISSION,
    })
}

pub(super) fn mission_count(target: (u8, u8), count: u16) -> MavMessage {
    MavMessage::MISSION_COUNT(mc::MISSION_COUNT_DATA {
        count,
        target_system: target.0,
        target_component: target.1,
        mission_type: mc::MavMissionType::MAV_MISSION_TYPE_MISSION,
        opaque_id: 0,
    })
}

pub(super) fn is_mission(t: mc::MavMissionType) -> bool {
    t == mc::MavMissionType::MAV_MISSION_TYPE_MISSION
}
