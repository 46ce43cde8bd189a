//! The estimator's settings: timing rules, the noise it assumes for each sensor, how fast it
//! lets each state wander, and its gates. Validated once by [`EstimatorConfig::validate`]
//! (which [`super::Estimator::new`] calls) and turned into the [`Tuning`] constants the filter
//! uses on every call, so no unit conversion happens on the hot path.

use serde::{Deserialize, Serialize};
use stx_types::validate::{check, non_negative, positive};
use thiserror::Error;

/// Why an estimator configuration was refused.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum EstimatorConfigError {
    /// A setting breaks its rule.
    #[error("estimator setting `{field}` = {value} is invalid: must be {rule}")]
    Invalid {
        /// Name of the setting.
        field: &'static str,
        /// The value given, in the setting's unit.
        value: f64,
        /// The rule it breaks.
        rule: &'static str,
    },
}

/// Settings of the navigation estimator. Every field has a default tuned on the simulated
/// STRAPLEX drone with the simulator's default sensors; a TOML or JSON file names only what
/// it changes, and unknown keys are refused.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EstimatorConfig {
    /// Longest delay from a measurement's instant to its arrival that is still used, s (> 0).
    /// Measurements are held this long so that late ones can be slotted in at their instant;
    /// older ones are counted as stale and dropped. Longer costs more re-processing per late
    /// arrival.
    pub max_latency_s: f64,
    /// How far a measurement's instant may lie after its arrival before it is refused as a
    /// clock error, s (≥ 0).
    pub max_clock_skew_s: f64,
    /// After this long without a usable GPS fix, `gps_ok` turns false, s (> 0).
    pub gps_timeout_s: f64,
    /// After this long without an AHRS sample, `attitude_ok` turns false, s (> 0).
    pub attitude_timeout_s: f64,
    /// After this long without a pitot sample, `air_data_ok` turns false, s (> 0).
    pub air_data_timeout_s: f64,
    /// Altitude of the local NED origin above mean sea level, m: where the barometric altitude
    /// is referred to.
    pub ground_altitude_msl_m: f64,

    /// Random walk of each horizontal wind component, m/s/√s (≥ 0): how fast the filter lets
    /// the wind change. Turbulence of intensity σ and time scale τ needs about σ·√(2/τ).
    pub wind_random_walk_mps_per_sqrt_s: f64,
    /// Random walk of each horizontal component of the velocity relative to the air (NED),
    /// m/s/√s (> 0): speed changes, gusts the stack has not yet followed, turns starting and
    /// stopping, and the drone's swing under the canopy (its air velocity changes by about
    /// 0.3 m/s every quarter second in turbulence).
    pub air_velocity_random_walk_mps_per_sqrt_s: f64,
    /// Random walk of its vertical component (sink rate), m/s/√s (> 0).
    pub sink_rate_random_walk_mps_per_sqrt_s: f64,
    /// Random walk of the turn rate of the air velocity, rad/s/√s (> 0): a turn reverses from
    /// +0.6 to −0.6 rad/s within about two seconds.
    pub turn_rate_random_walk_rad_s_per_sqrt_s: f64,
    /// Stationary 1-σ of the vertical wind (a Gauss–Markov process about zero), m/s (≥ 0).
    /// The pitot sees it through the drone's pitch, steep in a spiral.
    pub vertical_wind_sigma_mps: f64,
    /// Correlation time of the vertical wind, s (> 0).
    pub vertical_wind_correlation_s: f64,
    /// Random walk of the straight-flight sideslip offset (the drone's own, from its true
    /// heading), degrees/√s (≥ 0).
    pub sideslip_random_walk_deg_per_sqrt_s: f64,
    /// Random walk of the AHRS's heading bias (a magnetometer's drifts as the drone's
    /// electronics warm and the field changes), degrees/√s (≥ 0).
    pub heading_bias_random_walk_deg_per_sqrt_s: f64,
    /// Random walk of the position beyond what the velocity explains (vertical gusts, attitude
    /// errors), m/√s (≥ 0).
    pub position_random_walk_m_per_sqrt_s: f64,
    /// Random walk of the pitot's scale factor, 1/√s (≥ 0).
    pub pitot_scale_random_walk_per_sqrt_s: f64,
    /// Random walk of the barometric bias (weather, and the real atmosphere's departure from
    /// the standard one with height), in natural log of pressure per √s (≥ 0); 1e-4 is about
    /// 0.85 m near the ground.
    pub baro_bias_random_walk_per_sqrt_s: f64,
    /// White angular acceleration driving the roll and pitch filters, rad/s²/√Hz (> 0): large
    /// enough to follow the drone's swing, small enough that a rate estimated from 4-Hz angles
    /// is not mere noise.
    pub roll_pitch_acceleration_noise: f64,
    /// The same for the heading filter, rad/s²/√Hz (> 0).
    pub yaw_acceleration_noise: f64,
    /// Largest attitude rate the angle filters accept, rad/s (> 0): resolves the ambiguity of
    /// a wrapped angle sampled at a few hertz (see `angle.rs`).
    pub max_angular_rate_rad_s: f64,

    /// AHRS roll and pitch noise the filter assumes, 1-σ, degrees (> 0).
    pub ahrs_roll_pitch_noise_deg: f64,
    /// AHRS yaw noise the filter assumes, 1-σ, degrees (> 0).
    pub ahrs_yaw_noise_deg: f64,
    /// Differential-pressure noise the filter assumes, 1-σ, Pa (> 0).
    pub differential_pressure_noise_pa: f64,
    /// Smallest airspeed noise assumed for a pitot reading, 1-σ, m/s (> 0): covers the
    /// sensor's offset and the flow's angle at the tube.
    pub pitot_airspeed_noise_floor_mps: f64,
    /// Pitot readings below this airspeed are not used, m/s (≥ 0): a pitot cannot tell air from
    /// behind or from the side, and a swinging drone sometimes sees both.
    pub pitot_min_airspeed_mps: f64,
    /// Static-pressure noise the filter assumes, 1-σ, Pa (> 0).
    pub static_pressure_noise_pa: f64,
    /// Uncertainty of the measured air temperature, noise and calibration together, 1-σ, K
    /// (> 0): with the static pressure's, the uncertainty of the air density reported.
    pub temperature_sigma_k: f64,
    /// Smallest GPS horizontal position accuracy believed, 1-σ, m (> 0): receivers can be
    /// optimistic.
    pub gps_min_horizontal_accuracy_m: f64,
    /// Smallest GPS vertical position accuracy believed, 1-σ, m (> 0).
    pub gps_min_vertical_accuracy_m: f64,
    /// Smallest GPS speed accuracy believed, 1-σ, m/s (> 0).
    pub gps_min_speed_accuracy_mps: f64,

    /// Spread of the sideslip about its offset in straight flight (the drone's swing), 1-σ,
    /// degrees (> 0).
    pub straight_sideslip_sigma_deg: f64,
    /// The flight counts as straight while the air velocity turns slower than this, rad/s
    /// (> 0)...
    pub straight_turn_rate_rad_s: f64,
    /// ...and the drone's heading changes slower than this, rad/s (> 0)...
    pub straight_yaw_rate_rad_s: f64,
    /// ...and has done so for this long, s (≥ 0): a moment for the swing after a turn to
    /// fade.
    pub straight_settle_s: f64,

    /// Wind uncertainty when the filter starts, 1-σ per component, m/s (> 0).
    pub initial_wind_sigma_mps: f64,
    /// Pitot scale-factor uncertainty at start, 1-σ (> 0).
    pub initial_pitot_scale_sigma: f64,
    /// Uncertainty of the straight-flight sideslip offset at start, 1-σ, degrees (> 0): how
    /// far from its true heading the drone's trim may hold it in straight flight. In straight
    /// flight only this offset less the heading bias is seen, so the two priors split it: the
    /// simulated drone's is −0.4° ± 1.0° per run over the realistic dispersions.
    pub initial_sideslip_sigma_deg: f64,
    /// Uncertainty of the AHRS's heading bias at start, 1-σ, degrees (> 0): a magnetometer
    /// on a swinging drone, calibrated on the ground.
    pub initial_heading_bias_sigma_deg: f64,
    /// Barometric-bias uncertainty before the first pressure reading, 1-σ, natural log of
    /// pressure (> 0).
    pub initial_baro_bias_sigma: f64,

    /// Innovation gate: a measurement whose innovation is less likely than a normal deviate
    /// beyond this many σ is rejected and counted, σ (> 0).
    pub innovation_gate_sigma: f64,
    /// After this many consecutive rejected GPS positions (or velocities), the filter takes
    /// them from the fix rather than trust a state that has gone wrong (≥ 1).
    pub reset_after_rejections: u32,
}

