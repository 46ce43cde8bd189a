//! The station's state and logic, free of I/O: telemetry and link events in, JSON messages and
//! link actions out, the mission clock (`now_s`, seconds since the station started) passed in.
//!
//! - telemetry updates the latest of each kind and feeds the station's own estimator (the same
//!   code as onboard) with the GPS, AHRS and pitot measurements;
//! - a guidance replica follows the drone's mode and the plan the drone holds (read back from
//!   it, see [`sync`]), to draw the pattern and predict the landing ([`stx_gnc::predict`]) the
//!   way the drone will fly it;
//! - operators' requests become [`LinkAction`]s for the daemon to apply to the link, each with a
//!   request id whose outcome comes back as a `command_result`.

mod commands;
mod sync;
mod views;

use std::collections::{HashMap, VecDeque};

use nalgebra::Vector3;
use stx_dynamics::atmosphere::{Atmosphere, StandardAtmosphere};
use stx_gnc::estimate::Estimate;
use stx_gnc::estimator::{Estimator, EstimatorConfig};
use stx_gnc::geo::LocalFrame;
use stx_gnc::guidance::{Guidance, Plan};
use stx_gnc::measurement::{AirDataSample, AttitudeSample, GpsFix, Measurement};
use stx_gnc::mission::FlightMode;
use stx_gnc::predict::{LandingPrediction, PredictorConfig, predict};
use stx_link::endpoint::{GroundEvent, LinkEvent, LinkStats};
use stx_link::sansio::IoEvent;
use stx_link::telemetry::{Severity, Telemetry};

use crate::config::StationConfig;
use crate::messages::{EventMsg, Level, StateMsg, TrackPoint};

pub use commands::{ApiError, CommandRequest, CutdownArm, LinkAction};
pub use sync::TargetSource;

/// Most events kept for the log.
const MAX_EVENTS: usize = 10_000;
/// States kept for the plots of a newly connected page: 5 minutes at 1 Hz.
const MAX_HISTORY: usize = 300;
/// Seconds between track points.
const TRACK_PERIOD_S: f64 = 1.0;

/// Seconds the drone's clock may step back before the station takes it for a reboot.
const REBOOT_STEP_BACK_S: f64 = 5.0;

fn new_estimator() -> Estimator {
    match Estimator::new(EstimatorConfig::default()) {
        Ok(e) => e,
        // The default configuration is validated by the estimator's own tests.
        Err(e) => panic!("default estimator configuration is invalid: {e}"),
    }
}

/// Everything a landing prediction needs, detached from the station so it can run on another
/// thread while telemetry keeps flowing.
pub struct PredictionJob {
    estimate: Estimate,
    guidance: Guidance,
    performance: stx_gnc::performance::GlidePerformance,
    ground_altitude_msl_m: f64,
    config: PredictorConfig,
    /// When the sensor data behind the estimate arrived (mission time, s).
    data_s: Option<f64>,
}

/// A finished [`PredictionJob`].
pub struct Predicted {
    prediction: LandingPrediction,
    data_s: Option<f64>,
}

impl PredictionJob {
    /// Flies the plan and the uncontrolled glide from the estimate (milliseconds).
    pub fn run(&self) -> Predicted {
        Predicted {
            prediction: predict(
                &self.estimate,
                &self.guidance,
                &self.performance,
                &StandardAtmosphere,
                self.ground_altitude_msl_m,
                &self.config,
            ),
            data_s: self.data_s,
        }
    }
}

/// Latest telemetry of each kind with the mission time it arrived.
#[derive(Debug, Default, Clone)]
pub(crate) struct Latest {
    pub status: Option<(stx_link::telemetry::VehicleStatus, f64)>,
    pub gps: Option<(stx_link::telemetry::GpsRaw, f64)>,
    pub position: Option<(stx_link::telemetry::GlobalPosition, f64)>,
    pub attitude: Option<(stx_link::telemetry::Attitude, f64)>,
    pub air: Option<(stx_link::telemetry::AirData, f64)>,
    pub actuators: Option<(stx_link::telemetry::Actuators, f64)>,
    pub system: Option<(stx_link::telemetry::SystemStatus, f64)>,
    pub battery: Option<(stx_link::telemetry::BatteryStatus, f64)>,
    pub wind: Option<(stx_link::telemetry::Wind, f64)>,
    pub guidance: Option<(stx_link::telemetry::GuidanceStatus, f64)>,
    /// The drone's own prediction of its touchdown.
    pub predicted_landing: Option<(stx_link::telemetry::PredictedLanding, f64)>,
    /// The newest GPS, attitude or air data: what navigation last learnt from.
    pub sensors_s: Option<f64>,
    pub any_s: Option<f64>,
}

/// Something for the dashboards: broadcast to every WebSocket.
#[derive(Debug, Clone)]
pub enum Outbound {
    /// An `event`.
    Event(EventMsg),
    /// A `command_result`.
    CommandResult(crate::messages::CommandResultMsg),
    /// A `params` message.
    Params(crate::messages::ParamsMsg),
}

