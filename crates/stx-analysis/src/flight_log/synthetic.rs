//! Flights made up for tests and examples: a vehicle flown by stx-sim's open-loop simulator
//! (its own integrator, its own initial pose, not [`crate::compare::replay`]) through a
//! schedule of turns and brakes in a steady wind, and sampled as a drone's telemetry with
//! white sensor noise. A log of a vehicle whose coefficients are known, so that comparison
//! and identification can be checked against the truth.
//!
//! The log starts after `settle_s`, once the stack has settled from the scenario's rough
//! initial pose into its glide.
//!
//! [`SlowErrors`] adds what white noise leaves out of a real drone's log: a GPS position that
//! wanders (first-order Gauss–Markov) and a wind that turns with height or gusts while the
//! drone's wind estimate follows it late (a first-order lag). Their errors last tens of seconds, the case in which
//! identification's intervals must widen ([`crate::identify::covariance`]).

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal, StandardNormal};
use serde::{Deserialize, Serialize};
use stx_dynamics::model::Body;
use stx_dynamics::vehicle::Vehicle;
use stx_dynamics::wind::{MeanWindConfig, TurbulenceParams, WindConfig, WindField};
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
    /// A slow-error figure is out of range.
    #[error("slow error `{0}` must be finite and not negative (times: positive)")]
    SlowError(&'static str),
    /// The wind made of the flight's figures is invalid.
    #[error("synthetic flight wind")]
    Wind(#[from] stx_dynamics::wind::WindError),
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

/// Errors of a real drone's log that last tens of seconds, on top of [`SensorNoise`]'s white
/// noise.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SlowErrors {
    /// 1-σ of the GPS position's wander north and east, each, m.
    pub gps_horizontal_m: f64,
    /// 1-σ of the GPS altitude's wander, m.
    pub gps_vertical_m: f64,
    /// Correlation time of the wander (first-order Gauss–Markov), s.
    pub gps_correlation_s: f64,
    /// 1-σ of the horizontal gusts (Dryden, stx-dynamics' turbulence; none vertical), m/s.
    pub gust_mps: f64,
    /// Length scale of the gusts, m.
    pub gust_length_m: f64,
    /// 1-σ of each layer's departure from the steady wind, north and east each, m/s: the
    /// steady wind becomes a profile over altitude, which the stack descends through.
    pub layer_mps: f64,
    /// Thickness of those layers, m (the wind is interpolated between them).
    pub layer_m: f64,
    /// Time constant of the wind estimate's first-order lag behind the true wind, s (0: the
    /// estimate is the true wind).
    pub wind_lag_s: f64,
}

impl SlowErrors {
    /// A u-blox M8-class receiver and a wind estimate lagging a wind that turns with height:
    /// - GPS 2 m horizontal, 3 m vertical, 30 s. The NEO-M8 data sheet gives 2.5 m CEP
    ///   horizontal (autonomous GPS), 1-σ per axis 2.5/1.18 ≈ 2.1 m; it gives no vertical
    ///   figure, and 1.5 times the horizontal is the usual VDOP/HDOP ratio. Its error is
    ///   mostly atmospheric delay and multipath that change over tens of seconds to minutes;
    ///   30 s is our choice, short enough that a flight sees its error wander rather than sit
    ///   still (a still error is fitted away as the start's offset).
    /// - layers of 100 m whose wind departs from the steady 3 m/s by 0.5 m/s 1-σ each way,
    ///   changes of about 0.7 m/s per 100 m: an ordinary shear below 2 km, our choice.
    /// - the wind estimate 10 s behind: our choice for a drone that estimates the wind from
    ///   GPS and airspeed over turns, averaging over about one turn.
    ///
    /// No gusts: their quick part turns the canopy, which a replay in the estimated wind
    /// cannot reproduce; that is model error, not the estimate's lag (see
    /// [`crate::identify::covariance`] for what it does to the intervals).
    pub fn ublox_wind_shear() -> Self {
        Self {
            gps_horizontal_m: 2.0,
            gps_vertical_m: 3.0,
            gps_correlation_s: 30.0,
            gust_mps: 0.0,
            gust_length_m: 533.0,
            layer_mps: 0.5,
            layer_m: 100.0,
            wind_lag_s: 10.0,
        }
    }

    /// [`Self::ublox_wind_shear`] in light turbulence as well: Dryden gusts of 0.5 m/s (our
    /// choice) over 533 m (MIL-F-8785C's length scale above 1,750 ft), which at 6 m/s change
    /// over about 90 s.
    pub fn ublox_light_turbulence() -> Self {
        Self {
            gust_mps: 0.5,
            ..Self::ublox_wind_shear()
        }
    }

    fn validate(&self) -> Result<(), SyntheticError> {
        for (name, v, positive) in [
            ("gps_horizontal_m", self.gps_horizontal_m, false),
            ("gps_vertical_m", self.gps_vertical_m, false),
            ("gps_correlation_s", self.gps_correlation_s, true),
            ("gust_mps", self.gust_mps, false),
            ("gust_length_m", self.gust_length_m, true),
            ("layer_mps", self.layer_mps, false),
            ("layer_m", self.layer_m, true),
            ("wind_lag_s", self.wind_lag_s, false),
        ] {
            if !(v.is_finite() && v >= 0.0 && (v > 0.0 || !positive)) {
                return Err(SyntheticError::SlowError(name));
            }
        }
        Ok(())
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
    /// Slow errors on top of the white noise, if any.
    #[serde(default)]
    pub slow: Option<SlowErrors>,
    /// Noise seed (and the gusts').
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
            slow: None,
            seed,
        }
    }

    /// The manoeuvres' turns and brakes flown four times over (a turn each way and a braked
    /// straight every 50 s), for a log of 210 s from 15 s: long enough to hold several of the
    /// slow errors' correlation times ([`SlowErrors`]).
    pub fn long_manoeuvres(seed: u64) -> Self {
        let short = Self::manoeuvres(seed);
        let mut commands = vec![[0.0, 0.0, 0.0, 0.0]];
        for cycle in 0..4 {
            let offset = 50.0 * f64::from(cycle);
            commands.extend(
                short.commands[1..]
                    .iter()
                    .map(|c| [c[0] + offset, c[1], c[2], c[3]]),
            );
        }
        Self {
            altitude_m: 2000.0,
            commands,
            duration_s: 225.0,
            ..short
        }
    }

    /// The true wind: the steady wind, or layers about it, gusting when [`SlowErrors`] says so.
    fn wind(&self) -> WindConfig {
        let steady = MeanWindConfig::Constant {
            speed_mps: self.wind_speed_mps,
            from_deg: self.wind_from_deg,
        };
        let layered = self.slow.filter(|s| s.layer_mps > 0.0).map(|s| {
            let mut rng = ChaCha8Rng::seed_from_u64(self.seed ^ 0x1a7e5);
            let (sin, cos) = self.wind_from_deg.to_radians().sin_cos();
            let top_m = self.altitude_m + 2.0 * s.layer_m;
            let layers = (top_m / s.layer_m).ceil() as usize;
            let rows = (0..=layers)
                .map(|i| {
                    let mut draw = || -> f64 {
                        let g: f64 = StandardNormal.sample(&mut rng);
                        s.layer_mps * g
                    };
                    // Components of the air's velocity (blowing towards), then back to the
                    // profile's speed and from-direction.
                    let north = -self.wind_speed_mps * cos + draw();
                    let east = -self.wind_speed_mps * sin + draw();
                    let from_deg = (-east).atan2(-north).to_degrees().rem_euclid(360.0);
                    [i as f64 * s.layer_m, north.hypot(east), from_deg]
                })
                .collect();
            MeanWindConfig::Profile { rows }
        });
        WindConfig {
            mean: layered.unwrap_or(steady),
            turbulence: self
                .slow
                .filter(|s| s.gust_mps > 0.0)
                .map(|s| TurbulenceParams {
                    sigma_horizontal_mps: s.gust_mps,
                    sigma_vertical_mps: 0.0,
                    length_scale_horizontal_m: s.gust_length_m,
                    length_scale_vertical_m: s.gust_length_m,
                    // The glide's airspeed, at which the stack crosses the frozen gust field.
                    reference_airspeed_mps: 6.0,
                    seed: self.seed ^ 0x6057,
                    components: 64,
                }),
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
             [output]\ninterval_s = {}\n",
            self.duration_s, -self.altitude_m, self.interval_s,
        );
        for [at, ml, br, bl] in &self.commands {
            text.push_str(&format!(
                "[[controls]]\nat_s = {at}\nmain_line = {}\nbrake_right = {br}\nbrake_left = {bl}\n",
                ml * travel_m
            ));
        }
        let mut scenario = Scenario::from_toml_str("synthetic", &text)?;
        // Set after parsing, as the wind is a value, not text; `simulate` builds it first.
        scenario.environment.wind = Some(self.wind());
        Ok(scenario)
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
    if let Some(slow) = &flight.slow {
        slow.validate()?;
    }
    let wind_field = flight.wind().build()?;
    let run = open_loop::run(&flight.scenario(vehicle.main_line_travel_m)?, vehicle)?;
    let mut rng = ChaCha8Rng::seed_from_u64(flight.seed);
    let mut gauss = |sigma: f64| {
        Normal::new(0.0, sigma.max(0.0))
            .map(|d| d.sample(&mut rng))
            .unwrap_or(0.0)
    };
    let rad = f64::to_radians;
    let slow = flight.slow.unwrap_or(SlowErrors {
        gps_horizontal_m: 0.0,
        gps_vertical_m: 0.0,
        gps_correlation_s: 1.0,
        gust_mps: 0.0,
        gust_length_m: 1.0,
        layer_mps: 0.0,
        layer_m: 1.0,
        wind_lag_s: 0.0,
    });
    let gps_sigma = [
        slow.gps_horizontal_m,
        slow.gps_horizontal_m,
        slow.gps_vertical_m,
    ];
    // A generator of its own, so that a flight without slow errors draws its white noise as
    // before they existed. The wander starts from its stationary spread, as a receiver long
    // switched on.
    let mut slow_rng = ChaCha8Rng::seed_from_u64(flight.seed ^ 0x5_10e5);
    let mut slow_gauss = |sigma: f64| -> f64 {
        let g: f64 = StandardNormal.sample(&mut slow_rng);
        sigma * g
    };
    let mut wander: [f64; 3] = std::array::from_fn(|k| slow_gauss(gps_sigma[k]));
    let mut estimate: Option<[f64; 3]> = None;
    let mut last_time_s = flight.settle_s;
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
        let wind: [f64; 3] = wind_field
            .wind_ned_mps(sample.time_s, &d.position_ned_m.into())
            .into();
        let dt = sample.time_s - last_time_s;
        last_time_s = sample.time_s;
        // Exact discretisations of the Gauss–Markov wander and of the first-order lag, so
        // that neither depends on the log's interval. The estimate starts on the true wind:
        // an estimator that has had the settling time to converge.
        let phi = (-dt / slow.gps_correlation_s).exp();
        for k in 0..3 {
            wander[k] = phi * wander[k] + (1.0 - phi * phi).sqrt() * slow_gauss(gps_sigma[k]);
        }
        let follow = if slow.wind_lag_s > 0.0 {
            1.0 - (-dt / slow.wind_lag_s).exp()
        } else {
            1.0
        };
        let est = estimate.get_or_insert(wind);
        for k in 0..3 {
            est[k] += follow * (wind[k] - est[k]);
        }
        let air: f64 = (0..3)
            .map(|k| (d.velocity_ned_mps[k] - wind[k]).powi(2))
            .sum::<f64>()
            .sqrt();
        let [main_line, brake_right, brake_left] = flight.commands_at(sample.time_s);
        let white = [n.horizontal_m, n.horizontal_m, n.vertical_m];
        samples.push(LogSample {
            time_s: sample.time_s,
            position_ned_m: std::array::from_fn(|k| {
                d.position_ned_m[k] + wander[k] + gauss(white[k])
            }),
            velocity_ned_mps: d.velocity_ned_mps.map(|v| v + gauss(n.velocity_mps)),
            euler_rad: d.euler_deg.map(|a| rad(a + gauss(n.attitude_deg))),
            airspeed_mps: Some(air + gauss(n.airspeed_mps)),
            main_line,
            brake_right,
            brake_left,
            wind_ned_mps: *est,
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

    /// The slow errors are drawn from the seed alone, are there (the GPS is off by metres
    /// that change slowly; the logged wind is not the true one), and bad figures are named.
    #[test]
    fn slow_errors_are_seeded_slow_and_checked() {
        let mut flight = SyntheticFlight::manoeuvres(2);
        flight.duration_s = 45.0;
        flight.noise.horizontal_m = 0.0;
        let plain = simulate(&Vehicle::straplex(), &flight).unwrap();
        let gps_only = SlowErrors {
            gust_mps: 0.0,
            layer_mps: 0.0,
            wind_lag_s: 0.0,
            ..SlowErrors::ublox_wind_shear()
        };
        flight.slow = Some(gps_only);
        let a = simulate(&Vehicle::straplex(), &flight).unwrap();
        assert_eq!(a, simulate(&Vehicle::straplex(), &flight).unwrap());
        // Same air, no white noise north: the north error is the wander alone, metres,
        // changing by about 0.2 m from one 0.2 s sample to the next (white noise of its size
        // would jump by more than its RMS).
        let north: Vec<f64> = plain
            .samples()
            .iter()
            .zip(a.samples())
            .map(|(p, s)| s.position_ned_m[0] - p.position_ned_m[0])
            .collect();
        let rms = (north.iter().map(|e| e * e).sum::<f64>() / north.len() as f64).sqrt();
        let steps: Vec<f64> = north.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
        let step = steps.iter().sum::<f64>() / steps.len() as f64;
        assert!(rms > 0.3 && step < 0.3 * rms, "{rms} {step}");
        flight.slow = Some(SlowErrors::ublox_light_turbulence());
        let windy = simulate(&Vehicle::straplex(), &flight).unwrap();
        assert!(
            plain
                .samples()
                .iter()
                .zip(windy.samples())
                .any(|(p, s)| (p.wind_ned_mps[0] - s.wind_ned_mps[0]).abs() > 0.05)
        );
        for (field, bad) in [("gps_correlation_s", 0.0), ("layer_mps", -1.0)] {
            let mut slow = SlowErrors::ublox_wind_shear();
            match field {
                "gps_correlation_s" => slow.gps_correlation_s = bad,
                _ => slow.layer_mps = bad,
            }
            flight.slow = Some(slow);
            let err = simulate(&Vehicle::straplex(), &flight).unwrap_err();
            assert!(
                matches!(err, SyntheticError::SlowError(f) if f == field),
                "{err}"
            );
        }
    }
}
