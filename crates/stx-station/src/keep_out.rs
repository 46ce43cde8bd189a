//! The keep-out zones as the API shows them (`API.md`): the `keep_out` message (the answer of
//! `GET /api/keep-out` and `PUT /api/keep-out`, and what every page is sent when the zones
//! change), the body of `PUT /api/keep-out`, and the alarms of the `state` message when a
//! predicted landing lies in a zone. The zones themselves are GeoJSON (RFC 7946), passed
//! through as the operators wrote them; the core checks them ([`crate::core`]).

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// `PUT /api/keep-out`: every zone, as a GeoJSON FeatureCollection of Polygon and
/// MultiPolygon features, each with a non-empty `name` property. It replaces the zones.
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(transparent)]
pub struct KeepOutBody(pub serde_json::Value);

/// The keep-out zones now in force.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct KeepOutMsg {
    /// Always `keep_out`.
    #[serde(rename = "type")]
    #[schemars(extend("const" = "keep_out"))]
    pub kind: &'static str,
    /// The zones, a GeoJSON FeatureCollection (longitude, latitude in degrees); empty when
    /// there are none.
    pub zones: serde_json::Value,
    /// Areas in force (a MultiPolygon feature counts each of its polygons).
    pub areas: u32,
    /// The file they are kept in (`keep_out` of the station config); `null`: none, edits are
    /// lost at a restart.
    pub file: Option<String>,
    /// Why the configured file could not be read at start (the station then runs without
    /// its zones until an operator sets them); `null` when it was read.
    pub load_error: Option<String>,
    /// Who set them last; `null`: as read from the file.
    pub changed_by: Option<String>,
    /// Whether the drone holds them as its fence.
    pub fence: FenceView,
    /// Mission clock, s.
    pub time_s: f64,
}

/// The drone's copy of the zones in force (sent as MAVLink's fence).
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct FenceView {
    /// Where the transfer stands.
    pub state: FenceState,
    /// Why the last transfer failed; `null` after a success.
    pub last_error: Option<String>,
}

/// Where the drone's copy of the zones stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum FenceState {
    /// The station was given no zones: it leaves the drone's fence alone.
    None,
    /// To be sent when the drone is heard and the link takes it.
    Waiting,
    /// Sent; the drone has not answered yet.
    Sending,
    /// The drone acknowledged these zones.
    Held,
    /// Every try failed: the drone does not have them (until they change or it reconnects).
    Failed,
}

/// Which of the station's landing predictions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum PredictionKind {
    /// Flying the current plan.
    Planned,
    /// With the servos left neutral.
    Uncontrolled,
}

impl PredictionKind {
    /// As the log says it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Planned => "planned",
            Self::Uncontrolled => "uncontrolled",
        }
    }
}

/// A predicted landing inside a keep-out zone.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct KeepOutAlarmView {
    /// Which prediction.
    pub prediction: PredictionKind,
    /// The zone's name.
    pub zone: String,
    /// Mission time the prediction entered the zone, s.
    pub since_s: f64,
}
