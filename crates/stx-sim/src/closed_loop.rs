//! A guided flight: the 14-DOF model in the loop with navigation and the onboard guidance, one
//! control period (4 Hz, the drone's measurement rate) at a time.
//!
//! Each [`GuidedFlight::advance`] integrates the model over one period with the servo commands
//! held, stops exactly at ground contact, then lets navigation produce an estimate and guidance
//! the next commands. Navigation is a [`Navigator`]: the sensors and the estimator in every
//! scenario and Monte Carlo run; [`PerfectNavigation`] exists only to measure what navigation
//! errors cost.

use stx_dynamics::atmosphere::{Atmosphere, StandardAtmosphere};
use stx_dynamics::integrate::{Hooks, IntegrateError, Rk4, integrate};
use stx_dynamics::model::{Body, Kinematics, ParafoilModel};
use stx_dynamics::rotation::{euler_from_t, euler_rates, wrap_pi};
use stx_dynamics::state::{StateVector, idx, vec3_at};
use stx_gnc::control::LawPhase;
use stx_gnc::estimate::Estimate;
use stx_gnc::estimator::{Estimator, EstimatorConfig, EstimatorConfigError};
use stx_gnc::guidance::{Guidance, PhaseEvent};
use stx_gnc::mission::{FlightMode, GuidancePhase};

use crate::dispersions::ServoErrors;
use crate::geometry::{height_of_lowest_m, lowest_of};
use crate::sensors::{
    Delivery, DeliveryQueue, SensorConfig, SensorConfigError, SensorSuite, Truth,
};

/// Navigation as the drone does it: its sensors sample the truth, their measurements reach the
/// estimator after their latencies, and the estimator's output is what guidance sees.
#[derive(Debug, Clone)]
pub struct SensedNavigation {
    sensors: SensorSuite,
    in_flight: DeliveryQueue,
    estimator: Estimator,
}

/// Why navigation could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum NavigationError {
    /// Bad sensor settings.
    #[error(transparent)]
    Sensors(#[from] SensorConfigError),
    /// Bad estimator settings.
    #[error(transparent)]
    Estimator(#[from] EstimatorConfigError),
}

impl SensedNavigation {
    /// Sensors with `sensors` settings and noise seed `seed`, feeding an estimator.
    pub fn new(
        sensors: &SensorConfig,
        estimator: EstimatorConfig,
        seed: u64,
    ) -> Result<Self, NavigationError> {
        Ok(Self {
            sensors: SensorSuite::new(sensors, seed)?,
            in_flight: DeliveryQueue::new(),
            estimator: Estimator::new(estimator)?,
        })
    }

    /// The estimator, for its counters.
    pub fn estimator(&self) -> &Estimator {
        &self.estimator
    }

    /// The sensors, for the errors they drew.
    pub fn sensors(&self) -> &SensorSuite {
        &self.sensors
    }

    /// Samples the sensors on `truth` and hands the estimator every measurement that has
    /// reached it by `truth.time_s`; returns those measurements, in arrival order (the drone
    /// also sends them to the station). Any truth will do: the simulated drone's stages
    /// before the parafoil build theirs without the 14-DOF model.
    pub fn sense(&mut self, truth: &Truth) -> Vec<Delivery> {
        for delivery in self.sensors.sample(truth.time_s, truth) {
            self.in_flight.push(delivery);
        }
        let mut arrived = Vec::new();
        while let Some(delivery) = self.in_flight.pop_due(truth.time_s) {
            self.estimator
                .handle(delivery.arrival_s, &delivery.measurement);
            arrived.push(delivery);
        }
        arrived
    }

    /// The estimate at `time_s`.
    pub fn estimate(&self, time_s: f64) -> Estimate {
        self.estimator.estimate(time_s)
    }
}

impl Navigator for SensedNavigation {
    fn navigate(&mut self, model: &ParafoilModel, time_s: f64, x: &StateVector) -> Estimate {
        self.sense(&Truth::from_model(model, time_s, x));
        self.estimator.estimate(time_s)
    }

    fn sensor_errors(&self) -> Option<SensorErrors> {
        Some(SensorErrors {
            heading_bias_rad: self.sensors.ahrs_bias_rad().z,
            pitot_scale: self.sensors.pitot_airspeed_scale(),
        })
    }
}

/// The errors of the drone's sensors that the estimator learns, as drawn for a flight: what
/// its estimates of them are held against.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorErrors {
    /// The AHRS's heading bias now (its yaw minus the true yaw), rad.
    pub heading_bias_rad: f64,
    /// The pitot's airspeed scale (its airspeed over the true one along the x axis).
    pub pitot_scale: f64,
}

