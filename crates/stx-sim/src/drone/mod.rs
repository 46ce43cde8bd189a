//! The simulated STRAPLEX drone flying a whole mission — launch, balloon ascent, burst or
//! cutdown, round-chute descent, parafoil deployment, guided descent, landing — with its
//! onboard software, and talking to the station through the link's own types.
//!
//! Pure, like the rest of the crate: no sockets, no clock, no threads. [`Drone::step`] advances
//! mission time by one control period (0.25 s, the drone's 4 Hz loop); everything the station
//! sends goes in through methods ([`Drone::handle_command`], [`Drone::set_param`],
//! [`Drone::handle_plan`], [`Drone::set_sticks`], [`Drone::link_changed`]) and everything the
//! drone sends comes out of [`Drone::poll_output`]. The same seed and the same calls give the
//! same flight, bit for bit. [`link::LinkedDrone`] puts it behind a
//! [`stx_link::endpoint::VehicleEndpoint`]; the runner (`crate::runner`, feature `runner`) is
//! the thin tokio adapter that adds a socket and paces it in real or accelerated time.
//!
//! How the parts fit, one control period:
//!
//! ```text
//!  mission::MissionPhysics ── truth ──▶ sensors::SensorSuite ──▶ DeliveryQueue (latency)
//!        ▲                                                         │ measurements
//!        │ servo commands                                          ▼
//!  failures::ServoFault ◀── onboard::Onboard ◀── estimate ── stx_gnc Estimator
//!                              (modes, plan, params,               │
//!                               manual, GPS-loss policy,           │
//!                               stx_gnc Guidance)                  ▼
//!                                   └──────────────▶ telemetry (Streams, builders) ──▶ outputs
//! ```
//!
//! - [`config`]: the mission scenario file, validated before anything runs ([`config_error`]
//!   says why one is refused), and [`overrides`], what the command line changes in it;
//! - [`mission`]: the physics of each stage (balloon, round chute, 14-DOF parafoil);
//! - [`onboard`]: the drone's software;
//! - [`commands`]: what the station asks of the drone (commands, parameters, plans, sticks);
//! - [`outputs`]: what it sends each control period, scheduled and built by [`telemetry`]
//!   (which also models the battery);
//! - [`stages`]: stage and guidance-phase changes, recorded and told to the operator;
//! - [`summary`]: the mission in figures ([`MissionSummary`]);
//! - [`failures`]: link drops, packet loss, GPS loss and a stuck servo, for rehearsals;
//! - [`link`]: [`link::LinkedDrone`], the drone behind its MAVLink endpoint (still sans-io):
//!   what the runner (`crate::runner`, feature `runner`) drives over a socket and the tests
//!   drive against a ground endpoint.
//!
//! The estimator runs from launch so the station sees an onboard estimate all along; it is
//! restarted when the parafoil deploys, so that guidance starts from a filter that has only
//! seen parafoil flight (under the balloon and the round chute its air-velocity, wind and
//! pitot states describe a different vehicle).
//!
//! The predicted landing (POSITION_TARGET_GLOBAL_INT) is, once the parafoil is out, the
//! `stx_gnc::predict` touchdown of the plan flown (the uncontrolled one in uncontrolled and
//! manual mode); before, the point where the stack would come down under its round chute in
//! the wind forecast loaded before launch (the mission's mean wind) — where to look if the
//! parafoil never opened.

mod commands;
pub mod config;
pub mod config_error;
pub mod dispersed;
pub mod failures;
pub mod link;
pub mod mission;
pub mod onboard;
mod outputs;
pub mod overrides;
mod stages;
pub mod summary;
pub mod telemetry;

use std::collections::VecDeque;
use std::sync::Arc;

