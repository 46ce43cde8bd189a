//! [`Dispersions`]: the TOML file of how uncertain each quantity is, read, validated and named.

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// The shipped nominal set (`config/dispersions/nominal.toml`): the world guidance assumes.
pub const NOMINAL_TOML: &str = include_str!("../../../../config/dispersions/nominal.toml");
/// The shipped realistic set (`config/dispersions/realistic.toml`).
pub const REALISTIC_TOML: &str = include_str!("../../../../config/dispersions/realistic.toml");

/// Why a dispersion file was refused.
#[derive(Debug, Error)]
pub enum DispersionsError {
    /// Not TOML of this schema (unknown or missing key, wrong type); the parser says where.
    #[error("dispersion file is not valid TOML for the dispersion schema")]
    Parse(#[from] toml::de::Error),
    /// A value breaks its rule.
    #[error("dispersion setting `{field}` = {value} is invalid: must be {rule}")]
    Invalid {
        /// TOML path of the setting.
        field: &'static str,
        /// The value given.
        value: f64,
        /// The rule it breaks.
        rule: &'static str,
    },
    /// The file could not be read.
    #[error("cannot read dispersion file {path}")]
    Read {
        /// The path given.
        path: String,
        /// Why.
        #[source]
        source: std::io::Error,
    },
}

/// How far each uncertain quantity of a flight may differ from what guidance assumes. Relative
/// 1-σ values are fractions of the nominal value (0.2 = ±20 % 1-σ); every normal draw is clipped
/// at ±3 σ so that no coefficient changes sign.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Dispersions {
    /// Name reported with every campaign flown with this set.
    pub name: String,
    /// Aerodynamic coefficients.
    pub aero: AeroDispersions,
    /// Masses and inertias.
    pub mass: MassDispersions,
    /// Rigging and lines.
    pub rigging: RiggingDispersions,
    /// Servo errors.
    pub servos: ServoDispersions,
    /// Sensor errors beyond the sensor file's.
    pub sensors: SensorDispersions,
    /// Wind.
    pub wind: WindDispersions,
}

/// Aerodynamic coefficients, each drawn on its own.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AeroDispersions {
    /// Canopy lift, drag, side-force and moment coefficients (cd0, cd_alpha2, cl0, cl_alpha,
    /// cy_beta, clp, cmq, cnr, cn_beta), 1-σ, fraction (0 … 0.3).
    pub canopy_sigma: f64,
    /// Brake terms (cl_ds, cd_ds, cl_da, cn_da), 1-σ, fraction (0 … 0.3).
    pub brake_sigma: f64,
    /// Drag and damping coefficients of the drone, capsule and transponder, 1-σ, fraction
    /// (0 … 0.3).
    pub body_sigma: f64,
}

/// Masses and inertias of the four bodies, each drawn on its own.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MassDispersions {
    /// Each body's mass, 1-σ, fraction (0 … 0.3).
    pub mass_sigma: f64,
    /// The canopy's and the drone's inertia tensors (scaled whole), 1-σ, fraction (0 … 0.3).
    pub inertia_sigma: f64,
}

/// Rigging angle and line lengths.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RiggingDispersions {
    /// Rigging angle (the canopy's incidence to its lines), 1-σ, degrees (0 … 5).
    pub angle_sigma_deg: f64,
    /// Lengths of the canopy's lines and of the capsule's and transponder's lines, each drawn
    /// on its own, 1-σ, fraction (0 … 0.1).
    pub line_length_sigma: f64,
}

/// Servo errors, drawn once per flight.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ServoDispersions {
    /// Main-line zero offset, 1-σ, m (0 … 0.02).
    pub main_line_bias_sigma_m: f64,
    /// Each brake's zero offset, 1-σ, fraction of full travel (0 … 0.1).
    pub brake_bias_sigma: f64,
    /// Main-line dead band: a command that moves less than this from where the servo stands
    /// leaves it there, m (0 … 0.01).
    pub main_line_dead_band_m: f64,
    /// Brake dead band, fraction of full travel (0 … 0.1).
    pub brake_dead_band: f64,
}

