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
//!   [`Truth::from_model`] (this file);
//! - [`SensorConfig`] (`config.rs`) describes every sensor (rates, latencies, noise, biases, dropouts). It is
//!   read from TOML or built in code, and [`SensorConfig::validate`] checks it before a run;
//! - [`SensorSuite`] (`suite.rs`) is the running sensor set: call [`SensorSuite::sample`] every control tick
//!   with the truth at that instant; each sensor that is due emits a [`Delivery`] stamped with
//!   the sampled instant and the later instant it reaches the estimator;
//! - [`DeliveryQueue`] (`queue.rs`) holds deliveries until their arrival time, for the simulation loop.
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

mod config;
mod queue;
mod suite;
#[cfg(test)]
mod tests;

use nalgebra::Vector3;
use stx_dynamics::atmosphere::AirState;
use stx_dynamics::model::{Body, Kinematics, ParafoilModel};
use stx_dynamics::rotation::{euler_from_t, euler_rates};
use stx_dynamics::state::StateVector;
use stx_gnc::measurement::Measurement;

pub use config::{AhrsConfig, GpsConfig, PitotConfig, SensorConfig, SensorConfigError};
pub use queue::DeliveryQueue;
pub use suite::SensorSuite;
pub(crate) use suite::rng_for;

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
