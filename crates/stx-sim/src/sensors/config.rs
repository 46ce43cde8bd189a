//! [`SensorConfig`]: every sensor's rate, latency, noise, biases and dropouts, read from TOML
//! or built in code, and checked by [`SensorConfig::validate`] before a run.

use serde::Deserialize;
use stx_dynamics::validate::{check, non_negative, positive};
use thiserror::Error;

/// Why a sensor configuration was refused. `field` is the TOML path, e.g. `gps.rate_hz`.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SensorConfigError {
    /// A number breaks its rule.
    #[error("sensor setting `{field}` = {value} is invalid: must be {rule}")]
    Invalid {
        /// Path of the setting.
        field: &'static str,
        /// The value given, in the setting's unit.
        value: f64,
        /// The rule it breaks.
        rule: &'static str,
    },
    /// A dropout window is not an interval.
    #[error(
        "sensor setting `{field}` window {index} = [{from_s}, {to_s}] s is invalid: both ends \
         must be finite and from < to"
    )]
    DropoutWindow {
        /// Path of the setting.
        field: &'static str,
        /// Index of the window, from 0.
        index: usize,
        /// Its start, s.
        from_s: f64,
        /// Its end, s.
        to_s: f64,
    },
}

/// The whole sensor set. Every field has a realistic default, so a TOML file names only what it
/// changes; unknown keys are refused.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorConfig {
    /// GPS receiver.
    pub gps: GpsConfig,
    /// Attitude and heading reference system.
    pub ahrs: AhrsConfig,
    /// Pitot tube with differential and static pressure sensors and a thermometer.
    pub pitot: PitotConfig,
}

/// GPS receiver: position and velocity over the ground. Defaults: a small single-frequency
/// receiver (u-blox class) at 4 Hz, the drone's measurement rate (seed §3.3.2).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GpsConfig {
    /// Fixes per second, Hz (> 0).
    pub rate_hz: f64,
    /// Instant of the first fix, s (≥ 0): staggers sensors that share a rate.
    pub phase_s: f64,
    /// Delay from the fix's instant to its arrival at the estimator, s (≥ 0): receiver
    /// processing plus link.
    pub latency_s: f64,
    /// Windows `[from_s, to_s]` of mission time in which no fix is delivered, s.
    pub dropouts_s: Vec<[f64; 2]>,
    /// Probability that any one fix is lost, 0…1.
    pub dropout_probability: f64,
    /// White noise on each horizontal position component, 1-σ, m.
    pub horizontal_noise_m: f64,
    /// White noise on the vertical position, 1-σ, m.
    pub vertical_noise_m: f64,
    /// Slowly wandering horizontal position error (first-order Gauss–Markov: atmosphere and
    /// satellite geometry), stationary 1-σ per component, m.
    pub horizontal_wander_m: f64,
    /// The same for the vertical position, m.
    pub vertical_wander_m: f64,
    /// Correlation time of the wander, s (> 0).
    pub wander_correlation_s: f64,
    /// Constant horizontal position bias (a survey datum or antenna offset the receiver does
    /// not know), drawn once per run per component with this 1-σ, m.
    pub horizontal_bias_sigma_m: f64,
    /// Constant vertical position bias, drawn once per run with this 1-σ, m.
    pub vertical_bias_sigma_m: f64,
    /// Constant velocity bias on each component, drawn once per run with this 1-σ, m/s. The
    /// estimator cannot tell it from wind (both shift the ground velocity), so it shows up
    /// whole in the wind estimate: a test of what guidance makes of a biased wind.
    pub velocity_bias_sigma_mps: f64,
    /// White noise on each horizontal velocity component, 1-σ, m/s.
    pub velocity_noise_mps: f64,
    /// White noise on the vertical velocity, 1-σ, m/s.
    pub vertical_velocity_noise_mps: f64,
    /// Horizontal accuracy the receiver reports with every fix, 1-σ, m (> 0).
    pub reported_horizontal_accuracy_m: f64,
    /// Vertical accuracy it reports, 1-σ, m (> 0).
    pub reported_vertical_accuracy_m: f64,
    /// Speed accuracy it reports, 1-σ, m/s (> 0).
    pub reported_speed_accuracy_mps: f64,
}