impl Default for EstimatorConfig {
    fn default() -> Self {
        Self {
            max_latency_s: 0.6,
            max_clock_skew_s: 0.1,
            gps_timeout_s: 1.0,
            attitude_timeout_s: 0.75,
            air_data_timeout_s: 0.75,
            ground_altitude_msl_m: 0.0,

            wind_random_walk_mps_per_sqrt_s: 0.1,
            air_velocity_random_walk_mps_per_sqrt_s: 0.6,
            sink_rate_random_walk_mps_per_sqrt_s: 0.3,
            turn_rate_random_walk_rad_s_per_sqrt_s: 0.3,
            vertical_wind_sigma_mps: 0.5,
            vertical_wind_correlation_s: 10.0,
            sideslip_random_walk_deg_per_sqrt_s: 0.1,
            heading_bias_random_walk_deg_per_sqrt_s: 0.02,
            position_random_walk_m_per_sqrt_s: 0.1,
            pitot_scale_random_walk_per_sqrt_s: 1e-3,
            baro_bias_random_walk_per_sqrt_s: 1e-5,
            roll_pitch_acceleration_noise: 1.0,
            yaw_acceleration_noise: 1.0,
            max_angular_rate_rad_s: 3.0,

            ahrs_roll_pitch_noise_deg: 1.0,
            ahrs_yaw_noise_deg: 2.0,
            differential_pressure_noise_pa: 0.6,
            pitot_airspeed_noise_floor_mps: 0.1,
            pitot_min_airspeed_mps: 2.0,
            static_pressure_noise_pa: 3.0,
            temperature_sigma_k: 1.0,
            gps_min_horizontal_accuracy_m: 0.5,
            gps_min_vertical_accuracy_m: 1.0,
            gps_min_speed_accuracy_mps: 0.05,

            straight_sideslip_sigma_deg: 4.0,
            straight_turn_rate_rad_s: 0.15,
            straight_yaw_rate_rad_s: 0.6,
            straight_settle_s: 1.0,

            initial_wind_sigma_mps: 5.0,
            initial_pitot_scale_sigma: 0.05,
            initial_sideslip_sigma_deg: 1.0,
            initial_heading_bias_sigma_deg: 5.0,
            initial_baro_bias_sigma: 0.05,

            innovation_gate_sigma: 5.0,
            reset_after_rejections: 8,
        }
    }
}

