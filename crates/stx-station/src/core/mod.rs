//! The station's state and logic, free of I/O: telemetry and link events in, JSON messages and
//! link actions out, the mission clock (`now_s`, seconds since the station started) passed in.
//!
//! - `navigation`: telemetry feeds the station's own estimator (the same code as onboard);
//!   each [`StationCore::tick`] runs the guidance replica and the timers, and landing
//!   predictions run as detached [`PredictionJob`]s;
//! - `sync`: the replica follows the plan the drone holds, read back from it;
//! - operators' requests are checked (`requests`), followed through their whole life
//!   (`commands`: sent, answered, retried, timed out) and become [`LinkAction`]s with ids
//!   and deadlines (`actions`); the link driver's outcome of each comes back through
//!   [`StationCore::on_action_outcome`], the drone's answers through
//!   [`StationCore::on_link_event`], and every request ends in a `command_result`
//!   (`operator` ties these together; `cutdown` arms and confirms the cutdown, `manual`
//!   holds and releases the sticks);
//! - `ascent`: the wind measured from the balloon's drift during the ascent, by altitude
//!   band, and the profile ([`StationCore::wind_profile`]) the predictions fly in;
//!   `flight_path`: the burst, deploy and unsteered landing points flown in it while the
//!   balloon rises and the round chute falls;
//! - `params`: the drone's parameter table; `views`: the `state` and `params` messages;
//! - `keep_out`: the keep-out zones, the targets they refuse and the alarms they raise;
//!   `fence`: the zones sent to the drone as its fence, until it acknowledges them;
//! - `surface_wind`: the wind at the target (anemometer or operator) uplinked to the drone
//!   and given to the replica once the drone holds it;
//! - `readiness`: the go/no-go board (the station's checks, the checklist's ticks, a launch
//!   with checks open announced).

mod actions;
mod ascent;
mod commands;
mod cutdown;
mod fence;
mod flight_path;
mod footprint;
mod keep_out;
mod landing;
mod manual;
mod mission_clock;
mod navigation;
mod operator;
mod params;
mod phase_sync;
mod readiness;
mod replica;
mod requests;
mod stack;
mod surface_wind;
mod sync;
pub(crate) mod views;

use std::collections::VecDeque;

use stx_gnc::estimate::Estimate;
use stx_gnc::estimator::Estimator;
use stx_gnc::geo::LocalFrame;
use stx_gnc::guidance::Guidance;
use stx_gnc::predict::LandingPrediction;
use stx_link::endpoint::{GroundEvent, LinkEvent, LinkStats};
use stx_link::sansio::IoEvent;
use stx_link::telemetry::Severity;

use crate::config::StationConfig;
use crate::messages::{EventMsg, Level, StateMsg, TrackPoint};

pub use actions::{APPLY_WITHIN_S, ActionError, ActionId, LinkAction, LinkOp, OUTCOME_GRACE_S};
pub use ascent::REFIT_EVERY_S;
pub use commands::{ANSWER_PER_PLAN_ITEM_S, ANSWER_WITHIN_S, UPLOAD_RETRY_S, UPLOAD_TRIES};
pub use cutdown::CutdownArm;
pub use fence::{FENCE_RETRY_S, FENCE_TRIES};
pub use flight_path::FLIGHT_PATH_EVERY_S;
pub use footprint::{FootprintDone, FootprintJob};
pub use keep_out::{CLEAR_AFTER_S, CheckedZones};
pub use manual::MANUAL_SILENCE_S;
pub(crate) use navigation::{MAX_TRACK_POINTS, thin_track};
pub use navigation::{PREDICTION_EVERY_S, Predicted, PredictionJob};
pub use readiness::TickError;
pub use requests::{ApiError, CommandRequest};
pub use stack::BODY_MEASURED_WITHIN_S;
pub use sync::TargetSource;

/// Most events kept for the log.
const MAX_EVENTS: usize = 10_000;

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
    /// Times the drone's phase became the final approach, counted on every status heard: a
    /// page that sees only some states (the newest when it is ready) still learns of each.
    pub final_approaches: u32,
    /// The drone's own prediction of its touchdown.
    pub predicted_landing: Option<(stx_link::telemetry::PredictedLanding, f64)>,
    /// The drone's clock of the newest GPS_INPUT the estimator took, s.
    pub gps_solution_s: Option<f64>,
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
    /// An `ascent_wind` message: the ascent's bands changed.
    AscentWind(crate::messages::AscentWindMsg),
    /// An operator's request, accepted: for the recording (pages see its event).
    Command(crate::recording::station::CommandRecord),
    /// The keep-out zones, changed.
    KeepOut(crate::keep_out::KeepOutMsg),
}

