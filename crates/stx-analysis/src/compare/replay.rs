//! Flying the model through a recorded flight: from the recorded initial state, with the
//! recorded servo commands and the recorded wind estimate.
//!
//! A log holds the drone's position, velocity and attitude, not the 31 states of the stack,
//! so the start is the model's own steady glide ([`crate::trim`]) at the recorded altitude
//! with the recorded brakes (symmetric part; the main line is released in a trim, the
//! recorded one is applied from the first step), turned to the recorded heading, moved so
//! that the drone is where the GPS put it, and carried by the recorded wind: every body
//! hanging at equilibrium, as the model would fly it. The flight's first seconds then hold
//! the transient from that glide to the recorded one; a flight logged in a steady glide has
//! almost none.
//!
//! Each recorded command is held until the next one (see [`FlightLog::commands_at`]); the
//! integration (fixed-step RK4) steps land on the log's instants, so no step straddles a
//! command change. The wind is the
//! estimate interpolated in time, uniform in space: what the drone knew.
//!
//! Identification also corrects what the drone knew ([`Nuisance`]): its start's heading, and
//! the scale of its air data. An estimator whose airspeed reads a few per cent low puts the
//! missing air speed into the wind, along the drone's heading; a replay through that wind
//! flies a model that must be draggier to match the recorded ground track (the simulated
//! drone's recordings gave a drag 33 % high that way, see `stx_analysis::identify`).

use std::sync::Arc;

use nalgebra::Vector3;
use stx_dynamics::atmosphere::StandardAtmosphere;
use stx_dynamics::integrate::{Hooks, IntegrateError, Rk4, integrate};
use stx_dynamics::model::{Body, Environment, Kinematics, ParafoilModel};
use stx_dynamics::rotation::euler_from_t;
use stx_dynamics::state::{Controls, StateVector, idx};
use stx_dynamics::vehicle::Vehicle;
use stx_dynamics::wind::WindField;
use stx_sim::sensors::Truth;
use thiserror::Error;

use crate::flight_log::{FlightLog, LogSample};
use crate::trim::{TrimError, trim};

/// Why the model could not fly a log.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ReplayError {
    /// No steady glide to start from (the vehicle, the altitude or the brakes).
    #[error("no initial glide for the recorded start")]
    Trim(#[from] TrimError),
    /// The integration failed (the model diverged).
    #[error("the model could not fly the recorded commands")]
    Integrate(#[from] IntegrateError),
    /// The vehicle is not one the model can fly (a fitted value broke a rule).
    #[error("invalid vehicle: {0}")]
    InvalidVehicle(String),
    /// The integration step is not a positive number of seconds.
    #[error("integration step {0} s must be positive and finite")]
    BadStep(f64),
    /// The caller asked the replay to stop (a cancelled or timed-out Lab job).
    #[error("stopped at {time_s:.1} s of the flight")]
    Stopped {
        /// The log's time reached, s.
        time_s: f64,
    },
}

/// What the model's drone did at one recorded instant (what its sensors would have seen).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Flown {
    /// Time, s (the log's).
    pub time_s: f64,
    /// Drone position, NED (down from mean sea level), m.
    pub position_ned_m: [f64; 3],
    /// Drone velocity over the ground, NED, m/s.
    pub velocity_ned_mps: [f64; 3],
    /// Drone roll, pitch, yaw, rad.
    pub euler_rad: [f64; 3],
    /// Drone true airspeed, m/s.
    pub airspeed_mps: f64,
}

/// The recorded wind estimate as a wind field: interpolated in time, the same everywhere.
struct LogWind {
    times: Vec<f64>,
    winds: Vec<[f64; 3]>,
}

impl WindField for LogWind {
    fn wind_ned_mps(&self, time_s: f64, _position_ned_m: &Vector3<f64>) -> Vector3<f64> {
        let i = self.times.partition_point(|t| *t <= time_s);
        let w = if i == 0 {
            self.winds[0]
        } else if i == self.times.len() {
            self.winds[i - 1]
        } else {
            let (a, b) = (self.times[i - 1], self.times[i]);
            let f = (time_s - a) / (b - a);
            let (wa, wb) = (self.winds[i - 1], self.winds[i]);
            std::array::from_fn(|k| wa[k] + f * (wb[k] - wa[k]))
        };
        Vector3::from(w)
    }
}

/// What a replay corrects in a recorded flight besides the vehicle: fitted per flight by
/// identification, zero for a plain comparison.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Nuisance {
    /// Turn of the start from the recorded heading, rad (one noisy heading sample sets the
    /// course of the whole replay).
    pub turn_rad: f64,
    /// How much faster the air went past the drone than its recorded air data say, as a
    /// fraction `s`: the horizontal air velocity the drone estimated (its ground velocity less
    /// its wind) is taken as `1 + s` times too small, so the wind flown is `w − s·(v − w)` and
    /// the airspeed compared is `(1 + s)·a`.
    pub air_scale: f64,
}

impl Nuisance {
    /// The wind flown at a recorded instant, NED, m/s.
    pub fn wind_ned_mps(&self, s: &LogSample) -> [f64; 3] {
        let w = s.wind_ned_mps;
        let v = s.velocity_ned_mps;
        [
            w[0] - self.air_scale * (v[0] - w[0]),
            w[1] - self.air_scale * (v[1] - w[1]),
            w[2],
        ]
    }