impl Default for GpsConfig {
    fn default() -> Self {
        Self {
            rate_hz: 4.0,
            phase_s: 0.0,
            latency_s: 0.25,
            dropouts_s: Vec::new(),
            dropout_probability: 0.0,
            horizontal_noise_m: 0.5,
            vertical_noise_m: 1.0,
            horizontal_wander_m: 1.5,
            vertical_wander_m: 3.0,
            wander_correlation_s: 100.0,
            // Off by default: the wander already stands for a receiver's slow errors, and the
            // Monte Carlo figures are kept comparable; scenarios set them to test biases.
            horizontal_bias_sigma_m: 0.0,
            vertical_bias_sigma_m: 0.0,
            velocity_bias_sigma_mps: 0.0,
            velocity_noise_mps: 0.1,
            vertical_velocity_noise_mps: 0.15,
            // √(noise² + wander²), rounded up: an honest receiver.
            reported_horizontal_accuracy_m: 1.6,
            reported_vertical_accuracy_m: 3.2,
            reported_speed_accuracy_mps: 0.15,
        }
    }
}

/// AHRS: roll, pitch and yaw of the drone. Angles in degrees here because people write them.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AhrsConfig {
    /// Samples per second, Hz (> 0).
    pub rate_hz: f64,
    /// Instant of the first sample, s (≥ 0).
    pub phase_s: f64,
    /// Delay to the estimator, s (≥ 0).
    pub latency_s: f64,
    /// Windows `[from_s, to_s]` without samples, s.
    pub dropouts_s: Vec<[f64; 2]>,
    /// Probability that any one sample is lost, 0…1.
    pub dropout_probability: f64,
    /// White noise on roll, 1-σ, degrees.
    pub roll_noise_deg: f64,
    /// White noise on pitch, 1-σ, degrees.
    pub pitch_noise_deg: f64,
    /// White noise on yaw, 1-σ, degrees.
    pub yaw_noise_deg: f64,
    /// Constant roll bias, drawn once per run with this 1-σ, degrees (mounting error).
    pub roll_bias_sigma_deg: f64,
    /// Constant pitch bias, drawn once per run with this 1-σ, degrees.
    pub pitch_bias_sigma_deg: f64,
    /// Constant yaw bias, drawn once per run with this 1-σ, degrees: the magnetometer's
    /// calibration and declination error.
    pub yaw_bias_sigma_deg: f64,
    /// Random walk added to the yaw bias, degrees/√s.
    pub yaw_bias_random_walk_deg_per_sqrt_s: f64,
}

impl Default for AhrsConfig {
    fn default() -> Self {
        Self {
            rate_hz: 4.0,
            phase_s: 0.0,
            latency_s: 0.02,
            dropouts_s: Vec::new(),
            dropout_probability: 0.0,
            roll_noise_deg: 0.5,
            pitch_noise_deg: 0.5,
            yaw_noise_deg: 1.5,
            roll_bias_sigma_deg: 0.5,
            pitch_bias_sigma_deg: 0.5,
            yaw_bias_sigma_deg: 2.0,
            yaw_bias_random_walk_deg_per_sqrt_s: 0.02,
        }
    }
}

