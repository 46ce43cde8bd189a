//! The simulated drone's sensors (seed §2.2, §3.3.2): a GPS receiver, an AHRS and a pitot tube
//! with its differential, static pressure and temperature sensors, each with its own rate,
//! latency, noise, bias and dropouts.
//!
//! Why it exists: the estimator (`stx_gnc::estimator`) is only as good as the data it is tested
//! on. Feeding it the flight model's exact state would hide every difficulty the real drone has:
//! a pitot that sees only the air along the drone's x axis, a magnetometer's heading bias, a GPS
//! whose fixes wander and arrive late, sensors that fall silent. This layer produces exactly the
//! [`Measurement`]s the drone would send, so estimator and simulator are tested against each
//! other.
//!
//! How the parts fit:
//! - [`Truth`] is what the sensors look at: the drone's position, velocity, attitude,
//!   air-relative velocity and the air around it, built from the flight model's state by
//!   [`Truth::from_model`];
//! - [`SensorConfig`] describes every sensor (rates, latencies, noise, biases, dropouts). It is
//!   read from TOML or built in code, and [`SensorConfig::validate`] checks it before a run;
//! - [`SensorSuite`] is the running sensor set: call [`SensorSuite::sample`] every control tick
//!   with the truth at that instant; each sensor that is due emits a [`Delivery`] stamped with
//!   the sampled instant and the later instant it reaches the estimator;
//! - [`DeliveryQueue`] holds deliveries until their arrival time, for the simulation loop.
//!
//! Determinism: everything random is drawn from `ChaCha8Rng` seeded by the suite's seed, one
//! independent stream per sensor for its noise and one per sensor for its random dropouts.
//! The same seed and the same sequence of calls give bit-identical deliveries; switching one
//! sensor's dropouts on or off changes nothing in another sensor, and a dropped sample still
//! draws its noise, so a dropout removes samples without reshuffling the noise of the others.
//!
//! Sampling: a sensor due at `phase_s + n / rate_hz` is sampled at the first call at or after
//! that instant, and its measurement describes the call's instant (the truth handed in). Calls
//! at a control tick that divides the sensor period (the usual 0.05 s tick and 4 Hz sensors)
//! give exact rates; a coarser tick skips samples rather than inventing them.

use std::collections::VecDeque;
use std::f64::consts::FRAC_PI_2;

use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::Deserialize;
use stx_dynamics::atmosphere::AirState;
use stx_dynamics::model::{Body, Kinematics, ParafoilModel};
use stx_dynamics::rotation::{euler_from_t, euler_rates, wrap_pi};
use stx_dynamics::state::StateVector;
use stx_gnc::measurement::{AirDataSample, AttitudeSample, GpsFix, Measurement};
use thiserror::Error;

/// What the sensors look at: the drone's true state at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Truth {
    /// Instant described, s.
    pub time_s: f64,
    /// Drone CM position, local NED, m (the GPS antenna sits there).
    pub position_ned_m: Vector3<f64>,
    /// Drone CM velocity over the ground, NED, m/s.
    pub velocity_ned_mps: Vector3<f64>,
    /// Roll, pitch, yaw of the drone relative to NED (3-2-1), rad; yaw in (−π, π].
    pub euler_rad: Vector3<f64>,
    /// Rates of those angles, rad/s (the yaw rate is the heading rate the estimator reports).
    pub euler_rate_rad_s: Vector3<f64>,
    /// The drone's velocity relative to the air, in the drone frame (x forward, z down), m/s:
    /// what the pitot's x-axis measurement and the estimator's air-velocity state describe.
    pub air_velocity_body_mps: Vector3<f64>,
    /// Wind (the air's velocity) at the drone, NED, m/s.
    pub wind_ned_mps: Vector3<f64>,
    /// The air at the drone's altitude.
    pub air: AirState,
}

impl Truth {
    /// The truth for the drone of `model` at `time_s` in `state`, using the model's held main
    /// line command (its servo rate moves the drone), its atmosphere and its wind at the
    /// drone's own position.
    pub fn from_model(model: &ParafoilModel, time_s: f64, state: &StateVector) -> Self {
        let kin = Kinematics::new(&model.vehicle, state, model.controls().main_line_m);
        let drone = Body::Drone as usize;
        let t_ned_to_drone = kin.t_i_body[drone];
        let euler_rad = euler_from_t(&t_ned_to_drone);
        let euler_rate_rad_s = euler_rates(&euler_rad, &kin.omega_body[drone]);
        let position_ned_m = kin.position_ned_m[drone];
        let velocity_ned_mps = kin.velocity_ned_mps(Body::Drone);
        let env = &model.environment;
        let wind_ned_mps = env.wind.wind_ned_mps(time_s, &position_ned_m);
        let air = env
            .atmosphere
            .air_at(env.ground_altitude_msl_m - position_ned_m.z);
        Self {
            time_s,
            position_ned_m,
            velocity_ned_mps,
            euler_rad,
            euler_rate_rad_s,
            air_velocity_body_mps: t_ned_to_drone * (velocity_ned_mps - wind_ned_mps),
            wind_ned_mps,
            air,
        }
    }
}