    /// A recorded airspeed as corrected, m/s.
    pub fn airspeed_mps(&self, recorded_mps: f64) -> f64 {
        (1.0 + self.air_scale) * recorded_mps
    }
}

fn controls(log: &FlightLog, vehicle: &Vehicle, time_s: f64) -> Controls {
    let [main_line, brake_right, brake_left] = log.commands_at(time_s);
    Controls {
        main_line_m: main_line * vehicle.main_line_travel_m,
        brake_right,
        brake_left,
    }
    .saturated(vehicle.main_line_travel_m)
}

/// The stack's state at the log's first sample (see the module doc), corrected by
/// `nuisance` (its start turned from the recorded heading, its wind as corrected).
pub fn initial_state(
    log: &FlightLog,
    vehicle: &Vehicle,
    nuisance: Nuisance,
) -> Result<StateVector, ReplayError> {
    let first = log.samples()[0];
    let c = controls(log, vehicle, first.time_s);
    let brake = 0.5 * (c.brake_right + c.brake_left);
    let glide = trim(
        vehicle,
        -first.position_ned_m[2],
        Controls::symmetric_brake(brake),
    )?;
    let mut x = glide.state;
    let drone = Body::Drone as usize;
    let kin = Kinematics::new(vehicle, &x, 0.0);
    let drone_yaw = euler_from_t(&kin.t_i_body[drone]).z;
    x[idx::CANOPY_EULER + 2] += first.euler_rad[2] + nuisance.turn_rad - drone_yaw;
    x[idx::MAIN_LINE] = c.main_line_m;
    x[idx::BRAKE_RIGHT] = c.brake_right;
    x[idx::BRAKE_LEFT] = c.brake_left;
    let kin = Kinematics::new(vehicle, &x, c.main_line_m);
    let shift = Vector3::from(first.position_ned_m) - kin.position_ned_m[drone];
    let wind_canopy =
        kin.t_i_body[Body::Canopy as usize] * Vector3::from(nuisance.wind_ned_mps(&first));
    for k in 0..3 {
        x[idx::POSITION + k] += shift[k];
        x[idx::CANOPY_VELOCITY + k] += wind_canopy[k];
    }
    Ok(x)
}

/// Flies `vehicle` through `log` with RK4 steps of at most `step_s`, and returns what its
/// drone did at each of the log's instants.
pub fn fly(log: &FlightLog, vehicle: &Vehicle, step_s: f64) -> Result<Vec<Flown>, ReplayError> {
    fly_corrected(log, vehicle, step_s, Nuisance::default())
}

/// [`fly`] with the recorded flight corrected by `nuisance`.
pub fn fly_corrected(
    log: &FlightLog,
    vehicle: &Vehicle,
    step_s: f64,
    nuisance: Nuisance,
) -> Result<Vec<Flown>, ReplayError> {
    fly_from(log, vehicle, step_s, nuisance, |_, _| true)
}

/// [`fly`], telling `go(done, total)` the samples flown after each one; it stops with
/// [`ReplayError::Stopped`] when `go` answers false (a long recording flies for seconds, and a
/// Lab job must stop when cancelled).
pub fn fly_watched(
    log: &FlightLog,
    vehicle: &Vehicle,
    step_s: f64,
    go: impl FnMut(usize, usize) -> bool,
) -> Result<Vec<Flown>, ReplayError> {
    fly_from(log, vehicle, step_s, Nuisance::default(), go)
}

fn fly_from(
    log: &FlightLog,
    vehicle: &Vehicle,
    step_s: f64,
    nuisance: Nuisance,
    mut go: impl FnMut(usize, usize) -> bool,
) -> Result<Vec<Flown>, ReplayError> {
    if !(step_s.is_finite() && step_s > 0.0) {
        return Err(ReplayError::BadStep(step_s));
    }
    let samples = log.samples();
    let wind = LogWind {
        times: samples.iter().map(|s| s.time_s).collect(),
        winds: samples.iter().map(|s| nuisance.wind_ned_mps(s)).collect(),
    };
    let mut model = ParafoilModel::new(
        vehicle.clone(),
        Environment {
            atmosphere: Arc::new(StandardAtmosphere),
            wind: Arc::new(wind),
            ground_altitude_msl_m: 0.0,
        },
    );
    let mut x = initial_state(log, vehicle, nuisance)?;
    let mut out = Vec::with_capacity(samples.len());
    let mut t = samples[0].time_s;
    for (k, s) in samples.iter().enumerate() {
        if k > 0 {
            let span = s.time_s - t;
            let n = (span / step_s).ceil().max(1.0);
            let h = span / n;
            let mut stepper = Rk4::new(h);
            for i in 0..n as usize {
                let t0 = t + h * i as f64;
                model.set_controls(controls(log, vehicle, t0 + 0.5 * h));
                x = integrate(&mut stepper, &mut model, t0, &x, t0 + h, Hooks::default())?.state;
            }
            t = s.time_s;
        }
        model.set_controls(controls(log, vehicle, t));
        let truth = Truth::from_model(&model, t, &x);
        out.push(Flown {
            time_s: t,
            position_ned_m: truth.position_ned_m.into(),
            velocity_ned_mps: truth.velocity_ned_mps.into(),
            euler_rad: truth.euler_rad.into(),
            airspeed_mps: truth.air_velocity_body_mps.norm(),
        });
        if !go(k + 1, samples.len()) {
            return Err(ReplayError::Stopped { time_s: t });
        }
    }
    Ok(out)
}