/// Produces the estimate guidance flies on.
pub trait Navigator {
    /// The estimate at `time_s`, given the true state (from which sensors measure).
    fn navigate(&mut self, model: &ParafoilModel, time_s: f64, x: &StateVector) -> Estimate;

    /// The sensor errors the estimate should find, where there are sensors.
    fn sensor_errors(&self) -> Option<SensorErrors> {
        None
    }
}

/// The estimate read straight from the simulator's truth. Never used by scenarios or the Monte
/// Carlo: only to measure how much the real estimator costs in accuracy.
#[derive(Debug, Default, Clone, Copy)]
pub struct PerfectNavigation;

impl Navigator for PerfectNavigation {
    fn navigate(&mut self, model: &ParafoilModel, time_s: f64, x: &StateVector) -> Estimate {
        truth_estimate(model, time_s, x)
    }
}

/// What a perfect estimator would report, with zero uncertainty: the drone's position,
/// velocity, roll and pitch (where the GPS and AHRS are), the canopy's heading and heading rate
/// (the vehicle's, which the drone's twisting yaw only approximates), the air-relative speed.
pub fn truth_estimate(model: &ParafoilModel, time_s: f64, x: &StateVector) -> Estimate {
    let k = Kinematics::new(&model.vehicle, x, model.controls().main_line_m);
    let p = k.position_ned_m[Body::Drone as usize];
    let v = k.velocity_ned_mps(Body::Drone);
    let euler = euler_from_t(&k.t_i_body[Body::Drone as usize]);
    let canopy_rates = euler_rates(
        &vec3_at(x, idx::CANOPY_EULER),
        &vec3_at(x, idx::CANOPY_RATES),
    );
    let wind = model.environment.wind.wind_ned_mps(time_s, &p);
    let v_air = v - wind;
    let horizontal_air = v_air.x.hypot(v_air.y);
    let sink = v.z;
    Estimate {
        time_s,
        position_ned_m: p,
        position_sigma_m: Default::default(),
        velocity_ned_mps: v,
        velocity_sigma_mps: Default::default(),
        // The vehicle's heading is the canopy's: the drone twists about its lines by tens of
        // degrees in turns, which an estimator filters out of the AHRS yaw.
        heading_rad: wrap_pi(x[idx::CANOPY_EULER + 2]),
        heading_sigma_rad: 0.0,
        heading_rate_rad_s: canopy_rates.z,
        heading_rate_sigma_rad_s: 0.0,
        drone_yaw_rad: wrap_pi(euler.z),
        drone_yaw_rate_rad_s: 0.0,
        course_rad: v.y.atan2(v.x),
        course_sigma_rad: 0.0,
        roll_rad: euler.x,
        pitch_rad: euler.y,
        airspeed_mps: v_air.norm(),
        airspeed_sigma_mps: 0.0,
        sink_rate_mps: sink,
        sink_rate_sigma_mps: 0.0,
        glide_ratio_air: if sink > 0.1 {
            horizontal_air / sink
        } else {
            f64::INFINITY
        },
        glide_ratio_ground: if sink > 0.1 {
            v.x.hypot(v.y) / sink
        } else {
            f64::INFINITY
        },
        glide_ratio_air_sigma: 0.0,
        glide_ratio_ground_sigma: 0.0,
        air_density_kg_per_m3: model
            .environment
            .atmosphere
            .air_at(model.environment.ground_altitude_msl_m - p.z)
            .density_kg_per_m3,
        air_density_sigma_kg_per_m3: 0.0,
        wind_ned_mps: nalgebra::Vector3::new(wind.x, wind.y, 0.0),
        wind_sigma_mps: Default::default(),
        // No AHRS, no pitot: nothing to be biased.
        heading_bias_rad: 0.0,
        heading_bias_sigma_rad: 0.0,
        pitot_scale: 1.0,
        pitot_scale_sigma: 0.0,
        gps_ok: true,
        gps_age_s: 0.0,
        attitude_ok: true,
        air_data_ok: true,
    }
}

/// Where and how the stack met the ground.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Touchdown {
    /// Time of first contact, s.
    pub time_s: f64,
    /// Body that touched first.
    pub body: Body,
    /// Its position (north, east), m.
    pub position_ne_m: [f64; 2],
    /// Its vertical speed at contact, m/s (positive down).
    pub vertical_speed_mps: f64,
    /// Canopy heading at contact, rad.
    pub heading_rad: f64,
    /// Direction the wind came from at the ground at contact, rad (NaN in calm air).
    pub upwind_rad: f64,
}

