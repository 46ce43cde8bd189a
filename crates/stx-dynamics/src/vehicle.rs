//! The vehicle's parameters: what [`crate::model`] needs to know about the four bodies.
//!
//! Configuration is staged: [`VehicleConfig`] is the TOML file as written (every field with its
//! unit in its name and its source in the file), [`VehicleConfig::validate`] checks every rule
//! and names the field that breaks one, and [`Vehicle`] is the validated, derived form the model
//! runs on (inertia tensors, apparent-mass coefficients, control geometry).

use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use stx_types::validate::{Invalid, check};

/// The STRAPLEX vehicle file shipped with stx (`config/vehicle/straplex.toml`).
pub const STRAPLEX_TOML: &str = include_str!("../../../config/vehicle/straplex.toml");

/// Why a vehicle description was refused.
#[derive(Debug, Error)]
pub enum VehicleError {
    /// The text is not valid TOML for this schema (unknown or missing field, wrong type). The
    /// parser's message is the error's source, not part of its text, so that an error chain
    /// prints it once.
    #[error("vehicle file is not valid TOML for the vehicle schema")]
    Parse(#[from] toml::de::Error),
    /// A field has a value the model cannot fly with.
    #[error("vehicle field `{field}` = {value} breaks the rule: {rule}")]
    Invalid {
        field: &'static str,
        value: f64,
        rule: &'static str,
    },
}

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

/// A body's rigid-body and drag constants.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyConstants {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Drag reference area times drag coefficient, m².
    pub drag_area_m2: f64,
    /// Height, m (how far its lowest point hangs below its CM is half of it).
    pub height_m: f64,
}

/// Lissaman & Brown (1993) apparent mass and inertia of the canopy per unit air density: the
/// model multiplies them by ρ at the current altitude.
#[derive(Debug, Clone, PartialEq)]
pub struct ApparentMass {
    /// Diagonal apparent mass `[A, B, C]` / ρ along canopy x, y, z, m³.
    pub mass_per_density_m3: Vector3<f64>,
    /// Diagonal apparent inertia `[I_A, I_B, I_C]` / ρ about canopy x, y, z, m⁵.
    pub inertia_per_density_m5: Vector3<f64>,
}

impl ApparentMass {
    /// Lissaman & Brown's formulas (AIAA 93-1236), as printed in the seed (eqs. 4.66, 4.89)
    /// with their exponents restored, for span b, chord c, thickness t and arc height a;
    /// AR = b/c, a* = a/b, t* = t/c:
    ///
    /// - `A = 0.666 ρ (1 + 8/3·a*²) t² b` (0.666 = 0.848·π/4)
    /// - `B = 0.267 ρ (1 + 2 a*²/t*² · AR² (1 − t*²)) t² c` (0.267 = 0.339·π/4)
    /// - `C = 0.785 ρ √(1 + 2 a*² (1 − t*²)) · AR/(1 + AR) · c² b` (0.785 = π/4)
    /// - `I_A = 0.055 ρ AR/(1 + AR) · c² b³`
    /// - `I_B = 0.0308 ρ AR/(1 + AR) · (1 + π/6 (1 + AR) AR a*² t*²) · c⁴ b`
    /// - `I_C = 0.0555 ρ (1 + 8 a*²) t² b³`
    pub fn lissaman_brown(span_m: f64, chord_m: f64, thickness_m: f64, arc_m: f64) -> Self {
        let (b, c, t) = (span_m, chord_m, thickness_m);
        let aspect = b / c;
        let arc_rel = arc_m / b;
        let thick_rel = t / c;
        let (a2, t2) = (arc_rel * arc_rel, thick_rel * thick_rel);
        let ar_factor = aspect / (1.0 + aspect);
        let k_a = 0.848 * std::f64::consts::FRAC_PI_4;
        let k_b = 0.339 * std::f64::consts::FRAC_PI_4;
        let k_c = std::f64::consts::FRAC_PI_4;
        let mass = Vector3::new(
            k_a * (1.0 + 8.0 / 3.0 * a2) * t * t * b,
            k_b * (1.0 + 2.0 * a2 / t2 * aspect * aspect * (1.0 - t2)) * t * t * c,
            k_c * (1.0 + 2.0 * a2 * (1.0 - t2)).sqrt() * ar_factor * c * c * b,
        );
        let inertia = Vector3::new(
            0.055 * ar_factor * c * c * b.powi(3),
            0.0308
                * ar_factor
                * (1.0 + std::f64::consts::PI / 6.0 * (1.0 + aspect) * aspect * a2 * t2)
                * c.powi(4)
                * b,
            0.0555 * (1.0 + 8.0 * a2) * t * t * b.powi(3),
        );
        Self {
            mass_per_density_m3: mass,
            inertia_per_density_m5: inertia,
        }
    }
}