/// Sensor errors that the sensor file leaves at zero or that a campaign should vary; a key
/// left out keeps the sensor file's value.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorDispersions {
    /// GPS horizontal position bias, 1-σ, m (0 … 50).
    pub gps_horizontal_bias_sigma_m: Option<f64>,
    /// GPS vertical position bias, 1-σ, m (0 … 50).
    pub gps_vertical_bias_sigma_m: Option<f64>,
    /// GPS velocity bias, 1-σ, m/s (0 … 1).
    pub gps_velocity_bias_sigma_mps: Option<f64>,
    /// GPS horizontal random walk (its slowly wandering error), 1-σ, m (0 … 50).
    pub gps_horizontal_wander_m: Option<f64>,
    /// Mean number of GPS dropouts per flight (Poisson), placed uniformly over the first
    /// `gps_dropout_span_s` of the flight (0 … 20).
    pub gps_dropouts_per_flight: Option<f64>,
    /// Shortest and longest dropout, s (0 < shortest ≤ longest ≤ 60).
    pub gps_dropout_s: Option<[f64; 2]>,
    /// Span of the flight over which dropouts are placed, s (> 0).
    pub gps_dropout_span_s: Option<f64>,
    /// AHRS heading bias, 1-σ, degrees (0 … 20).
    pub ahrs_heading_bias_sigma_deg: Option<f64>,
    /// Pitot differential-pressure scale error, 1-σ, fraction (0 … 0.3).
    pub pitot_scale_sigma: Option<f64>,
    /// Pitot differential-pressure offset, 1-σ, Pa (0 … 20).
    pub pitot_offset_sigma_pa: Option<f64>,
}

/// The wind of a flight around its drawn mean speed and direction.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WindDispersions {
    /// Shear: the speed varies linearly with height by up to ± this fraction of the mean
    /// between the ground and the release height, uniform (0 … 1).
    pub shear_max_fraction: f64,
    /// Veer over the same height, up to ± this, uniform, degrees (0 … 180).
    pub veer_max_deg: f64,
    /// Turbulence intensity is 10 % of the mean speed (at least 0.1 m/s) times a factor drawn
    /// uniformly from 1 to this (1 … 4).
    pub gust_factor_max: f64,
    /// Below `low_level_height_m` the wind turns by up to ± this, uniform, degrees (0 … 180):
    /// the direction change near the ground that a final approach meets.
    pub low_level_turn_max_deg: f64,
    /// Height above the ground below which the low-level turn is complete, m (> 0); it grows
    /// linearly from twice this height down.
    pub low_level_height_m: f64,
}

impl Dispersions {
    /// The shipped nominal set.
    pub fn nominal() -> Self {
        Self::from_toml_str(NOMINAL_TOML).expect("the shipped nominal dispersions are valid")
    }

    /// The shipped realistic set.
    pub fn realistic() -> Self {
        Self::from_toml_str(REALISTIC_TOML).expect("the shipped realistic dispersions are valid")
    }

    /// `nominal`, `realistic`, or a path to a TOML file.
    pub fn load(name_or_path: &str) -> Result<Self, DispersionsError> {
        match name_or_path {
            "nominal" => Ok(Self::nominal()),
            "realistic" => Ok(Self::realistic()),
            path => {
                let text =
                    std::fs::read_to_string(path).map_err(|source| DispersionsError::Read {
                        path: path.to_string(),
                        source,
                    })?;
                Self::from_toml_str(&text)
            }
        }
    }

    /// Parses and validates a dispersion file.
    pub fn from_toml_str(text: &str) -> Result<Self, DispersionsError> {
        let d: Self = toml::from_str(text)?;
        d.validate()?;
        Ok(d)
    }

