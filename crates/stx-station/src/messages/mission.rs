//! What the station says about the mission as a whole: where the drone came down and how far
//! from its target (worked out once, by the station, and shown as it is on every page), and
//! where the guidance replica parts from the drone.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::LatLonAlt;

/// The landing, as the station measured it: one figure for every page, the log, the recording
/// and its replay.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct LandingView {
    /// The drone's clock at the first GPS fix on the ground, s (the mission clock).
    pub time_s: f64,
    /// Which body the position is of: `drone` (its GPS receiver is on the drone; the capsule
    /// and the transponder hang a few metres below it).
    pub body: String,
    /// Where: the drone's GPS receiver at its first 3-D fix after it reported `landed`.
    pub position: LatLonAlt,
    /// The landing target the miss is measured from: the drone's, as the station holds it
    /// (`null`: none known).
    pub target: Option<LatLonAlt>,
    /// Horizontal distance from `target`, m (`null` without a target).
    pub miss_m: Option<f64>,
}

/// The guidance replica and the drone disagree (or did, a few seconds ago).
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct DisagreementView {
    /// What they disagree on.
    #[schemars(extend("enum" = ["phase"]))]
    pub what: String,
    /// The replica's value.
    pub replica: String,
    /// The drone's.
    pub drone: String,
    /// The mission clock when it began, s.
    pub since_s: f64,
    /// How long it has lasted (or lasted), s.
    pub for_s: f64,
    /// It is over.
    pub resolved: bool,
    /// It ended with the replica taking the drone's value.
    pub adopted: bool,
}