/// The validated vehicle the model runs on.
#[derive(Debug, Clone, PartialEq)]
pub struct Vehicle {
    /// The description it was built from.
    pub config: VehicleConfig,
    /// Gravitational acceleration, m/s².
    pub gravity_mps2: f64,
    /// Canopy mass, kg.
    pub canopy_mass_kg: f64,
    /// Canopy inertia about its CM, frame C, kg·m² (eq. 4.94).
    pub canopy_inertia: Matrix3<f64>,
    /// Canopy apparent mass and inertia per unit density.
    pub apparent: ApparentMass,
    /// Drone mass, kg.
    pub drone_mass_kg: f64,
    /// Drone inertia about its CM, frame D, kg·m² (eq. 4.103).
    pub drone_inertia: Matrix3<f64>,
    /// Drone drag area C_D·S, m².
    pub drone_drag_area_m2: f64,
    /// Capsule constants.
    pub capsule: BodyConstants,
    /// Transponder constants.
    pub transponder: BodyConstants,
    /// Canopy pressure centre from canopy CM, frame C, m.
    pub r_cp_canopy_m: Vector3<f64>,
    /// Main-line canopy ends from canopy CM, frame C, m: `[right, left]`.
    pub r_lines_on_canopy_m: [Vector3<f64>; 2],
    /// Midpoint of the two canopy ends (the seed's R_TC/CMC, read as a mean), frame C, m.
    pub r_line_top_m: Vector3<f64>,
    /// Main lines, canopy end to drone end, frame L, m: `[right, left]`.
    pub lines_m: [Vector3<f64>; 2],
    /// Mean of the two lines (the seed's R_TD/TC, read as a mean), frame L, m.
    pub line_mean_m: Vector3<f64>,
    /// Drone pressure centre from drone CM, frame D, m.
    pub r_cp_drone_m: Vector3<f64>,
    /// Main-line drone ends from drone CM, frame D, m: `[right, left]`.
    pub r_lines_on_drone_m: [Vector3<f64>; 2],
    /// Drone CM from the midpoint of the drone ends (the seed's R_CMD/TD), frame D, m.
    pub r_drone_from_line_bottom_m: Vector3<f64>,
    /// Capsule line's drone end from drone CM, frame D, m.
    pub r_capsule_line_on_drone_m: Vector3<f64>,
    /// Drone–capsule line, m.
    pub capsule_line_length_m: f64,
    /// Capsule–transponder line, m.
    pub transponder_line_length_m: f64,
    /// Lateral drone shift per unit differential main-line displacement, ΔD/ΔL = 2·L0/B
    /// (eq. 3.3), m/m.
    pub lateral_shift_per_line_m: f64,
    /// Servo rate constants `[K_L, K_SR, K_SL]`, 1/s.
    pub servo_rate_per_s: Vector3<f64>,
    /// Largest |ΔL|, m.
    pub main_line_travel_m: f64,
}

fn vec3(a: [f64; 3]) -> Vector3<f64> {
    Vector3::new(a[0], a[1], a[2])
}

fn box_inertia(mass_kg: f64, x_m: f64, y_m: f64, z_m: f64) -> Matrix3<f64> {
    Matrix3::from_diagonal(&Vector3::new(
        y_m * y_m + z_m * z_m,
        x_m * x_m + z_m * z_m,
        x_m * x_m + y_m * y_m,
    )) * (mass_kg / 12.0)
}

/// Field names of the capsule's and the transponder's rules, in [`PendantConfig`]'s order.
const PENDANT_FIELDS: [[&str; 6]; 2] = [
    [
        "capsule.mass_kg",
        "capsule.width_m",
        "capsule.length_m",
        "capsule.height_m",
        "capsule.area_m2",
        "capsule.cd",
    ],
    [
        "transponder.mass_kg",
        "transponder.width_m",
        "transponder.length_m",
        "transponder.height_m",
        "transponder.area_m2",
        "transponder.cd",
    ],
];

