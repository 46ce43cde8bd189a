//! How fast the flight model runs (`stx bench dynamics`): derivative evaluations per second on
//! one core, and the real-time factor of the whole `stratospheric` descent for each integrator
//! with its loosest setting whose landing point stays within 1 m of a reference run at a 10×
//! tighter setting (a 10× smaller tolerance for Dormand–Prince, a 10× smaller step for RK4).
//!
//! The figures are wall time measured here, about itself, like a Monte Carlo's `wall_time_s`;
//! the flights themselves are deterministic.

use std::sync::Arc;
use std::time::Instant;

use serde::Serialize;
use stx_dynamics::atmosphere::StandardAtmosphere;
use stx_dynamics::integrate::{DormandPrince54, Hooks, IntegrateError, Rk4, Stepper, integrate};
use stx_dynamics::model::{Environment, Kinematics, ParafoilModel};
use stx_dynamics::state::StateVector;
use stx_dynamics::vehicle::Vehicle;
use stx_dynamics::wind::Calm;
use thiserror::Error;

use crate::geometry::{height_above_ground_m, lowest_point};
use crate::scenario::{Scenario, ScenarioError};

/// Longest descent flown, s: the stratospheric descent lands in about 2 h.
const MAX_DESCENT_S: f64 = 20_000.0;

/// Largest landing error against the 10× tighter reference that passes, m.
pub const LANDING_TOLERANCE_M: f64 = 1.0;

/// An integrator setting: a tolerance or a step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "method", rename_all = "snake_case")]
pub enum Setting {
    /// Dormand–Prince 5(4) with these tolerances (steps of at most 0.5 s).
    DormandPrince { rel_tol: f64, abs_tol: f64 },
    /// Classic RK4 with this step.
    Rk4 { step_s: f64 },
}

impl Setting {
    /// The reference setting: 10× tighter.
    pub fn tighter(self) -> Self {
        match self {
            Setting::DormandPrince { rel_tol, abs_tol } => Setting::DormandPrince {
                rel_tol: rel_tol / 10.0,
                abs_tol: abs_tol / 10.0,
            },
            Setting::Rk4 { step_s } => Setting::Rk4 {
                step_s: step_s / 10.0,
            },
        }
    }

    /// As people name it.
    pub fn describe(self) -> String {
        match self {
            Setting::DormandPrince { rel_tol, .. } => {
                format!("Dormand–Prince rel_tol {rel_tol:.0e}")
            }
            Setting::Rk4 { step_s } => format!("RK4 step {step_s} s"),
        }
    }

    /// Per integrator, loosest first: the settings tried until one holds the landing.
    pub fn ladders() -> [Vec<Setting>; 2] {
        [
            [0.08, 0.06, 0.05, 0.04, 0.03, 0.02, 0.01]
                .map(|step_s| Setting::Rk4 { step_s })
                .to_vec(),
            [1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6]
                .map(|tol| Setting::DormandPrince {
                    rel_tol: tol,
                    abs_tol: tol,
                })
                .to_vec(),
        ]
    }
}

/// One stratospheric descent.
#[derive(Debug, Clone, Serialize)]
pub struct DescentRun {
    /// The integrator setting.
    pub setting: Setting,
    /// Time flown, s.
    pub sim_time_s: f64,
    /// Wall time it took, s.
    pub wall_time_s: f64,
    /// Simulated over wall time.
    pub real_time_factor: f64,
    /// Derivative evaluations.
    pub rhs_evals: u64,
    /// Where the lowest body touched down, north, m.
    pub landing_x_m: f64,
    /// The same, east, m.
    pub landing_y_m: f64,
    /// Distance from the reference run's landing, m (once compared).
    pub landing_error_vs_reference_m: Option<f64>,
}

/// The whole measurement.
#[derive(Debug, Serialize)]
pub struct DynamicsReport {
    /// Derivative evaluations per second on one core.
    pub derivative_evals_per_s: f64,
    /// The same, as nanoseconds each.
    pub derivative_eval_ns: f64,
    /// The fastest run whose landing held within 1 m of its reference.
    pub best: DescentRun,
    /// Per integrator: its loosest passing setting and that setting's reference run.
    pub passing: Vec<(DescentRun, DescentRun)>,
    /// Settings that failed the 1 m criterion (or the integration), loosest first.
    pub rejected: Vec<String>,
}