stx_types::invalid_into!(EstimatorConfigError);

impl EstimatorConfig {
    /// Checks every setting; the error names the first one that breaks its rule.
    pub fn validate(&self) -> Result<(), EstimatorConfigError> {
        positive("max_latency_s", self.max_latency_s)?;
        non_negative("max_clock_skew_s", self.max_clock_skew_s)?;
        positive("gps_timeout_s", self.gps_timeout_s)?;
        positive("attitude_timeout_s", self.attitude_timeout_s)?;
        positive("air_data_timeout_s", self.air_data_timeout_s)?;
        check(
            "ground_altitude_msl_m",
            self.ground_altitude_msl_m,
            true,
            "finite",
        )?;
        non_negative(
            "wind_random_walk_mps_per_sqrt_s",
            self.wind_random_walk_mps_per_sqrt_s,
        )?;
        positive(
            "air_velocity_random_walk_mps_per_sqrt_s",
            self.air_velocity_random_walk_mps_per_sqrt_s,
        )?;
        positive(
            "sink_rate_random_walk_mps_per_sqrt_s",
            self.sink_rate_random_walk_mps_per_sqrt_s,
        )?;
        positive(
            "turn_rate_random_walk_rad_s_per_sqrt_s",
            self.turn_rate_random_walk_rad_s_per_sqrt_s,
        )?;
        non_negative("vertical_wind_sigma_mps", self.vertical_wind_sigma_mps)?;
        positive(
            "vertical_wind_correlation_s",
            self.vertical_wind_correlation_s,
        )?;
        non_negative(
            "position_random_walk_m_per_sqrt_s",
            self.position_random_walk_m_per_sqrt_s,
        )?;
        non_negative(
            "pitot_scale_random_walk_per_sqrt_s",
            self.pitot_scale_random_walk_per_sqrt_s,
        )?;
        non_negative(
            "baro_bias_random_walk_per_sqrt_s",
            self.baro_bias_random_walk_per_sqrt_s,
        )?;
        positive(
            "roll_pitch_acceleration_noise",
            self.roll_pitch_acceleration_noise,
        )?;
        positive("yaw_acceleration_noise", self.yaw_acceleration_noise)?;
        positive("max_angular_rate_rad_s", self.max_angular_rate_rad_s)?;
        positive("ahrs_roll_pitch_noise_deg", self.ahrs_roll_pitch_noise_deg)?;
        positive("ahrs_yaw_noise_deg", self.ahrs_yaw_noise_deg)?;
        positive(
            "differential_pressure_noise_pa",
            self.differential_pressure_noise_pa,
        )?;
        positive(
            "pitot_airspeed_noise_floor_mps",
            self.pitot_airspeed_noise_floor_mps,
        )?;
        non_negative("pitot_min_airspeed_mps", self.pitot_min_airspeed_mps)?;
        positive("static_pressure_noise_pa", self.static_pressure_noise_pa)?;
        positive("temperature_sigma_k", self.temperature_sigma_k)?;
        positive(
            "gps_min_horizontal_accuracy_m",
            self.gps_min_horizontal_accuracy_m,
        )?;
        positive(
            "gps_min_vertical_accuracy_m",
            self.gps_min_vertical_accuracy_m,
        )?;
        positive(
            "gps_min_speed_accuracy_mps",
            self.gps_min_speed_accuracy_mps,
        )?;
        positive("initial_wind_sigma_mps", self.initial_wind_sigma_mps)?;
        positive("initial_pitot_scale_sigma", self.initial_pitot_scale_sigma)?;
        positive("initial_baro_bias_sigma", self.initial_baro_bias_sigma)?;
        non_negative(
            "sideslip_random_walk_deg_per_sqrt_s",
            self.sideslip_random_walk_deg_per_sqrt_s,
        )?;
        positive(
            "straight_sideslip_sigma_deg",
            self.straight_sideslip_sigma_deg,
        )?;
        positive("straight_turn_rate_rad_s", self.straight_turn_rate_rad_s)?;
        positive("straight_yaw_rate_rad_s", self.straight_yaw_rate_rad_s)?;
        non_negative("straight_settle_s", self.straight_settle_s)?;
        positive(
            "initial_sideslip_sigma_deg",
            self.initial_sideslip_sigma_deg,
        )?;
        non_negative(
            "heading_bias_random_walk_deg_per_sqrt_s",
            self.heading_bias_random_walk_deg_per_sqrt_s,
        )?;
        positive(
            "initial_heading_bias_sigma_deg",
            self.initial_heading_bias_sigma_deg,
        )?;
        positive("innovation_gate_sigma", self.innovation_gate_sigma)?;
        if self.reset_after_rejections == 0 {
            return Err(EstimatorConfigError::Invalid {
                field: "reset_after_rejections",
                value: 0.0,
                rule: "≥ 1",
            });
        }
        Ok(())
    }
}