/// One guided flight.
pub struct GuidedFlight<N: Navigator> {
    /// The flight model with its environment.
    pub model: ParafoilModel,
    /// The true state.
    pub state: StateVector,
    /// Time, s.
    pub time_s: f64,
    /// Onboard guidance.
    pub guidance: Guidance,
    /// Navigation.
    pub navigator: N,
    step_s: f64,
    control_period_s: f64,
    /// Latest estimate guidance used.
    pub estimate: Option<Estimate>,
    /// Every phase entered, with its start time: guidance phases, and in localizer mode the
    /// phases of its laws (`localizer_approach`, `glide_slope_following`, …).
    pub phases: Vec<(String, f64)>,
    /// Every phase event, with its reason.
    pub events: Vec<PhaseEvent>,
    /// Each time guidance called the target out of reach: when, and the best reachable point
    /// (north, east, m) it announced then.
    pub best_reachable_announced: Vec<(f64, [f64; 2])>,
    /// What the servos do with guidance's commands (perfect unless a dispersion set says).
    pub servos: ServoErrors,
    /// The bodies whose ground contact ends a period: all of them, until the transponder is
    /// down and the payload flies on ([`Self::land_payload`]).
    pub touching: &'static [Body],
}

/// The bodies still flying once the transponder lies on the ground.
pub const PAYLOAD_BODIES: [Body; 3] = [Body::Canopy, Body::Drone, Body::Capsule];

/// What is left of the transponder's mass once its line is slack, as a fraction: a slack line
/// carries no force, and 1 % (17 g) keeps its two pendulum angles in the equations well posed
/// without a weight the stack would feel (0.2 % of its weight).
pub const SLACK_TRANSPONDER_MASS_FRACTION: f64 = 0.01;

/// Longest the payload is flown on after the transponder's contact before the run counts as
/// failed, s (its line is 5 m; the stack sinks at 1–3 m/s).
pub const PAYLOAD_LANDING_MAX_S: f64 = 20.0;

impl<N: Navigator> GuidedFlight<N> {
    /// A flight starting at `state` at `time_s`, integrated with RK4 steps of `step_s` and
    /// guided every `control_period_s`.
    pub fn new(
        model: ParafoilModel,
        state: StateVector,
        time_s: f64,
        guidance: Guidance,
        navigator: N,
        step_s: f64,
        control_period_s: f64,
    ) -> Self {
        let phase = guidance.phase();
        Self {
            model,
            state,
            time_s,
            guidance,
            navigator,
            step_s,
            control_period_s,
            estimate: None,
            phases: vec![(phase_name(phase), time_s)],
            events: Vec::new(),
            best_reachable_announced: Vec::new(),
            servos: ServoErrors::default(),
            touching: &Body::ALL,
        }
    }

    /// Navigates and guides at the current instant: new servo commands.
    pub fn guide(&mut self) {
        let est = self
            .navigator
            .navigate(&self.model, self.time_s, &self.state);
        // Guidance plans with the density the drone measures (in the estimate); until the
        // pitot has reported, with the standard atmosphere at the estimated height — what the
        // drone assumes, not the simulator's air.
        let assumed = StandardAtmosphere
            .air_at(self.model.environment.ground_altitude_msl_m - est.position_ned_m.z)
            .density_kg_per_m3;
        let command = self.guidance.update(&est, assumed);
        let controls = if self.servos.is_perfect() {
            command.controls
        } else {
            let travel = self.model.vehicle.main_line_travel_m;
            self.servos
                .apply(command.controls, self.model.controls(), travel)
        };
        self.model.set_controls(controls);
        for event in self.guidance.drain_events() {
            self.phases.push((phase_name(event.to), event.time_s));
            if event.to == GuidancePhase::BestReachable {
                self.best_reachable_announced.push((
                    event.time_s,
                    self.guidance.spiral_status().best_reachable_ne_m,
                ));
            }
            self.events.push(event);
        }
        if self.guidance.mode() == FlightMode::Localizer
            && let Some((horizontal, vertical)) = self.guidance.law_phases()
        {
            let mut note = |name: String| {
                let seen = self
                    .phases
                    .iter()
                    .rev()
                    .find(|(n, _)| n.starts_with(name.split('_').next().unwrap_or_default()));
                if seen.map(|(n, _)| n != &name).unwrap_or(true) {
                    self.phases.push((name, self.time_s));
                }
            };
            note(format!("localizer_{}", law_name(horizontal)));
            if let Some(v) = vertical {
                note(format!("glide_slope_{}", law_name(v)));
            }
        }
        self.estimate = Some(est);
    }