/// The station.
pub struct StationCore {
    pub(crate) config: StationConfig,
    pub(crate) frame: LocalFrame,
    /// Unix time at mission time 0, ms.
    wall_origin_ms: u64,
    pub(crate) latest: Latest,
    estimator: Estimator,
    /// The drone's clock (s since its boot) from the newest time-stamped telemetry:
    /// navigation runs on it, so radio delays and accelerated rehearsals do not distort it.
    drone_time_s: Option<f64>,
    pub(crate) estimate: Option<Estimate>,
    pub(crate) guidance: Guidance,
    pub(crate) prediction: Option<LandingPrediction>,
    /// When the sensor data the prediction started from arrived (mission time, s).
    pub(crate) prediction_data_s: Option<f64>,
    /// The plan download and where the replica's plan comes from.
    pub(crate) sync: sync::PlanSync,
    /// The drone's clock of the estimate guidance last ran on, s.
    guided_at_s: Option<f64>,
    pub(crate) track: Vec<TrackPoint>,
    next_track_s: f64,
    pub(crate) events: VecDeque<EventMsg>,
    pub(crate) history: VecDeque<StateMsg>,
    next_history_s: f64,
    pub(crate) link: LinkStats,
    pub(crate) commands: commands::Commands,
    outbound: Vec<Outbound>,
    last_connected: Option<bool>,
    /// What the guidance replica commands now (for the dashboard's comparison).
    pub(crate) replica_command: stx_dynamics::state::Controls,
    /// The vehicle's main-line servo travel, m: telemetry reports the servo in −1…1 of it.
    pub(crate) main_line_travel_m: f64,
}

impl StationCore {
    /// A station that has heard nothing yet; `wall_origin_ms` is the Unix time of mission
    /// time 0.
    pub fn new(config: StationConfig, wall_origin_ms: u64) -> Self {
        let frame = config.origin;
        let guidance = Guidance::new(config.guidance);
        let estimator = new_estimator();
        Self {
            frame,
            wall_origin_ms,
            latest: Latest::default(),
            estimator,
            drone_time_s: None,
            estimate: None,
            guidance,
            prediction: None,
            prediction_data_s: None,
            sync: sync::PlanSync::default(),
            guided_at_s: None,
            track: Vec::new(),
            next_track_s: 0.0,
            events: VecDeque::new(),
            history: VecDeque::new(),
            next_history_s: 0.0,
            link: LinkStats::default(),
            commands: commands::Commands::new(config.cutdown_window_s),
            outbound: Vec::new(),
            last_connected: None,
            replica_command: stx_dynamics::state::Controls::default(),
            main_line_travel_m: stx_dynamics::vehicle::Vehicle::straplex().main_line_travel_m,
            config,
        }
    }

    /// The configuration.
    pub fn config(&self) -> &StationConfig {
        &self.config
    }

    pub(crate) fn wall_ms(&self, now_s: f64) -> u64 {
        self.wall_origin_ms + (now_s.max(0.0) * 1000.0) as u64
    }

    /// Logs an event and queues it for the dashboards.
    pub fn log(&mut self, now_s: f64, level: Level, source: &'static str, text: String) {
        let event = EventMsg {
            kind: "event",
            time_s: now_s,
            wall_ms: self.wall_ms(now_s),
            level,
            source,
            text,
        };
        match level {
            Level::Info => tracing::info!(source, "{}", event.text),
            Level::Warning => tracing::warn!(source, "{}", event.text),
            Level::Error => tracing::error!(source, "{}", event.text),
        }
        if self.events.len() >= MAX_EVENTS {
            self.events.pop_front();
        }
        self.events.push_back(event.clone());
        self.outbound.push(Outbound::Event(event));
    }

    /// Takes what must be broadcast since the last call.
    pub fn drain_outbound(&mut self) -> Vec<Outbound> {
        std::mem::take(&mut self.outbound)
    }

    /// The link statistics last sampled.
    pub fn link_stats(&self) -> &LinkStats {
        &self.link
    }

    /// Link statistics sampled by the daemon.
    pub fn set_link_stats(&mut self, now_s: f64, stats: LinkStats) {
        if self.last_connected != Some(stats.connected) {
            let was = self.last_connected;
            self.last_connected = Some(stats.connected);
            if was.is_some() || stats.connected {
                let (level, text) = if stats.connected {
                    (Level::Info, "link to the drone up".to_string())
                } else {
                    (
                        Level::Warning,
                        "link to the drone lost: its data are stale".to_string(),
                    )
                };
                self.log(now_s, level, "link", text);
            }
        }
        let transmitting = stats.paths.iter().position(|p| p.transmitting);
        let before = self.link.paths.iter().position(|p| p.transmitting);
        if stats.paths.len() > 1
            && before.is_some()
            && transmitting != before
            && let Some(now) = transmitting
        {
            let text = format!("commands now go out on {}", self.radio_name(now));
            self.log(now_s, Level::Warning, "link", text);
        }
        self.link = stats;
    }

    /// How the operators know radio `path`: its number and address.
    fn radio_name(&self, path: usize) -> String {
        let address = self.config.link.addresses().nth(path).map_or("?", |a| a);
        format!("radio {} ({address})", path + 1)
    }