/// One measurement on its way to the estimator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Delivery {
    /// Instant it reaches the estimator, s: the sampled instant plus the sensor's latency.
    pub arrival_s: f64,
    /// The measurement, stamped with the sampled instant (`measurement.time_s()`).
    pub measurement: Measurement,
}

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
            static_noise_pa: 2.0,
            static_bias_sigma_pa: 20.0,
            temperature_noise_k: 0.3,
            temperature_bias_sigma_k: 1.0,
        }
    }
}

/// Checks of one number.
fn check(
    field: &'static str,
    value: f64,
    ok: impl Fn(f64) -> bool,
    rule: &'static str,
) -> Result<(), SensorConfigError> {
    if value.is_finite() && ok(value) {
        Ok(())
    } else {
        Err(SensorConfigError::Invalid { field, value, rule })
    }
}

fn non_negative(field: &'static str, value: f64) -> Result<(), SensorConfigError> {
    check(field, value, |v| v >= 0.0, "finite and ≥ 0")
}

fn positive(field: &'static str, value: f64) -> Result<(), SensorConfigError> {
    check(field, value, |v| v > 0.0, "finite and > 0")
}

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
            |v| v > 0.0 && v <= MAX_RATE_HZ,
            "finite, > 0 and ≤ 1000 Hz",
        )?;
        non_negative(self.phase_s.0, self.phase_s.1)?;
        non_negative(self.latency_s.0, self.latency_s.1)?;
        check(
            self.dropout_probability.0,
            self.dropout_probability.1,
            |v| (0.0..=1.0).contains(&v),
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
        non_negative("pitot.static_noise_pa", p.static_noise_pa)?;
        non_negative("pitot.static_bias_sigma_pa", p.static_bias_sigma_pa)?;
        non_negative("pitot.temperature_noise_k", p.temperature_noise_k)?;
        non_negative("pitot.temperature_bias_sigma_k", p.temperature_bias_sigma_k)?;
        Ok(())
    }
}

/// A standard normal draw.
fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    StandardNormal.sample(rng)
}

/// When a sensor samples and whether a sample gets through.
#[derive(Debug, Clone)]
struct Schedule {
    period_s: f64,
    phase_s: f64,
    latency_s: f64,
    dropouts_s: Vec<[f64; 2]>,
    dropout_probability: f64,
    /// Index `n` of the next due instant `phase + n·period`; counting instants rather than
    /// adding periods keeps long runs free of accumulated rounding.
    next_index: u64,
    /// Instant of the previous sample, s, to advance the noise processes by the real interval.
    last_sample_s: Option<f64>,
    /// Draws for random dropouts, apart from the noise so that they do not shift it.
    dropout_rng: ChaCha8Rng,
}

/// Slack on "due", s: control ticks summed in floating point land a hair early.
const DUE_TOLERANCE_S: f64 = 1e-6;

/// What the schedule decides at one call.
struct Due {
    /// Time since the sensor's previous sample, s (0 for its first).
    elapsed_s: f64,
    /// The sample gets through (false: dropped by a window or at random).
    delivered: bool,
}

impl Schedule {
    fn new(
        rate_hz: f64,
        phase_s: f64,
        latency_s: f64,
        dropouts_s: &[[f64; 2]],
        dropout_probability: f64,
        dropout_rng: ChaCha8Rng,
    ) -> Self {
        Self {
            period_s: 1.0 / rate_hz,
            phase_s,
            latency_s,
            dropouts_s: dropouts_s.to_vec(),
            dropout_probability,
            next_index: 0,
            last_sample_s: None,
            dropout_rng,
        }
    }

    /// Whether the sensor samples at `time_s`; if so, advances to the next due instant.
    fn poll(&mut self, time_s: f64) -> Option<Due> {
        let next_s = self.phase_s + self.next_index as f64 * self.period_s;
        if !time_s.is_finite() || time_s + DUE_TOLERANCE_S < next_s {
            return None;
        }
        // The next instant strictly after this call: skipped instants are not made up.
        let passed = ((time_s + DUE_TOLERANCE_S - self.phase_s) / self.period_s).floor();
        self.next_index = (passed.max(0.0) as u64).saturating_add(1);
        let elapsed_s = self.last_sample_s.map_or(0.0, |last| time_s - last);
        self.last_sample_s = Some(time_s);
        // Always draw, so the dropout stream stays aligned with the samples whatever the
        // windows are.
        let draw: f64 = rand::RngExt::random(&mut self.dropout_rng);
        let in_window = self
            .dropouts_s
            .iter()
            .any(|&[from_s, to_s]| (from_s..=to_s).contains(&time_s));
        Some(Due {
            elapsed_s,
            delivered: !in_window && draw >= self.dropout_probability,
        })
    }
}

/// A first-order Gauss–Markov process, started from its stationary distribution.
#[derive(Debug, Clone, Copy)]
struct GaussMarkov {
    value: f64,
    sigma: f64,
    correlation_s: f64,
}

impl GaussMarkov {
    fn new(sigma: f64, correlation_s: f64, rng: &mut ChaCha8Rng) -> Self {
        Self {
            value: sigma * gauss(rng),
            sigma,
            correlation_s,
        }
    }