use nalgebra::Vector3;
use stx_dynamics::atmosphere::{Atmosphere, StandardAtmosphere};
use stx_dynamics::state::Controls;
use stx_dynamics::vehicle::Vehicle;
use stx_dynamics::wind::{Calm, WindConfig, WindField};
use stx_gnc::estimate::Estimate;
use stx_gnc::estimator::Estimator;
use stx_gnc::geo::LocalFrame;
use stx_gnc::guidance::PhaseEvent;
use stx_gnc::measurement::{AirDataSample, AttitudeSample};
use stx_gnc::mission::{FlightMode, FlightStage};
use stx_link::param::{ParamSpec, ParamTableError};
use stx_link::telemetry::{Severity, SystemState, Telemetry, VehicleStatus};
use stx_types::stack::BodyImu;

use crate::closed_loop::{NavigationError, phase_name};
use crate::guided::CONTROL_PERIOD_S;
use crate::sensors::{DeliveryQueue, SensorSuite};
pub use config::MissionConfig;
pub use config_error::MissionError;
pub use dispersed::{DispersedDroneError, dispersed_inputs, truth_inputs};
use failures::{LinkFaults, Servo, ServoFault};
use mission::{MissionPhysics, PhysicsError};
use onboard::{HardwareRequest, Onboard, mode_name};
pub use overrides::{FailureFlags, MissionOverrides};
pub use summary::{BalloonEnd, Landing, MissionSummary, StageStart, stage_name};
use telemetry::{Battery, Streams};

/// Most outputs kept for a caller that does not drain them; older ones are dropped and
/// counted ([`Drone::outputs_dropped`]).
pub const MAX_QUEUED_OUTPUTS: usize = 20_000;

/// Shortest time between two guidance-phase texts, s of mission time.
pub const PHASE_TEXT_INTERVAL_S: f64 = 2.0;