/// Pitot tube and air-data sensors. The differential pressure is `½ρ·u_x·|u_x|` of the drone's
/// air-relative velocity along its own x axis (negative, apart from noise, when the air comes
/// from behind), plus the sensor's offset and noise.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PitotConfig {
    /// Samples per second, Hz (> 0).
    pub rate_hz: f64,
    /// Instant of the first sample, s (≥ 0).
    pub phase_s: f64,
    /// Delay to the estimator, s (≥ 0).
    pub latency_s: f64,
    /// Windows `[from_s, to_s]` without samples, s.
    pub dropouts_s: Vec<[f64; 2]>,
    /// Probability that any one sample is lost, 0…1.
    pub dropout_probability: f64,
    /// White noise on the differential pressure, 1-σ, Pa.
    pub differential_noise_pa: f64,
    /// Constant differential-pressure offset (zero error), drawn once per run with this 1-σ, Pa.
    pub differential_offset_sigma_pa: f64,
    /// Random walk of that offset (thermal drift), Pa/√s.
    pub differential_offset_random_walk_pa_per_sqrt_s: f64,
    /// Scale error of the differential pressure (the tube's placement in the drone's flow and
    /// its calibration), drawn once per run with this 1-σ as a fraction: the sensor reads
    /// `(1 + k)·q`. Clipped at ±3 σ.
    pub differential_scale_sigma: f64,
    /// White noise on the static pressure, 1-σ, Pa.
    pub static_noise_pa: f64,
    /// Constant static-pressure bias, drawn once per run with this 1-σ, Pa.
    pub static_bias_sigma_pa: f64,
    /// White noise on the air temperature, 1-σ, K.
    pub temperature_noise_k: f64,
    /// Constant temperature bias, drawn once per run with this 1-σ, K.
    pub temperature_bias_sigma_k: f64,
}

impl Default for PitotConfig {
    fn default() -> Self {
        Self {
            rate_hz: 4.0,
            phase_s: 0.0,
            latency_s: 0.02,
            dropouts_s: Vec::new(),
            dropout_probability: 0.0,
            differential_noise_pa: 0.5,
            differential_offset_sigma_pa: 0.3,
            differential_offset_random_walk_pa_per_sqrt_s: 0.005,
            differential_scale_sigma: 0.0,
            static_noise_pa: 2.0,
            static_bias_sigma_pa: 20.0,
            temperature_noise_k: 0.3,
            temperature_bias_sigma_k: 1.0,
        }
    }
}

stx_dynamics::invalid_into!(SensorConfigError);

