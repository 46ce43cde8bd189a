//! The vehicle's parameters: what [`crate::model`] needs to know about the four bodies.
//!
//! Configuration is staged: [`VehicleConfig`] is the TOML file as written (every field with its
//! unit in its name and its source in the file), [`VehicleConfig::validate`] checks every rule
//! and names the field that breaks one, and [`Vehicle`] is the validated, derived form the model
//! runs on (inertia tensors, apparent-mass coefficients, control geometry). The file's tables are
//! in `file`, its rules in `validate`.

use nalgebra::{Matrix3, Vector3};
use thiserror::Error;

mod file;
mod validate;

pub use file::*;

/// The STRAPLEX vehicle file shipped with stx (`config/vehicle/straplex.toml`).
pub const STRAPLEX_TOML: &str = include_str!("../../../../config/vehicle/straplex.toml");

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