/// The configuration as the filter uses it: variances and spectral densities in SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Tuning {
    pub max_latency_s: f64,
    pub max_clock_skew_s: f64,
    pub ground_altitude_msl_m: f64,
    /// Spectral densities of the random walks, unit²/s.
    pub q_wind: f64,
    pub q_air_horizontal: f64,
    pub q_air_vertical: f64,
    pub q_turn: f64,
    pub q_position: f64,
    pub vertical_wind_variance: f64,
    pub vertical_wind_correlation_s: f64,
    pub q_scale: f64,
    pub q_baro: f64,
    pub q_sideslip: f64,
    pub q_heading_bias: f64,
    pub straight_sideslip_sigma_rad: f64,
    pub straight_turn_rate_rad_s: f64,
    pub straight_yaw_rate_rad_s: f64,
    pub straight_settle_s: f64,
    pub initial_sideslip_variance: f64,
    pub initial_heading_bias_variance: f64,
    /// Angular-acceleration spectral densities, rad²/s³.
    pub q_roll_pitch: f64,
    pub q_yaw: f64,
    pub max_angular_rate_rad_s: f64,
    /// Measurement variances.
    pub r_roll_pitch: f64,
    pub r_yaw: f64,
    pub differential_pressure_noise_pa: f64,
    pub pitot_floor_variance: f64,
    pub pitot_min_airspeed_mps: f64,
    pub static_pressure_noise_pa: f64,
    pub temperature_sigma_k: f64,
    pub gps_min_horizontal_m: f64,
    pub gps_min_vertical_m: f64,
    pub gps_min_speed_mps: f64,
    /// Initial values and variances.
    pub initial_wind_variance: f64,
    pub initial_scale: f64,
    pub initial_scale_variance: f64,
    pub initial_heading_bias_rad: f64,
    pub initial_baro_variance: f64,
    /// Largest normalised innovation squared accepted for 1, 2 and 3 dimensions.
    pub gate_nis: [f64; 3],
    pub reset_after_rejections: u32,
}