/// The station.
pub struct StationCore {
    pub(crate) config: StationConfig,
    pub(crate) frame: LocalFrame,
    /// Unix time at mission time 0, ms.
    wall_origin_ms: u64,
    pub(crate) latest: Latest,
    pub(crate) estimator: Estimator,
    /// The wind measured from the ascent's drift.
    ascent: ascent::AscentWinds,
    /// The drone's clock (s since its boot) from the newest time-stamped telemetry:
    /// navigation runs on it, so radio delays and accelerated rehearsals do not distort it.
    pub(crate) drone_time_s: Option<f64>,
    /// The drone's clock carried forward between its readings, for the pages.
    pub(crate) mission_clock: mission_clock::MissionClock,
    pub(crate) estimate: Option<Estimate>,
    pub(crate) guidance: Guidance,
    pub(crate) prediction: Option<LandingPrediction>,
    /// When the sensor data the prediction started from arrived (mission time, s).
    pub(crate) prediction_data_s: Option<f64>,
    /// The latest reachable footprint, the mission time it was computed at (s), and the
    /// keep-out zones it overlaps (found once per footprint, not per state message).
    pub(crate) footprint: Option<(
        stx_gnc::footprint::Footprint,
        f64,
        Vec<stx_gnc::footprint::ZoneHit>,
    )>,
    /// The plan download and where the replica's plan comes from.
    pub(crate) sync: sync::PlanSync,
    /// The drone's clock of the estimate guidance last ran on, s.
    pub(crate) guided_at_s: Option<f64>,
    /// The replica's guidance phase against the drone's.
    pub(crate) phase_sync: phase_sync::PhaseSync,
    /// The landing, measured once.
    pub(crate) landing: landing::LandingWatch,
    /// The drone's clock of the estimate the last landing prediction started from, s.
    predicted_from_s: Option<f64>,
    pub(crate) track: Vec<TrackPoint>,
    next_track_s: f64,
    pub(crate) events: VecDeque<EventMsg>,
    pub(crate) history: VecDeque<StateMsg>,
    next_history_s: f64,
    pub(crate) link: LinkStats,
    /// Link actions for the driver, and those whose outcome has not come.
    outbox: actions::Outbox,
    /// Operators' requests.
    commands: commands::Commands,
    pub(crate) params: params::Table,
    pub(crate) cutdown: cutdown::Cutdown,
    /// Mission time of the last sticks, while they are held.
    manual_last_s: Option<f64>,
    outbound: Vec<Outbound>,
    last_connected: Option<bool>,
    /// What the guidance replica commands now (for the dashboard's comparison).
    pub(crate) replica_command: stx_dynamics::state::Controls,
    /// The vehicle's main-line servo travel, m: telemetry reports the servo in −1…1 of it.
    pub(crate) main_line_travel_m: f64,
    /// The keep-out zones and the alarms they raised.
    pub(crate) keep_out: keep_out::KeepOut,
    /// The drone's copy of the zones.
    fence: fence::FenceSync,
    /// The wind at the target and the drone's copy of it.
    surface_wind: surface_wind::SurfaceWindState,
    /// The go/no-go board's checklist, ticks and what the daemon tells it.
    readiness: readiness::Readiness,
    /// The unsteered flight path from the balloon or the round chute.
    live_path: flight_path::LivePath,
    /// The other bodies' own attitudes, as their IMUs report them.
    pub(crate) body_attitudes: stack::BodyAttitudes,
    /// The rigging that places the bodies around the drone (the shipped vehicle's, as the
    /// main-line travel above).
    pub(crate) rigging: stx_dynamics::vehicle::Vehicle,
}