/// Every rule's verdict, in the file's order: the first broken one is the error.
struct Rules(Vec<Result<(), Invalid>>);

impl Rules {
    fn check(&mut self, field: &'static str, value: f64, rule: &'static str, ok: bool) {
        self.0.push(check(field, value, ok, rule));
    }
    fn positive(&mut self, field: &'static str, value: f64) {
        self.check(field, value, "must be a finite number > 0", value > 0.0);
    }
    fn non_negative(&mut self, field: &'static str, value: f64) {
        self.check(field, value, "must be a finite number ≥ 0", value >= 0.0);
    }
    fn finite(&mut self, field: &'static str, value: f64) {
        self.check(field, value, "must be a finite number", true);
    }
    fn first_broken(self) -> Result<(), VehicleError> {
        Ok(self.0.into_iter().collect::<Result<(), Invalid>>()?)
    }
}

crate::invalid_into!(VehicleError);

impl VehicleConfig {
    /// Parses a vehicle file (it is not validated yet).
    pub fn from_toml_str(text: &str) -> Result<Self, VehicleError> {
        Ok(toml::from_str(text)?)
    }

    /// Checks every rule and builds the vehicle; the error names the first field that breaks one.
    pub fn validate(self) -> Result<Vehicle, VehicleError> {
        let mut rules = Rules(Vec::new());
        rules.positive("gravity_mps2", self.gravity_mps2);
        let c = &self.canopy;
        rules.positive("canopy.mass_kg", c.mass_kg);
        rules.positive("canopy.span_m", c.span_m);
        rules.positive("canopy.chord_m", c.chord_m);
        rules.positive("canopy.thickness_m", c.thickness_m);
        rules.check(
            "canopy.thickness_m",
            c.thickness_m,
            "must be less than canopy.chord_m",
            c.thickness_m < c.chord_m,
        );
        rules.non_negative("canopy.arc_height_m", c.arc_height_m);
        rules.check(
            "canopy.arc_height_m",
            c.arc_height_m,
            "must be less than half of canopy.span_m",
            c.arc_height_m < 0.5 * c.span_m,
        );
        rules.positive("canopy.area_m2", c.area_m2);
        rules.positive("canopy.main_line_length_m", c.main_line_length_m);
        rules.positive("canopy.beam_length_m", c.beam_length_m);
        let a = &c.aero;
        rules.non_negative("canopy.aero.cd0", a.cd0);
        rules.non_negative("canopy.aero.cd_alpha2", a.cd_alpha2);
        rules.finite("canopy.aero.cy_beta", a.cy_beta);
        rules.finite("canopy.aero.cl0", a.cl0);
        rules.finite("canopy.aero.cl_alpha", a.cl_alpha);
        rules.non_negative("canopy.aero.clp", a.clp);
        rules.non_negative("canopy.aero.cmq", a.cmq);
        rules.non_negative("canopy.aero.cnr", a.cnr);
        rules.finite("canopy.aero.cn_beta", a.cn_beta);
        let [alpha_low, alpha_high] = a.alpha_range_deg;
        rules.check(
            "canopy.aero.alpha_range_deg",
            alpha_low,
            "the lower end must lie in [-90, 90) degrees",
            (-90.0..90.0).contains(&alpha_low),
        );
        rules.check(
            "canopy.aero.alpha_range_deg",
            alpha_high,
            "the upper end must lie in (lower end, 90] degrees",
            alpha_high > alpha_low && alpha_high <= 90.0,
        );
        let b = &c.brakes;
        rules.finite("canopy.brakes.cl_ds", b.cl_ds);
        rules.non_negative("canopy.brakes.cd_ds", b.cd_ds);
        rules.finite("canopy.brakes.cl_da", b.cl_da);
        rules.finite("canopy.brakes.cn_da", b.cn_da);
        let d = &self.drone;
        rules.positive("drone.mass_kg", d.mass_kg);
        rules.positive("drone.length_m", d.length_m);
        rules.positive("drone.width_m", d.width_m);
        rules.positive("drone.height_m", d.height_m);
        rules.non_negative("drone.area_m2", d.area_m2);
        rules.non_negative("drone.cd", d.cd);
        rules.non_negative("drone.clp", d.clp);
        rules.non_negative("drone.cmq", d.cmq);
        rules.non_negative("drone.cnr", d.cnr);
        for (fields, p) in [
            (PENDANT_FIELDS[0], &self.capsule),
            (PENDANT_FIELDS[1], &self.transponder),
        ] {
            let [mass, width, length, height, area, cd] = fields;
            rules.positive(mass, p.mass_kg);
            rules.positive(width, p.width_m);
            rules.positive(length, p.length_m);
            rules.positive(height, p.height_m);
            rules.non_negative(area, p.area_m2);
            rules.non_negative(cd, p.cd);
        }
        let g = &self.geometry;
        let vectors: [(&'static str, [f64; 3]); 9] = [
            (
                "geometry.canopy_pressure_centre_m",
                g.canopy_pressure_centre_m,
            ),
            ("geometry.right_line_on_canopy_m", g.right_line_on_canopy_m),
            ("geometry.left_line_on_canopy_m", g.left_line_on_canopy_m),
            ("geometry.right_line_m", g.right_line_m),
            ("geometry.left_line_m", g.left_line_m),
            (
                "geometry.drone_pressure_centre_m",
                g.drone_pressure_centre_m,
            ),
            ("geometry.right_line_on_drone_m", g.right_line_on_drone_m),
            ("geometry.left_line_on_drone_m", g.left_line_on_drone_m),
            (
                "geometry.capsule_line_on_drone_m",
                g.capsule_line_on_drone_m,
            ),
        ];
        for (field, v) in vectors {
            for component in v {
                rules.finite(field, component);
            }
        }
        for (field, v) in [
            ("geometry.right_line_m", g.right_line_m),
            ("geometry.left_line_m", g.left_line_m),
        ] {
            rules.check(
                field,
                v[2],
                "the line must hang down (z component > 0 in the line frame)",
                v[2] > 0.0,
            );
        }
        rules.positive("geometry.capsule_line_length_m", g.capsule_line_length_m);
        rules.positive(
            "geometry.transponder_line_length_m",
            g.transponder_line_length_m,
        );
        let s = &self.servos;
        rules.positive("servos.main_line_rate_per_s", s.main_line_rate_per_s);
        rules.positive("servos.brake_right_rate_per_s", s.brake_right_rate_per_s);
        rules.positive("servos.brake_left_rate_per_s", s.brake_left_rate_per_s);
        rules.positive("servos.main_line_travel_m", s.main_line_travel_m);
        rules.check(
            "servos.main_line_travel_m",
            s.main_line_travel_m,
            "must be less than half of canopy.beam_length_m (the lines would cross)",
            s.main_line_travel_m < 0.5 * c.beam_length_m,
        );
        rules.first_broken()?;
        Ok(Vehicle::derive(self))
    }
}

impl Vehicle {
    /// Parses and validates a vehicle file.
    pub fn from_toml_str(text: &str) -> Result<Self, VehicleError> {
        VehicleConfig::from_toml_str(text)?.validate()
    }

