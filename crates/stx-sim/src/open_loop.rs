//! Flies a scenario's open-loop servo schedule with the flight model, to the ground or to the
//! scenario's end, and summarises it (seed §4.6 behaviour: settling, steady glide, peaks).
//!
//! The integrator runs one call per constant-command segment, so its interpolants never
//! straddle a command change; ground contact (lowest body reaching the ground) is an event
//! located inside the step that crossed it.

use std::sync::Arc;
use std::time::Instant;

use serde::Serialize;
use stx_dynamics::atmosphere::StandardAtmosphere;
use stx_dynamics::integrate::{Hooks, IntegrateError, integrate};
use stx_dynamics::model::{Body, Environment, Kinematics, ParafoilModel};
use stx_dynamics::output::Sample;
use stx_dynamics::state::{StateVector, idx};
use stx_dynamics::vehicle::Vehicle;
use stx_dynamics::wind::{Calm, WindField};
use thiserror::Error;

use crate::scenario::{Integrator, Scenario, ScenarioError};
use crate::summary::{StepRecord, Summary, summarise};

/// Why a run failed.
#[derive(Debug, Error)]
pub enum RunError {
    /// The scenario is invalid.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// The integrator could not follow the solution.
    #[error("integration failed")]
    Integrate(#[from] IntegrateError),
    /// Navigation could not be set up.
    #[error(transparent)]
    Navigation(#[from] crate::closed_loop::NavigationError),
}

/// A finished run.
#[derive(Debug, Clone, Serialize)]
pub struct Run {
    /// Recorded samples at the scenario's output interval (and the last instant).
    pub samples: Vec<Sample>,
    /// The summary.
    pub summary: Summary,
}

/// Height of the lowest point of the stack above the ground, m: the event that ends a flight.
/// Far above the ground the canopy's height stands in for it (both are positive there), which
/// spares walking the chain at every step.
pub fn height_above_ground_m(vehicle: &Vehicle, x: &StateVector) -> f64 {
    let canopy_height = -x[idx::POSITION + 2];
    let stack_height_m = 30.0;
    if canopy_height > stack_height_m {
        return canopy_height;
    }
    let k = Kinematics::new(vehicle, x, 0.0);
    lowest_point(vehicle, &k).1
}

/// The body whose lowest point is nearest the ground, and that point's height, m.
pub fn lowest_point(vehicle: &Vehicle, k: &Kinematics) -> (Body, f64) {
    let half_heights = [
        0.5 * vehicle.config.canopy.thickness_m,
        0.5 * vehicle.config.drone.height_m,
        0.5 * vehicle.capsule.height_m,
        0.5 * vehicle.transponder.height_m,
    ];
    Body::ALL
        .into_iter()
        .map(|b| {
            (
                b,
                -k.position_ned_m[b as usize].z - half_heights[b as usize],
            )
        })
        .fold((Body::Canopy, f64::INFINITY), |best, c| {
            if c.1 < best.1 { c } else { best }
        })
}

/// Runs `scenario` with `vehicle`: open loop, or closed loop when it has guidance.
pub fn run(scenario: &Scenario, vehicle: &Vehicle) -> Result<Run, RunError> {
    if scenario.guidance.is_some() {
        return crate::guided::run(scenario, vehicle);
    }
    let started = Instant::now();
    let wind: Arc<dyn WindField> = match &scenario.environment.wind {
        Some(w) => Arc::from(w.build().map_err(ScenarioError::from)?),
        None => Arc::new(Calm),
    };
    let mut model = ParafoilModel::new(
        vehicle.clone(),
        Environment {
            atmosphere: Arc::new(StandardAtmosphere),
            wind,
            ground_altitude_msl_m: scenario.environment.ground_altitude_msl_m,
        },
    );
    let mut integrator = scenario.integrator.build()?;
    let travel = vehicle.main_line_travel_m;
    let threshold = scenario.steady.rate_threshold_rad_s;

    let mut steps: Vec<StepRecord> = Vec::new();
    let mut recorded: Vec<(f64, StateVector, stx_dynamics::state::Controls)> = Vec::new();
    let mut next_record_s = 0.0;
    let mut x = scenario.initial.to_state();
    let mut t = 0.0;
    let mut landed = false;

    let mut boundaries: Vec<f64> = scenario.control_change_times();
    boundaries.retain(|b| *b < scenario.duration_s);
    boundaries.push(scenario.duration_s);
    let mut end_s = scenario.duration_s;
    let mut extended = 0.0;
    let mut segment = 0;
    loop {
        let segment_end = if segment < boundaries.len() {
            boundaries[segment]
        } else {
            end_s
        };
        let controls = scenario.controls_at(t, travel);
        model.set_controls(controls);
        let held = model.controls();
        let event_vehicle = vehicle.clone();
        let mut event = |_t: f64, x: &StateVector| height_above_ground_m(&event_vehicle, x);
        let interval = scenario.output.interval_s;
        let mut observer = |time_s: f64, x: &StateVector| {
            steps.push(StepRecord::from_state(time_s, x, threshold));
            if time_s >= next_record_s {
                recorded.push((time_s, *x, held));
                next_record_s = time_s + interval;
            }
        };
        let hooks = Hooks {
            event: Some(&mut event),
            observer: Some(&mut observer),
        };
        let outcome = match &mut integrator {
            Integrator::Rk4(s) => integrate(s, &mut model, t, &x, segment_end, hooks)?,
            Integrator::DormandPrince(s) => integrate(s, &mut model, t, &x, segment_end, hooks)?,
        };
        t = outcome.time_s;
        x = outcome.state;
        if recorded.last().map(|r| r.0) != Some(t) {
            recorded.push((t, x, held));
        }
        if outcome.event_time_s.is_some() {
            landed = true;
            break;
        }
        segment += 1;
        if segment < boundaries.len() {
            continue;
        }
        // The scenario is over: extend it until it has a steady stretch to report, if needed.
        let has_steady =
            crate::summary::steady_window(&steps, scenario.steady.window_s, scenario).is_some();
        if has_steady || extended >= scenario.steady.max_extension_s {
            break;
        }
        let more = 10.0_f64.min(scenario.steady.max_extension_s - extended);
        extended += more;
        end_s = t + more;
    }

    let samples: Vec<Sample> = recorded
        .iter()
        .map(|(time_s, state, controls)| {
            model.set_controls(*controls);
            model.sample(*time_s, state)
        })
        .collect();
    let line_errors: Vec<f64> = recorded
        .iter()
        .map(|(_, state, controls)| max_line_length_error_m(vehicle, state, controls.main_line_m))
        .collect();
    let landing = landed.then(|| {
        let k = Kinematics::new(vehicle, &x, model.controls().main_line_m);
        let (body, _) = lowest_point(vehicle, &k);
        let p = k.position_ned_m[body as usize];
        crate::summary::Landing {
            x_m: p.x,
            y_m: p.y,
            time_s: t,
            body: body.name(),
            vertical_speed_mps: k.velocity_ned_mps(body).z,
            miss_m: None,
            cross_track_m: None,
            along_track_m: None,
            heading_vs_upwind_deg: None,
        }
    });
    let summary = summarise(
        scenario,
        &steps,
        &samples,
        &line_errors,
        landing,
        extended,
        model.evaluations(),
        started.elapsed().as_secs_f64(),
    );
    Ok(Run { samples, summary })
}

/// Largest deviation of the constrained line lengths (mean main line, capsule line,
/// transponder line) from their design values, measured between the points the lines are
/// fixed to on each body, m. Those points come from the same chain that places the bodies,
/// so the lengths hold by construction and this measures rounding in the chain only.
pub fn max_line_length_error_m(
    vehicle: &Vehicle,
    x: &StateVector,
    main_line_command_m: f64,
) -> f64 {
    let k = Kinematics::new(vehicle, x, main_line_command_m);
    let ends = k.line_ends_ned_m(vehicle);
    let top = (ends[0].0 + ends[1].0) * 0.5;
    let bottom = (ends[0].1 + ends[1].1) * 0.5;
    [
        (top - bottom).norm() - k.line_drop_m.norm(),
        (ends[2].0 - ends[2].1).norm() - vehicle.capsule_line_length_m,
        (ends[3].0 - ends[3].1).norm() - vehicle.transponder_line_length_m,
    ]
    .into_iter()
    .fold(0.0, |m, e| m.max(e.abs()))
}
