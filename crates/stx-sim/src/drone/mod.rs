//! The simulated STRAPLEX drone flying a whole mission — launch, balloon ascent, burst or
//! cutdown, round-chute descent, parafoil deployment, guided descent, landing — with its
//! onboard software, and talking to the station through the link's own types.
//!
//! Pure, like the rest of the crate: no sockets, no clock, no threads. [`Drone::step`] advances
//! mission time by one control period (0.25 s, the drone's 4 Hz loop); everything the station
//! sends goes in through methods ([`Drone::handle_command`], [`Drone::set_param`],
//! [`Drone::handle_plan`], [`Drone::set_sticks`], [`Drone::link_changed`]) and everything the
//! drone sends comes out of [`Drone::poll_output`]. The same seed and the same calls give the
//! same flight, bit for bit. `stx drone` (crate `stx`) is the thin tokio adapter that puts a
//! [`stx_link::endpoint::VehicleEndpoint`] and a socket around it and paces it in real or
//! accelerated time.
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
//! - [`config`]: the mission scenario file, validated before anything runs;
//! - [`mission`]: the physics of each stage (balloon, round chute, 14-DOF parafoil);
//! - [`onboard`]: the drone's software;
//! - [`telemetry`]: what is sent when, and the battery model;
//! - [`failures`]: link drops, packet loss, GPS loss and a stuck servo, for rehearsals;
//! - [`link`]: [`link::LinkedDrone`], the drone behind its MAVLink endpoint (still sans-io):
//!   what `stx drone` drives over a socket and the tests drive against a ground endpoint.
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

pub mod config;
pub mod failures;
pub mod link;
pub mod mission;
pub mod onboard;
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
use stx_gnc::measurement::{AirDataSample, AttitudeSample, Measurement};
use stx_gnc::mission::{FlightMode, FlightStage};
use stx_gnc::params::ParamError;
use stx_gnc::predict::{PredictorConfig, predict};
use stx_link::command::{Command, CommandResult};
use stx_link::manual::Sticks;
use stx_link::param::{ParamSpec, ParamTableError};
use stx_link::plan::PlanItem;
use stx_link::telemetry::{
    GuidanceStatus, PredictedLanding, Severity, SystemState, SystemStatus, Telemetry, VehicleStatus,
};

use crate::closed_loop::{NavigationError, phase_name};
use crate::guided::CONTROL_PERIOD_S;
use crate::sensors::{DeliveryQueue, SensorSuite};
pub use config::{MissionConfig, MissionError};
use failures::{LinkFaults, Servo, ServoFault};
use mission::{MissionPhysics, PhysicsError, StageEvent};
use onboard::{HardwareRequest, Onboard, mode_name};
use telemetry::{Battery, Streams, msg};

/// Most outputs kept for a caller that does not drain them; older ones are dropped and
/// counted ([`Drone::outputs_dropped`]).
pub const MAX_QUEUED_OUTPUTS: usize = 20_000;

/// Shortest time between two guidance-phase texts, s of mission time.
pub const PHASE_TEXT_INTERVAL_S: f64 = 2.0;

/// SYS_STATUS sensor bits (MAV_SYS_STATUS_SENSOR): magnetometer (the AHRS's heading),
/// absolute and differential pressure, GPS, motor outputs (the servos), AHRS, battery.
mod sensor_bits {
    pub const MAG: u32 = 4;
    pub const ABSOLUTE_PRESSURE: u32 = 8;
    pub const DIFFERENTIAL_PRESSURE: u32 = 16;
    pub const GPS: u32 = 32;
    pub const SERVOS: u32 = 32_768;
    pub const AHRS: u32 = 2_097_152;
    pub const BATTERY: u32 = 33_554_432;
    pub const ALL: u32 =
        MAG | ABSOLUTE_PRESSURE | DIFFERENTIAL_PRESSURE | GPS | SERVOS | AHRS | BATTERY;
}

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
}

/// Where and how the mission ended.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Landing {
    /// Mission time of ground contact, s.
    pub time_s: f64,
    /// Where (north, east of the launch site), m.
    pub position_ne_m: [f64; 2],
    /// Distance from the landing target, m, if there is one.
    pub miss_m: Option<f64>,
    /// Vertical speed at contact, m/s.
    pub vertical_speed_mps: f64,
    /// Stage it landed from (parafoil, or round chute if the parafoil never deployed).
    pub under_parafoil: bool,
    /// Where, latitude, degrees.
    pub lat_deg: f64,
    /// Where, longitude, degrees.
    pub lon_deg: f64,
}