    /// Reports what happened on the drone link's socket, worded for the operators. Waiting
    /// for the drone is said once, not at every heartbeat.
    /// With several radios the text names the one it happened on.
    pub fn on_io_event(&mut self, now_s: f64, path: usize, event: IoEvent) {
        let (level, text) = match event {
            IoEvent::QueuedWithoutPeer { queued: 1 } => (
                Level::Info,
                "waiting for the drone: nothing heard on the link yet".to_string(),
            ),
            IoEvent::QueuedWithoutPeer { .. } => return,
            IoEvent::DroppedWithoutPeer { dropped_total } => {
                tracing::debug!(
                    dropped_total,
                    "uplink frames dropped while no drone is heard"
                );
                return;
            }
            IoEvent::PeerChanged { peer } => (Level::Info, format!("drone heard from {peer}")),
            IoEvent::Connected { peer } => (Level::Info, format!("link connected to {peer}")),
            IoEvent::Disconnected { reason } => {
                (Level::Warning, format!("link disconnected: {reason}"))
            }
            IoEvent::RecvError { error, count } => (
                Level::Warning,
                format!("link read failed ({count} so far): {error}"),
            ),
            IoEvent::SendError { error, count } => (
                Level::Warning,
                format!("link write failed ({count} so far): {error}"),
            ),
            IoEvent::PersistFailed { path, error } => (
                Level::Error,
                format!("signing timestamp not saved to {}: {error}", path.display()),
            ),
        };
        let text = if self.config.link.more_addresses.is_empty() {
            text
        } else {
            format!("{}: {text}", self.radio_name(path))
        };
        self.log(now_s, level, "link", text);
    }

    /// Handles one event of the ground endpoint.
    pub fn on_link_event(&mut self, now_s: f64, event: GroundEvent) {
        match event {
            GroundEvent::Telemetry { telemetry, .. } => self.on_telemetry(now_s, telemetry),
            GroundEvent::StatusText { severity, text, .. } => {
                let level = match severity {
                    Severity::Emergency
                    | Severity::Alert
                    | Severity::Critical
                    | Severity::Error => Level::Error,
                    Severity::Warning => Level::Warning,
                    _ => Level::Info,
                };
                self.log(now_s, level, "vehicle", text);
            }
            GroundEvent::Command(e) => {
                if let Some(msg) = self.commands.on_command_event(now_s, &e) {
                    self.after_command_result(now_s, &msg);
                }
            }
            GroundEvent::Param(e) => {
                let (results, changed) = self.commands.on_param_event(&e);
                for r in results {
                    self.after_command_result(now_s, &r);
                }
                if changed {
                    let params = self.params_msg(now_s);
                    self.outbound.push(Outbound::Params(params));
                }
            }
            GroundEvent::Plan(stx_link::plan::PlanEvent::DownloadDone { items }) => {
                self.on_plan_downloaded(now_s, &items);
            }
            GroundEvent::Plan(stx_link::plan::PlanEvent::DownloadFailed { reason }) => {
                self.on_plan_download_failed(now_s, &reason);
            }
            GroundEvent::Plan(e) => {
                if let Some(msg) = self.commands.on_plan_event(&e) {
                    self.after_command_result(now_s, &msg);
                }
            }
            GroundEvent::Link(LinkEvent::FrameError(e)) => {
                tracing::debug!(error = %e, "frame dropped (counted in the link statistics)");
            }
            GroundEvent::Link(LinkEvent::Connected { system_id, .. }) => {
                tracing::info!(system_id, "drone heartbeat");
                // A drone heard for the first time, or again, may fly a plan the station has
                // not seen.
                self.want_plan_download(now_s);
            }
            GroundEvent::Link(LinkEvent::Lost { .. }) => {}
            GroundEvent::Link(LinkEvent::PersistSigningTimestamp(_)) => {}
            GroundEvent::Other(_) => {}
        }
    }

    fn after_command_result(&mut self, now_s: f64, msg: &crate::messages::CommandResultMsg) {
        let level = match msg.outcome {
            crate::messages::Outcome::Accepted | crate::messages::Outcome::InProgress => {
                Level::Info
            }
            _ => Level::Warning,
        };
        if msg.outcome != crate::messages::Outcome::InProgress {
            self.log(
                now_s,
                level,
                "command",
                format!("{} {:?}: {}", msg.command, msg.outcome, msg.detail),
            );
        }
        // The replica flies the plan the drone accepted.
        if msg.outcome == crate::messages::Outcome::Accepted
            && let Some(plan_change) = self.commands.take_accepted_plan(&msg.request_id)
        {
            self.apply_plan_change(now_s, plan_change);
        }
        self.outbound.push(Outbound::CommandResult(msg.clone()));
    }

    fn apply_plan_change(&mut self, now_s: f64, change: commands::PlanChange) {
        let mut plan: Plan = *self.guidance.plan();
        let mut read_back = true;
        match change {
            commands::PlanChange::Target {
                target_ned_m,
                approach_course_rad,
            } => {
                plan.target_ned_m = target_ned_m;
                plan.approach_course_rad = approach_course_rad;
                self.sync.target = Some(TargetSource::Operator);
            }
            commands::PlanChange::Heading(h) => {
                plan.heading_rad = h;
                read_back = false;
            }
            commands::PlanChange::Course(c) => {
                plan.course_rad = c;
                read_back = false;
            }
            commands::PlanChange::Localizer { line, glide_slope } => {
                plan.localizer = line;
                plan.localizer_glide_slope = glide_slope;
                self.sync.line_known = true;
            }
            commands::PlanChange::Upload(points) => {
                // The drone's own mapping of an upload.
                let update = stx_gnc::plan_upload::apply(&plan, &points);
                plan = update.plan;
                if update.target_set {
                    self.sync.target = Some(TargetSource::Operator);
                }
                if update.line == stx_gnc::plan_upload::LineChange::Set {
                    self.sync.line_known = true;
                }
            }
        }
        self.set_replica_plan(now_s, plan);
        if read_back {
            // What the drone holds now is the truth: read it back.
            self.want_plan_download(now_s);
        }
    }