impl StationCore {
    /// A station that has heard nothing yet; `wall_origin_ms` is the Unix time of mission
    /// time 0.
    pub fn new(config: StationConfig, wall_origin_ms: u64) -> Self {
        let frame = config.origin;
        let guidance = Guidance::new(config.guidance);
        let estimator = navigation::new_estimator(config.origin.alt_msl_m);
        Self {
            frame,
            wall_origin_ms,
            latest: Latest::default(),
            estimator,
            ascent: ascent::AscentWinds::new(config.ascent_wind),
            drone_time_s: None,
            mission_clock: Default::default(),
            estimate: None,
            guidance,
            prediction: None,
            prediction_data_s: None,
            footprint: None,
            sync: sync::PlanSync::default(),
            guided_at_s: None,
            phase_sync: Default::default(),
            landing: Default::default(),
            predicted_from_s: None,
            track: Vec::new(),
            next_track_s: 0.0,
            events: VecDeque::new(),
            history: VecDeque::new(),
            next_history_s: 0.0,
            link: LinkStats::default(),
            outbox: actions::Outbox::default(),
            commands: commands::Commands::default(),
            params: params::Table::default(),
            cutdown: cutdown::Cutdown::new(config.cutdown_window_s),
            manual_last_s: None,
            outbound: Vec::new(),
            last_connected: None,
            replica_command: stx_dynamics::state::Controls::default(),
            main_line_travel_m: stx_dynamics::vehicle::Vehicle::straplex().main_line_travel_m,
            body_attitudes: stack::BodyAttitudes::default(),
            rigging: stx_dynamics::vehicle::Vehicle::straplex(),
            keep_out: keep_out::KeepOut::default(),
            fence: fence::FenceSync::default(),
            surface_wind: Default::default(),
            readiness: readiness::Readiness::default(),
            live_path: flight_path::LivePath::default(),
            config,
        }
    }

    /// The configuration.
    pub fn config(&self) -> &StationConfig {
        &self.config
    }

    /// Unix time of mission time 0, ms.
    pub fn wall_origin_ms(&self) -> u64 {
        self.wall_origin_ms
    }

    pub(crate) fn wall_ms(&self, now_s: f64) -> u64 {
        self.wall_origin_ms + (now_s.max(0.0) * 1000.0) as u64
    }

    /// Logs an event and queues it for the dashboards.
    pub fn log(&mut self, now_s: f64, level: Level, source: &'static str, text: String) {
        let event = EventMsg {
            kind: "event",
            time_s: now_s,
            mission_time_s: self.mission_clock.at(now_s),
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
            // A body's own IMU speaks as its own component of the drone's system: its
            // ATTITUDE is that body's, never the drone's (the estimator reads the drone's).
            GroundEvent::Telemetry { from, telemetry } => {
                match (
                    stx_types::stack::BodyImu::from_component_id(from.1),
                    telemetry,
                ) {
                    (Some(body), stx_link::telemetry::Telemetry::Attitude(a)) => {
                        self.body_attitudes.heard(body, a, now_s);
                    }
                    (Some(_), _) => {}
                    (None, telemetry) => self.on_telemetry(now_s, telemetry),
                }
            }
            GroundEvent::StatusText { severity, text, .. } => {
                let level = match severity {
                    Severity::Emergency
                    | Severity::Alert
                    | Severity::Critical
                    | Severity::Error => Level::Error,
                    Severity::Warning => Level::Warning,
                    _ => Level::Info,
                };
                if level != Level::Info {
                    self.commands.on_vehicle_warning(now_s, &text);
                }
                self.log(now_s, level, "vehicle", text);
            }
            GroundEvent::Command(e) if surface_wind::SurfaceWindState::owns(e.request_id) => {
                self.on_surface_wind_answer(now_s, &e);
            }
            GroundEvent::Command(e) => {
                if let Some(msg) = self.commands.on_command_event(now_s, &e) {
                    self.after_command_result(now_s, &msg);
                }
            }
            GroundEvent::Param(e) => {
                if let Some(msg) = self.commands.on_param_event(&e) {
                    self.after_command_result(now_s, &msg);
                }
                if self.params.on_event(&e) {
                    self.replica_on_params(now_s);
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
            GroundEvent::Fence(e) => self.on_fence_event(now_s, e),
            GroundEvent::Link(LinkEvent::FrameError(e)) => {
                tracing::debug!(error = %e, "frame dropped (counted in the link statistics)");
            }
            GroundEvent::Link(LinkEvent::Connected { system_id, .. }) => {
                tracing::info!(system_id, "drone heartbeat");
                // A drone heard for the first time, or again, may hold parameters and fly a
                // plan the station has not seen.
                self.outbox.issue(
                    now_s,
                    LinkOp::ParamList,
                    actions::Purpose::ParamList,
                    APPLY_WITHIN_S,
                );
                self.want_plan_download(now_s);
                self.fence_link(now_s, true);
                self.surface_wind_link(now_s, true);
            }
            GroundEvent::Link(LinkEvent::Lost { .. }) => {
                self.fence_link(now_s, false);
                self.surface_wind_link(now_s, false);
            }
            GroundEvent::Link(LinkEvent::PersistSigningTimestamp(_)) => {}
            GroundEvent::Other(_) => {}
        }
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
}

#[cfg(test)]
mod ascent_tests;
#[cfg(test)]
mod surface_wind_tests;
#[cfg(test)]
mod tests;
