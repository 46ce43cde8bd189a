//! The sensed, dispersed check: a candidate's step experiments flown on stacks drawn from a
//! dispersion set (their own trim, aerodynamics, masses, rigging and servo errors), with
//! guidance fed by the sensor models and the estimator it flies with, not by the truth.
//!
//! Perfect navigation on the nominal model tells what the laws can do; the drone flies
//! through the estimator's lag and noise on a canopy that is not the model, learning in
//! flight what it flies with (the main line's trim). Gains that are
//! best there are what the flight needs, so the tuner's last word is this check's cost: the
//! mean over the draws of each draw's step cost. The draws and the sensors' seeds are fixed
//! for a tuning run, so every candidate meets the same stacks and the same noise and the cost
//! is a deterministic function of the gains. A draw with no steady glide to step from (a
//! stack that settles in a deep stall) is left out and named in the report.

use serde::Serialize;
use stx_dynamics::vehicle::Vehicle;
use stx_gnc::control::ControlGains;
use stx_gnc::estimator::EstimatorConfig;
use stx_gnc::guidance::GuidanceConfig;
use stx_sim::closed_loop::SensedNavigation;
use stx_sim::dispersions::{DispersedFlight, Dispersions, ServoErrors};
use stx_sim::sensors::SensorConfig;

use super::controller::Controller;
use super::experiment::Experiment;

/// Seconds flown on the reference before the step, for the estimator to converge and
/// guidance to learn the main line's trim (its time constant is 30 s).
pub const SETTLE_S: f64 = 60.0;
/// Cost of a step whose flight failed (diverged or reached the ground): more than any
/// response the metrics score.
const FAILED_COST: f64 = 100.0;

/// What to draw the sensed set from.
#[derive(Debug, Clone)]
pub struct SensedSpec {
    /// The dispersion set.
    pub dispersions: Dispersions,
    /// The sensors' settings the draws start from.
    pub sensors: SensorConfig,
    /// How many stacks.
    pub count: usize,
    /// Seed of the draws (each stack's seed is derived from it).
    pub seed: u64,
}

/// What the report says of the sensed set.
#[derive(Debug, Clone, Serialize)]
pub struct SensedSummary {
    /// Name of the dispersion set.
    pub dispersions: String,
    /// Seed of the draws.
    pub seed: u64,
    /// Indices of the draws checked on.
    pub draws: Vec<usize>,
    /// Draws left out, with why.
    pub excluded: Vec<String>,
    /// Seconds flown on the reference before each step.
    pub settle_s: f64,
}

/// The stacks and sensors a candidate is checked on.
#[derive(Debug, Clone)]
pub struct SensedSet {
    /// Name of the dispersion set the stacks were drawn from.
    pub dispersions: String,
    /// The seed of the draws.
    pub seed: u64,
    draws: Vec<Draw>,
    /// Draws left out, with why.
    pub excluded: Vec<String>,
}

#[derive(Debug, Clone)]
struct Draw {
    index: usize,
    seed: u64,
    sensors: SensorConfig,
    servos: ServoErrors,
    small: Experiment,
    large: Experiment,
}

/// The check's cost of one gain set.
#[derive(Debug, Clone, Serialize)]
pub struct SensedCost {
    /// Mean over the draws of the mean of the small and the large step's costs.
    pub mean: f64,
    /// Each draw's cost, in draw order.
    pub per_draw: Vec<f64>,
    /// Steps whose flight failed (each counted at a cost of 100).
    pub failed_steps: usize,
}

impl SensedSet {
    /// The stacks `spec` asks for, drawn around `vehicle` and trimmed for `controller`'s
    /// experiments at `altitude_m`.
    pub fn draw(
        controller: Controller,
        vehicle: &Vehicle,
        altitude_m: f64,
        base: GuidanceConfig,
        spec: &SensedSpec,
    ) -> Self {
        let SensedSpec {
            dispersions,
            sensors,
            count,
            seed,
        } = spec;
        let (count, seed) = (*count, *seed);
        let mut draws = Vec::with_capacity(count);
        let mut excluded = Vec::new();
        for index in 0..count {
            let draw_seed = seed
                .wrapping_mul(0x9E37_79B9_7F4A_7C15)
                .wrapping_add(index as u64 + 1);
            let flight =
                match DispersedFlight::draw(dispersions, &vehicle.config, sensors, draw_seed) {
                    Ok(f) => f,
                    Err(e) => {
                        excluded.push(format!("draw {index}: vehicle refused: {e}"));
                        continue;
                    }
                };
            let experiment =
                |step: f64| Experiment::new(controller, &flight.vehicle, altitude_m, base, step);
            match (
                experiment(controller.step()),
                experiment(controller.large_step()),
            ) {
                (Ok(small), Ok(large)) => draws.push(Draw {
                    index,
                    seed: draw_seed,
                    sensors: flight.sensors.clone(),
                    servos: flight.servos,
                    small,
                    large,
                }),
                (Err(e), _) | (_, Err(e)) => excluded.push(format!(
                    "draw {index} (rigging {:+.1}°, lift slope ×{:.2}): no steady glide to \
                     step from: {e}",
                    flight.summary.rigging_deg, flight.summary.cl_alpha
                )),
            }
        }
        Self {
            dispersions: dispersions.name.clone(),
            seed,
            draws,
            excluded,
        }
    }

    /// Number of stacks checked on.
    pub fn len(&self) -> usize {
        self.draws.len()
    }

    /// Whether no stack is left to check on.
    pub fn is_empty(&self) -> bool {
        self.draws.is_empty()
    }

    /// The check's cost of `gains`.
    pub fn cost(&self, gains: &ControlGains) -> SensedCost {
        let mut failed_steps = 0;
        let per_draw: Vec<f64> = self
            .draws
            .iter()
            .map(|d| {
                let mut step_cost = |e: &Experiment| {
                    let navigator =
                        match SensedNavigation::new(&d.sensors, EstimatorConfig::default(), d.seed)
                        {
                            Ok(n) => n,
                            Err(_) => {
                                failed_steps += 1;
                                return FAILED_COST;
                            }
                        };
                    match e.flown_response(gains, navigator, d.servos, SETTLE_S, true) {
                        Ok(r) => e.score(&r, gains).cost.min(FAILED_COST),
                        Err(_) => {
                            failed_steps += 1;
                            FAILED_COST
                        }
                    }
                };
                0.5 * (step_cost(&d.small) + step_cost(&d.large))
            })
            .collect();
        let mean = if per_draw.is_empty() {
            f64::INFINITY
        } else {
            per_draw.iter().sum::<f64>() / per_draw.len() as f64
        };
        SensedCost {
            mean,
            per_draw,
            failed_steps,
        }
    }

    /// What the report says of it.
    pub fn summary(&self) -> SensedSummary {
        SensedSummary {
            dispersions: self.dispersions.clone(),
            seed: self.seed,
            draws: self.draws.iter().map(|d| d.index).collect(),
            excluded: self.excluded.clone(),
            settle_s: SETTLE_S,
        }
    }
}