/// How the balloon stage ended.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BalloonEnd {
    /// It burst by itself.
    Burst,
    /// It was cut away (operator's command or `MIS_CUTDOWN_M`).
    Cutdown,
}

/// A stage and when it began.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct StageStart {
    /// The stage (snake case).
    pub stage: String,
    /// Mission time it began, s.
    pub start_s: f64,
}

/// A mission in figures, from the simulator's truth: what a run is judged by and what
/// `stx drone --summary-json` prints.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MissionSummary {
    /// Mission name.
    pub mission: String,
    /// Seed flown.
    pub seed: u64,
    /// Mission time reached, s.
    pub mission_time_s: f64,
    /// Every stage entered, in order.
    pub stages: Vec<StageStart>,
    /// How the balloon stage ended, when, and how high (m MSL).
    pub balloon_end: Option<(BalloonEnd, f64, f64)>,
    /// Highest altitude reached, m MSL.
    pub max_altitude_msl_m: f64,
    /// Fastest fall (under the round chute in a whole mission), m/s.
    pub peak_descent_mps: f64,
    /// When and how high above the site the parafoil deployed, s and m.
    pub deployment: Option<(f64, f64)>,
    /// The landing target, latitude and longitude, degrees.
    pub target_lat_lon_deg: Option<[f64; 2]>,
    /// Where and how it landed.
    pub landing: Option<Landing>,
    /// Guidance phases entered, with their mission time.
    pub phases: Vec<StageStart>,
    /// Status texts sent.
    pub texts: u64,
    /// Outputs dropped because nobody drained them.
    pub outputs_dropped: u64,
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
            texts: self.texts_sent,
            outputs_dropped: self.outputs_dropped,
        }
    }

    fn drain_onboard_texts(&mut self) {
        while let Some((severity, text)) = self.onboard.poll_text() {
            self.say(severity, text);
        }
    }

    /// Whether `name` may take `value` now (range, kind, the rules between parameters, the
    /// servo travel), without changing anything: the link's table asks this before it takes a
    /// set from the station or echoes it.
    pub fn check_param(&self, name: &str, value: f32) -> Result<(), ParamError> {
        self.onboard.check_param(name, value).map(drop)
    }

    /// Sets a parameter from the station (checked against the shared catalog); effective at
    /// the next period. On refusal nothing changes and the reason goes to the operator's log.
    pub fn set_param(&mut self, name: &str, value: f32) -> Result<(), ParamError> {
        match self.onboard.set_param(name, value) {
            Ok(()) => {
                self.physics.settle_s = self.onboard.settings().mission.settle_s;
                self.say(Severity::Info, format!("parameter {name} = {value}"));
                Ok(())
            }
            Err(e) => {
                self.say(Severity::Warning, format!("parameter refused: {e}"));
                Err(e)
            }
        }
    }

    /// The sticks as the link's receiver has them (`None` when stale): call before every
    /// [`step`](Self::step) and whenever they change.
    pub fn set_sticks(&mut self, sticks: Option<Sticks>) {
        self.onboard.set_sticks(self.time_s(), sticks);
        self.drain_onboard_texts();
    }

    /// An uploaded plan.
    pub fn handle_plan(&mut self, items: &[PlanItem]) {
        self.onboard.handle_plan(self.time_s(), items);
        self.drain_onboard_texts();
    }

    /// The plan held, as mission items.
    pub fn plan_items(&self) -> Vec<PlanItem> {
        self.onboard.plan_items()
    }

    /// The station's heartbeats stopped (`false`) or came back (`true`). Nothing changes in
    /// flight: the drone keeps flying its plan; when the link returns it says what it did.
    pub fn link_changed(&mut self, connected: bool) {
        let now = self.time_s();
        if !connected {
            self.link_lost_at_s.get_or_insert(now);
        } else if let Some(lost) = self.link_lost_at_s.take() {
            let stage = self.stage();
            self.say(
                Severity::Notice,
                format!(
                    "link back after {:.0} s: {}, {}, {:.0} m",
                    now - lost,
                    stage_name(stage),
                    mode_name(self.onboard.mode()),
                    self.estimate.map_or(f64::NAN, |e| e.height_m()),
                ),
            );
        }
    }

    /// Executes an operator command; every command gets a result (COMMAND_ACK), refusals
    /// with a reason in the log.
    pub fn handle_command(&mut self, command: &Command) -> CommandResult {
        let result = match *command {
            Command::Cutdown => match self.physics.cutdown() {
                Ok(event) => {
                    self.stage_event(event);
                    CommandResult::Accepted
                }
                Err(why) => {
                    self.say(Severity::Warning, format!("cutdown refused: {why}"));
                    CommandResult::Denied
                }
            },
            Command::RequestMessage { message_id } => self.streams.request(message_id),
            Command::SetMessageInterval {
                message_id,
                interval_us,
            } => self.streams.set_interval(message_id, interval_us),
            _ => self.onboard.handle_command(self.time_s(), command),
        };
        self.drain_onboard_texts();
        result
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

    /// Tells the operator of a guidance phase change, with its reason. Changes closer than
    /// [`PHASE_TEXT_INTERVAL_S`] to the last one told are counted and told with the next, so a
    /// guidance that hesitates between phases cannot flood the link (the heartbeat carries
    /// the phase in any case).
    fn announce_phase(&mut self, event: &PhaseEvent) {
        let now = event.time_s;
        if self
            .last_phase_text_s
            .is_some_and(|last| now - last < PHASE_TEXT_INTERVAL_S)
        {
            self.phase_texts_held += 1;
            return;
        }
        let held = std::mem::take(&mut self.phase_texts_held);
        let more = if held > 0 {
            format!(" (+{held} changes in the last {PHASE_TEXT_INTERVAL_S:.0} s)")
        } else {
            String::new()
        };
        self.last_phase_text_s = Some(now);
        self.say(
            Severity::Info,
            format!("phase {}: {}{more}", phase_name(event.to), event.reason),
        );
    }

    fn stage_event(&mut self, event: StageEvent) {
        let now = self.time_s();
        let stage = self.stage();
        if self.stage_log.last().map(|s| s.0) != Some(stage) {
            self.stage_log.push((stage, now));
        }
        let (severity, text) = match event {
            StageEvent::Launched => (
                Severity::Notice,
                format!(
                    "launched: ascending at {:.1} m/s on average ({:.1} m/s now) to burst at {:.0} m",
                    self.config.balloon.mean_ascent_rate_mps,
                    self.physics.balloon().launch_rate_mps(),
                    self.physics.burst_altitude_msl_m()
                ),
            ),
            StageEvent::Burst { altitude_msl_m } => {
                self.balloon_end = Some((BalloonEnd::Burst, now, altitude_msl_m));
                (
                    Severity::Notice,
                    format!("balloon burst at {altitude_msl_m:.0} m MSL: round chute"),
                )
            }
            StageEvent::CutDown { altitude_msl_m } => {
                self.balloon_end = Some((BalloonEnd::Cutdown, now, altitude_msl_m));
                (
                    Severity::Notice,
                    format!("cutdown at {altitude_msl_m:.0} m MSL: balloon released, round chute"),
                )
            }
            StageEvent::Deployed {
                height_m,
                heading_rad,
            } => {
                self.deployment = Some((now, height_m));
                // Guidance starts from a filter that has only seen the parafoil fly.
                if let Ok(e) = Estimator::new(self.config.estimator.clone()) {
                    self.estimator = e;
                    self.estimate = None;
                }
                (
                    Severity::Notice,
                    format!(
                        "round chute released at {height_m:.0} m: parafoil deploying, heading {:.0}°",
                        heading_rad.to_degrees().rem_euclid(360.0)
                    ),
                )
            }
            StageEvent::Flying => (
                Severity::Notice,
                format!("parafoil flying: {}", mode_name(self.onboard.mode())),
            ),
            StageEvent::Landed(t) => {
                let target = self.target_ned_m();
                let miss =
                    target.map(|p| (t.position_ne_m[0] - p.x).hypot(t.position_ne_m[1] - p.y));
                let (lat_deg, lon_deg, _) = self.frame.to_geodetic(&Vector3::new(
                    t.position_ne_m[0],
                    t.position_ne_m[1],
                    0.0,
                ));
                self.landing = Some(Landing {
                    time_s: t.time_s,
                    position_ne_m: t.position_ne_m,
                    miss_m: miss,
                    vertical_speed_mps: t.vertical_speed_mps,
                    under_parafoil: self.physics.parafoil().is_some(),
                    lat_deg,
                    lon_deg,
                });
                let from_target = miss
                    .map(|m| format!(", {m:.0} m from the target"))
                    .unwrap_or_default();
                (
                    Severity::Notice,
                    format!(
                        "landed at {:.0} m N {:.0} m E{from_target}, {:.1} m/s down",
                        t.position_ne_m[0], t.position_ne_m[1], t.vertical_speed_mps
                    ),
                )
            }
        };
        self.say(severity, text);
    }

    /// Raw sensor telemetry, as each measurement reaches the drone's computer.
    fn raw_telemetry(&mut self, arrival_s: f64, m: &Measurement) {
        match m {
            Measurement::Gps(fix) => {
                self.last_gps_arrival_s = Some(arrival_s);
                if self.streams.due(msg::GPS_RAW_INT, arrival_s) {
                    self.send(Telemetry::GpsRaw(telemetry::gps_raw(&self.frame, fix)));
                }
            }
            Measurement::Attitude(a) => {
                if self.streams.due(msg::ATTITUDE, arrival_s) {
                    let att = telemetry::attitude(a, self.last_attitude.as_ref());
                    self.send(Telemetry::Attitude(att));
                }
                self.last_attitude = Some(*a);
            }
            Measurement::AirData(a) => {
                self.last_air = Some(*a);
                if self.streams.due(msg::SCALED_PRESSURE, arrival_s) {
                    self.send(Telemetry::AirData(telemetry::air_data(a)));
                }
            }
        }
    }

    fn periodic_telemetry(&mut self, t: f64, stage: FlightStage) {
        let travel = self.physics.vehicle().main_line_travel_m;
        let est = self.estimate;
        // Messages asked for while the sensor-driven ones had nothing new.
        if self.streams.take_request(msg::ATTITUDE)
            && let Some(a) = self.last_attitude
        {
            self.send(Telemetry::Attitude(telemetry::attitude(&a, None)));
        }
        if self.streams.take_request(msg::SCALED_PRESSURE)
            && let Some(a) = self.last_air
        {
            self.send(Telemetry::AirData(telemetry::air_data(&a)));
        }
        let gps_silent = self.last_gps_arrival_s.is_none_or(|a| t - a > 1.0);
        let whole_second = (t - t.floor()) < 1e-6;
        if gps_silent && (whole_second || self.streams.take_request(msg::GPS_RAW_INT)) {
            self.send(Telemetry::GpsRaw(telemetry::gps_no_fix(t)));
        }
        if let Some(e) = &est {
            if self.streams.due(msg::GLOBAL_POSITION_INT, t) {
                self.send(Telemetry::Position(telemetry::position(&self.frame, e)));
            }
            if self.streams.due(msg::VFR_HUD, t) {
                self.send(Telemetry::Hud(telemetry::hud(&self.frame, e)));
            }
            if self.streams.due(msg::WIND_COV, t) {
                self.send(Telemetry::Wind(telemetry::wind(&self.frame, e)));
            }
            if self.streams.due(msg::NAV_CONTROLLER_OUTPUT, t) {
                let g = self.guidance_status(e);
                self.send(Telemetry::Guidance(g));
            }
            if self.streams.due(msg::POSITION_TARGET_GLOBAL_INT, t)
                && let Some(p) = self.predict(stage, e)
            {
                self.send(Telemetry::PredictedLanding(p));
            }
        }
        if self.streams.due(msg::SERVO_OUTPUT_RAW, t) {
            // Where the servos are (lagging their commands, or stuck), not where they were sent.
            let a = telemetry::actuators(t, &self.physics.servo_positions(), travel);
            self.send(Telemetry::Actuators(a));
        }
        if self.streams.due(msg::SYS_STATUS, t) {
            let s = self.system_status(t);
            self.send(Telemetry::System(s));
        }
        if self.streams.due(msg::BATTERY_STATUS, t) {
            self.send(Telemetry::Battery(self.battery.status()));
        }
    }

    fn system_status(&self, t: f64) -> SystemStatus {
        let mut health = sensor_bits::ALL;
        if self.last_gps_arrival_s.is_none_or(|a| t - a > 1.0) {
            health &= !sensor_bits::GPS;
        }
        let est = self.estimate.as_ref();
        if !est.is_some_and(|e| e.attitude_ok) {
            health &= !(sensor_bits::AHRS | sensor_bits::MAG);
        }
        if !est.is_some_and(|e| e.air_data_ok) {
            health &= !(sensor_bits::ABSOLUTE_PRESSURE | sensor_bits::DIFFERENTIAL_PRESSURE);
        }
        if self.servo_fault.active_at(t) {
            health &= !sensor_bits::SERVOS;
        }
        SystemStatus {
            battery_voltage_v: Some(self.battery.voltage_v()),
            battery_current_a: Some(self.battery.current_a()),
            battery_remaining_pct: Some(self.battery.remaining_pct()),
            load_pct: 0.0,
            comm_drop_rate_pct: 0.0,
            comm_errors: 0,
            sensors_present: sensor_bits::ALL,
            sensors_enabled: sensor_bits::ALL,
            sensors_health: health,
        }
    }

    /// NAV_CONTROLLER_OUTPUT: what guidance is after, per mode.
    fn guidance_status(&self, e: &Estimate) -> GuidanceStatus {
        let g = self.onboard.guidance();
        let plan = g.plan();
        let to_target = plan.target_ned_m - e.position_ned_m;
        let bearing = to_target
            .y
            .atan2(to_target.x)
            .to_degrees()
            .rem_euclid(360.0);
        let position = [e.position_ned_m.x, e.position_ned_m.y];
        let (desired_heading_deg, xtrack_error_m, alt_error_m) = match g.mode() {
            FlightMode::Heading => (plan.heading_rad.to_degrees(), 0.0, 0.0),
            FlightMode::Course => (plan.course_rad.to_degrees(), 0.0, 0.0),
            FlightMode::Localizer => (
                plan.localizer.course_rad.to_degrees(),
                plan.localizer.cross_track_m(position),
                0.0,
            ),
            FlightMode::SpiralLanding => {
                let s = g.spiral_status();
                (bearing, 0.0, s.final_approach_height_m - s.height_m)
            }
            FlightMode::Uncontrolled | FlightMode::Manual => (e.heading_rad.to_degrees(), 0.0, 0.0),
        };
        GuidanceStatus {
            desired_roll_deg: 0.0,
            desired_heading_deg: desired_heading_deg.rem_euclid(360.0).round(),
            bearing_to_target_deg: bearing.round(),
            distance_to_target_m: if self.onboard.has_target() {
                to_target.x.hypot(to_target.y).round().min(65_535.0)
            } else {
                0.0
            },
            alt_error_m: if alt_error_m.is_finite() {
                alt_error_m
            } else {
                0.0
            },
            xtrack_error_m,
        }
    }

    /// The predicted landing point (see the module documentation).
    fn predict(&mut self, stage: FlightStage, e: &Estimate) -> Option<PredictedLanding> {
        let ne = match stage {
            FlightStage::PreLaunch | FlightStage::Ascent | FlightStage::RoundChute => {
                self.physics
                    .forecast_round_chute_landing(&e.position_ned_m, self.forecast.as_ref())?
                    .0
            }
            FlightStage::ParafoilDeploy | FlightStage::Parafoil => {
                let g = self.onboard.guidance();
                let p = predict(
                    e,
                    g,
                    &g.config().performance,
                    &StandardAtmosphere,
                    self.frame.alt_msl_m,
                    &PredictorConfig::default(),
                );
                let manual = g.mode() == FlightMode::Manual;
                if manual || g.mode() == FlightMode::Uncontrolled || stage != FlightStage::Parafoil
                {
                    p.uncontrolled.position_ne_m
                } else {
                    p.planned.position_ne_m
                }
            }
            FlightStage::Landed => return None,
        };
        if !(ne[0].is_finite() && ne[1].is_finite()) {
            return None;
        }
        self.prediction = Some(ne);
        let (lat_deg, lon_deg, alt_msl_m) =
            self.frame.to_geodetic(&Vector3::new(ne[0], ne[1], 0.0));
        Some(PredictedLanding {
            time_boot_ms: telemetry::boot_ms(e.time_s),
            lat_deg,
            lon_deg,
            alt_msl_m,
        })
    }
}

/// Snake-case name of a stage, as the operator reads it.
pub fn stage_name(stage: FlightStage) -> String {
    serde_json::to_value(stage)
        .ok()
        .and_then(|v| v.as_str().map(String::from))
        .unwrap_or_else(|| format!("{stage:?}"))
}
