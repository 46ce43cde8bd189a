//! The drone's end of the link (simulated or not): sends telemetry and its status heartbeat;
//! answers commands, parameters, plan transfers and requests for its identity
//! (AUTOPILOT_VERSION, `identity.rs`); turns MANUAL_CONTROL into sticks that go
//! stale.

use std::collections::VecDeque;
use std::time::Duration;

use mavlink::dialects::common as mc;
use mavlink::dialects::common::MavMessage;

use super::core::{LinkConfig, LinkCore, LinkEvent};
use super::identity::{Identity, IdentityServer};
use super::stats::LinkStats;
use crate::command::{CommandResult, CommandServer, IncomingCommand, IncomingId};
use crate::frame::Frame;
use crate::manual::{ManualEvent, ManualReceiver, Sticks};
use crate::param::{
    ParamChange, ParamRefusal, ParamSpec, ParamTable, ParamTableError, ParamValidator, RangeOnly,
};
use crate::plan::{FenceItem, FenceServer, PlanConfig, PlanItem, PlanServer};
use crate::signing::SigningConfig;
use crate::telemetry::{Severity, SystemState, Telemetry, VehicleStatus, split_status_text};

/// Everything the vehicle endpoint needs.
#[derive(Debug, Clone)]
pub struct VehicleConfig {
    /// Link settings.
    pub link: LinkConfig,
    /// The parameter table.
    pub params: Vec<ParamSpec>,
    /// Plan transfer timing.
    pub plan: PlanConfig,
    /// Sticks stale after this long without MANUAL_CONTROL.
    pub manual_timeout: Duration,
    /// How long commands are remembered to recognise retries.
    pub command_dedup_window: Duration,
    /// Status sent in heartbeats until the application sets one.
    pub initial_status: VehicleStatus,
    /// How the drone names itself when a ground station asks (AUTOPILOT_VERSION).
    pub identity: Identity,
}

impl Default for VehicleConfig {
    fn default() -> Self {
        use stx_types::mission::{FlightMode, FlightStage, GuidancePhase};
        Self {
            link: LinkConfig::vehicle(),
            params: Vec::new(),
            plan: PlanConfig::default(),
            manual_timeout: Duration::from_millis(500),
            command_dedup_window: Duration::from_secs(5),
            initial_status: VehicleStatus {
                mode: FlightMode::Uncontrolled,
                stage: FlightStage::PreLaunch,
                phase: GuidancePhase::Idle,
                state: SystemState::Standby,
            },
            identity: Identity::default(),
        }
    }
}

/// What the vehicle endpoint reports.
#[derive(Debug, Clone, PartialEq)]
pub enum VehicleEvent {
    /// Link state (peer = a ground station), dropped frames, signing timestamp to persist.
    Link(LinkEvent),
    /// A command to execute; answer with [`VehicleEndpoint::respond_command`].
    Command(IncomingCommand),
    /// A parameter changed (by the station).
    ParamChanged(ParamChange),
    /// A parameter set from the station was refused (range or the application's validator);
    /// the station was answered with the value in force.
    ParamRefused(ParamRefusal),
    /// A new plan was uploaded.
    PlanReceived(Vec<PlanItem>),
    /// A new keep-out fence was uploaded (its polygons checked whole).
    FenceReceived(Vec<FenceItem>),
    /// Stick values, or their going stale.
    Manual(ManualEvent),
    /// Any other message.
    Other(Box<Frame>),
}

/// The drone's end of the link (sans-io).
#[derive(Debug)]
pub struct VehicleEndpoint {
    core: LinkCore,
    status: VehicleStatus,
    commands: CommandServer,
    identity: IdentityServer,
    params: ParamTable,
    plan: PlanServer,
    fence: FenceServer,
    manual: ManualReceiver,
    next_text_id: u16,
    events: VecDeque<VehicleEvent>,
}

