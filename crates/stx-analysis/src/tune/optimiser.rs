//! The optimiser's driver: Nelder–Mead on the logarithm of the gains over the linear closed
//! loop's cost, from the current gains and from the seed's, then a restart from the better;
//! with a sensed, dispersed set ([`SensedSet`]), a last Nelder–Mead from there on that set's
//! cost. The result is rounded, flown on the nonlinear model (and the sensed set) beside the
//! current and the seed's gains, and adopted only if it does better there: on the sensed set
//! when there is one, else on the nominal model with perfect navigation.

use serde::Serialize;
use stx_dynamics::vehicle::Vehicle;
use stx_gnc::control::ControlGains;
use stx_gnc::guidance::GuidanceConfig;

use super::controller::Controller;
use super::experiment::{Experiment, TuneError};
use super::metrics::{StepMetrics, StepResponse};
use super::sensed::{SensedCost, SensedSet, SensedSummary};
use crate::nelder_mead::{NelderMeadOptions, minimize};

/// One experiment flown with one gain set.
#[derive(Debug, Clone, Serialize)]
pub struct Trial {
    /// Step size, rad or m.
    pub step: f64,
    /// Linear closed-loop step metrics.
    pub linear: StepMetrics,
    /// Nonlinear step metrics (None if the flight failed).
    pub nonlinear: Option<StepMetrics>,
    /// Why the nonlinear flight failed, if it did.
    pub nonlinear_error: Option<String>,
    /// Step responses (linear, nonlinear), for plots.
    #[serde(skip)]
    pub responses: (StepResponse, Option<StepResponse>),
}

impl Trial {
    fn fly(experiment: &Experiment, g: &ControlGains) -> Self {
        let linear_response = experiment.linear_response(g);
        let linear = experiment.score(&linear_response, g);
        let (nonlinear, nonlinear_error, nonlinear_response) =
            match experiment.nonlinear_response(g) {
                Ok(r) => (Some(experiment.score(&r, g)), None, Some(r)),
                Err(e) => (None, Some(e.to_string()), None),
            };
        Self {
            step: experiment.step,
            linear,
            nonlinear,
            nonlinear_error,
            responses: (linear_response, nonlinear_response),
        }
    }
}

/// One gain set's results.
#[derive(Debug, Clone, Serialize)]
pub struct Candidate {
    /// "current", "tuned" or "seed A.13".
    pub label: String,
    /// The full gain set.
    pub gains: ControlGains,
    /// The tuned gains' values, in the order of [`Controller::gain_names`].
    pub values: Vec<f64>,
    /// The small step (the law's linear range).
    pub small: Trial,
    /// The large step (saturation, approach phases).
    pub large: Trial,
    /// Mean of the two linear costs: what the optimiser minimised.
    pub linear_cost: f64,
    /// Mean of the two nonlinear costs (None if a flight failed): what adoption is judged on
    /// without a sensed set.
    pub nonlinear_cost: Option<f64>,
    /// The cost on the sensed, dispersed set, when tuned with one: what adoption is judged on.
    pub sensed: Option<SensedCost>,
    /// Largest real part of the closed-loop eigenvalues other than the invariances, s⁻¹.
    pub closed_loop_max_real_part: f64,
    /// The closed-loop eigenvalues `[re, im]`.
    pub closed_loop_eigenvalues: Vec<[f64; 2]>,
}

/// What `stx tune` reports.
#[derive(Debug, Clone, Serialize)]
pub struct TuneReport {
    /// The controller.
    pub controller: Controller,
    /// Gains it tunes.
    pub gain_names: Vec<&'static str>,
    /// Trim altitude, m.
    pub altitude_m: f64,
    /// Trim airspeed, m/s.
    pub trim_airspeed_mps: f64,
    /// Symmetric brake at trim.
    pub trim_brake: f64,
    /// The two experiments, in words.
    pub experiment: String,
    /// Before tuning.
    pub current: Candidate,
    /// After tuning.
    pub tuned: Candidate,
    /// The seed's appendix A.13 gains.
    pub seed: Candidate,
    /// The sensed, dispersed set tuned and judged on, if any.
    pub sensed_set: Option<SensedSummary>,
    /// Cost evaluations of the optimiser, over its three runs.
    pub evaluations: usize,
    /// Whether the run that gave the result met its tolerance.
    pub converged: bool,
    /// Whether the tuned gains are adopted (better on the nonlinear model than the current).
    pub adopted: bool,
    /// Why or why not.
    pub verdict: String,
    /// The gains to write: tuned if adopted, else the current ones.
    pub gains_out: ControlGains,
}