impl Tuning {
    pub(crate) fn new(c: &EstimatorConfig) -> Self {
        let z = c.innovation_gate_sigma;
        Self {
            max_latency_s: c.max_latency_s,
            max_clock_skew_s: c.max_clock_skew_s,
            ground_altitude_msl_m: c.ground_altitude_msl_m,
            q_wind: c.wind_random_walk_mps_per_sqrt_s.powi(2),
            q_air_horizontal: c.air_velocity_random_walk_mps_per_sqrt_s.powi(2),
            q_air_vertical: c.sink_rate_random_walk_mps_per_sqrt_s.powi(2),
            q_turn: c.turn_rate_random_walk_rad_s_per_sqrt_s.powi(2),
            q_position: c.position_random_walk_m_per_sqrt_s.powi(2),
            vertical_wind_variance: c.vertical_wind_sigma_mps.powi(2),
            vertical_wind_correlation_s: c.vertical_wind_correlation_s,
            q_scale: c.pitot_scale_random_walk_per_sqrt_s.powi(2),
            q_baro: c.baro_bias_random_walk_per_sqrt_s.powi(2),
            q_sideslip: c.sideslip_random_walk_deg_per_sqrt_s.to_radians().powi(2),
            q_heading_bias: c
                .heading_bias_random_walk_deg_per_sqrt_s
                .to_radians()
                .powi(2),
            straight_sideslip_sigma_rad: c.straight_sideslip_sigma_deg.to_radians(),
            straight_turn_rate_rad_s: c.straight_turn_rate_rad_s,
            straight_yaw_rate_rad_s: c.straight_yaw_rate_rad_s,
            straight_settle_s: c.straight_settle_s,
            initial_sideslip_variance: c.initial_sideslip_sigma_deg.to_radians().powi(2),
            initial_heading_bias_variance: c.initial_heading_bias_sigma_deg.to_radians().powi(2),
            q_roll_pitch: c.roll_pitch_acceleration_noise.powi(2),
            q_yaw: c.yaw_acceleration_noise.powi(2),
            max_angular_rate_rad_s: c.max_angular_rate_rad_s,
            r_roll_pitch: c.ahrs_roll_pitch_noise_deg.to_radians().powi(2),
            r_yaw: c.ahrs_yaw_noise_deg.to_radians().powi(2),
            differential_pressure_noise_pa: c.differential_pressure_noise_pa,
            pitot_floor_variance: c.pitot_airspeed_noise_floor_mps.powi(2),
            pitot_min_airspeed_mps: c.pitot_min_airspeed_mps,
            static_pressure_noise_pa: c.static_pressure_noise_pa,
            temperature_sigma_k: c.temperature_sigma_k,
            gps_min_horizontal_m: c.gps_min_horizontal_accuracy_m,
            gps_min_vertical_m: c.gps_min_vertical_accuracy_m,
            gps_min_speed_mps: c.gps_min_speed_accuracy_mps,
            initial_wind_variance: c.initial_wind_sigma_mps.powi(2),
            initial_scale: 1.0,
            initial_scale_variance: c.initial_pitot_scale_sigma.powi(2),
            initial_heading_bias_rad: 0.0,
            initial_baro_variance: c.initial_baro_bias_sigma.powi(2),
            gate_nis: [1, 2, 3].map(|dof| chi_square_quantile(dof, z)),
            reset_after_rejections: c.reset_after_rejections,
        }
    }
}

