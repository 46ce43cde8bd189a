//! Identification (issue 16 item 2): fit chosen aerodynamic coefficients, brake terms and the
//! rigging angle ([`params`]) to one or several recorded flights by least squares over the
//! simulated-minus-recorded error, with confidence intervals and correlations, and write the
//! fitted vehicle file.
//!
//! The residuals are those of [`crate::compare`]'s replay: at every recorded instant the
//! model's drone minus the log's, for position (north, east, height), velocity (three axes),
//! attitude (roll, pitch, yaw wrapped) and airspeed, each divided by its measurement's
//! 1-σ noise ([`SensorNoise`]) so that the channels weigh alike. Every candidate vehicle is
//! flown from its own trimmed start. [`lm`] minimises them.
//!
//! Two nuisances of each flight's start are fitted with the parameters, because the replay
//! takes its start from one noisy sample and a single sample's error lasts the whole flight:
//! - the start's position: a GPS error of 1.5 m in the first fix shifts the whole replayed
//!   track by as much (and so does a GPS bias). The shift is taken out exactly by removing
//!   each flight's mean position residual (the least-squares fit of a constant offset);
//! - the start's heading: 1° of AHRS noise in the first heading turns the replayed course, and
//!   the track drifts across by 9 cm/s, metres over a minute. Each flight's turn is fitted
//!   as an extra parameter (degrees) and not reported.
//!
//! - optionally (`fit_air_scale`), the flight's air data: an estimator whose airspeed reads a
//!   few per cent low puts the missing air speed into its wind, along the heading, and a
//!   replay through that wind wants a draggier, lower-lift canopy. Each flight's scale `s` is
//!   fitted ([`Nuisance::air_scale`](crate::compare::Nuisance)): the wind flown becomes
//!   `w − s·(v − w)`, the airspeed compared `(1 + s)·a`. On the simulated drone's recording of a
//!   stack with `cl_alpha` 1.840 (`crates/stx/tests/cli/identify_rehearsal.rs`) it moved the fitted
//!   lift slope from 1.943 (interval 1.908 … 1.977) to 1.899 (1.823 … 1.974) and the drag from
//!   0.200 to 0.189 (truth 0.150). It is off by default: the scale and the drag both set the
//!   airspeed's level, which then only turns tell apart, so on flights whose air data are right
//!   it costs precision and can pull the drag (with the true wind written into the same
//!   recording, cl_alpha/cd0 came out 1.828/0.157 without it and 1.888/0.182 with it).
//!
//! Without the first two the fitted coefficients soaked up these errors: over 10 seeds the truth was
//! inside the 95 % interval in 2, 0 and 0 of 10 trials for cl_alpha, cd0 and cn_da, with the
//! residuals slow and correlated. With them: 20, 19 and 20 of 20 (29, 28, 29 of 30), worst
//! errors 0.5 %, 0.5 % and 0.0002 (cn_da, about 2 % of it) against a dispersion of 20–30 %.
//!
//! The intervals come from [`covariance`]: a sandwich `B·S·B` over the per-instant scores,
//! with a Newey–West lag found from how long the residuals stay correlated (or longer, with
//! `correlation_s`). On white-noise flights the residuals forget in a sample and the lag is
//! 5 samples: 20, 18, 20 of 20 inside (lag 0 gave 20, 19, 20; a lag of 25 samples gave 17 of
//! 20 for cd0, because what is left of the error there is a small bias, not slow noise: over
//! 30 trials the estimates sit 1.3 σ high on cd0 and 0.6 σ and 0.5 σ low on cl_alpha and
//! cn_da, with a spread of about 0.65 σ, the same with half the integration step or 20 s
//! more settling).
//!
//! On flights whose GPS wanders and whose wind estimate lags
//! ([`SlowErrors`](crate::flight_log::synthetic::SlowErrors), 20 trials each, cl_alpha, cd0,
//! cn_da inside the 95 % interval; "lag 0" is the white-noise sandwich used before):
//!
//! | flights | lag 0 (before) | lag found (now) |
//! |---|---|---|
//! | white noise, 60 s | 20, 19, 20 | 20, 18, 20 |
//! | GPS wander 2 m / 3 m over 30 s, wind estimate 10 s behind a wind turning with height, 60 s | 4, 11, 3 | 18, 19, 19 |
//! | the same with light Dryden gusts, 60 s | 4, 8, 2 | 16, 20, 14 |
//! | GPS wander and lagging wind, 210 s ([`long_manoeuvres`](crate::flight_log::synthetic::SyntheticFlight::long_manoeuvres)) | 5, 5, 2 | 16, 18, 14 |
//!
//! ("Lag found" is the lag from the residuals with the fixed-b quantile, see [`covariance`];
//! the 210 s "lag 0" figures were taken with the Student t quantile of the time, 1.96 at
//! lag 0 as the fixed-b one is.) So on a wandering GPS and a lagging wind estimate the
//! intervals hold the truth about as often as they say; with gusts, whose quick part turns
//! the canopy in a way a replay in the estimated wind cannot, 70–80 % for cl_alpha and cn_da:
//! model error, which no lag makes up for. Longer flights did worse, not better: the
//! open-loop replay carries a wind error on into position for the whole flight, so what the
//! errors remember grows with it, and the lag is capped at a third of the flight. The first
//! two rows are the coverage tests in `tests.rs` run with `STX_IDENTIFY_TRIALS=20` (the
//! second is the one named `own_claim_…`), the others the second with its flights changed.
//!
//! Pure: logs and a vehicle in, a report out; a cancel flag and a progress callback let a
//! caller (the Lab page) stop and watch it.