/// Why the measurement could not be made.
#[derive(Debug, Error)]
pub enum SpeedError {
    /// The built-in `stratospheric` scenario does not load.
    #[error("the stratospheric scenario")]
    Scenario(#[from] ScenarioError),
    /// The integrator failed.
    #[error("stratospheric descent with {setting}")]
    Integrate {
        setting: String,
        #[source]
        source: IntegrateError,
    },
    /// The descent did not end on the ground.
    #[error("the descent did not reach the ground in 20,000 s")]
    NoLanding,
    /// No setting passed.
    #[error("no integrator setting kept the landing within 1 m of its reference")]
    NoneHeld,
}

fn stratospheric_model() -> Result<(ParafoilModel, StateVector), ScenarioError> {
    let scenario = Scenario::builtin("stratospheric")?;
    let model = ParafoilModel::new(
        Vehicle::straplex(),
        Environment {
            atmosphere: Arc::new(StandardAtmosphere),
            wind: Arc::new(Calm),
            ground_altitude_msl_m: 0.0,
        },
    );
    Ok((model, scenario.initial.to_state()))
}

/// Flies the stratospheric descent in calm air with `setting`.
pub fn descend(setting: Setting) -> Result<DescentRun, SpeedError> {
    match setting {
        Setting::DormandPrince { rel_tol, abs_tol } => descend_with(
            setting,
            &mut DormandPrince54::new(rel_tol, abs_tol).with_max_step_s(0.5),
        ),
        Setting::Rk4 { step_s } => descend_with(setting, &mut Rk4::new(step_s)),
    }
}

fn descend_with(setting: Setting, stepper: &mut impl Stepper) -> Result<DescentRun, SpeedError> {
    let (mut model, x0) = stratospheric_model()?;
    let vehicle = model.vehicle.clone();
    let mut event = |_t: f64, x: &StateVector| height_above_ground_m(&vehicle, x);
    let started = Instant::now();
    let outcome = integrate(
        stepper,
        &mut model,
        0.0,
        &x0,
        MAX_DESCENT_S,
        Hooks {
            event: Some(&mut event),
            observer: None,
        },
    )
    .map_err(|source| SpeedError::Integrate {
        setting: setting.describe(),
        source,
    })?;
    let wall = started.elapsed().as_secs_f64();
    if outcome.event_time_s.is_none() {
        return Err(SpeedError::NoLanding);
    }
    let k = Kinematics::new(&model.vehicle, &outcome.state, 0.0);
    let (body, _) = lowest_point(&model.vehicle, &k);
    let p = k.position_ned_m[body as usize];
    Ok(DescentRun {
        setting,
        sim_time_s: outcome.time_s,
        wall_time_s: wall,
        real_time_factor: outcome.time_s / wall,
        rhs_evals: model.evaluations(),
        landing_x_m: p.x,
        landing_y_m: p.y,
        landing_error_vs_reference_m: None,
    })
}

/// Derivative evaluations per second, timed for `seconds`.
pub fn evals_per_second(seconds: f64) -> Result<f64, SpeedError> {
    let (mut model, x0) = stratospheric_model()?;
    // Steady glide near the ground: the state the model spends most of a descent in.
    let mut x = x0;
    x[2] = -500.0;
    let started = Instant::now();
    let mut n = 0_u64;
    let mut sink = 0.0;
    while started.elapsed().as_secs_f64() < seconds {
        for _ in 0..1000 {
            x[0] += 1e-9;
            sink += model.derivative(0.0, &x)[6];
        }
        n += 1000;
    }
    std::hint::black_box(sink);
    Ok(n as f64 / started.elapsed().as_secs_f64())
}

/// The whole measurement: evaluations timed for `eval_seconds`, then per integrator the
/// settings of [`Setting::ladders`] loosest first until one holds its landing within
/// [`LANDING_TOLERANCE_M`] of its reference. `compared(run)` is called with each run compared
/// (its `landing_error_vs_reference_m` set), for a progress display.
pub fn measure(
    eval_seconds: f64,
    mut compared: impl FnMut(&DescentRun),
) -> Result<DynamicsReport, SpeedError> {
    let rate = evals_per_second(eval_seconds)?;
    let mut passing = Vec::new();
    let mut rejected = Vec::new();
    for ladder in Setting::ladders() {
        for setting in ladder {
            let attempt = descend(setting).and_then(|run| Ok((run, descend(setting.tighter())?)));
            let (mut run, reference) = match attempt {
                Ok(pair) => pair,
                Err(error) => {
                    rejected.push(format!("{}: {:#}", setting.describe(), Chain(&error)));
                    continue;
                }
            };
            let error = (run.landing_x_m - reference.landing_x_m)
                .hypot(run.landing_y_m - reference.landing_y_m);
            run.landing_error_vs_reference_m = Some(error);
            compared(&run);
            if error <= LANDING_TOLERANCE_M {
                passing.push((run, reference));
                break;
            }
            rejected.push(format!(
                "{}: landing {error:.3} m from its reference",
                setting.describe()
            ));
        }
    }
    let best = passing
        .iter()
        .map(|(run, _)| run)
        .max_by(|a, b| a.real_time_factor.total_cmp(&b.real_time_factor))
        .cloned()
        .ok_or(SpeedError::NoneHeld)?;
    Ok(DynamicsReport {
        derivative_evals_per_s: rate,
        derivative_eval_ns: 1e9 / rate,
        best,
        passing,
        rejected,
    })
}

/// An error with its sources, `a: b: c`, as `anyhow`'s `{:#}` prints it.
struct Chain<'a>(&'a (dyn std::error::Error + 'static));

impl std::fmt::Display for Chain<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.0)?;
        let mut source = self.0.source();
        while let Some(s) = source {
            write!(f, ": {s}")?;
            source = s.source();
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reference_is_ten_times_tighter_and_ladders_go_loosest_first() {
        assert_eq!(
            Setting::Rk4 { step_s: 0.05 }.tighter(),
            Setting::Rk4 { step_s: 0.005 }
        );
        assert_eq!(
            Setting::DormandPrince {
                rel_tol: 1e-4,
                abs_tol: 1e-4
            }
            .tighter(),
            Setting::DormandPrince {
                rel_tol: 1e-5,
                abs_tol: 1e-5
            }
        );
        for ladder in Setting::ladders() {
            let looseness: Vec<f64> = ladder
                .iter()
                .map(|s| match s {
                    Setting::Rk4 { step_s } => *step_s,
                    Setting::DormandPrince { rel_tol, .. } => *rel_tol,
                })
                .collect();
            assert!(looseness.windows(2).all(|w| w[0] > w[1]), "{looseness:?}");
        }
        assert_eq!(Setting::Rk4 { step_s: 0.05 }.describe(), "RK4 step 0.05 s");
    }

    #[test]
    fn an_error_prints_with_its_sources() {
        let e = SpeedError::NoLanding;
        assert_eq!(
            Chain(&e).to_string(),
            "the descent did not reach the ground in 20,000 s"
        );
    }
}
