//! The command micro-protocol: the operator's [`Command`]s, their MAVLink encoding, the
//! ground side that retries until acknowledged ([`CommandClient`]) and the vehicle side that
//! decodes, de-duplicates and acknowledges ([`CommandServer`]).
//!
//! Every command is acknowledged (COMMAND_ACK) or retried and reported as failed, and the
//! operator sees which: each request carries the operator's [`RequestId`] into its final
//! [`CommandEvent`].
//!
//! ## Encoding
//! | [`Command`] | MAVLink | parameters |
//! |---|---|---|
//! | `SetMode` | COMMAND_LONG `MAV_CMD_DO_SET_MODE` | p1 = `MAV_MODE_FLAG_CUSTOM_MODE_ENABLED`, p2 = custom mode = the mode code (stage and phase bits zero: the vehicle decides those) |
//! | `HoldHeading` | COMMAND_LONG `MAV_CMD_CONDITION_YAW` | p1 = heading deg, p2 = 0 (default rate), p3 = 0 (shortest way), p4 = 0 (absolute) |
//! | `HoldCourse` | COMMAND_LONG `MAV_CMD_GUIDED_CHANGE_HEADING` | p1 = `HEADING_TYPE_COURSE_OVER_GROUND`, p2 = course deg, p3 = 0 (default rate) |
//! | `SetLandingTarget` | COMMAND_INT `MAV_CMD_NAV_LAND`, `MAV_FRAME_GLOBAL` | p4 = approach heading deg, NaN = into the wind (the vehicle's default yaw mode); x/y degE7, z m MSL |
//! | `SetLocalizer` | COMMAND_INT `MAV_CMD_DO_REPOSITION`, `MAV_FRAME_GLOBAL` | p1 = −1 (default speed), p2 = 0, p3 = glide-slope angle deg or NaN (p3 is the loiter radius, meaningless for a parafoil: documented re-use), p4 = course of the localizer line in **rad** (DO_REPOSITION's yaw unit), x/y = a point on the line, z = NaN (no altitude change) |
//! | `Cutdown` | COMMAND_LONG `MAV_CMD_DO_FLIGHTTERMINATION` | p1 = 1 |
//! | `RequestMessage` | COMMAND_LONG `MAV_CMD_REQUEST_MESSAGE` | p1 = message id |
//! | `SetMessageInterval` | COMMAND_LONG `MAV_CMD_SET_MESSAGE_INTERVAL` | p1 = message id, p2 = interval µs (−1 stop, 0 default) |
//! | `SetSurfaceWind` | COMMAND_LONG `MAV_CMD_USER_1` | p1 = speed m/s (0…60), p2 = direction the wind blows from, degrees true, p3 = age of the measurement when sent, s (0…3600; guidance ignores a surface wind older than 120 s, so the station withdraws one by sending it 3600 s old): the common dialect has no message for a wind measured on the ground, and USER_1 is the range it leaves to vehicle-specific commands |
//!
//! COMMAND_LONG retries carry an incremented `confirmation`; COMMAND_INT has no such field, so
//! its retries are identical copies, which the vehicle recognises by content within
//! [`CommandServer::dedup_window`].
//!
//! A request for AUTOPILOT_VERSION (`MAV_CMD_REQUEST_MESSAGE` with p1 = 148, or
//! `MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES`) never reaches the command server: the vehicle
//! endpoint answers it itself (`endpoint/identity.rs`), since what the link implements is the
//! link's to say.
//!
//! ## Files
//! - `encoding.rs`: [`Command`], [`CommandResult`], [`CommandDecodeError`] and the mapping
//!   above.
//! - `client.rs`: the ground side, [`CommandClient`], with its [`CommandConfig`] and
//!   [`CommandEvent`]s.
//! - `server.rs`: the vehicle side, [`CommandServer`], handing out [`IncomingCommand`]s.

mod client;
mod encoding;
mod server;

pub use client::{
    CommandClient, CommandConfig, CommandEvent, CommandOutcome, CommandSendError, RequestId,
};
pub use encoding::{
    Command, CommandDecodeError, CommandResult, SURFACE_WIND_MAX_AGE_S, SURFACE_WIND_MAX_MPS,
};
pub use server::{CommandServer, CommandServerStats, IncomingCommand, IncomingId};