pub mod covariance;
pub mod lm;
pub mod params;

use std::sync::atomic::AtomicBool;

use nalgebra::DVector;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use stx_dynamics::vehicle::{VehicleConfig, VehicleError};
use thiserror::Error;

use crate::compare::{DEFAULT_STEP_S, Nuisance, ReplayError, fly_corrected, wrap_deg};
use crate::flight_log::FlightLog;
use crate::flight_log::synthetic::SensorNoise;
pub use covariance::{Layout, sandwich};
pub use lm::{LmOptions, Step, Stop};
pub use params::{Param, UnknownParam};

/// z of the two-sided 95 % normal interval.
pub const Z95: f64 = stx_gnc::stats::Z_975;

/// Why nothing was identified.
#[derive(Debug, Error)]
pub enum IdentifyError {
    /// No parameter was asked for.
    #[error("no parameters to identify")]
    NoParams,
    /// A parameter was asked for twice.
    #[error("parameter `{0}` is listed twice")]
    Duplicate(&'static str),
    /// No flight was given.
    #[error("no flights to identify from")]
    NoFlights,
    /// The starting vehicle is invalid.
    #[error("the starting vehicle is invalid")]
    Vehicle(#[from] VehicleError),
    /// The starting vehicle cannot fly flight `flight` (index in the list).
    #[error("the starting vehicle cannot fly flight {flight}")]
    Replay {
        flight: usize,
        #[source]
        source: ReplayError,
    },
    /// The starting point could not be evaluated a second time (a model that is not
    /// deterministic: a bug).
    #[error("the starting vehicle flew once but not twice")]
    StartFailed,
    /// Fewer residuals than parameters.
    #[error("{residuals} residuals cannot determine {params} parameters")]
    TooFewResiduals { residuals: usize, params: usize },
}

/// Settings of an identification.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct IdentifyOptions {
    /// Largest integration step of the replays, s.
    pub step_s: f64,
    /// Most Levenberg–Marquardt iterations.
    pub max_iterations: usize,
    /// Measurement noise the residuals are divided by.
    #[serde(default)]
    pub noise: SensorNoise,
    /// How long the residuals stay correlated at least, s: the shortest Newey–West lag of the
    /// intervals (see [`covariance`]).
    #[serde(default = "default_correlation_s")]
    pub correlation_s: f64,
    /// Whether the lag may be longer than `correlation_s` says, as long as the residuals'
    /// scores show they stay correlated (Andrews' plug-in, see [`covariance`]).
    #[serde(default = "default_automatic_lag")]
    pub automatic_lag: bool,
    /// Whether each flight's air-data scale is fitted too (see the module doc): the recorded
    /// wind estimate and airspeed corrected for an airspeed that read a few per cent off.
    /// Off by default: on flights whose air data are right it only widens the intervals.
    #[serde(default = "default_fit_air_scale")]
    pub fit_air_scale: bool,
}

fn default_fit_air_scale() -> bool {
    false
}

fn default_automatic_lag() -> bool {
    true
}

fn default_correlation_s() -> f64 {
    DEFAULT_CORRELATION_S
}

/// The residuals' correlation time the intervals assume by default, s: none beyond what the
/// residuals show (see the module doc).
pub const DEFAULT_CORRELATION_S: f64 = 0.0;

impl Default for IdentifyOptions {
    fn default() -> Self {
        Self {
            step_s: DEFAULT_STEP_S,
            max_iterations: 30,
            noise: SensorNoise::default(),
            correlation_s: DEFAULT_CORRELATION_S,
            automatic_lag: true,
            fit_air_scale: false,
        }
    }
}

/// One fitted parameter.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ParamEstimate {
    /// Name, as in the vehicle file (`rigging_deg`: change of rigging angle, degrees).
    pub name: String,
    /// Value before the fit.
    pub initial: f64,
    /// Fitted value.
    pub estimate: f64,
    /// Standard error, when the fit determines it (`null` when `JᵀJ` is singular).
    pub std_error: Option<f64>,
    /// 95 % interval `[low, high]`.
    pub interval95: Option<[f64; 2]>,
}