/// The χ² value with `dof` degrees of freedom exceeded as rarely as a standard normal deviate
/// exceeds `z` (one-sided), by the Wilson–Hilferty cube-root approximation (a few per cent high
/// at 5σ: a slightly looser gate, which is the safe side for an outlier gate).
fn chi_square_quantile(dof: u32, z: f64) -> f64 {
    let k = f64::from(dof);
    let a = 2.0 / (9.0 * k);
    k * (1.0 - a + z * a.sqrt()).powi(3)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_errors_name_the_field() {
        EstimatorConfig::default()
            .validate()
            .expect("defaults valid");
        let bad = EstimatorConfig {
            turn_rate_random_walk_rad_s_per_sqrt_s: 0.0,
            ..Default::default()
        };
        match bad.validate() {
            Err(EstimatorConfigError::Invalid { field, .. }) => {
                assert_eq!(field, "turn_rate_random_walk_rad_s_per_sqrt_s")
            }
            other => panic!("expected an error naming the field, got {other:?}"),
        }
        let nan = EstimatorConfig {
            max_latency_s: f64::NAN,
            ..Default::default()
        };
        assert!(nan.validate().is_err());
    }

    #[test]
    fn chi_square_gate_is_close_to_the_exact_quantiles() {
        // Exact quantiles at the one-sided normal tail of 3σ (p = 1.35e-3) and 5σ
        // (p = 2.87e-7): χ²₂ = −2 ln p; χ²₃ solved from its closed-form survival function.
        let close = |approx: f64, exact: f64, tolerance: f64| {
            assert!(
                (approx / exact - 1.0).abs() < tolerance,
                "{approx} vs {exact}"
            )
        };
        close(chi_square_quantile(2, 3.0), 13.215, 0.03);
        close(chi_square_quantile(3, 3.0), 15.630, 0.03);
        close(chi_square_quantile(2, 5.0), 30.130, 0.12);
        close(chi_square_quantile(3, 5.0), 33.240, 0.12);
    }
}