/// `v` rounded to `digits` significant figures.
pub fn round_significant(v: f64, digits: i32) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let scale = 10f64.powi(digits - 1 - v.abs().log10().floor() as i32);
    (v * scale).round() / scale
}

/// Cost evaluations of each optimiser run.
pub const MAX_EVALUATIONS: usize = 120;
/// Cost evaluations of the last run on the sensed set (each flies every draw's two steps).
pub const MAX_SENSED_EVALUATIONS: usize = 30;

/// Tunes `controller` starting from `current` (its other gains are kept), last on `sensed`
/// if given, checks the result on the nonlinear model (and `sensed`), and compares with the
/// seed's. `progress(done, total)` is called as the optimiser and the checks proceed.
pub fn tune(
    controller: Controller,
    vehicle: &Vehicle,
    altitude_m: f64,
    base: GuidanceConfig,
    sensed: Option<&SensedSet>,
    mut progress: impl FnMut(usize, usize),
) -> Result<TuneReport, TuneError> {
    let sensed = sensed.filter(|set| !set.is_empty());
    let current = base.gains;
    let small = Experiment::new(controller, vehicle, altitude_m, base, controller.step())?;
    let large = Experiment::new(
        controller,
        vehicle,
        altitude_m,
        base,
        controller.large_step(),
    )?;
    let linear_cost = |g: &ControlGains| {
        0.5 * (small.score(&small.linear_response(g), g).cost
            + large.score(&large.linear_response(g), g).cost)
    };
    let start = controller.get(&current);
    // The logarithm of each gain, relative to where it starts (a zero gain starts at 10⁻⁴ of
    // a unit so that it can grow).
    let anchor: Vec<f64> = start.iter().map(|&g| g.max(1e-4)).collect();
    let gains_at = |p: &[f64]| -> ControlGains {
        let values: Vec<f64> = p.iter().zip(&anchor).map(|(z, a)| a * z.exp()).collect();
        controller.with(&current, &values)
    };
    // Nelder–Mead finds a local minimum, and saturation gives this cost more than one: start
    // from the current gains and from the seed's, then restart from the better end with a
    // fresh simplex (the usual cure for a simplex that collapsed early).
    let seed_start: Vec<f64> = controller
        .get(&controller.seed_gains(&current))
        .iter()
        .zip(&anchor)
        .map(|(g, a)| (g.max(1e-6) / a).ln())
        .collect();
    let sensed_evaluations = if sensed.is_some() {
        MAX_SENSED_EVALUATIONS
    } else {
        0
    };
    let total = 3 * MAX_EVALUATIONS + sensed_evaluations + 10;
    let mut used = 0usize;
    let mut run = |from: &[f64], used_before: usize| {
        minimize(
            |p| linear_cost(&gains_at(p)),
            from,
            &NelderMeadOptions {
                initial_step: 0.7,
                cost_tolerance: 1e-4,
                position_tolerance: 0.01,
                max_evaluations: MAX_EVALUATIONS,
            },
            |n| progress(used_before + n.min(MAX_EVALUATIONS), total),
        )
    };
    let from_current = run(&vec![0.0; start.len()], used);
    used += from_current.evaluations;
    let from_seed = run(&seed_start, used);
    used += from_seed.evaluations;
    let better = if from_seed.cost < from_current.cost {
        from_seed
    } else {
        from_current
    };
    let restarted = run(&better.x, used);
    used += restarted.evaluations;
    let mut minimum = if restarted.cost <= better.cost {
        restarted
    } else {
        better
    };
    if let Some(set) = sensed {
        // The linear optimum is the start; the sensed cost has the last word.
        let start_cost = set.cost(&gains_at(&minimum.x)).mean;
        let used_before = used;
        let on_sensed = minimize(
            |p| set.cost(&gains_at(p)).mean,
            &minimum.x,
            &NelderMeadOptions {
                initial_step: 0.3,
                cost_tolerance: 1e-3,
                position_tolerance: 0.02,
                max_evaluations: MAX_SENSED_EVALUATIONS,
            },
            |n| progress(used_before + n.min(MAX_SENSED_EVALUATIONS), total),
        );
        used += on_sensed.evaluations;
        if on_sensed.cost < start_cost {
            minimum = on_sensed;
        }
    }
    // Three significant figures: what a person can read and type, and well inside the
    // optimum's flat bottom.
    let rounded: Vec<f64> = controller
        .get(&gains_at(&minimum.x))
        .into_iter()
        .map(|v| round_significant(v, 3))
        .collect();
    let tuned_gains = controller.with(&current, &rounded);
    let candidate = |label: &str, g: ControlGains| -> Candidate {
        let small_trial = Trial::fly(&small, &g);
        let large_trial = Trial::fly(&large, &g);
        let nonlinear_cost = match (small_trial.nonlinear, large_trial.nonlinear) {
            (Some(a), Some(b)) => Some(0.5 * (a.cost + b.cost)),
            _ => None,
        };
        let cl = small.closed_loop_eigenvalues(&g);
        let max_real = cl
            .iter()
            .filter(|e| e.0.hypot(e.1) >= crate::analysis::zero_tolerance(small.trim()))
            .map(|e| e.0)
            .fold(f64::NEG_INFINITY, f64::max);
        Candidate {
            label: label.into(),
            gains: g,
            values: controller.get(&g),
            linear_cost: 0.5 * (small_trial.linear.cost + large_trial.linear.cost),
            nonlinear_cost,
            sensed: sensed.map(|set| set.cost(&g)),
            small: small_trial,
            large: large_trial,
            closed_loop_max_real_part: max_real,
            closed_loop_eigenvalues: cl.iter().map(|&(re, im)| [re, im]).collect(),
        }
    };
    let current_c = candidate("current", current);
    progress(total - 6, total);
    let tuned_c = candidate("tuned", tuned_gains);
    progress(total - 3, total);
    let seed_c = candidate("seed A.13", controller.seed_gains(&current));
    progress(total, total);
    // Judged on the sensed set when there is one: that is the system the drone flies.
    let (judged, judged_cost): (&str, fn(&Candidate) -> f64) = if sensed.is_some() {
        ("sensed, dispersed", |c| {
            c.sensed.as_ref().map_or(f64::INFINITY, |s| s.mean)
        })
    } else {
        ("nonlinear", |c| c.nonlinear_cost.unwrap_or(f64::INFINITY))
    };
    let (adopted, verdict) = if judged_cost(&tuned_c) < judged_cost(&current_c) {
        (
            true,
            format!(
                "tuned gains lower the {judged} cost from {:.3} to {:.3}",
                judged_cost(&current_c),
                judged_cost(&tuned_c)
            ),
        )
    } else {
        (
            false,
            format!(
                "tuned gains do not improve the {judged} cost ({:.3} against {:.3} now): \
                 current gains kept",
                judged_cost(&tuned_c),
                judged_cost(&current_c)
            ),
        )
    };
    let t = small.trim();
    Ok(TuneReport {
        controller,
        gain_names: controller.gain_names().to_vec(),
        altitude_m,
        trim_airspeed_mps: t.airspeed_mps,
        trim_brake: t.controls.brake_right,
        experiment: match controller {
            Controller::Heading => "heading steps of 30° and 90° from a trimmed glide".into(),
            Controller::Course => "course steps of 30° and 90° from a trimmed glide".into(),
            Controller::Localizer => {
                "6 m (following phase) and 40 m (approach, then following) off a localizer".into()
            }
            Controller::Vertical => format!(
                "5 m (following phase) and 10 m (approach) above a glide path at the slope \
                 trimmed with brake {:.2}",
                t.controls.brake_right
            ),
        },
        gains_out: if adopted { tuned_gains } else { current },
        current: current_c,
        tuned: tuned_c,
        seed: seed_c,
        sensed_set: sensed.map(SensedSet::summary),
        evaluations: used,
        converged: minimum.converged,
        adopted,
        verdict,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Too much proportional gain and almost no damping: a lightly damped turn; the gains and
    /// a guidance configuration flying them.
    fn lightly_damped_heading() -> (ControlGains, GuidanceConfig) {
        let bad = ControlGains {
            hk1_m_per_rad: 0.04,
            hk2_m_s_per_rad: 0.001,
            ..ControlGains::default()
        };
        let base = GuidanceConfig {
            gains: bad,
            ..GuidanceConfig::default()
        };
        (bad, base)
    }

    #[test]
    fn rounding_keeps_three_significant_figures() {
        assert_eq!(round_significant(0.010502721, 3), 0.0105);
        assert_eq!(round_significant(6.54321, 3), 6.54);
        assert_eq!(round_significant(-0.000226183, 3), -0.000226);
        assert_eq!(round_significant(0.0, 3), 0.0);
    }

    #[test]
    fn tuning_the_heading_loop_from_bad_gains_lowers_its_cost_on_both_models() {
        let vehicle = Vehicle::straplex();
        let (bad, base) = lightly_damped_heading();
        let mut calls = 0;
        let report = tune(Controller::Heading, &vehicle, 600.0, base, None, |_, _| {
            calls += 1
        })
        .expect("tunes");
        assert!(calls > 10);
        assert!(report.adopted, "{}", report.verdict);
        let before = report.current.nonlinear_cost.expect("flies");
        let after = report.tuned.nonlinear_cost.expect("flies");
        assert!(after < 0.8 * before, "{before} → {after}");
        assert!(report.tuned.linear_cost < report.current.linear_cost);
        assert!(report.tuned.closed_loop_max_real_part < 0.0);
        // The other gains are untouched.
        assert_eq!(report.gains_out.hk3_m_per_m, bad.hk3_m_per_m);
        assert_eq!(report.gains_out.vk1, bad.vk1);
        // And the linear closed loop predicts the nonlinear one: same metrics within a few
        // tenths of a second and per cent.
        let (l, n) = (
            report.tuned.small.linear,
            report.tuned.small.nonlinear.expect("flies"),
        );
        let (lr, nr) = (l.rise_time_s.expect("rises"), n.rise_time_s.expect("rises"));
        assert!((lr - nr).abs() < 0.5, "{lr} vs {nr}");
        assert!((l.overshoot_pct - n.overshoot_pct).abs() < 3.0);
    }

    #[test]
    fn with_a_sensed_set_the_gains_are_tuned_and_judged_on_dispersed_stacks_with_the_estimator() {
        let vehicle = Vehicle::straplex();
        let (bad, base) = lightly_damped_heading();
        let spec = crate::tune::SensedSpec {
            dispersions: stx_sim::dispersions::Dispersions::load("realistic").expect("set"),
            sensors: stx_sim::sensors::SensorConfig::default(),
            count: 2,
            seed: 7,
        };
        let set = SensedSet::draw(Controller::Heading, &vehicle, 600.0, base, &spec);
        assert_eq!(set.len() + set.excluded.len(), 2);
        assert!(!set.is_empty(), "{:?}", set.excluded);
        let report = tune(
            Controller::Heading,
            &vehicle,
            600.0,
            base,
            Some(&set),
            |_, _| {},
        )
        .expect("tunes");
        let sensed = |c: &Candidate| c.sensed.as_ref().expect("judged on the set").mean;
        // The lightly damped gains turn worse on the dispersed stacks too, and the tuned ones
        // are adopted on that judgement.
        assert!(report.adopted, "{}", report.verdict);
        assert!(
            report.verdict.contains("sensed, dispersed"),
            "{}",
            report.verdict
        );
        assert!(
            sensed(&report.tuned) < sensed(&report.current),
            "{} against {}",
            sensed(&report.tuned),
            sensed(&report.current)
        );
        // The set's costs are not the perfect-navigation model's: the estimator and the
        // dispersed stacks are in the loop.
        let perfect = report.tuned.nonlinear_cost.expect("flies");
        assert!((sensed(&report.tuned) - perfect).abs() > 1e-3);
        assert!(report.evaluations > 3 * MAX_EVALUATIONS.min(10));
        assert_eq!(
            report.sensed_set.as_ref().map(|s| s.draws.len()),
            Some(set.len())
        );
        // Deterministic: the same set gives the same cost.
        assert_eq!(set.cost(&bad).mean, set.cost(&bad).mean);
    }
}
