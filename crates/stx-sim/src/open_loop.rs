//! Flies a scenario's open-loop servo schedule with the flight model, to the ground or to the
//! scenario's end, and summarises it (seed §4.6 behaviour: settling, steady glide, peaks).
//!
//! The integrator runs one call per constant-command segment, so its interpolants never
//! straddle a command change; ground contact (lowest body reaching the ground) is an event
//! located inside the step that crossed it.

use std::sync::Arc;
use std::time::Instant;

use stx_dynamics::atmosphere::StandardAtmosphere;
use stx_dynamics::integrate::{Hooks, integrate};
use stx_dynamics::model::{Environment, Kinematics, ParafoilModel};
use stx_dynamics::output::Sample;
use stx_dynamics::state::StateVector;
use stx_dynamics::vehicle::Vehicle;
use stx_dynamics::wind::{Calm, WindField};

pub use crate::geometry::{height_above_ground_m, lowest_point, max_line_length_error_m};
pub use crate::run::{Run, RunError};
use crate::scenario::{Integrator, Scenario, ScenarioError};
use crate::summary::{StepRecord, summarise};

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