    /// Advances by `dt_s` with the exact discrete transition (any step keeps the variance σ²).
    fn step(&mut self, dt_s: f64, rng: &mut ChaCha8Rng) -> f64 {
        let decay = (-dt_s / self.correlation_s).exp();
        self.value = decay * self.value + self.sigma * (1.0 - decay * decay).sqrt() * gauss(rng);
        self.value
    }
}

/// The GPS receiver's running errors.
#[derive(Debug, Clone)]
struct Gps {
    config: GpsConfig,
    schedule: Schedule,
    rng: ChaCha8Rng,
    wander: [GaussMarkov; 3],
    /// This run's constant position (m) and velocity (m/s) biases, NED.
    position_bias_m: [f64; 3],
    velocity_bias_mps: [f64; 3],
}

impl Gps {
    fn sample(&mut self, time_s: f64, truth: &Truth) -> Option<Delivery> {
        let due = self.schedule.poll(time_s)?;
        let c = &self.config;
        let rng = &mut self.rng;
        let mut position = truth.position_ned_m;
        let mut velocity = truth.velocity_ned_mps;
        for axis in 0..3 {
            let (noise_m, vel_noise_mps) = if axis < 2 {
                (c.horizontal_noise_m, c.velocity_noise_mps)
            } else {
                (c.vertical_noise_m, c.vertical_velocity_noise_mps)
            };
            position[axis] += self.position_bias_m[axis]
                + self.wander[axis].step(due.elapsed_s, rng)
                + noise_m * gauss(rng);
            velocity[axis] += self.velocity_bias_mps[axis] + vel_noise_mps * gauss(rng);
        }
        due.delivered.then_some(Delivery {
            arrival_s: time_s + self.schedule.latency_s,
            measurement: Measurement::Gps(GpsFix {
                time_s,
                position_ned_m: position,
                velocity_ned_mps: velocity,
                horizontal_accuracy_m: c.reported_horizontal_accuracy_m,
                vertical_accuracy_m: c.reported_vertical_accuracy_m,
                speed_accuracy_mps: c.reported_speed_accuracy_mps,
            }),
        })
    }
}

/// The AHRS's running errors.
#[derive(Debug, Clone)]
struct Ahrs {
    config: AhrsConfig,
    schedule: Schedule,
    rng: ChaCha8Rng,
    /// Roll, pitch, yaw biases, rad.
    bias_rad: [f64; 3],
}

impl Ahrs {
    fn sample(&mut self, time_s: f64, truth: &Truth) -> Option<Delivery> {
        let due = self.schedule.poll(time_s)?;
        let c = &self.config;
        let rng = &mut self.rng;
        self.bias_rad[2] +=
            c.yaw_bias_random_walk_deg_per_sqrt_s.to_radians() * due.elapsed_s.sqrt() * gauss(rng);
        let noise_rad = [c.roll_noise_deg, c.pitch_noise_deg, c.yaw_noise_deg]
            .map(|sigma_deg| sigma_deg.to_radians() * gauss(rng));
        let angle = |axis: usize| truth.euler_rad[axis] + self.bias_rad[axis] + noise_rad[axis];
        due.delivered.then_some(Delivery {
            arrival_s: time_s + self.schedule.latency_s,
            measurement: Measurement::Attitude(AttitudeSample {
                time_s,
                roll_rad: wrap_pi(angle(0)),
                // An AHRS reports pitch in [−90°, 90°]; noise cannot push it past.
                pitch_rad: angle(1).clamp(-FRAC_PI_2, FRAC_PI_2),
                yaw_rad: wrap_pi(angle(2)),
            }),
        })
    }
}

/// The pitot's running errors.
#[derive(Debug, Clone)]
struct Pitot {
    config: PitotConfig,
    schedule: Schedule,
    rng: ChaCha8Rng,
    differential_offset_pa: f64,
    static_bias_pa: f64,
    temperature_bias_k: f64,
}

impl Pitot {
    fn sample(&mut self, time_s: f64, truth: &Truth) -> Option<Delivery> {
        let due = self.schedule.poll(time_s)?;
        let c = &self.config;
        let rng = &mut self.rng;
        self.differential_offset_pa +=
            c.differential_offset_random_walk_pa_per_sqrt_s * due.elapsed_s.sqrt() * gauss(rng);
        let u_x = truth.air_velocity_body_mps.x;
        let rho = truth.air.density_kg_per_m3;
        let differential_pressure_pa = 0.5 * rho * u_x * u_x.abs()
            + self.differential_offset_pa
            + c.differential_noise_pa * gauss(rng);
        let static_pressure_pa =
            truth.air.pressure_pa + self.static_bias_pa + c.static_noise_pa * gauss(rng);
        let temperature_k =
            truth.air.temperature_k + self.temperature_bias_k + c.temperature_noise_k * gauss(rng);
        due.delivered.then_some(Delivery {
            arrival_s: time_s + self.schedule.latency_s,
            measurement: Measurement::AirData(AirDataSample {
                time_s,
                differential_pressure_pa,
                static_pressure_pa,
                temperature_k,
            }),
        })
    }
}