impl VehicleEndpoint {
    /// A vehicle endpoint started at `now`; fails if the parameter table is invalid.
    pub fn new(config: VehicleConfig, now: Duration) -> Result<Self, ParamTableError> {
        let (sys, comp) = (config.link.system_id, config.link.component_id);
        let mut commands = CommandServer::new(sys, comp);
        commands.dedup_window = config.command_dedup_window;
        Ok(Self {
            params: ParamTable::new(sys, comp, config.params)?,
            plan: PlanServer::new(sys, comp, config.plan),
            fence: FenceServer::new(sys, comp, config.plan),
            manual: ManualReceiver::new(sys, config.manual_timeout),
            commands,
            identity: IdentityServer::new(sys, comp, config.identity),
            status: config.initial_status,
            core: LinkCore::new(config.link, now),
            next_text_id: 1,
            events: VecDeque::new(),
        })
    }

    /// Feeds bytes received from the transport; parameter sets are checked against the
    /// table's ranges only.
    pub fn handle_bytes(&mut self, now: Duration, bytes: &[u8]) {
        self.handle_bytes_with(now, bytes, &mut RangeOnly);
    }

    /// Feeds bytes received from the transport; a parameter set within its range is put to
    /// `validator` (the application's rules) before it is taken or echoed.
    pub fn handle_bytes_with(
        &mut self,
        now: Duration,
        bytes: &[u8],
        validator: &mut impl ParamValidator,
    ) {
        self.handle_bytes_on_with(0, now, bytes, validator);
    }

    /// [`handle_bytes_with`](Self::handle_bytes_with) for radio `path`
    /// ([`LinkConfig::paths`]).
    pub fn handle_bytes_on_with(
        &mut self,
        path: usize,
        now: Duration,
        bytes: &[u8],
        validator: &mut impl ParamValidator,
    ) {
        let frames = self.core.ingest(path, now, bytes);
        self.dispatch(now, frames, validator);
    }

    /// [`handle_bytes`](Self::handle_bytes) for radio `path`.
    pub fn handle_bytes_on(&mut self, path: usize, now: Duration, bytes: &[u8]) {
        self.handle_bytes_on_with(path, now, bytes, &mut RangeOnly);
    }

    /// Feeds one whole datagram (UDP) received on radio `path`; returns whether it carried a
    /// frame accepted (CRC checked and, with signing on, correctly signed) from the ground
    /// station this vehicle serves — the only kind of datagram whose source a UDP-in
    /// transport may take as the station's address. That station is the one whose heartbeats
    /// the vehicle tracks, or any that announces itself with a ground-station heartbeat (as
    /// the vehicle then serves it); before any has, a frame from any other system counts, so
    /// a tool that commands before its first heartbeat is answered. A frame left incomplete
    /// at the datagram's end is dropped as truncated.
    pub fn handle_datagram_on_with(
        &mut self,
        path: usize,
        now: Duration,
        datagram: &[u8],
        validator: &mut impl ParamValidator,
    ) -> bool {
        let (tracked, own) = (self.core.peer(), self.core.config.system_id);
        let (frames, from_station) =
            self.core
                .ingest_datagram(path, now, datagram, |f| match (tracked, &f.message) {
                    (_, MavMessage::HEARTBEAT(h)) if h.mavtype == mc::MavType::MAV_TYPE_GCS => true,
                    (Some((system, _)), _) => f.header.system_id == system,
                    (None, _) => f.header.system_id != own,
                });
        self.dispatch(now, frames, validator);
        from_station
    }

    /// [`handle_datagram_on_with`](Self::handle_datagram_on_with) with parameter sets checked
    /// against the table's ranges only.
    pub fn handle_datagram_on(&mut self, path: usize, now: Duration, datagram: &[u8]) -> bool {
        self.handle_datagram_on_with(path, now, datagram, &mut RangeOnly)
    }

    /// [`handle_stream_end`](Self::handle_stream_end) for radio `path`.
    pub fn handle_stream_end_on(&mut self, path: usize, now: Duration) {
        self.handle_stream_end_on_with(path, now, &mut RangeOnly);
    }

