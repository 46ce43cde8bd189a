//! Flights made up for tests and examples: a vehicle flown by stx-sim's open-loop simulator
//! (its own integrator, its own initial pose, not [`crate::compare::replay`]) through a
//! schedule of turns and brakes in a steady wind, and sampled as a drone's telemetry with
//! white sensor noise. A log of a vehicle whose coefficients are known, so that comparison
//! and identification can be checked against the truth.
//!
//! The log starts after `settle_s`, once the stack has settled from the scenario's rough
//! initial pose into its glide.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};
use stx_dynamics::model::Body;
use stx_dynamics::vehicle::Vehicle;
use stx_sim::open_loop;
use stx_sim::run::RunError;
use stx_sim::scenario::{Scenario, ScenarioError};
use thiserror::Error;

use super::{FlightLog, FlightLogError, LogSample};

/// Why no synthetic flight was made.
#[derive(Debug, Error)]
pub enum SyntheticError {
    /// The scenario built from the flight is invalid.
    #[error("synthetic flight scenario")]
    Scenario(#[from] ScenarioError),
    /// The simulator failed.
    #[error("synthetic flight simulation")]
    Run(#[from] RunError),
    /// The result is not a usable log (too short: the stack landed).
    #[error("synthetic flight log")]
    Log(#[from] FlightLogError),
    /// A noise level is negative or not finite.
    #[error("sensor noise `{0}` must be finite and not negative")]
    Noise(&'static str),
}

/// One-sigma white noise of the simulated sensors (and the weights of identification's
/// residuals).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct SensorNoise {
    /// GPS horizontal position, m.
    pub horizontal_m: f64,
    /// GPS altitude, m.
    pub vertical_m: f64,
    /// GPS velocity, each axis, m/s.
    pub velocity_mps: f64,
    /// AHRS roll, pitch and yaw, degrees.
    pub attitude_deg: f64,
    /// Airspeed, m/s.
    pub airspeed_mps: f64,
}

impl Default for SensorNoise {
    /// A small GPS receiver and AHRS: 1.5 m, 3 m, 0.1 m/s, 1°, 0.3 m/s.
    fn default() -> Self {
        Self {
            horizontal_m: 1.5,
            vertical_m: 3.0,
            velocity_mps: 0.1,
            attitude_deg: 1.0,
            airspeed_mps: 0.3,
        }
    }
}

/// A made-up flight.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SyntheticFlight {
    /// Release altitude above mean sea level, m.
    pub altitude_m: f64,
    /// Wind speed, m/s.
    pub wind_speed_mps: f64,
    /// Direction the wind blows from, degrees clockwise from north.
    pub wind_from_deg: f64,
    /// Commands `[time s, main line −1…1, right brake, left brake]`, each held until the next.
    pub commands: Vec<[f64; 4]>,
    /// Flight length, s.
    pub duration_s: f64,
    /// Time before the log starts, s.
    pub settle_s: f64,
    /// Sample interval of the log, s.
    pub interval_s: f64,
    /// Sensor noise.
    pub noise: SensorNoise,
    /// Noise seed.
    pub seed: u64,
}

impl SyntheticFlight {
    /// Settling, then a right turn, a braked straight, a left turn and a straight: a flight
    /// that shows the lift, drag, brake and turn coefficients. 75 s, logged at 5 Hz from 15 s.
    pub fn manoeuvres(seed: u64) -> Self {
        Self {
            altitude_m: 1500.0,
            wind_speed_mps: 3.0,
            wind_from_deg: 250.0,
            commands: vec![
                [0.0, 0.0, 0.0, 0.0],
                [20.0, 0.5, 0.0, 0.0],
                [30.0, 0.0, 0.0, 0.0],
                [37.0, 0.0, 0.7, 0.7],
                [47.0, 0.0, 0.0, 0.0],
                [54.0, -0.6, 0.0, 0.3],
                [63.0, 0.0, 0.0, 0.0],
            ],
            duration_s: 75.0,
            settle_s: 15.0,
            interval_s: 0.2,
            noise: SensorNoise::default(),
            seed,
        }
    }

    fn scenario(&self, travel_m: f64) -> Result<Scenario, ScenarioError> {
        let mut text = format!(
            "name = \"synthetic\"\ndescription = \"made-up flight\"\nduration_s = {}\n\
             [initial]\nposition_ned_m = [0.0, 0.0, {}]\ncanopy_euler_deg = [0.0, 6.5, 0.0]\n\
             canopy_velocity_mps = [3.3, 0.0, 1.0]\nline_pitch_deg = -9.0\n\
             drone_euler_deg = [0.0, 20.0, 0.0]\ncapsule_angles_deg = [0.0, -7.0]\n\
             transponder_angles_deg = [0.0, 5.0]\n\
             [integrator]\nmethod = \"rk4\"\nstep_s = 0.01\n\
             [output]\ninterval_s = {}\n\
             [environment.wind]\nkind = \"constant\"\nspeed_mps = {}\nfrom_deg = {}\n",
            self.duration_s,
            -self.altitude_m,
            self.interval_s,
            self.wind_speed_mps,
            self.wind_from_deg
        );
        for [at, ml, br, bl] in &self.commands {
            text.push_str(&format!(
                "[[controls]]\nat_s = {at}\nmain_line = {}\nbrake_right = {br}\nbrake_left = {bl}\n",
                ml * travel_m
            ));
        }
        Scenario::from_toml_str("synthetic", &text)
    }

    fn commands_at(&self, time_s: f64) -> [f64; 3] {
        let mut c = [0.0; 3];
        for [at, ml, br, bl] in &self.commands {
            if *at <= time_s + 1e-9 {
                c = [*ml, *br, *bl];
            }
        }
        c
    }
}

/// Flies `vehicle` through `flight` and returns the drone's noisy log.
pub fn simulate(vehicle: &Vehicle, flight: &SyntheticFlight) -> Result<FlightLog, SyntheticError> {
    let n = &flight.noise;
    for (name, v) in [
        ("horizontal_m", n.horizontal_m),
        ("vertical_m", n.vertical_m),
        ("velocity_mps", n.velocity_mps),
        ("attitude_deg", n.attitude_deg),
        ("airspeed_mps", n.airspeed_mps),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(SyntheticError::Noise(name));
        }
    }
    let run = open_loop::run(&flight.scenario(vehicle.main_line_travel_m)?, vehicle)?;
    let mut rng = ChaCha8Rng::seed_from_u64(flight.seed);
    let mut gauss = |sigma: f64| {
        Normal::new(0.0, sigma.max(0.0))
            .map(|d| d.sample(&mut rng))
            .unwrap_or(0.0)
    };
    let (s, c) = flight.wind_from_deg.to_radians().sin_cos();
    let wind = [-flight.wind_speed_mps * c, -flight.wind_speed_mps * s, 0.0];
    let rad = f64::to_radians;
    let mut samples = Vec::new();
    for sample in run
        .samples
        .iter()
        // The simulator flies on past the scenario's end with its last commands held until it
        // finds a steady stretch for its own summary; commands scheduled after the end would
        // then be logged but never flown.
        .filter(|s| s.time_s >= flight.settle_s - 1e-9 && s.time_s <= flight.duration_s + 1e-9)
    {
        let d = sample.body(Body::Drone);
        let air: f64 = (0..3)
            .map(|k| (d.velocity_ned_mps[k] - wind[k]).powi(2))
            .sum::<f64>()
            .sqrt();
        let [main_line, brake_right, brake_left] = flight.commands_at(sample.time_s);
        samples.push(LogSample {
            time_s: sample.time_s,
            position_ned_m: [
                d.position_ned_m[0] + gauss(n.horizontal_m),
                d.position_ned_m[1] + gauss(n.horizontal_m),
                d.position_ned_m[2] + gauss(n.vertical_m),
            ],
            velocity_ned_mps: d.velocity_ned_mps.map(|v| v + gauss(n.velocity_mps)),
            euler_rad: d.euler_deg.map(|a| rad(a + gauss(n.attitude_deg))),
            airspeed_mps: Some(air + gauss(n.airspeed_mps)),
            main_line,
            brake_right,
            brake_left,
            wind_ned_mps: wind,
        });
    }
    Ok(FlightLog::new(samples)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Regression: a flight cut short of its last commands was logged on past its end with
    /// those commands, which the simulator (flying on with the old ones held for its steady
    /// summary) never flew; a replay of the true vehicle then turned where the log did not.
    #[test]
    fn the_log_ends_with_the_flight_and_its_commands_were_flown() {
        let mut flight = SyntheticFlight::manoeuvres(5);
        flight.duration_s = 50.0;
        let log = simulate(&Vehicle::straplex(), &flight).unwrap();
        let last = log.samples().last().unwrap();
        assert!(last.time_s <= 50.0 + 1e-9, "{}", last.time_s);
        assert_eq!(
            [last.main_line, last.brake_right, last.brake_left],
            [0.0; 3]
        );
    }
}
