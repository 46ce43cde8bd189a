//! Upload and download of the guidance plan (landing target and localizer points) and of the
//! keep-out fence with the MAVLink mission protocol, so the station can send the plan the
//! drone flies and the zones it keeps out of, and read back what it actually holds.
//!
//! Upload: station MISSION_COUNT → drone MISSION_REQUEST_INT(seq) → station
//! MISSION_ITEM_INT(seq) … → drone MISSION_ACK. Download: station MISSION_REQUEST_LIST →
//! drone MISSION_COUNT → station MISSION_REQUEST_INT(seq) → drone MISSION_ITEM_INT(seq) … →
//! station MISSION_ACK. Both sides re-send their last message after a quiet timeout and give up
//! after a number of retries; progress resets the retry count.
//!
//! Items: [`PlanItem::Waypoint`] ↔ `MAV_CMD_NAV_WAYPOINT`, [`PlanItem::Land`] ↔
//! `MAV_CMD_NAV_LAND` (param4 = approach heading in degrees, NaN = into the wind), both in
//! `MAV_FRAME_GLOBAL` (altitude MSL), latitude/longitude in degE7.
//!
//! The fence (`MAV_MISSION_TYPE_FENCE`) travels the same way, its items exclusion polygons'
//! vertices (`fence.rs`).
//!
//! ## Files
//! - `item.rs`: [`PlanItem`] and its MISSION_ITEM_INT.
//! - `fence.rs`: [`FenceItem`], and the keep-out zones as a fence and back.
//! - `mission.rs`: [`PlanConfig`], [`MAX_PLAN_ITEMS`], what an item of a list must say of
//!   itself ([`MissionItem`]) and the messages both sides send.
//! - `client.rs`: the ground side, [`MissionClient`] ([`PlanClient`], [`FenceClient`]),
//!   reporting [`TransferEvent`]s.
//! - `server.rs`: the vehicle side, [`MissionServer`] ([`PlanServer`], [`FenceServer`]).

mod client;
mod fence;
mod item;
mod mission;
mod server;

pub use client::{MissionClient, PlanClient, PlanEvent, PlanRequestError, TransferEvent};
pub use fence::{
    FenceClient, FenceError, FenceEvent, FenceItem, FenceItemError, FenceServer, fence_polygons,
    fence_to_zones, zones_to_fence,
};
pub use item::{PlanItem, PlanItemError};
pub use mission::{MAX_PLAN_ITEMS, MissionItem, PlanConfig};
pub use server::{MissionServer, PlanServer, PlanServerStats};

#[cfg(test)]
mod tests;