/// What an identification found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct IdentifyReport {
    /// Each parameter, in the order asked.
    pub params: Vec<ParamEstimate>,
    /// Correlation matrix of the estimates, rows and columns in the order of `params`
    /// (`null` when the fit does not determine them).
    pub correlation: Option<Vec<Vec<f64>>>,
    /// RMS of the normalised residuals (multiples of the measurement noise) before the fit.
    pub residual_rms_before: f64,
    /// The same after.
    pub residual_rms_after: f64,
    /// Flights fitted.
    pub flights: usize,
    /// Residuals (samples × channels).
    pub residuals: usize,
    /// Iterations.
    pub iterations: usize,
    /// Flights of the model flown.
    pub evaluations: usize,
    /// Why the fit stopped.
    pub stop: Stop,
    /// Half-width of the 95 % intervals in standard errors (the fixed-b quantile for the
    /// Newey–West lag, see [`covariance`]; `null` with the intervals).
    pub interval_t: Option<f64>,
    /// Newey–West lag of the intervals, samples.
    pub newey_west_lag: Option<usize>,
    /// Each flight's fitted air-data scale, per cent: how much faster the air went past
    /// the drone than its recorded airspeed and wind estimate say (empty when not fitted).
    #[serde(default)]
    pub air_scale_percent: Vec<f64>,
    /// The fitted vehicle file (TOML, the vehicle schema).
    pub vehicle_toml: String,
}

/// Progress of an identification, after each iteration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Progress {
    /// Iteration, from 1.
    pub iteration: usize,
    /// Model flights flown so far.
    pub evaluations: usize,
    /// RMS of the normalised residuals now.
    pub residual_rms: f64,
}

/// The normalised residuals of `vehicle` over `logs`, each flight corrected by its
/// `nuisances` (one per flight, or none for no correction), with each flight's mean position
/// error taken out (see the module doc), and where each instant's sit; or why it cannot fly
/// one.
pub fn residuals(
    logs: &[FlightLog],
    vehicle: &VehicleConfig,
    nuisances: &[Nuisance],
    options: &IdentifyOptions,
) -> Result<(Vec<f64>, Layout), (usize, ReplayError)> {
    let v = vehicle
        .clone()
        .validate()
        .map_err(|e| (0, ReplayError::InvalidVehicle(e.to_string())))?;
    let n = &options.noise;
    let floor = |s: f64| s.max(1e-6);
    let (h, z, vel, att, air) = (
        floor(n.horizontal_m),
        floor(n.vertical_m),
        floor(n.velocity_mps),
        floor(n.attitude_deg),
        floor(n.airspeed_mps),
    );
    let mut out = Vec::new();
    let mut layout = Layout::default();
    for (i, log) in logs.iter().enumerate() {
        let nuisance = nuisances.get(i).copied().unwrap_or_default();
        let flown = fly_corrected(log, &v, options.step_s, nuisance).map_err(|e| (i, e))?;
        let samples = log.samples();
        let mut starts = Vec::with_capacity(samples.len());
        let mut mean = [0.0; 3];
        for (s, f) in samples.iter().zip(&flown) {
            starts.push(out.len());
            let dp: [f64; 3] = std::array::from_fn(|k| f.position_ned_m[k] - s.position_ned_m[k]);
            out.extend([dp[0] / h, dp[1] / h, dp[2] / z]);
            out.extend((0..3).map(|k| (f.velocity_ned_mps[k] - s.velocity_ned_mps[k]) / vel));
            for k in 0..3 {
                out.push(wrap_deg((f.euler_rad[k] - s.euler_rad[k]).to_degrees()) / att);
            }
            if let Some(a) = s.airspeed_mps {
                out.push((f.airspeed_mps - nuisance.airspeed_mps(a)) / air);
            }
        }
        for start in &starts {
            for (k, m) in mean.iter_mut().enumerate() {
                *m += out[start + k] / starts.len() as f64;
            }
        }
        for start in &starts {
            for (k, m) in mean.iter().enumerate() {
                out[start + k] -= m;
            }
        }
        let span_s = samples[samples.len() - 1].time_s - samples[0].time_s;
        layout
            .intervals_s
            .push(span_s / (samples.len() - 1).max(1) as f64);
        layout.flights.push((starts, out.len()));
    }
    Ok((out, layout))
}

fn rms(r: &[f64]) -> f64 {
    (r.iter().map(|x| x * x).sum::<f64>() / r.len().max(1) as f64).sqrt()
}