    /// [`handle_stream_end_with`](Self::handle_stream_end_with) for radio `path`.
    pub fn handle_stream_end_on_with(
        &mut self,
        path: usize,
        now: Duration,
        validator: &mut impl ParamValidator,
    ) {
        let frames = self.core.stream_end(path, now);
        self.dispatch(now, frames, validator);
    }

    /// The radio that frames from [`poll_transmit`](Self::poll_transmit) go out on now.
    pub fn transmit_path(&self, now: Duration) -> usize {
        self.core.transmit_path(now)
    }

    /// The stream connection (TCP, serial) ended: a frame cut off by it is counted as
    /// truncated and any frame behind it still delivered.
    pub fn handle_stream_end(&mut self, now: Duration) {
        self.handle_stream_end_with(now, &mut RangeOnly);
    }

    /// [`handle_stream_end`](Self::handle_stream_end) with the application's parameter rules.
    pub fn handle_stream_end_with(&mut self, now: Duration, validator: &mut impl ParamValidator) {
        self.handle_stream_end_on_with(0, now, validator);
    }

    /// The signing timestamp high-water mark in force, to be persisted before frames signed
    /// under it leave (`None`: signing off).
    pub fn signing_timestamp_mark(&self) -> Option<u64> {
        self.core.signing_mark()
    }

    fn dispatch(&mut self, now: Duration, frames: Vec<Frame>, validator: &mut impl ParamValidator) {
        for frame in frames {
            let from = (frame.header.system_id, frame.header.component_id);
            let msg = &frame.message;
            let handled = match msg {
                MavMessage::HEARTBEAT(h) => {
                    if h.mavtype == mc::MavType::MAV_TYPE_GCS {
                        self.core.peer_heartbeat(now, from);
                    }
                    false
                }
                _ => {
                    self.identity.handle_message(from, msg)
                        || self.commands.handle_message(now, from, msg)
                        || self.params.handle_message_with(msg, validator)
                        || self.plan.handle_message(now, from, msg)
                        || self.fence.handle_message(now, from, msg)
                        || self.manual.handle_message(now, msg)
                }
            };
            if !handled {
                self.events.push_back(VehicleEvent::Other(Box::new(frame)));
            }
        }
    }

    /// Sets the status sent in heartbeats (mode, stage, phase, state).
    pub fn set_status(&mut self, status: VehicleStatus) {
        self.status = status;
    }

    /// The status sent in heartbeats.
    pub fn status(&self) -> VehicleStatus {
        self.status
    }

    /// Sends a telemetry item now.
    pub fn send_telemetry(&mut self, now: Duration, telemetry: &Telemetry) {
        self.core.send(now, &telemetry.to_mavlink());
    }

    /// Sends a telemetry item now as another component of the drone's system (a body's own
    /// IMU, `stx_types::stack::BodyImu`).
    pub fn send_telemetry_from(&mut self, now: Duration, component_id: u8, telemetry: &Telemetry) {
        self.core
            .send_from(now, component_id, &telemetry.to_mavlink());
    }

    /// Sends a text of any length (split into STATUSTEXT chunks when over 50 bytes).
    pub fn send_status_text(&mut self, now: Duration, severity: Severity, text: &str) {
        let id = self.next_text_id;
        self.next_text_id = self.next_text_id.checked_add(1).unwrap_or(1);
        for chunk in split_status_text(severity, text, id) {
            self.core
                .send(now, &Telemetry::StatusText(chunk).to_mavlink());
        }
    }

    /// Answers a command.
    pub fn respond_command(&mut self, id: IncomingId, result: CommandResult) -> bool {
        self.commands.respond(id, result)
    }

    /// The parameter table.
    pub fn params(&self) -> &ParamTable {
        &self.params
    }

    /// The parameter table, to set values from onboard (announced to the station).
    pub fn params_mut(&mut self) -> &mut ParamTable {
        &mut self.params
    }