/// Stream numbers of the independent random sequences drawn from one seed.
mod stream {
    pub const GPS_NOISE: u64 = 1;
    pub const AHRS_NOISE: u64 = 2;
    pub const PITOT_NOISE: u64 = 3;
    pub const GPS_DROPOUT: u64 = 11;
    pub const AHRS_DROPOUT: u64 = 12;
    pub const PITOT_DROPOUT: u64 = 13;
    pub const GPS_BIAS: u64 = 21;
}

fn rng_for(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

/// The running sensor set of one simulated flight.
#[derive(Debug, Clone)]
pub struct SensorSuite {
    gps: Gps,
    ahrs: Ahrs,
    pitot: Pitot,
}

impl SensorSuite {
    /// Validates `config` and draws this run's biases from `seed`.
    pub fn new(config: &SensorConfig, seed: u64) -> Result<Self, SensorConfigError> {
        config.validate()?;
        let g = &config.gps;
        let mut gps_rng = rng_for(seed, stream::GPS_NOISE);
        let wander = [
            g.horizontal_wander_m,
            g.horizontal_wander_m,
            g.vertical_wander_m,
        ]
        .map(|sigma| GaussMarkov::new(sigma, g.wander_correlation_s, &mut gps_rng));
        // A stream of their own, so that switching the biases on changes nothing else.
        let mut bias_rng = rng_for(seed, stream::GPS_BIAS);
        let position_bias_m = [
            g.horizontal_bias_sigma_m,
            g.horizontal_bias_sigma_m,
            g.vertical_bias_sigma_m,
        ]
        .map(|sigma| sigma * gauss(&mut bias_rng));
        let velocity_bias_mps =
            [g.velocity_bias_sigma_mps; 3].map(|sigma| sigma * gauss(&mut bias_rng));
        let gps = Gps {
            schedule: Schedule::new(
                g.rate_hz,
                g.phase_s,
                g.latency_s,
                &g.dropouts_s,
                g.dropout_probability,
                rng_for(seed, stream::GPS_DROPOUT),
            ),
            config: g.clone(),
            rng: gps_rng,
            wander,
            position_bias_m,
            velocity_bias_mps,
        };

        let a = &config.ahrs;
        let mut ahrs_rng = rng_for(seed, stream::AHRS_NOISE);
        let bias_rad = [
            a.roll_bias_sigma_deg,
            a.pitch_bias_sigma_deg,
            a.yaw_bias_sigma_deg,
        ]
        .map(|sigma_deg| sigma_deg.to_radians() * gauss(&mut ahrs_rng));
        let ahrs = Ahrs {
            schedule: Schedule::new(
                a.rate_hz,
                a.phase_s,
                a.latency_s,
                &a.dropouts_s,
                a.dropout_probability,
                rng_for(seed, stream::AHRS_DROPOUT),
            ),
            config: a.clone(),
            rng: ahrs_rng,
            bias_rad,
        };

        let p = &config.pitot;
        let mut pitot_rng = rng_for(seed, stream::PITOT_NOISE);
        let differential_offset_pa = p.differential_offset_sigma_pa * gauss(&mut pitot_rng);
        let static_bias_pa = p.static_bias_sigma_pa * gauss(&mut pitot_rng);
        let temperature_bias_k = p.temperature_bias_sigma_k * gauss(&mut pitot_rng);
        let pitot = Pitot {
            schedule: Schedule::new(
                p.rate_hz,
                p.phase_s,
                p.latency_s,
                &p.dropouts_s,
                p.dropout_probability,
                rng_for(seed, stream::PITOT_DROPOUT),
            ),
            config: p.clone(),
            rng: pitot_rng,
            differential_offset_pa,
            static_bias_pa,
            temperature_bias_k,
        };
        Ok(Self { gps, ahrs, pitot })
    }

    /// Samples every sensor that is due at `time_s` (call every control tick, times
    /// non-decreasing) and returns what gets through, in the order AHRS, GPS, pitot.
    pub fn sample(&mut self, time_s: f64, truth: &Truth) -> Vec<Delivery> {
        [
            self.ahrs.sample(time_s, truth),
            self.gps.sample(time_s, truth),
            self.pitot.sample(time_s, truth),
        ]
        .into_iter()
        .flatten()
        .collect()
    }

    /// This run's AHRS biases (roll, pitch, yaw), rad: what a test compares the estimator's
    /// heading error with.
    pub fn ahrs_bias_rad(&self) -> Vector3<f64> {
        Vector3::from(self.ahrs.bias_rad)
    }

    /// This run's differential-pressure offset, Pa.
    pub fn differential_offset_pa(&self) -> f64 {
        self.pitot.differential_offset_pa
    }
}

/// Deliveries waiting for their arrival time, handed out in arrival order (ties in the order
/// they were pushed).
#[derive(Debug, Clone, Default)]
pub struct DeliveryQueue {
    waiting: VecDeque<Delivery>,
}

impl DeliveryQueue {
    /// An empty queue.
    pub fn new() -> Self {
        Self::default()
    }

    /// Queues a delivery.
    pub fn push(&mut self, delivery: Delivery) {
        // Few deliveries wait at once (latency × rates), so a linear insertion is cheapest.
        let at = self
            .waiting
            .iter()
            .rposition(|d| d.arrival_s <= delivery.arrival_s)
            .map_or(0, |i| i + 1);
        self.waiting.insert(at, delivery);
    }

    /// The earliest delivery that has arrived by `now_s`, if any.
    pub fn pop_due(&mut self, now_s: f64) -> Option<Delivery> {
        if self.waiting.front()?.arrival_s <= now_s {
            self.waiting.pop_front()
        } else {
            None
        }
    }

    /// Deliveries still waiting.
    pub fn len(&self) -> usize {
        self.waiting.len()
    }

    /// Whether none is waiting.
    pub fn is_empty(&self) -> bool {
        self.waiting.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;
    use stx_dynamics::atmosphere::{Atmosphere, StandardAtmosphere};
    use stx_dynamics::model::Environment;
    use stx_dynamics::state::Pose;
    use stx_dynamics::vehicle::Vehicle;
    use stx_dynamics::wind::ConstantWind;

    const TICK_S: f64 = 0.05;

    /// A drone gliding north-east at 1000 m with 7 m/s along its x axis.
    fn truth_at(time_s: f64) -> Truth {
        Truth {
            time_s,
            position_ned_m: Vector3::new(100.0, -50.0, -1000.0),
            velocity_ned_mps: Vector3::new(4.0, 3.0, 3.0),
            euler_rad: Vector3::new(0.05, -0.1, 0.6),
            euler_rate_rad_s: Vector3::zeros(),
            air_velocity_body_mps: Vector3::new(7.0, 0.3, 2.2),
            wind_ned_mps: Vector3::new(-1.0, 2.0, 0.0),
            air: StandardAtmosphere.air_at(1000.0),
        }
    }

    /// A configuration with every error switched off, for exact checks.
    fn noiseless() -> SensorConfig {
        let mut c = SensorConfig::default();
        let g = &mut c.gps;
        g.horizontal_noise_m = 0.0;
        g.vertical_noise_m = 0.0;
        g.horizontal_wander_m = 0.0;
        g.vertical_wander_m = 0.0;
        g.velocity_noise_mps = 0.0;
        g.vertical_velocity_noise_mps = 0.0;
        let a = &mut c.ahrs;
        a.roll_noise_deg = 0.0;
        a.pitch_noise_deg = 0.0;
        a.yaw_noise_deg = 0.0;
        a.roll_bias_sigma_deg = 0.0;
        a.pitch_bias_sigma_deg = 0.0;
        a.yaw_bias_sigma_deg = 0.0;
        a.yaw_bias_random_walk_deg_per_sqrt_s = 0.0;
        let p = &mut c.pitot;
        p.differential_noise_pa = 0.0;
        p.differential_offset_sigma_pa = 0.0;
        p.differential_offset_random_walk_pa_per_sqrt_s = 0.0;
        p.static_noise_pa = 0.0;
        p.static_bias_sigma_pa = 0.0;
        p.temperature_noise_k = 0.0;
        p.temperature_bias_sigma_k = 0.0;
        c
    }

    /// Every delivery of a run of `duration_s` ticked every 0.05 s.
    fn run(config: &SensorConfig, seed: u64, duration_s: f64) -> Vec<Delivery> {
        let mut suite = SensorSuite::new(config, seed).expect("valid config");
        let ticks = (duration_s / TICK_S).round() as usize;
        (0..ticks)
            .flat_map(|k| {
                let t = k as f64 * TICK_S;
                suite.sample(t, &truth_at(t))
            })
            .collect()
    }

    fn gps(d: &[Delivery]) -> Vec<GpsFix> {
        d.iter()
            .filter_map(|d| match d.measurement {
                Measurement::Gps(g) => Some(g),
                _ => None,
            })
            .collect()
    }

    fn attitude(d: &[Delivery]) -> Vec<AttitudeSample> {
        d.iter()
            .filter_map(|d| match d.measurement {
                Measurement::Attitude(a) => Some(a),
                _ => None,
            })
            .collect()
    }

    fn air_data(d: &[Delivery]) -> Vec<AirDataSample> {
        d.iter()
            .filter_map(|d| match d.measurement {
                Measurement::AirData(a) => Some(a),
                _ => None,
            })
            .collect()
    }

    fn mean_and_sigma(values: impl Iterator<Item = f64>) -> (f64, f64) {
        let v: Vec<f64> = values.collect();
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
        (mean, var.sqrt())
    }

    #[test]
    fn each_sensor_samples_at_its_own_rate_and_phase() {
        let mut c = SensorConfig::default();
        c.gps.rate_hz = 4.0;
        c.gps.phase_s = 0.1;
        c.ahrs.rate_hz = 10.0;
        c.pitot.rate_hz = 5.0;
        let d = run(&c, 1, 100.0);
        let fixes = gps(&d);
        assert_eq!(fixes.len(), 400);
        assert!((fixes[0].time_s - 0.1).abs() < 1e-9);
        for pair in fixes.windows(2) {
            assert!((pair[1].time_s - pair[0].time_s - 0.25).abs() < 1e-9);
        }
        assert_eq!(attitude(&d).len(), 1000);
        assert_eq!(air_data(&d).len(), 500);
    }

    #[test]
    fn a_tick_coarser_than_the_period_skips_samples_rather_than_bunching_them() {
        let mut c = SensorConfig::default();
        c.ahrs.rate_hz = 50.0;
        let mut suite = SensorSuite::new(&c, 1).expect("valid");
        let mut count = 0;
        for k in 0..100 {
            let t = k as f64 * 0.1;
            count += attitude(&suite.sample(t, &truth_at(t))).len();
        }
        assert_eq!(count, 100, "one sample per call, none invented");
    }

    #[test]
    fn arrival_is_the_sampled_instant_plus_the_sensors_latency() {
        let mut c = SensorConfig::default();
        c.gps.latency_s = 0.3;
        c.ahrs.latency_s = 0.02;
        c.pitot.latency_s = 0.07;
        for d in run(&c, 2, 10.0) {
            let latency = match d.measurement {
                Measurement::Gps(_) => 0.3,
                Measurement::Attitude(_) => 0.02,
                Measurement::AirData(_) => 0.07,
            };
            assert!((d.arrival_s - d.measurement.time_s() - latency).abs() < 1e-12);
        }
    }

    #[test]
    fn without_errors_the_sensors_report_the_truth() {
        let d = run(&noiseless(), 3, 5.0);
        let truth = truth_at(0.0);
        let fix = gps(&d)[3];
        assert!((fix.position_ned_m - truth.position_ned_m).norm() < 1e-12);
        assert!((fix.velocity_ned_mps - truth.velocity_ned_mps).norm() < 1e-12);
        let a = attitude(&d)[3];
        assert!(
            (Vector3::new(a.roll_rad, a.pitch_rad, a.yaw_rad) - truth.euler_rad).norm() < 1e-12
        );
        let p = air_data(&d)[3];
        assert!((p.static_pressure_pa - truth.air.pressure_pa).abs() < 1e-9);
        assert!((p.temperature_k - truth.air.temperature_k).abs() < 1e-9);
        // Bernoulli with the density from p and T gives back u_x (the ideal-gas constants
        // of the atmosphere and the measurement agree to 1e-6).
        let u_x = truth.air_velocity_body_mps.x;
        assert!((p.indicated_airspeed_mps() - u_x).abs() < 1e-4 * u_x);
    }

    #[test]
    fn air_from_behind_gives_a_negative_differential_pressure_and_no_airspeed() {
        let mut suite = SensorSuite::new(&noiseless(), 4).expect("valid");
        let mut truth = truth_at(0.0);
        truth.air_velocity_body_mps.x = -3.0;
        let p = air_data(&suite.sample(0.0, &truth))[0];
        let rho = truth.air.density_kg_per_m3;
        assert!((p.differential_pressure_pa + 0.5 * rho * 9.0).abs() < 1e-9);
        assert_eq!(p.indicated_airspeed_mps(), 0.0);
    }

    #[test]
    fn noise_has_the_configured_spread_and_biases_are_drawn_once() {
        let mut c = noiseless();
        c.gps.horizontal_noise_m = 0.8;
        c.gps.velocity_noise_mps = 0.2;
        c.ahrs.yaw_noise_deg = 1.5;
        c.ahrs.yaw_bias_sigma_deg = 3.0;
        c.pitot.differential_noise_pa = 0.5;
        c.pitot.differential_offset_sigma_pa = 0.4;
        let truth = truth_at(0.0);
        let d = run(&c, 5, 1000.0);
        let fixes = gps(&d);
        let (mean, sigma) = mean_and_sigma(
            fixes
                .iter()
                .map(|f| f.position_ned_m.x - truth.position_ned_m.x),
        );
        assert!(
            mean.abs() < 0.05 && (sigma / 0.8 - 1.0).abs() < 0.05,
            "{mean} {sigma}"
        );
        let (mean, sigma) = mean_and_sigma(
            fixes
                .iter()
                .map(|f| f.velocity_ned_mps.y - truth.velocity_ned_mps.y),
        );
        assert!(
            mean.abs() < 0.02 && (sigma / 0.2 - 1.0).abs() < 0.05,
            "{mean} {sigma}"
        );

        let suite = SensorSuite::new(&c, 5).expect("valid");
        let bias = suite.ahrs_bias_rad().z;
        let (mean, sigma) = mean_and_sigma(
            attitude(&d)
                .iter()
                .map(|a| wrap_pi(a.yaw_rad - truth.euler_rad.z)),
        );
        assert!((mean - bias).abs() < 1e-3, "mean {mean} is the bias {bias}");
        assert!((sigma / 1.5f64.to_radians() - 1.0).abs() < 0.05);

        let offset = suite.differential_offset_pa();
        let rho = truth.air.density_kg_per_m3;
        let u_x = truth.air_velocity_body_mps.x;
        let (mean, sigma) = mean_and_sigma(
            air_data(&d)
                .iter()
                .map(|p| p.differential_pressure_pa - 0.5 * rho * u_x * u_x),
        );
        assert!(
            (mean - offset).abs() < 0.02,
            "mean {mean} is the offset {offset}"
        );
        assert!((sigma / 0.5 - 1.0).abs() < 0.05);

        // Over seeds the biases spread as configured.
        let biases: Vec<f64> = (0..400)
            .map(|seed| {
                SensorSuite::new(&c, seed)
                    .expect("valid")
                    .ahrs_bias_rad()
                    .z
                    .to_degrees()
            })
            .collect();
        let (mean, sigma) = mean_and_sigma(biases.into_iter());
        assert!(
            mean.abs() < 0.5 && (sigma / 3.0 - 1.0).abs() < 0.1,
            "{mean} {sigma}"
        );
    }

    #[test]
    fn gps_wander_is_a_slow_gauss_markov_error() {
        let mut c = noiseless();
        c.gps.horizontal_wander_m = 2.0;
        c.gps.wander_correlation_s = 20.0;
        let truth = truth_at(0.0);
        let errors: Vec<f64> = gps(&run(&c, 6, 4000.0))
            .iter()
            .map(|f| f.position_ned_m.y - truth.position_ned_m.y)
            .collect();
        let (_, sigma) = mean_and_sigma(errors.iter().copied());
        assert!((sigma / 2.0 - 1.0).abs() < 0.15, "stationary σ {sigma}");
        // Correlation over one fix (0.25 s) is e^(−0.25/20) ≈ 0.988; over 20 s, e^(−1).
        let correlation = |lag: usize| {
            let n = errors.len() - lag;
            let c: f64 = (0..n).map(|i| errors[i] * errors[i + lag]).sum::<f64>() / n as f64;
            c / sigma.powi(2)
        };
        assert!((correlation(1) - 0.988).abs() < 0.01, "{}", correlation(1));
        assert!(
            (correlation(80) - (-1f64).exp()).abs() < 0.12,
            "{}",
            correlation(80)
        );
    }

    #[test]
    fn the_same_seed_gives_the_same_deliveries_and_another_seed_others() {
        let c = SensorConfig::default();
        assert_eq!(run(&c, 7, 30.0), run(&c, 7, 30.0));
        assert_ne!(run(&c, 7, 30.0), run(&c, 8, 30.0));
    }

    #[test]
    fn dropout_windows_and_random_losses_remove_samples_and_nothing_else() {
        let base = SensorConfig::default();
        let mut c = base.clone();
        c.gps.dropouts_s = vec![[10.0, 20.0]];
        c.pitot.dropout_probability = 0.3;
        let full = run(&base, 9, 60.0);
        let lossy = run(&c, 9, 60.0);
        let fixes = gps(&lossy);
        assert!(fixes.iter().all(|f| !(10.0..=20.0).contains(&f.time_s)));
        // 41 fixes fall in [10, 20] at 4 Hz.
        assert_eq!(fixes.len(), gps(&full).len() - 41);
        // The fixes that remain are the very same: a dropout does not reshuffle the noise.
        assert!(fixes.iter().all(|f| gps(&full).contains(f)));
        assert_eq!(attitude(&lossy), attitude(&full));
        let kept = air_data(&lossy).len() as f64 / air_data(&full).len() as f64;
        assert!((kept - 0.7).abs() < 0.05, "kept {kept}");
        assert!(air_data(&lossy).iter().all(|p| air_data(&full).contains(p)));
    }

    #[test]
    fn invalid_settings_are_refused_with_the_field_named() {
        let mut c = SensorConfig::default();
        c.gps.rate_hz = 0.0;
        assert!(matches!(
            SensorSuite::new(&c, 0),
            Err(SensorConfigError::Invalid {
                field: "gps.rate_hz",
                ..
            })
        ));
        let mut c = SensorConfig::default();
        c.pitot.differential_noise_pa = f64::NAN;
        assert!(matches!(
            c.validate(),
            Err(SensorConfigError::Invalid {
                field: "pitot.differential_noise_pa",
                ..
            })
        ));
        let mut c = SensorConfig::default();
        c.ahrs.dropouts_s = vec![[5.0, 6.0], [8.0, 7.0]];
        assert!(matches!(
            c.validate(),
            Err(SensorConfigError::DropoutWindow {
                field: "ahrs.dropouts_s",
                index: 1,
                ..
            })
        ));
        let mut c = SensorConfig::default();
        c.gps.dropout_probability = 1.5;
        let message = c.validate().expect_err("refused").to_string();
        assert!(message.contains("gps.dropout_probability"), "{message}");
    }

    #[test]
    fn toml_names_only_what_it_changes_and_unknown_keys_are_refused() {
        let c: SensorConfig = toml::from_str(
            "[gps]\nlatency_s = 0.4\ndropouts_s = [[60.0, 70.0]]\n[ahrs]\nyaw_bias_sigma_deg = 5.0\n",
        )
        .expect("valid TOML");
        assert_eq!(c.gps.latency_s, 0.4);
        assert_eq!(c.gps.dropouts_s, vec![[60.0, 70.0]]);
        assert_eq!(c.ahrs.yaw_bias_sigma_deg, 5.0);
        assert_eq!(c.pitot, PitotConfig::default());
        assert!(toml::from_str::<SensorConfig>("[gps]\nlatncy_s = 0.4\n").is_err());
        assert!(toml::from_str::<SensorConfig>("[magnetometer]\n").is_err());
    }

    #[test]
    fn the_queue_hands_out_deliveries_in_arrival_order_when_due() {
        let mut q = DeliveryQueue::new();
        let mut suite = SensorSuite::new(&SensorConfig::default(), 10).expect("valid");
        for d in suite.sample(0.0, &truth_at(0.0)) {
            q.push(d);
        }
        // AHRS and pitot arrive at 0.02 s, GPS at 0.25 s.
        assert!(q.pop_due(0.01).is_none());
        let first = q.pop_due(0.05).expect("due");
        let second = q.pop_due(0.05).expect("due");
        assert!(matches!(first.measurement, Measurement::Attitude(_)));
        assert!(matches!(second.measurement, Measurement::AirData(_)));
        assert!(q.pop_due(0.05).is_none());
        assert_eq!(q.len(), 1);
        assert!(matches!(
            q.pop_due(0.25).expect("due").measurement,
            Measurement::Gps(_)
        ));
        assert!(q.is_empty());
    }

    #[test]
    fn truth_from_the_model_is_the_drones_state_in_the_models_air() {
        let wind = ConstantWind::from_speed_direction(4.0, 270.0).expect("valid wind");
        let model = ParafoilModel::new(
            Vehicle::straplex(),
            Environment {
                atmosphere: Arc::new(StandardAtmosphere),
                wind: Arc::new(wind),
                ground_altitude_msl_m: 300.0,
            },
        );
        let x = Pose {
            position_ned_m: [0.0, 0.0, -500.0],
            canopy_euler_deg: [0.0, 6.5, 30.0],
            canopy_velocity_mps: [6.0, 0.0, 2.0],
            line_pitch_deg: -5.0,
            drone_euler_deg: [0.0, 5.0, 0.0],
            ..Default::default()
        }
        .to_state();
        let truth = Truth::from_model(&model, 3.0, &x);
        let kin = Kinematics::new(&model.vehicle, &x, 0.0);
        assert_eq!(
            truth.position_ned_m,
            kin.position_ned_m[Body::Drone as usize]
        );
        // Wind from the west blows east.
        assert!((truth.wind_ned_mps - Vector3::new(0.0, 4.0, 0.0)).norm() < 1e-12);
        // The air at the drone's altitude above sea level (ground at 300 m).
        let altitude = 300.0 - truth.position_ned_m.z;
        assert_eq!(truth.air, StandardAtmosphere.air_at(altitude));
        // Air-relative velocity in the drone frame has the same length as in NED.
        let speed = (truth.velocity_ned_mps - truth.wind_ned_mps).norm();
        assert!((truth.air_velocity_body_mps.norm() - speed).abs() < 1e-12);
        // The canopy yaws 30°, the drone hangs aligned with it.
        assert!((truth.euler_rad.z - 30f64.to_radians()).abs() < 1e-9);
    }

    /// The GPS's constant biases: the same offset on every fix of a run, drawn from the seed
    /// (another seed, another offset), nothing without them.
    #[test]
    fn gps_bias_is_constant_over_a_run_and_drawn_from_the_seed() {
        let mut c = noiseless();
        let errors = |config: &SensorConfig, seed: u64| {
            let mut suite = SensorSuite::new(config, seed).expect("valid");
            let mut out = Vec::new();
            for k in 0..40 {
                let t = 0.25 * k as f64;
                let truth = truth_at(t);
                for d in suite.sample(t, &truth) {
                    if let Measurement::Gps(g) = d.measurement {
                        out.push((
                            g.position_ned_m - truth.position_ned_m,
                            g.velocity_ned_mps - truth.velocity_ned_mps,
                        ));
                    }
                }
            }
            out
        };
        let none = errors(&c, 7);
        assert!(none.iter().all(|(p, v)| p.norm() < 1e-9 && v.norm() < 1e-9));
        c.gps.horizontal_bias_sigma_m = 2.0;
        c.gps.vertical_bias_sigma_m = 3.0;
        c.gps.velocity_bias_sigma_mps = 0.2;
        let biased = errors(&c, 7);
        assert!(biased.len() > 30);
        let (p0, v0) = biased[0];
        assert!(p0.norm() > 1e-3 && v0.norm() > 1e-4, "{p0:?} {v0:?}");
        assert!(
            biased
                .iter()
                .all(|(p, v)| (p - p0).norm() < 1e-9 && (v - v0).norm() < 1e-9),
            "constant over the run"
        );
        assert_eq!(errors(&c, 7)[0].0, p0, "same seed, same bias");
        assert_ne!(errors(&c, 8)[0].0, p0, "another seed, another bias");
        c.gps.velocity_bias_sigma_mps = -1.0;
        assert!(SensorSuite::new(&c, 1).is_err());
    }
}
