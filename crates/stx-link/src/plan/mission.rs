//! What both sides of the transfer share: the largest list, the timing, what a list's
//! element must say of itself ([`MissionItem`]: its mission type and its MISSION_ITEM_INT),
//! and the mission-protocol messages each side sends (MISSION_COUNT, MISSION_REQUEST_INT,
//! MISSION_ACK) for one mission type. The same protocol carries the guidance plan
//! (`MAV_MISSION_TYPE_MISSION`) and the keep-out fence (`MAV_MISSION_TYPE_FENCE`).

use std::fmt::Debug;
use std::time::Duration;

use mavlink::dialects::common as mc;
use mavlink::dialects::common::{MavMessage, MavMissionResult, MavMissionType};

/// An element of a list the mission protocol carries.
pub trait MissionItem: Sized + Clone + Debug + PartialEq {
    /// The list's mission type.
    const MISSION_TYPE: MavMissionType;
    /// Why a MISSION_ITEM_INT is not an element.
    type Error: std::error::Error;
    /// The MISSION_ITEM_INT carrying this element at `seq`, to `target`.
    fn to_mavlink(&self, target: (u8, u8), seq: u16) -> MavMessage;
    /// The element a MISSION_ITEM_INT carries.
    fn from_mavlink(m: &mc::MISSION_ITEM_INT_DATA) -> Result<Self, Self::Error>;
    /// The MISSION_ACK result refusing an element for `error`.
    fn refusal(error: &Self::Error) -> MavMissionResult;
    /// Whether the whole list makes sense (elements that only mean something together, like
    /// a polygon's vertices); the reason when not. Every list does unless said otherwise.
    fn check_list(_items: &[Self]) -> Result<(), String> {
        Ok(())
    }
}

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

pub(super) fn mission_ack(
    target: (u8, u8),
    result: MavMissionResult,
    mission_type: MavMissionType,
) -> MavMessage {
    MavMessage::MISSION_ACK(mc::MISSION_ACK_DATA {
        target_system: target.0,
        target_component: target.1,
        mavtype: result,
        mission_type,
        opaque_id: 0,
    })
}

pub(super) fn mission_request(
    target: (u8, u8),
    seq: u16,
    mission_type: MavMissionType,
) -> MavMessage {
    MavMessage::MISSION_REQUEST_INT(mc::MISSION_REQUEST_INT_DATA {
        seq,
        target_system: target.0,
        target_component: target.1,
        mission_type,
    })
}

pub(super) fn mission_count(
    target: (u8, u8),
    count: u16,
    mission_type: MavMissionType,
) -> MavMessage {
    MavMessage::MISSION_COUNT(mc::MISSION_COUNT_DATA {
        count,
        target_system: target.0,
        target_component: target.1,
        mission_type,
        opaque_id: 0,
    })
}