    /// Advances the drone's clock with a message's time stamp; a clock that steps far back
    /// means the drone restarted, and navigation starts over.
    fn observe_drone_clock(&mut self, now_s: f64, time_boot_ms: u32) -> f64 {
        let t = f64::from(time_boot_ms) / 1000.0;
        match self.drone_time_s {
            Some(last) if last - t > REBOOT_STEP_BACK_S => {
                self.estimator = new_estimator();
                self.estimate = None;
                self.log(
                    now_s,
                    Level::Warning,
                    "vehicle",
                    format!("the drone's clock went back from {last:.1} s to {t:.1} s: it restarted; navigation starts over"),
                );
                self.drone_time_s = Some(t);
                self.guided_at_s = None;
                self.want_plan_download(now_s);
            }
            Some(last) => self.drone_time_s = Some(last.max(t)),
            None => self.drone_time_s = Some(t),
        }
        t
    }

    fn on_telemetry(&mut self, now_s: f64, telemetry: Telemetry) {
        self.latest.any_s = Some(now_s);
        match telemetry {
            Telemetry::Status(s) => {
                let previous = self.latest.status.map(|(p, _)| p);
                self.latest.status = Some((s, now_s));
                if previous.map(|p| p.mode) != Some(s.mode) {
                    let at = self.drone_time_s.unwrap_or(0.0);
                    self.guidance.set_mode(s.mode, at);
                }
                if let Some(p) = previous
                    && p.stage != s.stage
                {
                    self.log(
                        now_s,
                        Level::Info,
                        "vehicle",
                        format!("stage: {:?} → {:?}", p.stage, s.stage),
                    );
                }
            }
            Telemetry::GpsRaw(g) => {
                self.latest.gps = Some((g, now_s));
                self.latest.sensors_s = Some(now_s);
                // GPS_RAW_INT's time may be the receiver's (Unix) clock: it is stamped with
                // the drone's clock of the burst it came in.
                if let Some(t) = self.drone_time_s
                    && let Some(m) = self.gps_measurement(t, now_s, &g)
                {
                    self.estimator.handle(t, &m);
                }
            }
            Telemetry::Position(p) => {
                self.observe_drone_clock(now_s, p.time_boot_ms);
                self.latest.position = Some((p, now_s));
            }
            Telemetry::Attitude(a) => {
                let t = self.observe_drone_clock(now_s, a.time_boot_ms);
                self.latest.attitude = Some((a, now_s));
                self.latest.sensors_s = Some(now_s);
                let m = Measurement::Attitude(AttitudeSample {
                    time_s: t,
                    roll_rad: a.roll_rad,
                    pitch_rad: a.pitch_rad,
                    yaw_rad: a.yaw_rad,
                });
                self.estimator.handle(self.drone_time_s.unwrap_or(t), &m);
            }
            Telemetry::AirData(a) => {
                let t = self.observe_drone_clock(now_s, a.time_boot_ms);
                self.latest.air = Some((a, now_s));
                self.latest.sensors_s = Some(now_s);
                let m = Measurement::AirData(AirDataSample {
                    time_s: t,
                    differential_pressure_pa: a.diff_pressure_pa,
                    static_pressure_pa: a.abs_pressure_pa,
                    temperature_k: a.temperature_c + 273.15,
                });
                self.estimator.handle(self.drone_time_s.unwrap_or(t), &m);
            }
            Telemetry::Actuators(a) => self.latest.actuators = Some((a, now_s)),
            Telemetry::System(s) => self.latest.system = Some((s, now_s)),
            Telemetry::Battery(b) => self.latest.battery = Some((b, now_s)),
            Telemetry::Wind(w) => self.latest.wind = Some((w, now_s)),
            Telemetry::Guidance(g) => {
                self.latest.guidance = Some((g, now_s));
                self.on_guidance_status(now_s, g);
            }
            Telemetry::PredictedLanding(p) => {
                self.observe_drone_clock(now_s, p.time_boot_ms);
                self.latest.predicted_landing = Some((p, now_s));
            }
            // VFR_HUD repeats GLOBAL_POSITION_INT and the air data; STATUSTEXT arrives as
            // `GroundEvent::StatusText`.
            Telemetry::Hud(_) | Telemetry::StatusText(_) => {}
        }
    }

