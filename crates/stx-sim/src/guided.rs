//! Flies a scenario in closed loop (seed chapter 5): the onboard software — sensors, estimator,
//! guidance — steers the 14-DOF model at 4 Hz from the scenario's `guidance.start_s`, to the
//! ground or the scenario's end, and the run is summarised like an open-loop one plus where and
//! how it landed and which phases guidance went through.

use std::sync::Arc;
use std::time::Instant;

use stx_dynamics::atmosphere::StandardAtmosphere;
use stx_dynamics::model::{Environment, ParafoilModel};
use stx_dynamics::output::Sample;
use stx_dynamics::rotation::wrap_pi;
use stx_dynamics::state::StateVector;
use stx_dynamics::vehicle::Vehicle;
use stx_dynamics::wind::{Calm, WindField};
use stx_gnc::guidance::Guidance;

use crate::closed_loop::{GuidedFlight, SensedNavigation, Touchdown};
use crate::geometry::max_line_length_error_m;
use crate::run::{Run, RunError};
use crate::scenario::{Scenario, ScenarioError};
use crate::summary::{Landing, PhaseStart, StepRecord, summarise};

/// RK4 step of closed-loop flights, s: stable with margin in glides and turns (the model needs
/// < 0.08 s), five per control period; [`GuidedFlight::advance`] refines it where it fails.
pub const STEP_S: f64 = 0.05;
/// Control period: the drone's measurement and control rate, 4 Hz (seed §3.3.2).
pub use stx_gnc::guidance::CONTROL_PERIOD_S;

/// Runs a scenario that has a `[guidance]` section.
pub fn run(scenario: &Scenario, vehicle: &Vehicle) -> Result<Run, RunError> {
    let started = Instant::now();
    let Some(g) = &scenario.guidance else {
        return Err(ScenarioError::Invalid {
            field: "guidance".into(),
            value: "absent".into(),
            rule: "a closed-loop run needs a guidance section",
        }
        .into());
    };
    let wind: Arc<dyn WindField> = match &scenario.environment.wind {
        Some(w) => Arc::from(w.build().map_err(ScenarioError::from)?),
        None => Arc::new(Calm),
    };
    let model = ParafoilModel::new(
        vehicle.clone(),
        Environment {
            atmosphere: Arc::new(StandardAtmosphere),
            wind,
            ground_altitude_msl_m: scenario.environment.ground_altitude_msl_m,
        },
    );
    let mut guidance = Guidance::new(g.config);
    guidance.set_plan(g.plan(), 0.0);
    let navigation = SensedNavigation::new(&g.sensors, g.estimator.clone(), g.seed)?;
    let mut flight = GuidedFlight::new(
        model,
        scenario.initial.to_state(),
        0.0,
        guidance,
        navigation,
        STEP_S,
        CONTROL_PERIOD_S,
    );
    let threshold = scenario.steady.rate_threshold_rad_s;
    let mut steps = vec![StepRecord::from_state(0.0, &flight.state, threshold)];
    let mut recorded: Vec<(f64, StateVector, stx_dynamics::state::Controls)> = Vec::new();
    let mut next_record_s = 0.0;
    let mut mode_set = false;
    let touchdown = loop {
        if !mode_set && flight.time_s >= g.start_s {
            flight.guidance.set_mode(g.mode, flight.time_s);
            mode_set = true;
        }
        if flight.time_s >= next_record_s {
            recorded.push((flight.time_s, flight.state, flight.model.controls()));
            next_record_s = flight.time_s + scenario.output.interval_s;
        }
        let touchdown = flight.advance()?;
        steps.push(StepRecord::from_state(
            flight.time_s,
            &flight.state,
            threshold,
        ));
        if touchdown.is_some() || flight.time_s >= scenario.duration_s {
            break touchdown;
        }
    };
    recorded.push((flight.time_s, flight.state, flight.model.controls()));

    let mut model = flight.model.clone();
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
    let localizer = (g.mode == stx_gnc::mission::FlightMode::Localizer).then(|| g.plan().localizer);
    let landing_of = |t: &Touchdown| Landing {
        x_m: t.position_ne_m[0],
        y_m: t.position_ne_m[1],
        time_s: t.time_s,
        body: t.body.name(),
        vertical_speed_mps: t.vertical_speed_mps,
        miss_m: match (g.aim_ne_m(), localizer) {
            (Some(aim), _) => {
                Some((t.position_ne_m[0] - aim[0]).hypot(t.position_ne_m[1] - aim[1]))
            }
            (None, Some(line)) => Some(line.cross_track_m(t.position_ne_m).abs()),
            (None, None) => None,
        },
        cross_track_m: localizer.map(|line| line.cross_track_m(t.position_ne_m)),
        along_track_m: localizer.map(|line| line.along_track_m(t.position_ne_m)),
        heading_vs_upwind_deg: t
            .upwind_rad
            .is_finite()
            .then(|| wrap_pi(t.heading_rad - t.upwind_rad).to_degrees()),
    };
    let landing = touchdown.as_ref().map(landing_of);
    // The payload is what the target is for: fly on to the capsule's touchdown, as the Monte
    // Carlo does (the recorded samples end at the first contact, as before).
    let payload_landing = match touchdown {
        Some(first) => Some(landing_of(
            &flight
                .land_payload(first)
                .map_err(|reason| RunError::Payload { reason })?,
        )),
        None => None,
    };
    let mut summary = summarise(
        scenario,
        &steps,
        &samples,
        &line_errors,
        landing,
        0.0,
        flight.model.evaluations(),
        started.elapsed().as_secs_f64(),
    );
    summary.payload_landing = payload_landing;
    summary.phases = flight
        .phases
        .iter()
        .map(|(phase, start)| PhaseStart {
            phase: phase.clone(),
            start_time_s: *start,
        })
        .collect();
    Ok(Run { samples, summary })
}
