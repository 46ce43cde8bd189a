//! Upload and download of the guidance plan (landing target and localizer points) with the
//! MAVLink mission protocol, so the station can send the plan the drone flies and read back
//! what it actually holds.
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
//! ## Files
//! - `item.rs`: [`PlanItem`] and its MISSION_ITEM_INT.
//! - `mission.rs`: [`PlanConfig`], [`MAX_PLAN_ITEMS`] and the messages both sides send.
//! - `client.rs`: the ground side, [`PlanClient`], reporting [`PlanEvent`]s.
//! - `server.rs`: the vehicle side, [`PlanServer`].

mod client;
mod item;
mod mission;
mod server;

pub use client::{PlanClient, PlanEvent, PlanRequestError};
pub use item::{PlanItem, PlanItemError};
pub use mission::{MAX_PLAN_ITEMS, PlanConfig};
pub use server::{PlanServer, PlanServerStats};

#[cfg(test)]
mod tests;