    /// A GPS measurement for the estimator. GPS_RAW_INT carries no vertical velocity: the
    /// drone's own estimate (GLOBAL_POSITION_INT) stands in for it when it is recent.
    fn gps_measurement(
        &self,
        drone_s: f64,
        now_s: f64,
        g: &stx_link::telemetry::GpsRaw,
    ) -> Option<Measurement> {
        use stx_link::telemetry::GpsFix as Fix;
        if !matches!(
            g.fix,
            Fix::Fix3d | Fix::Dgps | Fix::RtkFloat | Fix::RtkFixed | Fix::Static | Fix::Ppp
        ) {
            return None;
        }
        let position = self.frame.to_ned(g.lat_deg, g.lon_deg, g.alt_msl_m);
        let speed = g.ground_speed_mps?;
        let course = g.course_deg.unwrap_or(0.0).to_radians();
        let down = self
            .latest
            .position
            .filter(|(_, t)| now_s - t < 1.0)
            .map_or(0.0, |(p, _)| p.v_down_mps);
        Some(Measurement::Gps(GpsFix {
            time_s: drone_s,
            position_ned_m: position,
            velocity_ned_mps: Vector3::new(speed * course.cos(), speed * course.sin(), down),
            horizontal_accuracy_m: g.h_acc_m.unwrap_or(2.5),
            vertical_accuracy_m: g.v_acc_m.unwrap_or(5.0),
            speed_accuracy_mps: 0.3,
        }))
    }

    /// Runs navigation and the guidance replica and returns the `state` message for `now_s`.
    /// The landing prediction is not run here (it flies the plan in fast time, too slow for the
    /// telemetry path): see [`StationCore::prediction_job`].
    pub fn tick(&mut self, now_s: f64) -> StateMsg {
        let est = self.drone_time_s.map(|t| self.estimator.estimate(t));
        let usable = est.filter(|e| e.position_sigma_m.iter().all(|s| s.is_finite()));
        if let Some(est) = usable {
            let mode = self.guidance.mode();
            if !self.plan_known_for(mode) {
                // Flying towards a target the drone may not have would draw and log a
                // pattern that does not exist.
                self.replica_command = stx_dynamics::state::Controls::default();
            } else if self.guided_at_s.is_none_or(|t| est.time_s > t) {
                // Only new navigation data move guidance on: a stale link does not make
                // the replica fly on by itself.
                self.guided_at_s = Some(est.time_s);
                let density = StandardAtmosphere
                    .air_at(self.frame.alt_msl_m - est.position_ned_m.z)
                    .density_kg_per_m3;
                self.replica_command = self.guidance.update(&est, density).controls;
            }
            for e in self.guidance.drain_events() {
                self.log(
                    now_s,
                    Level::Info,
                    "guidance",
                    format!("{:?} → {:?}: {}", e.from, e.to, e.reason),
                );
            }
            // One point per second of flight, also when a rehearsal runs faster than real time.
            if est.time_s >= self.next_track_s {
                self.next_track_s = est.time_s + TRACK_PERIOD_S;
                let (lat, lon, alt) = self.frame.to_geodetic(&est.position_ned_m);
                self.track.push(TrackPoint {
                    time_s: now_s,
                    lat_deg: lat,
                    lon_deg: lon,
                    alt_msl_m: alt,
                });
            }
            self.estimate = Some(est);
        } else {
            self.estimate = None;
        }
        if let Some(expired) = self.commands.expire_cutdown(now_s) {
            self.log(now_s, Level::Info, "command", expired);
        }
        let state = self.state_msg_now(now_s);
        if now_s >= self.next_history_s {
            self.next_history_s = now_s + 1.0;
            if self.history.len() >= MAX_HISTORY {
                self.history.pop_front();
            }
            self.history.push_back(state.clone());
        }
        state
    }

    /// A landing prediction from the current estimate and plan, to be run away from the
    /// telemetry path; `None` until navigation has a solution.
    pub fn prediction_job(&self) -> Option<PredictionJob> {
        let estimate = self.estimate?;
        Some(PredictionJob {
            data_s: self.latest.sensors_s,
            estimate,
            guidance: self.guidance.clone(),
            performance: self.config.guidance.performance,
            ground_altitude_msl_m: self.frame.alt_msl_m,
            config: PredictorConfig {
                hang_height_m: self.config.guidance.spiral.hang_height_m,
                ..PredictorConfig::default()
            },
        })
    }

    /// Takes the result of a [`PredictionJob`].
    pub fn set_prediction(&mut self, predicted: Predicted) {
        self.prediction = Some(predicted.prediction);
        self.prediction_data_s = predicted.data_s;
    }

    /// The plan the guidance replica flies.
    pub fn replica_plan(&self) -> &Plan {
        self.guidance.plan()
    }

    /// The mode the drone reports (uncontrolled before the first heartbeat).
    pub fn vehicle_mode(&self) -> FlightMode {
        self.latest
            .status
            .map_or(FlightMode::Uncontrolled, |(s, _)| s.mode)
    }

    /// Operator requests: validates and records them, returning the request id and what the
    /// daemon must do on the link.
    pub fn request(
        &mut self,
        now_s: f64,
        who: &str,
        request: CommandRequest,
    ) -> Result<(String, LinkAction), ApiError> {
        let (id, action, text) = self.commands.request(now_s, &self.frame, request)?;
        self.log(now_s, Level::Info, "command", format!("{who}: {text}"));
        Ok((id, action))
    }

    /// Arms the cutdown for the window of the configuration.
    pub fn arm_cutdown(&mut self, now_s: f64, who: &str) -> CutdownArm {
        let arm = self.commands.arm_cutdown(now_s, who);
        self.log(
            now_s,
            Level::Warning,
            "command",
            format!(
                "{who} armed the cutdown ({} s to confirm)",
                arm.expires_in_s
            ),
        );
        arm
    }