/// The timing settings every sensor has, named by their TOML paths.
struct TimingFields<'a> {
    rate_hz: (&'static str, f64),
    phase_s: (&'static str, f64),
    latency_s: (&'static str, f64),
    dropouts_s: (&'static str, &'a [[f64; 2]]),
    dropout_probability: (&'static str, f64),
}

impl TimingFields<'_> {
    fn validate(&self) -> Result<(), SensorConfigError> {
        check(
            self.rate_hz.0,
            self.rate_hz.1,
            self.rate_hz.1 > 0.0 && self.rate_hz.1 <= MAX_RATE_HZ,
            "finite, > 0 and ≤ 1000 Hz",
        )?;
        non_negative(self.phase_s.0, self.phase_s.1)?;
        non_negative(self.latency_s.0, self.latency_s.1)?;
        check(
            self.dropout_probability.0,
            self.dropout_probability.1,
            (0.0..=1.0).contains(&self.dropout_probability.1),
            "in [0, 1]",
        )?;
        for (index, &[from_s, to_s]) in self.dropouts_s.1.iter().enumerate() {
            if !(from_s.is_finite() && to_s.is_finite() && from_s < to_s) {
                return Err(SensorConfigError::DropoutWindow {
                    field: self.dropouts_s.0,
                    index,
                    from_s,
                    to_s,
                });
            }
        }
        Ok(())
    }
}

/// Highest sensor rate accepted, Hz: a guard against a typo that would flood the estimator.
const MAX_RATE_HZ: f64 = 1000.0;

impl SensorConfig {
    /// Checks every setting; the error names the first one that breaks its rule.
    pub fn validate(&self) -> Result<(), SensorConfigError> {
        let g = &self.gps;
        TimingFields {
            rate_hz: ("gps.rate_hz", g.rate_hz),
            phase_s: ("gps.phase_s", g.phase_s),
            latency_s: ("gps.latency_s", g.latency_s),
            dropouts_s: ("gps.dropouts_s", &g.dropouts_s),
            dropout_probability: ("gps.dropout_probability", g.dropout_probability),
        }
        .validate()?;
        non_negative("gps.horizontal_noise_m", g.horizontal_noise_m)?;
        non_negative("gps.vertical_noise_m", g.vertical_noise_m)?;
        non_negative("gps.horizontal_wander_m", g.horizontal_wander_m)?;
        non_negative("gps.vertical_wander_m", g.vertical_wander_m)?;
        positive("gps.wander_correlation_s", g.wander_correlation_s)?;
        non_negative("gps.horizontal_bias_sigma_m", g.horizontal_bias_sigma_m)?;
        non_negative("gps.vertical_bias_sigma_m", g.vertical_bias_sigma_m)?;
        non_negative("gps.velocity_bias_sigma_mps", g.velocity_bias_sigma_mps)?;
        non_negative("gps.velocity_noise_mps", g.velocity_noise_mps)?;
        non_negative(
            "gps.vertical_velocity_noise_mps",
            g.vertical_velocity_noise_mps,
        )?;
        positive(
            "gps.reported_horizontal_accuracy_m",
            g.reported_horizontal_accuracy_m,
        )?;
        positive(
            "gps.reported_vertical_accuracy_m",
            g.reported_vertical_accuracy_m,
        )?;
        positive(
            "gps.reported_speed_accuracy_mps",
            g.reported_speed_accuracy_mps,
        )?;

        let a = &self.ahrs;
        TimingFields {
            rate_hz: ("ahrs.rate_hz", a.rate_hz),
            phase_s: ("ahrs.phase_s", a.phase_s),
            latency_s: ("ahrs.latency_s", a.latency_s),
            dropouts_s: ("ahrs.dropouts_s", &a.dropouts_s),
            dropout_probability: ("ahrs.dropout_probability", a.dropout_probability),
        }
        .validate()?;
        non_negative("ahrs.roll_noise_deg", a.roll_noise_deg)?;
        non_negative("ahrs.pitch_noise_deg", a.pitch_noise_deg)?;
        non_negative("ahrs.yaw_noise_deg", a.yaw_noise_deg)?;
        non_negative("ahrs.roll_bias_sigma_deg", a.roll_bias_sigma_deg)?;
        non_negative("ahrs.pitch_bias_sigma_deg", a.pitch_bias_sigma_deg)?;
        non_negative("ahrs.yaw_bias_sigma_deg", a.yaw_bias_sigma_deg)?;
        non_negative(
            "ahrs.yaw_bias_random_walk_deg_per_sqrt_s",
            a.yaw_bias_random_walk_deg_per_sqrt_s,
        )?;

        let p = &self.pitot;
        TimingFields {
            rate_hz: ("pitot.rate_hz", p.rate_hz),
            phase_s: ("pitot.phase_s", p.phase_s),
            latency_s: ("pitot.latency_s", p.latency_s),
            dropouts_s: ("pitot.dropouts_s", &p.dropouts_s),
            dropout_probability: ("pitot.dropout_probability", p.dropout_probability),
        }
        .validate()?;
        non_negative("pitot.differential_noise_pa", p.differential_noise_pa)?;
        non_negative(
            "pitot.differential_offset_sigma_pa",
            p.differential_offset_sigma_pa,
        )?;
        non_negative(
            "pitot.differential_offset_random_walk_pa_per_sqrt_s",
            p.differential_offset_random_walk_pa_per_sqrt_s,
        )?;
        check(
            "pitot.differential_scale_sigma",
            p.differential_scale_sigma,
            (0.0..=0.3).contains(&p.differential_scale_sigma),
            "in [0, 0.3]",
        )?;
        non_negative("pitot.static_noise_pa", p.static_noise_pa)?;
        non_negative("pitot.static_bias_sigma_pa", p.static_bias_sigma_pa)?;
        non_negative("pitot.temperature_noise_k", p.temperature_noise_k)?;
        non_negative("pitot.temperature_bias_sigma_k", p.temperature_bias_sigma_k)?;
        Ok(())
    }
}