/// Fits `params` of `vehicle` to `logs` (see the module doc). `cancel` stops it after the
/// current iteration (the report then holds the best point so far); `progress` hears of each
/// iteration.
pub fn identify(
    logs: &[FlightLog],
    params: &[Param],
    vehicle: &VehicleConfig,
    options: &IdentifyOptions,
    cancel: &AtomicBool,
    progress: &mut dyn FnMut(Progress),
) -> Result<IdentifyReport, IdentifyError> {
    if params.is_empty() {
        return Err(IdentifyError::NoParams);
    }
    if logs.is_empty() {
        return Err(IdentifyError::NoFlights);
    }
    for (i, p) in params.iter().enumerate() {
        if params[..i].contains(p) {
            return Err(IdentifyError::Duplicate(p.name()));
        }
    }
    vehicle.clone().validate()?;
    let with = |x: &DVector<f64>| {
        let mut v = vehicle.clone();
        for (p, value) in params.iter().zip(x.iter()) {
            p.set(&mut v, *value);
        }
        v
    };
    let p = params.len();
    let flights = logs.len();
    let scaled = if options.fit_air_scale { flights } else { 0 };
    // The fitted vector: the parameters, then each flight's turn of its start (degrees),
    // then each flight's air-data scale (per cent) when fitted.
    let x0 = DVector::from_iterator(
        p + flights + scaled,
        params
            .iter()
            .map(|q| q.get(vehicle))
            .chain((0..flights + scaled).map(|_| 0.0)),
    );
    let nuisances = |x: &DVector<f64>| -> Vec<Nuisance> {
        (0..flights)
            .map(|i| Nuisance {
                turn_rad: x[p + i].to_radians(),
                air_scale: if scaled > 0 {
                    x[p + flights + i] / 100.0
                } else {
                    0.0
                },
            })
            .collect()
    };
    let (before, layout) = residuals(logs, vehicle, &[], options)
        .map_err(|(flight, source)| IdentifyError::Replay { flight, source })?;
    let m = before.len();
    if m <= x0.len() {
        return Err(IdentifyError::TooFewResiduals {
            residuals: m,
            params: params.len(),
        });
    }
    let mut evaluate = |x: &DVector<f64>| {
        residuals(logs, &with(x), &nuisances(x), options)
            .ok()
            .map(|(r, _)| r)
            .filter(|r| r.len() == m)
            .map(DVector::from_vec)
    };
    let scales: Vec<f64> = params
        .iter()
        .zip(x0.iter())
        .map(|(p, v)| p.scale(*v))
        .chain((0..flights + scaled).map(|_| 1.0))
        .collect();
    let scale = |i: usize, _: f64| scales[i];
    let lm_options = LmOptions {
        max_iterations: options.max_iterations,
        ..LmOptions::default()
    };
    let mut on_step = |s: Step| {
        progress(Progress {
            iteration: s.iteration,
            evaluations: s.evaluations,
            residual_rms: (2.0 * s.cost / m as f64).sqrt(),
        })
    };
    let fit = lm::minimize(
        &mut evaluate,
        &scale,
        x0.clone(),
        &lm_options,
        cancel,
        &mut on_step,
    )
    .ok_or(IdentifyError::StartFailed)?;
    let covariance = sandwich(
        &fit.jacobian,
        &fit.residuals,
        &layout,
        options.correlation_s,
        options.automatic_lag,
    );
    let t95 = covariance.as_ref().map(|c| c.t95);
    let lag = covariance.as_ref().map(|c| c.lag);
    let covariance = covariance.map(|c| c.matrix.view((0, 0), (p, p)).into_owned());
    let estimates = params
        .iter()
        .enumerate()
        .map(|(i, param)| {
            let sd = covariance.as_ref().map(|c| c[(i, i)].max(0.0).sqrt());
            ParamEstimate {
                name: param.name().into(),
                initial: x0[i],
                estimate: fit.x[i],
                std_error: sd,
                interval95: sd
                    .zip(t95)
                    .map(|(sd, t)| [fit.x[i] - t * sd, fit.x[i] + t * sd]),
            }
        })
        .collect();
    let correlation = covariance.map(|c| {
        (0..p)
            .map(|i| {
                (0..p)
                    .map(|j| c[(i, j)] / (c[(i, i)] * c[(j, j)]).sqrt())
                    .collect()
            })
            .collect()
    });
    let fitted = with(&fit.x);
    Ok(IdentifyReport {
        params: estimates,
        correlation,
        residual_rms_before: rms(&before),
        residual_rms_after: rms(fit.residuals.as_slice()),
        flights: logs.len(),
        residuals: m,
        iterations: fit.iterations,
        evaluations: fit.evaluations,
        stop: fit.stop,
        interval_t: t95,
        newey_west_lag: lag,
        air_scale_percent: fit.x.as_slice()[p + flights..].to_vec(),
        vehicle_toml: toml::to_string(&fitted).unwrap_or_default(),
    })
}

#[cfg(test)]
mod tests;