    /// Confirms an armed cutdown: the request id and the action to send.
    pub fn confirm_cutdown(
        &mut self,
        now_s: f64,
        who: &str,
        arm_id: &str,
    ) -> Result<(String, LinkAction), ApiError> {
        let (id, action) = self.commands.confirm_cutdown(now_s, who, arm_id)?;
        self.log(
            now_s,
            Level::Warning,
            "command",
            format!("{who} confirmed the CUTDOWN"),
        );
        Ok((id, action))
    }

    /// A request the link could not queue (e.g. the same command is still waiting).
    pub fn refuse(&mut self, now_s: f64, request_id: &str, reason: String) {
        if let Some(msg) = self.commands.refuse(request_id, reason) {
            self.after_command_result(now_s, &msg);
        }
    }

    /// The outcome of a request, if it is known.
    pub fn command_result(&self, request_id: &str) -> Option<crate::messages::CommandResultMsg> {
        self.commands.result(request_id)
    }

    /// Events since `since_s`.
    pub fn events_since(&self, since_s: f64) -> Vec<EventMsg> {
        self.events
            .iter()
            .filter(|e| e.time_s >= since_s)
            .cloned()
            .collect()
    }

    /// The track, one point every `every_s` at most.
    pub fn track(&self, every_s: f64) -> Vec<TrackPoint> {
        let mut out: Vec<TrackPoint> = Vec::new();
        for p in &self.track {
            if out.last().is_none_or(|l| p.time_s - l.time_s >= every_s) {
                out.push(*p);
            }
        }
        out
    }

    /// The last states kept for plots.
    pub fn history(&self) -> Vec<StateMsg> {
        self.history.iter().cloned().collect()
    }