/// Why the drone cannot be built or go on.
#[derive(Debug, thiserror::Error)]
pub enum DroneError {
    /// The mission file.
    #[error(transparent)]
    Mission(#[from] MissionError),
    /// Sensors or estimator.
    #[error(transparent)]
    Navigation(#[from] NavigationError),
    /// The physics.
    #[error(transparent)]
    Physics(#[from] PhysicsError),
    /// The onboard parameter table.
    #[error("onboard parameter table: {0}")]
    Params(#[from] ParamTableError),
    /// Still flying at the mission's longest duration.
    #[error("mission still flying after {time_s:.0} s (max_duration_s)")]
    TooLong { time_s: f64 },
}

/// Something the drone sends.
#[derive(Debug, Clone, PartialEq)]
pub enum Output {
    /// A telemetry message.
    Telemetry(Telemetry),
    /// A text for the operator's log (STATUSTEXT, split by the link when long).
    Text { severity: Severity, text: String },
    /// A telemetry message from another body's own IMU, sent as that body's component.
    Body { body: BodyImu, telemetry: Telemetry },
}

/// The simulated drone.
pub struct Drone {
    config: MissionConfig,
    frame: LocalFrame,
    physics: MissionPhysics,
    onboard: Onboard,
    sensors: SensorSuite,
    in_flight: DeliveryQueue,
    estimator: Estimator,
    estimate: Option<Estimate>,
    forecast: Box<dyn WindField>,
    servo_fault: ServoFault,
    commanded: Controls,
    streams: Streams,
    battery: Battery,
    last_attitude: Option<AttitudeSample>,
    last_gps_arrival_s: Option<f64>,
    last_air: Option<AirDataSample>,
    prediction: Option<[f64; 2]>,
    outputs: VecDeque<Output>,
    outputs_dropped: u64,
    stage_log: Vec<(FlightStage, f64)>,
    phase_events: Vec<PhaseEvent>,
    link_lost_at_s: Option<f64>,
    landing: Option<Landing>,
    balloon_end: Option<(BalloonEnd, f64, f64)>,
    deployment: Option<(f64, f64)>,
    max_altitude_msl_m: f64,
    peak_descent_mps: f64,
    texts_sent: u64,
    last_phase_text_s: Option<f64>,
    phase_texts_held: u32,
    /// Mission time the body IMUs' next attitudes are due, s.
    next_body_attitude_s: f64,
}

impl std::fmt::Debug for Drone {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Drone")
            .field("mission", &self.config.name)
            .field("physics", &self.physics)
            .field("mode", &self.onboard.mode())
            .finish_non_exhaustive()
    }
}

impl Drone {
    /// The drone of `config` (validated again here) flying `vehicle`, at mission time 0.
    pub fn new(config: &MissionConfig, vehicle: Vehicle) -> Result<Self, DroneError> {
        let mut config = config.clone();
        config.estimator.ground_altitude_msl_m = config.site.alt_msl_m;
        config
            .sensors
            .gps
            .dropouts_s
            .extend_from_slice(&config.failures.gps_loss_s);
        config.validate()?;
        let (wind, forecast): (Arc<dyn WindField>, Box<dyn WindField>) = match &config.wind {
            Some(w) => (
                Arc::from(w.build().map_err(MissionError::from)?),
                WindConfig {
                    mean: w.mean.clone(),
                    turbulence: None,
                }
                .build()
                .map_err(MissionError::from)?,
            ),
            None => (Arc::new(Calm), Box::new(Calm)),
        };
        let travel = vehicle.main_line_travel_m;
        let line_max = config.onboard.guidance.gains.main_line_limit_m;
        if line_max > travel {
            return Err(MissionError::Invalid {
                field: "onboard.guidance.gains.main_line_limit_m".into(),
                value: line_max.to_string(),
                rule: "must not exceed the vehicle's main-line servo travel",
            }
            .into());
        }
        let physics = MissionPhysics::new(&config, vehicle, wind)?;
        let onboard = Onboard::new(&config, travel);
        // The table must build as the link will build it.
        stx_link::param::ParamTable::new(1, 1, onboard.param_specs())?;
        let sensors =
            SensorSuite::new(&config.sensors, config.seed).map_err(NavigationError::from)?;
        let estimator = Estimator::new(config.estimator.clone()).map_err(NavigationError::from)?;
        let mut drone = Self {
            frame: config.site,
            stage_log: vec![(physics.stage(), 0.0)],
            physics,
            onboard,
            sensors,
            in_flight: DeliveryQueue::new(),
            estimator,
            estimate: None,
            forecast,
            servo_fault: ServoFault::new(config.failures.stuck_servo),
            commanded: Controls::default(),
            streams: Streams::new(config.telemetry.prediction_period_s),
            battery: Battery::new(&config.battery),
            last_attitude: None,
            last_gps_arrival_s: None,
            last_air: None,
            prediction: None,
            outputs: VecDeque::new(),
            outputs_dropped: 0,
            phase_events: Vec::new(),
            link_lost_at_s: None,
            landing: None,
            balloon_end: None,
            deployment: None,
            max_altitude_msl_m: f64::NEG_INFINITY,
            peak_descent_mps: 0.0,
            texts_sent: 0,
            last_phase_text_s: None,
            phase_texts_held: 0,
            next_body_attitude_s: 0.0,
            config,
        };
        drone.say(
            Severity::Info,
            format!(
                "STRAPLEX drone ready: mission {}, stage {}, plan {}",
                drone.config.name,
                stage_name(drone.physics.stage()),
                mode_name(drone.onboard.mode())
            ),
        );
        Ok(drone)
    }

    /// The mission flown.
    pub fn config(&self) -> &MissionConfig {
        &self.config
    }

    /// Mission time, s.
    pub fn time_s(&self) -> f64 {
        self.physics.time_s()
    }

    /// The stage.
    pub fn stage(&self) -> FlightStage {
        self.physics.stage()
    }

    /// The mode in force.
    pub fn mode(&self) -> FlightMode {
        self.onboard.mode()
    }

    /// What the heartbeat says.
    pub fn status(&self) -> VehicleStatus {
        let stage = self.stage();
        VehicleStatus {
            mode: self.onboard.mode(),
            stage,
            phase: self.onboard.phase(stage),
            state: match stage {
                FlightStage::PreLaunch | FlightStage::Landed => SystemState::Standby,
                _ if self.onboard.gps_failsafe_active() => SystemState::Critical,
                _ => SystemState::Active,
            },
        }
    }

    /// The physics (truth, for tests and the adapter's progress report).
    pub fn physics(&self) -> &MissionPhysics {
        &self.physics
    }

    /// The onboard software.
    pub fn onboard(&self) -> &Onboard {
        &self.onboard
    }

    /// The latest onboard estimate with a navigation solution.
    pub fn estimate(&self) -> Option<&Estimate> {
        self.estimate.as_ref()
    }

    /// The servo commands of the last control period (after any injected failure).
    pub fn commanded_controls(&self) -> Controls {
        self.commanded
    }

    /// Every stage entered, with its mission time.
    pub fn stage_log(&self) -> &[(FlightStage, f64)] {
        &self.stage_log
    }

    /// Every guidance phase change so far, with its reason.
    pub fn phase_events(&self) -> &[PhaseEvent] {
        &self.phase_events
    }

    /// How the mission ended, once landed.
    pub fn landing(&self) -> Option<Landing> {
        self.landing
    }

    /// The landing target, local NED, if set.
    pub fn target_ned_m(&self) -> Option<Vector3<f64>> {
        self.onboard
            .has_target()
            .then(|| self.onboard.guidance().plan().target_ned_m)
    }

    /// The latest predicted landing point (north, east), m.
    pub fn predicted_landing_ne_m(&self) -> Option<[f64; 2]> {
        self.prediction
    }

    /// The link's failures (windows and random loss) for the adapter to apply to datagrams.
    pub fn link_faults(&self) -> LinkFaults {
        LinkFaults::new(&self.config.failures, self.config.seed)
    }

    /// The parameter table with current values (for the link's table).
    pub fn param_specs(&self) -> Vec<ParamSpec> {
        self.onboard.param_specs()
    }

    /// A parameter's value.
    pub fn param(&self, name: &str) -> Option<f32> {
        self.onboard.param(name)
    }

    /// The stick staleness timeout in force, s (the link's receiver applies it).
    pub fn manual_timeout_s(&self) -> f64 {
        self.onboard.settings().failsafe.manual_timeout_s
    }

    /// Outputs dropped because nobody drained them.
    pub fn outputs_dropped(&self) -> u64 {
        self.outputs_dropped
    }

    /// Takes the next thing to send.
    pub fn poll_output(&mut self) -> Option<Output> {
        self.outputs.pop_front()
    }

    fn push(&mut self, output: Output) {
        if self.outputs.len() >= MAX_QUEUED_OUTPUTS {
            self.outputs.pop_front();
            self.outputs_dropped += 1;
        }
        self.outputs.push_back(output);
    }

    fn send(&mut self, telemetry: Telemetry) {
        self.push(Output::Telemetry(telemetry));
    }

    fn say(&mut self, severity: Severity, text: String) {
        self.texts_sent += 1;
        self.push(Output::Text { severity, text });
    }

    /// The mission in figures so far (see [`MissionSummary`]).
    pub fn summary(&self) -> MissionSummary {
        let start = |(name, start_s): (String, f64)| StageStart {
            stage: name,
            start_s,
        };
        MissionSummary {
            mission: self.config.name.clone(),
            seed: self.config.seed,
            mission_time_s: self.time_s(),
            stages: self
                .stage_log
                .iter()
                .map(|(s, t)| start((stage_name(*s), *t)))
                .collect(),
            balloon_end: self.balloon_end,
            max_altitude_msl_m: self.max_altitude_msl_m.max(self.physics.altitude_msl_m()),
            peak_descent_mps: self.peak_descent_mps,
            deployment: self.deployment,
            target_lat_lon_deg: self.target_ned_m().map(|t| {
                let (lat, lon, _) = self.frame.to_geodetic(&t);
                [lat, lon]
            }),
            landing: self.landing,
            phases: self
                .phase_events
                .iter()
                .map(|e| start((phase_name(e.to), e.time_s)))
                .collect(),
            final_course_deg: {
                let g = self.onboard.guidance();
                g.spiral_has_run().then(|| {
                    g.spiral_status()
                        .final_course_rad
                        .to_degrees()
                        .rem_euclid(360.0)
                })
            },
            texts: self.texts_sent,
            outputs_dropped: self.outputs_dropped,
        }
    }

    fn drain_onboard_texts(&mut self) {
        while let Some((severity, text)) = self.onboard.poll_text() {
            self.say(severity, text);
        }
    }

    /// Flies one control period: sensors, estimator, onboard software, telemetry, physics.
    pub fn step(&mut self) -> Result<(), DroneError> {
        let t = self.time_s();
        if t > self.config.max_duration_s {
            return Err(DroneError::TooLong { time_s: t });
        }
        let stage = self.stage();

        // Sensors sample the truth; what has arrived goes to the estimator and the station.
        let truth = self.physics.truth();
        for delivery in self.sensors.sample(t, &truth) {
            self.in_flight.push(delivery);
        }
        while let Some(d) = self.in_flight.pop_due(t) {
            self.estimator.handle(d.arrival_s, &d.measurement);
            self.raw_telemetry(d.arrival_s, &d.measurement);
        }
        let est = self.estimator.estimate(t);
        self.estimate = est
            .position_sigma_m
            .iter()
            .all(|s| s.is_finite())
            .then_some(est);

        // The onboard software decides the servo commands.
        let gps_age_s = self.last_gps_arrival_s.map_or(f64::INFINITY, |a| t - a);
        self.onboard.update_gps(
            t,
            stage,
            gps_age_s,
            self.config.estimator.gps_timeout_s,
            self.estimate.as_ref(),
        );
        let density = StandardAtmosphere
            .air_at(
                self.frame.alt_msl_m
                    + self
                        .estimate
                        .map_or(-truth.position_ned_m.z, |e| e.height_m()),
            )
            .density_kg_per_m3;
        let request = self.onboard.mission_request(stage, self.estimate.as_ref());
        // The decision first, then what the hardware did.
        self.drain_onboard_texts();
        match request {
            Some(HardwareRequest::Cutdown) => match self.physics.cutdown() {
                Ok(event) => self.stage_event(event),
                Err(why) => self.say(Severity::Warning, format!("cutdown failed: {why}")),
            },
            Some(HardwareRequest::Deploy) => match self.physics.deploy() {
                Ok(event) => self.stage_event(event),
                Err(why) => self.say(Severity::Warning, format!("deployment failed: {why}")),
            },
            None => {}
        }
        self.drain_onboard_texts();
        let stage = self.stage();
        let commanded = self.onboard.control(stage, self.estimate.as_ref(), density);
        for event in self.onboard.guidance_mut().drain_events() {
            self.announce_phase(&event);
            self.phase_events.push(event);
        }
        self.drain_onboard_texts();
        let (applied, started) =
            self.servo_fault
                .apply(t, commanded, self.physics.servo_positions());
        if started {
            let servo = match self.servo_fault.servo() {
                Some(Servo::Main) => "main line",
                Some(Servo::Right) => "right brake",
                Some(Servo::Left) => "left brake",
                None => "servo",
            };
            self.say(
                Severity::Alert,
                format!("failure injected: {servo} servo stuck"),
            );
        }
        self.commanded = commanded;

        self.periodic_telemetry(t, stage);

        let events = self.physics.step(applied, CONTROL_PERIOD_S)?;
        let truth = self.physics.truth();
        self.max_altitude_msl_m = self
            .max_altitude_msl_m
            .max(self.frame.alt_msl_m - truth.position_ned_m.z);
        self.peak_descent_mps = self.peak_descent_mps.max(truth.velocity_ned_mps.z);
        self.battery.draw(
            CONTROL_PERIOD_S,
            &applied,
            self.physics.vehicle().main_line_travel_m,
        );
        for event in events {
            self.stage_event(event);
        }
        Ok(())
    }
}