    /// Flies one control period (guiding first); `Some` when the stack touched down in it.
    ///
    /// The period is integrated by [`fly_period`].
    pub fn advance(&mut self) -> Result<Option<Touchdown>, IntegrateError> {
        self.guide();
        let (time_s, state, contact_s) = fly_period_over(
            &mut self.model,
            self.time_s,
            &self.state,
            self.step_s,
            self.control_period_s,
            self.touching,
        )?;
        self.time_s = time_s;
        self.state = state;
        Ok(contact_s.map(|t| touchdown_of(&self.model, &self.state, t, self.touching)))
    }

    /// Flies on after the first contact `first` until the capsule (the payload) is down, and
    /// returns its touchdown. When the transponder touched first its line goes slack: the
    /// stack, lighter by the transponder's weight, flies on under guidance (still flaring)
    /// until the capsule touches. The slack line is modelled by keeping the transponder's
    /// pendulum with [`SLACK_TRANSPONDER_MASS_FRACTION`] of its mass and no drag, let through
    /// the ground. When another body touched first, that contact is the payload's landing too.
    pub fn land_payload(&mut self, first: Touchdown) -> Result<Touchdown, String> {
        if first.body != Body::Transponder {
            return Ok(first);
        }
        let transponder = &mut self.model.vehicle.transponder;
        transponder.mass_kg *= SLACK_TRANSPONDER_MASS_FRACTION;
        transponder.drag_area_m2 = 0.0;
        self.touching = &PAYLOAD_BODIES;
        let give_up_s = self.time_s + PAYLOAD_LANDING_MAX_S;
        while self.time_s < give_up_s {
            if let Some(t) = self.advance().map_err(|e| e.to_string())? {
                return Ok(t);
            }
        }
        Err(format!(
            "the payload still flying {PAYLOAD_LANDING_MAX_S} s after the transponder touched"
        ))
    }
}

/// Largest difference between an RK4 step's 4th- and 3rd-order solutions in any state (m,
/// rad, m/s, rad/s) before the step counts as failed and its period is flown again with
/// shorter steps ([`Rk4::with_max_error`]).
///
/// A 0.05 s step loses two kinds of flight, both seen only in dispersed stacks:
/// - a dive: the canopy's pitch against its lines is a fast, heavily damped mode (≈ −32 1/s at
///   the trim) whose rate grows with airspeed; at 10–11 m/s with a low-drag, nose-down rigged
///   canopy it passes −56 1/s, beyond RK4's stability at 0.05 s, and the mode doubles each
///   step (seed 3 runs 372 and 514, realistic: −67 1/s two seconds after release);
/// - a pendant near its chart's pole: a hanging body's relative pitch turns at `q / cos φ`,
///   so a line swinging past near-sideways (roll 80°, with the drone spinning about its lines)
///   turns the pitch 140° in 40 ms (seed 7 run 2712 at 45.7 s; through the pole itself, at
///   roll 90°, no step helps: `crates/stx-gnc/GNC_NOTES.md`, "Failed runs").
///
/// Either used to be accepted while finite and to overflow seconds later, so the shorter steps
/// started from a lost state and the run failed. The bound sees such a step when it happens:
/// the unstable pitch mode differs by 2–4 rad/s a step within a second of its start. It is 1
/// (m, rad, m/s or rad/s) in one step: in 400 realistic runs (seed 7) every step after the
/// first 0.3 s stayed below 0.26 but in one run, 0.79. The transient at release, where a
/// dispersed stack starts out of its trim, reaches 1–3.6 in 7 of those runs, whose first
/// period is then flown with the shorter steps.
pub const MAX_STEP_ERROR: f64 = 1.0;

/// How many times shorter than the nominal step the last retry of a failed period steps.
const FINEST_REFINEMENT: f64 = 16.0;

