//! The stack as the 3-D view draws it: each body's attitude and place relative to the drone,
//! and the lines between them (the `stack` block of the `state` message).

use schemars::JsonSchema;
use serde::Serialize;

/// A body of the stack.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum StackBody {
    /// The parafoil canopy.
    Canopy,
    /// The control drone (its AHRS is the link's ATTITUDE).
    Drone,
    /// The payload capsule.
    Capsule,
    /// The transponder.
    Transponder,
}

/// Where a body's attitude comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum BodySource {
    /// Its own IMU's ATTITUDE (the drone's AHRS for the drone), heard within
    /// `BODY_MEASURED_WITHIN_S`.
    Measured,
    /// Nothing heard: hung straight down from the drone by the vehicle's rigging, level, at
    /// the drone's heading.
    Rigging,
}

/// One body.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct StackBodyView {
    /// Which.
    pub body: StackBody,
    /// Roll, degrees.
    pub roll_deg: f64,
    /// Pitch, degrees.
    pub pitch_deg: f64,
    /// Yaw (heading of its x axis), degrees.
    pub yaw_deg: f64,
    /// Its centre of mass from the drone's, east/north/up, m.
    pub position_enu_m: [f64; 3],
    /// Its size along its own x (forward), y (right), z (down) axes, m: the canopy's chord,
    /// span and arc height plus thickness; the other bodies' boxes.
    pub size_m: [f64; 3],
    /// Where its attitude comes from.
    pub source: BodySource,
    /// Age of its attitude, s; `null` for a body placed by the rigging.
    pub age_s: Option<f64>,
}

/// A line of the rigging.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum StackLine {
    /// Right main line, canopy to drone.
    MainRight,
    /// Left main line, canopy to drone.
    MainLeft,
    /// Drone to capsule.
    Capsule,
    /// Capsule to transponder.
    Transponder,
}

/// One line between two attachment points.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct StackLineView {
    /// Which.
    pub line: StackLine,
    /// Its upper end from the drone's centre of mass, east/north/up, m.
    pub top_enu_m: [f64; 3],
    /// Its lower end, east/north/up, m.
    pub bottom_enu_m: [f64; 3],
}

/// The four bodies and their lines; present once the drone's attitude is heard.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct StackView {
    /// Canopy, drone, capsule, transponder.
    pub bodies: Vec<StackBodyView>,
    /// Right and left main lines, the capsule's and the transponder's.
    pub lines: Vec<StackLineView>,
}