    /// Known requests by id (for tests).
    pub fn pending_requests(&self) -> HashMap<String, String> {
        self.commands.pending()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::DEFAULT_STATION_TOML;
    use stx_link::telemetry::{
        AirData, Attitude, GpsFix as Fix, GpsRaw, SystemState, VehicleStatus,
    };

    fn core() -> StationCore {
        StationCore::new(
            StationConfig::from_toml_str(DEFAULT_STATION_TOML).expect("config"),
            0,
        )
    }

    /// Telemetry of a parafoil gliding north in still air at 6 m/s, sinking 3 m/s, from 800 m
    /// above the origin, as the drone sends it at 4 Hz.
    fn glide(core: &mut StationCore, from_s: f64, to_s: f64) -> Vector3<f64> {
        glide_at_speed(core, from_s, to_s, 1.0)
    }

    /// As [`glide`], with the drone's clock running `speed` times faster than the station's
    /// (an accelerated rehearsal).
    fn glide_at_speed(core: &mut StationCore, from_s: f64, to_s: f64, speed: f64) -> Vector3<f64> {
        let air = StandardAtmosphere;
        let mut t = from_s;
        let mut truth = Vector3::zeros();
        while t < to_s {
            truth = Vector3::new(6.0 * t, 0.0, -800.0 + 3.0 * t);
            let (lat, lon, alt) = core.frame.to_geodetic(&truth);
            let ms = (t * 1000.0) as u32;
            let state = air.air_at(alt);
            let airspeed = (6.0_f64.powi(2) + 3.0_f64.powi(2)).sqrt();
            let pitch = -(3.0_f64 / 6.0).atan();
            for telemetry in [
                Telemetry::Status(VehicleStatus {
                    mode: FlightMode::Heading,
                    stage: stx_gnc::mission::FlightStage::Parafoil,
                    phase: stx_gnc::mission::GuidancePhase::Idle,
                    state: SystemState::Active,
                }),
                Telemetry::Position(stx_link::telemetry::GlobalPosition {
                    time_boot_ms: ms,
                    lat_deg: lat,
                    lon_deg: lon,
                    alt_msl_m: alt,
                    alt_rel_m: alt - core.frame.alt_msl_m,
                    v_north_mps: 6.0,
                    v_east_mps: 0.0,
                    v_down_mps: 3.0,
                    heading_deg: Some(0.0),
                }),
                Telemetry::GpsRaw(GpsRaw {
                    time_usec: u64::from(ms) * 1000,
                    fix: Fix::Fix3d,
                    lat_deg: lat,
                    lon_deg: lon,
                    alt_msl_m: alt,
                    ground_speed_mps: Some(6.0),
                    course_deg: Some(0.0),
                    satellites: Some(10),
                    h_acc_m: Some(1.5),
                    v_acc_m: Some(3.0),
                }),
                Telemetry::Attitude(Attitude {
                    time_boot_ms: ms,
                    roll_rad: 0.0,
                    pitch_rad: pitch,
                    yaw_rad: 0.0,
                    roll_rate_radps: 0.0,
                    pitch_rate_radps: 0.0,
                    yaw_rate_radps: 0.0,
                }),
                Telemetry::AirData(AirData {
                    time_boot_ms: ms,
                    abs_pressure_pa: state.pressure_pa,
                    diff_pressure_pa: 0.5 * state.density_kg_per_m3 * airspeed * airspeed,
                    temperature_c: state.temperature_k - 273.15,
                    diff_temperature_c: None,
                }),
            ] {
                core.on_link_event(
                    t,
                    GroundEvent::Telemetry {
                        from: (1, 1),
                        telemetry,
                    },
                );
            }
            core.set_link_stats(
                t,
                LinkStats {
                    connected: true,
                    ..LinkStats::default()
                },
            );
            core.tick(t / speed);
            t += 0.25;
        }
        truth
    }

    #[test]
    fn live_telemetry_becomes_an_estimate_with_still_air_and_a_prediction() {
        let mut core = core();
        assert!(
            core.tick(0.0).estimate.is_none(),
            "no estimate before telemetry"
        );
        let truth = glide(&mut core, 0.0, 40.0);
        let est = core.estimate.expect("an estimate");
        assert!(
            (est.position_ned_m - truth).norm() < 5.0,
            "{:?} vs {truth:?}",
            est.position_ned_m
        );
        assert!(
            est.wind_ned_mps.xy().norm() < 0.5,
            "still air: {:?}",
            est.wind_ned_mps
        );
        let state = core.state_msg_now(40.0);
        assert_eq!(
            state
                .vehicle
                .as_ref()
                .and_then(|v| v.mode.clone())
                .as_deref(),
            Some("heading")
        );
        assert!(
            state.prediction.is_none(),
            "the prediction runs only when asked"
        );
        let job = core.prediction_job().expect("a prediction can run");
        core.set_prediction(job.run());
        let prediction = core.state_msg_now(40.0).prediction.expect("a prediction");
        // Uncontrolled, straight north: lands north of where it is now, about 2:1 further on.
        let uncontrolled = prediction.uncontrolled;
        let (lat_now, _, _) = core.frame.to_geodetic(&truth);
        assert!(uncontrolled.lat_deg > lat_now, "{uncontrolled:?}");
    }

    #[test]
    fn navigation_runs_on_the_drones_clock_in_accelerated_rehearsals() {
        let mut core = core();
        let truth = glide_at_speed(&mut core, 0.0, 40.0, 20.0);
        let est = core.estimate.expect("an estimate");
        assert!(
            (est.position_ned_m - truth).norm() < 5.0,
            "{:?} vs {truth:?}",
            est.position_ned_m
        );
        assert!(
            (est.velocity_ned_mps - Vector3::new(6.0, 0.0, 3.0)).norm() < 0.5,
            "{:?}",
            est.velocity_ned_mps
        );
        assert!(
            (core.track.len() as f64 - 40.0).abs() <= 1.0,
            "one track point per flight second"
        );
    }

    #[test]
    fn a_drone_restart_starts_navigation_over() {
        let mut core = core();
        glide(&mut core, 30.0, 60.0);
        assert!(core.estimate.is_some());
        glide(&mut core, 0.0, 0.5);
        assert!(core.events.iter().any(|e| e.text.contains("restarted")));
        let est = core.estimate.expect("estimate after restart");
        assert!(
            est.time_s < 1.0,
            "navigation on the new clock: {}",
            est.time_s
        );
    }

    #[test]
    fn silence_turns_the_vehicle_stale_and_the_stage_change_is_logged() {
        let mut core = core();
        glide(&mut core, 0.0, 5.0);
        assert!(!core.state_msg_now(5.0).link.stale);
        let stale_after = core.config.link.stale_after_s;
        assert!(core.state_msg_now(5.0 + stale_after + 0.5).link.stale);
        core.on_link_event(
            6.0,
            GroundEvent::Telemetry {
                from: (1, 1),
                telemetry: Telemetry::Status(VehicleStatus {
                    mode: FlightMode::Heading,
                    stage: stx_gnc::mission::FlightStage::Landed,
                    phase: stx_gnc::mission::GuidancePhase::Landed,
                    state: SystemState::Standby,
                }),
            },
        );
        assert!(core.events.iter().any(|e| e.text.contains("Landed")));
    }

    #[test]
    fn guidance_telemetry_gives_the_drones_target_until_its_plan_is_read() {
        let mut core = core();
        glide(&mut core, 0.0, 5.0);
        assert!(
            core.state_msg_now(5.0)
                .guidance
                .and_then(|g| g.target)
                .is_none()
        );
        // The drone's NAV_CONTROLLER_OUTPUT towards its target 300 m N, 2,500 m E.
        let (p, _) = core.latest.position.expect("a position");
        let here = core.frame.to_ned(p.lat_deg, p.lon_deg, p.alt_msl_m);
        let to = Vector3::new(300.0, 2500.0, 0.0) - here;
        let status = stx_link::telemetry::GuidanceStatus {
            desired_roll_deg: 0.0,
            desired_heading_deg: 0.0,
            bearing_to_target_deg: to.y.atan2(to.x).to_degrees().rem_euclid(360.0).round(),
            distance_to_target_m: to.xy().norm().round(),
            alt_error_m: 0.0,
            xtrack_error_m: 0.0,
        };
        let guidance = |core: &mut StationCore, t: f64| {
            core.on_link_event(
                t,
                GroundEvent::Telemetry {
                    from: (1, 1),
                    telemetry: Telemetry::Guidance(status),
                },
            );
        };
        guidance(&mut core, 5.0);
        let g = core.state_msg_now(5.0).guidance.expect("guidance");
        assert_eq!(g.target_source, Some("drone_telemetry"));
        let t = g.target.expect("a target");
        let ne = core.frame.to_ned(t.lat_deg, t.lon_deg, t.alt_msl_m);
        // Whole degrees of bearing at 2.5 km: within about 22 m.
        assert!(
            (ne.xy() - nalgebra::Vector2::new(300.0, 2500.0)).norm() < 25.0,
            "{ne:?}"
        );
        assert_eq!(core.take_link_actions(5.0), vec![LinkAction::PlanDownload]);
        assert!(core.take_link_actions(5.1).is_empty(), "asked once");
        // The plan read back is exact, and agreeing telemetry changes nothing.
        let (lat, lon, alt) = core.frame.to_geodetic(&Vector3::new(300.0, 2500.0, 0.0));
        core.on_link_event(
            6.0,
            GroundEvent::Plan(stx_link::plan::PlanEvent::DownloadDone {
                items: vec![stx_link::plan::PlanItem::Land {
                    lat_deg: lat,
                    lon_deg: lon,
                    alt_msl_m: alt,
                    approach_heading_deg: None,
                }],
            }),
        );
        guidance(&mut core, 6.5);
        let g = core.state_msg_now(6.5).guidance.expect("guidance");
        assert_eq!(g.target_source, Some("drone_plan"));
        assert!(
            (core.replica_plan().target_ned_m.xy() - nalgebra::Vector2::new(300.0, 2500.0)).norm()
                < 0.5
        );
        assert!(core.take_link_actions(20.0).is_empty(), "no new download");
    }

    #[test]
    fn failed_plan_reads_are_retried_later_and_later_and_said_once() {
        let mut core = core();
        core.on_link_event(
            0.0,
            GroundEvent::Link(LinkEvent::Connected {
                system_id: 1,
                component_id: 1,
            }),
        );
        assert_eq!(core.take_link_actions(0.0), vec![LinkAction::PlanDownload]);
        let fail = |core: &mut StationCore, t: f64| {
            core.on_link_event(
                t,
                GroundEvent::Plan(stx_link::plan::PlanEvent::DownloadFailed {
                    reason: "no answer".into(),
                }),
            );
        };
        fail(&mut core, 1.0);
        assert!(core.take_link_actions(5.9).is_empty(), "not before 5 s");
        assert_eq!(core.take_link_actions(6.0), vec![LinkAction::PlanDownload]);
        fail(&mut core, 7.0);
        assert!(core.take_link_actions(16.9).is_empty(), "then 10 s");
        assert_eq!(core.take_link_actions(17.0), vec![LinkAction::PlanDownload]);
        let said = core
            .events
            .iter()
            .filter(|e| e.text.contains("plan could not be read"))
            .count();
        assert_eq!(said, 1);
    }

    #[test]
    fn derived_values_turn_stale_with_the_link() {
        let mut core = core();
        glide(&mut core, 0.0, 10.0);
        let job = core.prediction_job().expect("a prediction");
        core.set_prediction(job.run());
        let fresh = core.state_msg_now(10.0);
        assert!(!fresh.estimate.as_ref().expect("estimate").stale);
        assert!(!fresh.vehicle.as_ref().expect("vehicle").stale);
        assert!(!fresh.prediction.as_ref().expect("prediction").stale);
        assert!(!fresh.guidance.as_ref().expect("guidance").stale);
        let later = 10.0 + core.config.link.stale_after_s + 1.0;
        let old = core.state_msg_now(later);
        let estimate = old.estimate.expect("the last estimate is still shown");
        assert!(estimate.stale && estimate.age_s > core.config.link.stale_after_s);
        assert!(old.vehicle.expect("vehicle").stale);
        assert!(old.prediction.expect("prediction").stale);
        assert!(old.guidance.expect("guidance").stale);
        assert!(old.link.stale);
    }

    #[test]
    fn kml_predicted_landings_lie_on_the_ground_not_at_sea_level() {
        let mut core = core();
        glide(&mut core, 0.0, 10.0);
        let job = core.prediction_job().expect("a prediction");
        core.set_prediction(job.run());
        core.on_link_event(
            10.0,
            GroundEvent::Telemetry {
                from: (1, 1),
                telemetry: Telemetry::PredictedLanding(stx_link::telemetry::PredictedLanding {
                    time_boot_ms: 10_000,
                    lat_deg: 38.54,
                    lon_deg: -7.88,
                    alt_msl_m: 245.0,
                }),
            },
        );
        let doc = crate::kml::live("test", &core.track(1.0), &core.state_msg_now(10.0));
        let predicted: Vec<&str> = doc
            .lines()
            .filter(|l| l.contains("predicted landing"))
            .collect();
        assert_eq!(
            predicted.len(),
            3,
            "station plan, uncontrolled, drone's own: {doc}"
        );
        for p in predicted {
            // The site is 245 m above the sea: altitude 0 absolute would be underground.
            assert!(
                p.contains("<altitudeMode>clampToGround</altitudeMode>"),
                "{p}"
            );
            assert!(!p.contains("absolute"), "{p}");
        }
        assert!(doc.contains("predicted landing (drone's own)"));
    }

    #[test]
    fn waiting_for_the_drone_is_said_once() {
        let mut core = core();
        for queued in 1..10 {
            core.on_io_event(
                f64::from(queued as u32),
                0,
                IoEvent::QueuedWithoutPeer { queued },
            );
        }
        assert_eq!(core.events.len(), 1);
    }
}
