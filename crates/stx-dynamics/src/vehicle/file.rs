//! The vehicle file as written: one struct per TOML table, every field with its unit in its
//! name. Nothing here is checked; [`VehicleConfig::validate`] does that.

use serde::{Deserialize, Serialize};

/// Canopy description (seed Table 3.1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CanopyConfig {
    /// Mass of canopy, lines and beam, kg.
    pub mass_kg: f64,
    /// Span b, m.
    pub span_m: f64,
    /// Chord c, m.
    pub chord_m: f64,
    /// Maximum thickness d, m.
    pub thickness_m: f64,
    /// Height of the lateral arc a at mid-span, m.
    pub arc_height_m: f64,
    /// Reference area S, m².
    pub area_m2: f64,
    /// Natural main-line length L0 of the control geometry, m.
    pub main_line_length_m: f64,
    /// Anti-twist beam length B of the control geometry, m.
    pub beam_length_m: f64,
    /// Whether the canopy feels the Munk moment `−V_rel × (M_app·V_rel)` of its apparent mass
    /// (Kirchhoff). If not given, no: the seed's model (its A.11) leaves it out.
    #[serde(default)]
    pub munk_moment: bool,
    /// Aerodynamic coefficients.
    pub aero: CanopyAeroConfig,
    /// Brake coefficients.
    pub brakes: BrakeConfig,
}

/// Canopy aerodynamic coefficients (seed Table 4.2); rate-damping terms are magnitudes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CanopyAeroConfig {
    /// Drag coefficient at zero angle of attack.
    pub cd0: f64,
    /// Drag growth with α², 1/rad².
    pub cd_alpha2: f64,
    /// Side-force slope with sideslip, 1/rad (force opposes sideslip).
    pub cy_beta: f64,
    /// Lift coefficient at zero angle of attack.
    pub cl0: f64,
    /// Lift slope, 1/rad.
    pub cl_alpha: f64,
    /// Roll damping magnitude (per non-dimensional roll rate b·p/2V).
    pub clp: f64,
    /// Pitch damping magnitude (per non-dimensional pitch rate c·q/2V).
    pub cmq: f64,
    /// Yaw damping magnitude (per non-dimensional yaw rate b·r/2V).
    pub cnr: f64,
    /// Yaw moment with sideslip, 1/rad, in the seed's sign (negative weathervanes).
    pub cn_beta: f64,
    /// Angles of attack `[lowest, highest]` over which these coefficients describe a gliding
    /// canopy, degrees. A trim outside them is refused as a glide the model does not describe
    /// (flights pass through other angles in transients and are flown regardless).
    #[serde(default = "default_alpha_range_deg")]
    pub alpha_range_deg: [f64; 2],
}

/// The angle-of-attack range of a vehicle file that gives none, degrees (see
/// `config/vehicle/straplex.toml` for the reasoning).
pub fn default_alpha_range_deg() -> [f64; 2] {
    [0.0, 45.0]
}

/// Brake coefficients per unit of normalised deflection (0 released … 1 fully pulled).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BrakeConfig {
    /// Lift added by symmetric deflection δs.
    pub cl_ds: f64,
    /// Drag added by symmetric deflection δs.
    pub cd_ds: f64,
    /// Roll moment of asymmetric deflection δa = right − left.
    pub cl_da: f64,
    /// Yaw moment of asymmetric deflection δa = right − left.
    pub cn_da: f64,
}

/// Drone description (seed Tables 3.2, 4.2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DroneConfig {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Box length c (x), m.
    pub length_m: f64,
    /// Box width b (y), m.
    pub width_m: f64,
    /// Box height d (z), m.
    pub height_m: f64,
    /// Drag reference area, m².
    pub area_m2: f64,
    /// Drag coefficient, the same in every direction.
    pub cd: f64,
    /// Roll damping magnitude.
    pub clp: f64,
    /// Pitch damping magnitude.
    pub cmq: f64,
    /// Yaw damping magnitude.
    pub cnr: f64,
}

/// A body hanging on a line whose own rotation the model neglects (capsule, transponder).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PendantConfig {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Width, m.
    pub width_m: f64,
    /// Length, m.
    pub length_m: f64,
    /// Height, m.
    pub height_m: f64,
    /// Drag reference area, m².
    pub area_m2: f64,
    /// Drag coefficient.
    pub cd: f64,
}

/// Attachment points and lines (seed Table 4.1), metres, each in the frame its doc names.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GeometryConfig {
    /// Canopy pressure centre from the canopy CM, frame C.
    pub canopy_pressure_centre_m: [f64; 3],
    /// Right main line's canopy end from the canopy CM, frame C.
    pub right_line_on_canopy_m: [f64; 3],
    /// Left main line's canopy end from the canopy CM, frame C.
    pub left_line_on_canopy_m: [f64; 3],
    /// Right main line from its canopy end to its drone end, frame L.
    pub right_line_m: [f64; 3],
    /// Left main line from its canopy end to its drone end, frame L.
    pub left_line_m: [f64; 3],
    /// Drone pressure centre from the drone CM, frame D.
    pub drone_pressure_centre_m: [f64; 3],
    /// Right main line's drone end from the drone CM, frame D.
    pub right_line_on_drone_m: [f64; 3],
    /// Left main line's drone end from the drone CM, frame D.
    pub left_line_on_drone_m: [f64; 3],
    /// Capsule line's drone end from the drone CM, frame D.
    pub capsule_line_on_drone_m: [f64; 3],
    /// Drone–capsule line, m.
    pub capsule_line_length_m: f64,
    /// Capsule–transponder line, m.
    pub transponder_line_length_m: f64,
}

/// Servo dynamics and travel (eqs. 4.15–4.17).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ServoConfig {
    /// Main-line servo rate constant K_L, 1/s.
    pub main_line_rate_per_s: f64,
    /// Right brake servo rate constant K_SR, 1/s.
    pub brake_right_rate_per_s: f64,
    /// Left brake servo rate constant K_SL, 1/s.
    pub brake_left_rate_per_s: f64,
    /// Largest differential main-line displacement |ΔL|, m.
    pub main_line_travel_m: f64,
}

/// The vehicle file as written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VehicleConfig {
    /// Gravitational acceleration, m/s².
    pub gravity_mps2: f64,
    /// The canopy.
    pub canopy: CanopyConfig,
    /// The control drone.
    pub drone: DroneConfig,
    /// The payload capsule.
    pub capsule: PendantConfig,
    /// The transponder.
    pub transponder: PendantConfig,
    /// Attachment points and lines.
    pub geometry: GeometryConfig,
    /// Servos.
    pub servos: ServoConfig,
}