/// Integrates `model` from `state` at `time_s` over `period_s` with the servo commands held,
/// in fixed RK4 steps of `step_s`, stopping exactly at ground contact. Returns the time
/// reached, the state there and the contact time if the stack touched down.
///
/// If a step fails, the same period is flown again from the same state with steps four and
/// then sixteen times shorter, so a run is deterministic and only its rare violent seconds cost
/// more. A step fails when it goes non-finite, when a speed or rate reaches 1,000 m/s or rad/s
/// (hard main-line reversals can spin the drone about its lines faster than a 0.05 s step
/// follows), or, but for the shortest steps, when its two orders differ by more than
/// [`MAX_STEP_ERROR`]: see there for what else a 0.05 s step cannot follow.
pub fn fly_period(
    model: &mut ParafoilModel,
    time_s: f64,
    state: &StateVector,
    step_s: f64,
    period_s: f64,
) -> Result<(f64, StateVector, Option<f64>), IntegrateError> {
    fly_period_over(model, time_s, state, step_s, period_s, &Body::ALL)
}

/// [`fly_period`] stopping at the ground contact of one of `bodies` only.
pub fn fly_period_over(
    model: &mut ParafoilModel,
    time_s: f64,
    state: &StateVector,
    step_s: f64,
    period_s: f64,
    bodies: &[Body],
) -> Result<(f64, StateVector, Option<f64>), IntegrateError> {
    let vehicle = model.vehicle.clone();
    let mut event = |_t: f64, x: &StateVector| height_of_lowest_m(&vehicle, x, bodies);
    let end_s = time_s + period_s;
    let mut outcome = Err(IntegrateError::InvalidSpan {
        start_time_s: time_s,
        end_time_s: end_s,
    });
    for refinement in [1.0, 4.0, FINEST_REFINEMENT] {
        // The shortest steps take every finite step: a flight still that violent is flown as
        // well as the model can, not failed.
        let method = Rk4::new(step_s / refinement);
        outcome = integrate(
            &mut if refinement < FINEST_REFINEMENT {
                method.with_max_error(MAX_STEP_ERROR)
            } else {
                method
            },
            model,
            time_s,
            state,
            end_s,
            Hooks {
                event: Some(&mut event),
                observer: None,
            },
        );
        // A step that diverged without overflowing yet (speeds of kilometres per second) is
        // as lost as a non-finite one, and is flown again with the shorter steps too.
        if let Ok(o) = &outcome
            && let Some(component) = idx::SPEEDS
                .into_iter()
                .find(|&k| o.state[k].is_nan() || o.state[k].abs() >= 1e3)
        {
            outcome = Err(IntegrateError::NonFiniteStep {
                time_s,
                step_s: step_s / refinement,
                component,
            });
        }
        if !matches!(
            outcome,
            Err(IntegrateError::NonFiniteStep { .. } | IntegrateError::InaccurateStep { .. })
        ) {
            break;
        }
    }
    let outcome = outcome?;
    Ok((outcome.time_s, outcome.state, outcome.event_time_s))
}

/// How the stack in `state` meets the ground at `time_s`: the lowest body, its position and
/// vertical speed, the canopy's heading and where the wind comes from there.
pub fn touchdown(model: &ParafoilModel, state: &StateVector, time_s: f64) -> Touchdown {
    touchdown_of(model, state, time_s, &Body::ALL)
}

/// [`touchdown`] of the lowest of `bodies`.
pub fn touchdown_of(
    model: &ParafoilModel,
    state: &StateVector,
    time_s: f64,
    bodies: &[Body],
) -> Touchdown {
    let k = Kinematics::new(&model.vehicle, state, model.controls().main_line_m);
    let (body, _) = lowest_of(&model.vehicle, &k, bodies);
    let p = k.position_ned_m[body as usize];
    let v = k.velocity_ned_mps(body);
    let wind = model.environment.wind.wind_ned_mps(time_s, &p);
    let upwind = if wind.x.hypot(wind.y) > 1e-6 {
        (-wind.y).atan2(-wind.x)
    } else {
        f64::NAN
    };
    let heading = euler_from_t(&k.t_i_body[Body::Canopy as usize]).z;
    Touchdown {
        time_s,
        body,
        position_ne_m: [p.x, p.y],
        vertical_speed_mps: v.z,
        heading_rad: heading,
        upwind_rad: upwind,
    }
}

/// Snake-case name of a guidance phase.
pub fn phase_name(phase: GuidancePhase) -> String {
    serde_json::to_value(phase)
        .ok()
        .and_then(|v| v.as_str().map(String::from))
        .unwrap_or_else(|| format!("{phase:?}"))
}

fn law_name(phase: LawPhase) -> &'static str {
    match phase {
        LawPhase::Approach => "approach",
        LawPhase::Following => "following",
    }
}