    /// The plan held.
    pub fn plan(&self) -> &[PlanItem] {
        self.plan.plan()
    }

    /// Replaces the plan held (the vehicle's own, e.g. loaded before launch), so that a
    /// download returns what the vehicle actually flies.
    pub fn set_plan(&mut self, plan: Vec<PlanItem>) {
        self.plan.set_plan(plan);
    }

    /// The keep-out fence held.
    pub fn fence(&self) -> &[FenceItem] {
        self.fence.plan()
    }

    /// Changes how long sticks stay fresh without a MANUAL_CONTROL (a parameter the station
    /// may edit).
    pub fn set_manual_timeout(&mut self, timeout: Duration) {
        self.manual.timeout = timeout;
    }

    /// Current sticks; `None` when stale or never received.
    pub fn sticks(&self, now: Duration) -> Option<Sticks> {
        self.manual.sticks(now)
    }

    /// Runs timers: heartbeats, liveness, plan re-requests, manual staleness.
    pub fn handle_timeout(&mut self, now: Duration) {
        if self.core.handle_timeout(now) {
            let hb = Telemetry::Status(self.status).to_mavlink();
            self.core.send(now, &hb);
        }
        self.plan.handle_timeout(now);
        self.fence.handle_timeout(now);
        self.manual.handle_timeout(now);
    }

    /// Earliest time [`handle_timeout`](Self::handle_timeout) must run.
    pub fn poll_timeout(&self) -> Option<Duration> {
        [
            Some(self.core.poll_timeout()),
            self.plan.poll_timeout(),
            self.fence.poll_timeout(),
            self.manual.poll_timeout(),
        ]
        .into_iter()
        .flatten()
        .min()
    }

    /// Next frame to send.
    pub fn poll_transmit(&mut self, now: Duration) -> Option<Vec<u8>> {
        while let Some(m) = self.commands.poll_transmit() {
            self.core.send(now, &m);
        }
        while let Some(m) = self.identity.poll_transmit() {
            self.core.send(now, &m);
        }
        while let Some(m) = self.params.poll_transmit() {
            self.core.send(now, &m);
        }
        while let Some((severity, text)) = self.params.poll_text() {
            self.send_status_text(now, severity, &text);
        }
        while let Some(m) = self.plan.poll_transmit() {
            self.core.send(now, &m);
        }
        while let Some(m) = self.fence.poll_transmit() {
            self.core.send(now, &m);
        }
        self.core.out.pop_front()
    }

    /// Next event.
    pub fn poll_event(&mut self) -> Option<VehicleEvent> {
        while let Some(e) = self.core.events.pop_front() {
            self.events.push_back(VehicleEvent::Link(e));
        }
        while let Some(e) = self.commands.poll_event() {
            self.events.push_back(VehicleEvent::Command(e));
        }
        while let Some(c) = self.params.poll_change() {
            self.events.push_back(VehicleEvent::ParamChanged(c));
        }
        while let Some(r) = self.params.poll_refusal() {
            self.events.push_back(VehicleEvent::ParamRefused(r));
        }
        while let Some(p) = self.plan.poll_plan() {
            self.events.push_back(VehicleEvent::PlanReceived(p));
        }
        while let Some(f) = self.fence.poll_plan() {
            self.events.push_back(VehicleEvent::FenceReceived(f));
        }
        while let Some(m) = self.manual.poll_event() {
            self.events.push_back(VehicleEvent::Manual(m));
        }
        self.events.pop_front()
    }

    /// Link quality now.
    pub fn link_stats(&mut self, now: Duration) -> LinkStats {
        self.core.stats(now)
    }

    /// Whether a ground station's heartbeats are arriving.
    pub fn is_connected(&self) -> bool {
        self.core.connected
    }

    /// Switches MAVLink 2 signing on (`Some`) or off (`None`).
    pub fn set_signing(&mut self, now: Duration, signing: Option<SigningConfig>) {
        self.core.set_signing(now, signing);
    }
}