    /// Checks every value; the error names the first that breaks its rule.
    pub fn validate(&self) -> Result<(), DispersionsError> {
        let within = |field: &'static str, value: f64, lo: f64, hi: f64, rule: &'static str| {
            if value.is_finite() && (lo..=hi).contains(&value) {
                Ok(())
            } else {
                Err(DispersionsError::Invalid { field, value, rule })
            }
        };
        const FRACTION: &str = "a fraction in [0, 0.3]";
        within(
            "aero.canopy_sigma",
            self.aero.canopy_sigma,
            0.0,
            0.3,
            FRACTION,
        )?;
        within(
            "aero.brake_sigma",
            self.aero.brake_sigma,
            0.0,
            0.3,
            FRACTION,
        )?;
        within("aero.body_sigma", self.aero.body_sigma, 0.0, 0.3, FRACTION)?;
        within("mass.mass_sigma", self.mass.mass_sigma, 0.0, 0.3, FRACTION)?;
        within(
            "mass.inertia_sigma",
            self.mass.inertia_sigma,
            0.0,
            0.3,
            FRACTION,
        )?;
        let r = &self.rigging;
        within(
            "rigging.angle_sigma_deg",
            r.angle_sigma_deg,
            0.0,
            5.0,
            "in [0, 5] degrees",
        )?;
        within(
            "rigging.line_length_sigma",
            r.line_length_sigma,
            0.0,
            0.1,
            "a fraction in [0, 0.1]",
        )?;
        let s = &self.servos;
        within(
            "servos.main_line_bias_sigma_m",
            s.main_line_bias_sigma_m,
            0.0,
            0.02,
            "in [0, 0.02] m",
        )?;
        within(
            "servos.brake_bias_sigma",
            s.brake_bias_sigma,
            0.0,
            0.1,
            "in [0, 0.1]",
        )?;
        within(
            "servos.main_line_dead_band_m",
            s.main_line_dead_band_m,
            0.0,
            0.01,
            "in [0, 0.01] m",
        )?;
        within(
            "servos.brake_dead_band",
            s.brake_dead_band,
            0.0,
            0.1,
            "in [0, 0.1]",
        )?;
        let n = &self.sensors;
        let optional = |field, value: Option<f64>, lo, hi, rule| match value {
            Some(v) => within(field, v, lo, hi, rule),
            None => Ok(()),
        };
        optional(
            "sensors.gps_horizontal_bias_sigma_m",
            n.gps_horizontal_bias_sigma_m,
            0.0,
            50.0,
            "in [0, 50] m",
        )?;
        optional(
            "sensors.gps_vertical_bias_sigma_m",
            n.gps_vertical_bias_sigma_m,
            0.0,
            50.0,
            "in [0, 50] m",
        )?;
        optional(
            "sensors.gps_velocity_bias_sigma_mps",
            n.gps_velocity_bias_sigma_mps,
            0.0,
            1.0,
            "in [0, 1] m/s",
        )?;
        optional(
            "sensors.gps_horizontal_wander_m",
            n.gps_horizontal_wander_m,
            0.0,
            50.0,
            "in [0, 50] m",
        )?;
        optional(
            "sensors.gps_dropouts_per_flight",
            n.gps_dropouts_per_flight,
            0.0,
            20.0,
            "in [0, 20]",
        )?;
        if let Some([shortest, longest]) = n.gps_dropout_s {
            within(
                "sensors.gps_dropout_s[0]",
                shortest,
                1e-3,
                60.0,
                "in (0, 60] s",
            )?;
            within(
                "sensors.gps_dropout_s[1]",
                longest,
                shortest,
                60.0,
                "in [shortest, 60] s",
            )?;
        }
        optional(
            "sensors.gps_dropout_span_s",
            n.gps_dropout_span_s,
            1.0,
            1e6,
            "in [1, 1e6] s",
        )?;
        optional(
            "sensors.ahrs_heading_bias_sigma_deg",
            n.ahrs_heading_bias_sigma_deg,
            0.0,
            20.0,
            "in [0, 20] degrees",
        )?;
        optional(
            "sensors.pitot_scale_sigma",
            n.pitot_scale_sigma,
            0.0,
            0.3,
            FRACTION,
        )?;
        optional(
            "sensors.pitot_offset_sigma_pa",
            n.pitot_offset_sigma_pa,
            0.0,
            20.0,
            "in [0, 20] Pa",
        )?;
        let w = &self.wind;
        within(
            "wind.shear_max_fraction",
            w.shear_max_fraction,
            0.0,
            1.0,
            "in [0, 1]",
        )?;
        within(
            "wind.veer_max_deg",
            w.veer_max_deg,
            0.0,
            180.0,
            "in [0, 180] degrees",
        )?;
        within(
            "wind.gust_factor_max",
            w.gust_factor_max,
            1.0,
            4.0,
            "in [1, 4]",
        )?;
        within(
            "wind.low_level_turn_max_deg",
            w.low_level_turn_max_deg,
            0.0,
            180.0,
            "in [0, 180] degrees",
        )?;
        within(
            "wind.low_level_height_m",
            w.low_level_height_m,
            1.0,
            1000.0,
            "in [1, 1000] m",
        )?;
        Ok(())
    }
}