    /// The STRAPLEX vehicle shipped with stx.
    pub fn straplex() -> Self {
        // The shipped file is covered by tests; failing here is a build defect, not bad input.
        Self::from_toml_str(STRAPLEX_TOML).expect("config/vehicle/straplex.toml is valid")
    }

    fn derive(config: VehicleConfig) -> Self {
        let c = &config.canopy;
        let d = &config.drone;
        let g = &config.geometry;
        let r_lines_on_canopy_m = [
            vec3(g.right_line_on_canopy_m),
            vec3(g.left_line_on_canopy_m),
        ];
        let lines_m = [vec3(g.right_line_m), vec3(g.left_line_m)];
        let r_lines_on_drone_m = [vec3(g.right_line_on_drone_m), vec3(g.left_line_on_drone_m)];
        let pendant = |p: &PendantConfig| BodyConstants {
            mass_kg: p.mass_kg,
            drag_area_m2: p.cd * p.area_m2,
            height_m: p.height_m,
        };
        Self {
            gravity_mps2: config.gravity_mps2,
            canopy_mass_kg: c.mass_kg,
            // Eq. 4.94: the canopy as a box of span × chord × thickness.
            canopy_inertia: box_inertia(c.mass_kg, c.chord_m, c.span_m, c.thickness_m),
            apparent: ApparentMass::lissaman_brown(
                c.span_m,
                c.chord_m,
                c.thickness_m,
                c.arc_height_m,
            ),
            drone_mass_kg: d.mass_kg,
            drone_inertia: box_inertia(d.mass_kg, d.length_m, d.width_m, d.height_m),
            drone_drag_area_m2: d.cd * d.area_m2,
            capsule: pendant(&config.capsule),
            transponder: pendant(&config.transponder),
            r_cp_canopy_m: vec3(g.canopy_pressure_centre_m),
            r_line_top_m: (r_lines_on_canopy_m[0] + r_lines_on_canopy_m[1]) * 0.5,
            r_lines_on_canopy_m,
            line_mean_m: (lines_m[0] + lines_m[1]) * 0.5,
            lines_m,
            r_cp_drone_m: vec3(g.drone_pressure_centre_m),
            r_drone_from_line_bottom_m: -(r_lines_on_drone_m[0] + r_lines_on_drone_m[1]) * 0.5,
            r_lines_on_drone_m,
            r_capsule_line_on_drone_m: vec3(g.capsule_line_on_drone_m),
            capsule_line_length_m: g.capsule_line_length_m,
            transponder_line_length_m: g.transponder_line_length_m,
            lateral_shift_per_line_m: 2.0 * c.main_line_length_m / c.beam_length_m,
            servo_rate_per_s: Vector3::new(
                config.servos.main_line_rate_per_s,
                config.servos.brake_right_rate_per_s,
                config.servos.brake_left_rate_per_s,
            ),
            main_line_travel_m: config.servos.main_line_travel_m,
            config,
        }
    }

