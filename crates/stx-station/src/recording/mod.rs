//! What the station records of a flight, and under which MCAP topics: the one place a
//! recording's layout is defined, so the station, `stx import` (tlogs), `stx export` and
//! replay agree on it. Pure: it turns the station's inputs and outputs into channel specs
//! and JSON payloads; the file thread that writes them is stx-record's `Recorder`, started by
//! the daemon.
//!
//! Topics (every channel JSON with a JSON Schema; times are MCAP log times, ns since the Unix
//! epoch):
//! - [`FRAMES`]: the link's bytes, both ways, per radio (`stx.MavlinkFrame`). Received
//!   entries are what the radio delivered — one UDP datagram (a MAVLink frame, or garbage a
//!   stranger sent) or one read of a stream — so a replay meets exactly what the station met;
//!   sent entries are one frame each.
//! - `/telemetry/<MAVLINK_MESSAGE>` ([`telemetry_topic`]): each decoded telemetry message, as
//!   stx-link's typed telemetry (`stx.telemetry.<MAVLINK_MESSAGE>`).
//! - [`VEHICLE_GPS`] (`foxglove.LocationFix`, the drone's GPS with its accuracy) and
//!   [`VEHICLE_ATTITUDE`] (`foxglove.FrameTransform`, body in the local NED frame): for
//!   Foxglove's map and 3-D panels.
//! - [`STATE`]: the station's `state` message at 1 Hz (link, vehicle, estimate, guidance phase
//!   and pattern, prediction, mission, the recording itself) — what the dashboard showed.
//! - [`ESTIMATE_POSITION`], [`PREDICTED_LANDING`] (`foxglove.LocationFix`): the station's
//!   estimate and predicted landing, with covariance, for the map.
//! - [`EVENTS`] (`stx.EventMsg`) and [`LOG`] (`foxglove.Log`): the event log.
//! - [`COMMANDS`] (who asked for what, when) and [`COMMAND_RESULTS`] (what became of it).
//! - [`PARAMS`]: the drone's parameter table each time it changes.
//! - [`CONFIG`]: the station's configuration at start, without secrets (token names and roles
//!   only, never a token or the signing key).

pub mod settings;
pub mod station;
pub mod summary;
pub mod telemetry;
pub mod tlog;

/// The link's raw bytes, both directions.
pub const FRAMES: &str = "/mavlink/frames";
/// Prefix of the decoded telemetry topics.
pub const TELEMETRY_PREFIX: &str = "/telemetry/";
/// The drone's GPS position (`foxglove.LocationFix`).
pub const VEHICLE_GPS: &str = "/vehicle/gps";
/// The drone's attitude (`foxglove.FrameTransform`, parent `ned`, child `body`).
pub const VEHICLE_ATTITUDE: &str = "/vehicle/attitude";
/// The station's `state` messages.
pub const STATE: &str = "/station/state";
/// The station's estimate of the position (`foxglove.LocationFix`).
pub const ESTIMATE_POSITION: &str = "/station/estimate/position";
/// The station's predicted landing point (`foxglove.LocationFix`).
pub const PREDICTED_LANDING: &str = "/station/prediction/landing";
/// The station's events.
pub const EVENTS: &str = "/station/events";
/// The same events for Foxglove's log panel (`foxglove.Log`).
pub const LOG: &str = "/log";
/// Operators' requests: who asked for what.
pub const COMMANDS: &str = "/station/commands";
/// What became of each request.
pub const COMMAND_RESULTS: &str = "/station/command_results";
/// The drone's parameter table.
pub const PARAMS: &str = "/station/params";
/// The station's configuration, without secrets.
pub const CONFIG: &str = "/station/config";

/// The topic of a decoded telemetry message, by its MAVLink name (`GLOBAL_POSITION_INT` →
/// `/telemetry/GLOBAL_POSITION_INT`).
pub fn telemetry_topic(mavlink_name: &str) -> String {
    format!("{TELEMETRY_PREFIX}{mavlink_name}")
}
