//! What the dashboard sends (`API.md`): the bodies of the command endpoints and the
//! WebSocket's client messages. Checked by serde on arrival (unknown fields refused, the
//! reason names the field); [`crate::http`] turns them into the core's requests.

use schemars::JsonSchema;
use serde::Deserialize;
use stx_gnc::mission::FlightMode;

/// `POST /api/commands/mode`.
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ModeBody {
    /// The mode to fly.
    pub mode: FlightMode,
}

/// `POST /api/commands/heading`.
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct HeadingBody {
    /// Heading to hold, degrees from north.
    pub heading_deg: f64,
}

/// `POST /api/surface_wind`: the operator's reading of the wind at the target.
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SurfaceWindBody {
    /// Speed, m/s (0–60).
    pub speed_mps: f64,
    /// Where the wind blows from, degrees true.
    pub from_deg: f64,
}

/// `POST /api/commands/course`.
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CourseBody {
    /// Course over the ground to hold, degrees from north.
    pub course_deg: f64,
}

/// `POST /api/commands/localizer`.
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LocalizerBody {
    /// Latitude of the line's point, degrees.
    pub lat_deg: f64,
    /// Longitude of the line's point, degrees.
    pub lon_deg: f64,
    /// The line's course, degrees from north.
    pub course_deg: f64,
    /// Glide slope (sink over ground speed) down the line to its point; absent or `null`: none.
    #[serde(default)]
    pub glide_slope: Option<f64>,
}

/// `POST /api/commands/target`.
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TargetBody {
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Longitude, degrees.
    pub lon_deg: f64,
    /// Altitude above mean sea level of the touchdown point, m.
    pub alt_msl_m: f64,
    /// Final-approach course, degrees from north; absent or `null`: into the wind.
    #[serde(default)]
    pub approach_course_deg: Option<f64>,
}

/// A plan item as the API spells it (`approach_course_deg`, like the target endpoint).
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum PlanItemBody {
    /// A point to fly over.
    Waypoint {
        /// Latitude, degrees.
        lat_deg: f64,
        /// Longitude, degrees.
        lon_deg: f64,
        /// Altitude above mean sea level, m.
        alt_msl_m: f64,
    },
    /// The landing point (the target).
    Land {
        /// Latitude, degrees.
        lat_deg: f64,
        /// Longitude, degrees.
        lon_deg: f64,
        /// Altitude above mean sea level, m.
        alt_msl_m: f64,
        /// Final-approach course, degrees from north; absent or `null`: into the wind.
        #[serde(default)]
        approach_course_deg: Option<f64>,
    },
}

/// `POST /api/commands/plan`.
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PlanBody {
    /// Waypoints and the land item, at most 512.
    pub items: Vec<PlanItemBody>,
}

/// `POST /api/params/{name}`.
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ParamBody {
    /// The new value.
    pub value: f64,
}

/// `POST /api/cutdown/confirm`.
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ConfirmBody {
    /// The id `POST /api/cutdown/arm` answered.
    pub arm_id: String,
}

/// A message from the page on the WebSocket.
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ClientMessage {
    /// Joystick sticks, operator only, sent at a steady rate (10 Hz) while the dead-man is
    /// held; each in −1…1 (`y` drives the main line, `z` the symmetric brake). The station
    /// stops uplinking them 0.5 s after the last one.
    Manual {
        /// Left stick, left/right (forwarded; the dashboard sends 0).
        #[serde(default)]
        x: f64,
        /// Right stick, left/right: the main line.
        #[serde(default)]
        y: f64,
        /// Throttle: the symmetric brake.
        #[serde(default)]
        z: f64,
        /// Rudder (forwarded; the dashboard sends 0).
        #[serde(default)]
        r: f64,
        /// The gamepad's buttons, a bitmask.
        #[serde(default)]
        buttons: u32,
    },
    /// The dead-man was let go or the page lost focus: stop the sticks now (operator only).
    ManualRelease,
    /// Answered with `pong`.
    Ping,
    /// The page has handled a `state` (or a frame it could not read, which may have been one).
    /// From a page's first, the station sends it a new state only while fewer than two are
    /// unacknowledged (and once every 2 s regardless), so that a busy page is sent the newest
    /// state, not a backlog of old ones queued in the network's buffers. Any role.
    StateAck,
    /// From a public relay (`stx relay`) on this socket: the pages it serves, its own and those
    /// of the relays below it, for the station's sharing panel. Sent when the figure changes
    /// (at most once a second) and every 10 s. Any role; a page never sends it.
    RelayViewers {
        /// Pages served through the relay.
        viewers: u32,
    },
}

/// `POST /api/replay` (only while replaying): any of pause/play, speed and position; what is
/// left out stays as it is.
#[derive(Debug, Clone, Default, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ReplayBody {
    /// Pause (`true`) or play (`false`).
    pub paused: Option<bool>,
    /// × real time, 0.25–64.
    pub speed: Option<f64>,
    /// Jump to this many ms after the recording's start.
    pub position_ms: Option<i64>,
}