    /// Total mass of the four bodies, kg.
    pub fn total_mass_kg(&self) -> f64 {
        self.canopy_mass_kg + self.drone_mass_kg + self.capsule.mass_kg + self.transponder.mass_kg
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shipped_vehicle_is_valid_and_weighs_what_the_seed_says() {
        let v = Vehicle::straplex();
        assert!((v.total_mass_kg() - 9.205).abs() < 1e-9);
        // Wing loading ≈ 3 kg/m² (seed §3.2.1).
        assert!((v.total_mass_kg() / v.config.canopy.area_m2 - 3.07).abs() < 0.01);
        // The main lines meet at the drone: their mean is the seed's 2.55 m drop below T_C.
        assert!((v.line_mean_m - Vector3::new(-0.08, 0.0, 2.55)).norm() < 1e-12);
        assert!((v.lateral_shift_per_line_m - 2.0 * 3.2 / 0.345).abs() < 1e-12);
    }

    #[test]
    fn apparent_mass_of_this_canopy_at_sea_level_is_dominated_by_the_normal_axis() {
        let rho = 1.225;
        let app = Vehicle::straplex().apparent;
        let m = app.mass_per_density_m3 * rho;
        let i = app.inertia_per_density_m5 * rho;
        // Hand evaluation of Lissaman & Brown for b = 3.3, c = 0.9, t = 0.07, a = 0.75:
        // A ≈ 0.0150 kg, B ≈ 0.332 kg, C ≈ 2.12 kg; I_A ≈ 1.54, I_B ≈ 0.0644, I_C ≈ 0.0169 kg·m².
        assert!((m.x - 0.0150).abs() < 0.0005, "A = {}", m.x);
        assert!((m.y - 0.332).abs() < 0.005, "B = {}", m.y);
        assert!((m.z - 2.12).abs() < 0.02, "C = {}", m.z);
        assert!((i.x - 1.54).abs() < 0.02, "I_A = {}", i.x);
        assert!((i.y - 0.0644).abs() < 0.001, "I_B = {}", i.y);
        assert!((i.z - 0.0169).abs() < 0.0005, "I_C = {}", i.z);
        // The normal-axis apparent mass is a few kg, larger than the canopy's own 0.7 kg.
        assert!(m.z > 3.0 * 0.7 && m.z > m.x && m.z > m.y);
    }

    #[test]
    fn a_broken_field_is_named_with_its_rule() {
        let text = STRAPLEX_TOML.replace("mass_kg = 1.770", "mass_kg = -1.770");
        match Vehicle::from_toml_str(&text) {
            Err(VehicleError::Invalid { field, value, .. }) => {
                assert_eq!(field, "drone.mass_kg");
                assert_eq!(value, -1.77);
            }
            other => panic!("expected drone.mass_kg to be refused, got {other:?}"),
        }
        let text = STRAPLEX_TOML.replace("thickness_m = 0.070", "thickness_m = 1.5");
        let err = Vehicle::from_toml_str(&text).unwrap_err().to_string();
        assert!(
            err.contains("canopy.thickness_m") && err.contains("chord"),
            "{err}"
        );
    }

    /// The error and its causes, as an error chain prints them.
    fn chain(err: &VehicleError) -> String {
        let mut text = err.to_string();
        let mut source = std::error::Error::source(err);
        while let Some(cause) = source {
            text.push_str(&format!(": {cause}"));
            source = cause.source();
        }
        text
    }

    #[test]
    fn unknown_and_missing_fields_are_refused_with_their_name() {
        let text = STRAPLEX_TOML.replace("cd0 = 0.150", "cd_zero = 0.150");
        let err = chain(&Vehicle::from_toml_str(&text).unwrap_err());
        assert!(err.contains("cd_zero"), "{err}");
        let text = STRAPLEX_TOML.replace("cnr = 0.090", "");
        let err = chain(&Vehicle::from_toml_str(&text).unwrap_err());
        assert!(err.contains("cnr"), "{err}");
    }

    #[test]
    fn a_parse_error_keeps_the_parsers_message_out_of_its_own_text() {
        // Regression: the message was in both the error's text and its source, so a printed
        // error chain showed the TOML parser's report twice.
        let err = Vehicle::from_toml_str("gravity_mps2 = \"down\"\n").unwrap_err();
        let source = std::error::Error::source(&err)
            .expect("the parser's error")
            .to_string();
        assert!(
            source.contains("gravity_mps2") || source.contains("down"),
            "{source}"
        );
        assert!(!err.to_string().contains("TOML parse error"), "{err}");
    }

    #[test]
    fn the_angle_of_attack_range_is_checked_and_defaults_when_absent() {
        assert_eq!(
            Vehicle::straplex().config.canopy.aero.alpha_range_deg,
            default_alpha_range_deg()
        );
        let text = STRAPLEX_TOML.replace("alpha_range_deg = [0.0, 45.0]", "");
        assert_ne!(text, STRAPLEX_TOML);
        let v = Vehicle::from_toml_str(&text).expect("valid without the range");
        assert_eq!(v.config.canopy.aero.alpha_range_deg, [0.0, 45.0]);
        for bad in [
            "[30.0, 10.0]",
            "[-95.0, 10.0]",
            "[0.0, 120.0]",
            "[nan, 10.0]",
        ] {
            let text = STRAPLEX_TOML.replace("[0.0, 45.0]", bad);
            let err = Vehicle::from_toml_str(&text).unwrap_err().to_string();
            assert!(err.contains("canopy.aero.alpha_range_deg"), "{bad}: {err}");
        }
    }

    #[test]
    fn the_munk_moment_switch_is_read_and_defaults_to_the_seeds_model() {
        assert!(!Vehicle::straplex().config.canopy.munk_moment);
        let on = STRAPLEX_TOML.replace("munk_moment = false", "munk_moment = true");
        assert_ne!(on, STRAPLEX_TOML);
        assert!(
            Vehicle::from_toml_str(&on)
                .expect("valid")
                .config
                .canopy
                .munk_moment
        );
        // A file written before the switch existed flies the model it was written for.
        let without = STRAPLEX_TOML.replace("munk_moment = false", "");
        let v = Vehicle::from_toml_str(&without).expect("valid without the switch");
        assert!(!v.config.canopy.munk_moment);
        // Anything but a boolean is refused, naming the field.
        let bad = STRAPLEX_TOML.replace("munk_moment = false", "munk_moment = 1");
        let err = chain(&Vehicle::from_toml_str(&bad).unwrap_err());
        assert!(err.contains("munk_moment"), "{err}");
    }

    #[test]
    fn non_finite_values_are_refused() {
        let text = STRAPLEX_TOML.replace("cl_alpha = 2.300", "cl_alpha = nan");
        let err = Vehicle::from_toml_str(&text).unwrap_err().to_string();
        assert!(err.contains("canopy.aero.cl_alpha"), "{err}");
    }
}
