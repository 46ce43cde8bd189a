//! The station's end of the link: sends commands, parameter and plan requests and the
//! joystick; receives telemetry (STATUSTEXT re-assembled); tracks whether the drone is
//! connected.

use std::collections::VecDeque;
use std::time::Duration;

use mavlink::dialects::common as mc;
use mavlink::dialects::common::MavMessage;

use super::core::{LinkConfig, LinkCore, LinkEvent};
use super::stats::LinkStats;
use crate::command::{
    Command, CommandClient, CommandConfig, CommandEvent, CommandSendError, RequestId,
};
use crate::frame::Frame;
use crate::manual::{ManualSender, Sticks};
use crate::param::{ParamClient, ParamConfig, ParamEvent, ParamRequestError};
use crate::plan::{
    FenceClient, FenceEvent, FenceItem, PlanClient, PlanConfig, PlanEvent, PlanItem,
    PlanRequestError,
};
use crate::signing::SigningConfig;
use crate::telemetry::{Severity, StatusTextAssembler, Telemetry};

/// Everything the ground endpoint needs.
#[derive(Debug, Clone)]
pub struct GroundConfig {
    /// Link settings (ids, heartbeat, signing).
    pub link: LinkConfig,
    /// The drone's (system, component).
    pub vehicle: (u8, u8),
    /// Command retries.
    pub command: CommandConfig,
    /// Parameter retries.
    pub param: ParamConfig,
    /// Plan transfer timing.
    pub plan: PlanConfig,
    /// Time between MANUAL_CONTROL messages while the stick is held (100 ms = 10 Hz).
    pub manual_period: Duration,
}

impl Default for GroundConfig {
    fn default() -> Self {
        Self {
            link: LinkConfig::ground(),
            vehicle: (1, 1),
            command: CommandConfig::default(),
            param: ParamConfig::default(),
            plan: PlanConfig::default(),
            manual_period: Duration::from_millis(100),
        }
    }
}

/// What the ground endpoint reports.
#[derive(Debug, Clone, PartialEq)]
pub enum GroundEvent {
    /// Link state, dropped frames, signing timestamp to persist.
    Link(LinkEvent),
    /// A telemetry item from the drone (its system; any component).
    Telemetry {
        from: (u8, u8),
        telemetry: Telemetry,
    },
    /// A complete (re-assembled) STATUSTEXT.
    StatusText {
        from: (u8, u8),
        severity: Severity,
        text: String,
    },
    /// Outcome of a command.
    Command(CommandEvent),
    /// Outcome of a parameter operation.
    Param(ParamEvent),
    /// Outcome of a plan transfer.
    Plan(PlanEvent),
    /// Outcome of a keep-out fence transfer.
    Fence(FenceEvent),
    /// Any other message from the drone, and every message from another system (for
    /// recording and other tools).
    Other(Box<Frame>),
}

/// The station's end of the link (sans-io).
#[derive(Debug)]
pub struct GroundEndpoint {
    core: LinkCore,
    vehicle: (u8, u8),
    commands: CommandClient,
    params: ParamClient,
    plan: PlanClient,
    fence: FenceClient,
    manual: ManualSender,
    texts: StatusTextAssembler,
    events: VecDeque<GroundEvent>,
}

impl GroundEndpoint {
    /// A ground endpoint started at `now`.
    pub fn new(config: GroundConfig, now: Duration) -> Self {
        Self {
            core: LinkCore::new(config.link, now),
            vehicle: config.vehicle,
            commands: CommandClient::new(config.command),
            params: ParamClient::new(config.param),
            plan: PlanClient::new(config.plan),
            fence: FenceClient::new(config.plan),
            manual: ManualSender::new(config.manual_period),
            texts: StatusTextAssembler::default(),
            events: VecDeque::new(),
        }
    }

    /// Feeds bytes received from the transport (the primary one, with several radios).
    pub fn handle_bytes(&mut self, now: Duration, bytes: &[u8]) {
        self.handle_bytes_on(0, now, bytes);
    }

    /// Feeds bytes received on radio `path` ([`LinkConfig::paths`]).
    pub fn handle_bytes_on(&mut self, path: usize, now: Duration, bytes: &[u8]) {
        for frame in self.core.ingest(path, now, bytes) {
            self.dispatch(now, frame);
        }
    }

    /// Feeds one whole datagram (UDP) received on radio `path`; returns whether it carried a
    /// frame accepted from the drone's system (CRC checked and, with signing on, correctly
    /// signed), the only kind of datagram whose source a UDP-in transport may take as the
    /// drone's address. A frame left incomplete at the datagram's end is dropped as
    /// truncated, so a datagram cannot finish a frame that another one began.
    pub fn handle_datagram_on(&mut self, path: usize, now: Duration, datagram: &[u8]) -> bool {
        let drone = self.vehicle.0;
        let (frames, from_drone) = self
            .core
            .ingest_datagram(path, now, datagram, |f| f.header.system_id == drone);
        for frame in frames {
            self.dispatch(now, frame);
        }
        from_drone
    }

    /// The stream connection (TCP, serial) ended: a frame cut off by it is counted as
    /// truncated and any frame behind it still delivered.
    pub fn handle_stream_end(&mut self, now: Duration) {
        self.handle_stream_end_on(0, now);
    }

    /// [`handle_stream_end`](Self::handle_stream_end) for radio `path`.
    pub fn handle_stream_end_on(&mut self, path: usize, now: Duration) {
        for frame in self.core.stream_end(path, now) {
            self.dispatch(now, frame);
        }
    }

    /// The radio that frames from [`poll_transmit`](Self::poll_transmit) go out on now.
    pub fn transmit_path(&self, now: Duration) -> usize {
        self.core.transmit_path(now)
    }

    /// The signing timestamp high-water mark in force, to be persisted before frames signed
    /// under it leave (`None`: signing off).
    pub fn signing_timestamp_mark(&self) -> Option<u64> {
        self.core.signing_mark()
    }

    fn dispatch(&mut self, now: Duration, frame: Frame) {
        let from = (frame.header.system_id, frame.header.component_id);
        // Another system's frames (another vehicle, a ground station, someone on the network
        // forging them) are passed on as they are, never read as the drone's telemetry or
        // texts.
        if from.0 != self.vehicle.0 {
            self.events.push_back(GroundEvent::Other(Box::new(frame)));
            return;
        }
        let msg = &frame.message;
        if let MavMessage::HEARTBEAT(h) = msg
            && h.mavtype != mc::MavType::MAV_TYPE_GCS
        {
            self.core.peer_heartbeat(now, from);
        }
        let our = self.core.config.system_id;
        self.commands.handle_message(now, from.0, our, msg);
        self.params.handle_message(now, from.0, msg);
        self.plan.handle_message(now, from.0, msg);
        self.fence.handle_message(now, from.0, msg);
        match Telemetry::from_mavlink(msg) {
            Some(telemetry) => {
                if let Telemetry::StatusText(chunk) = &telemetry
                    && let Some((severity, text)) = self.texts.push(from.0, from.1, chunk)
                {
                    self.events.push_back(GroundEvent::StatusText {
                        from,
                        severity,
                        text,
                    });
                }
                self.events
                    .push_back(GroundEvent::Telemetry { from, telemetry });
            }
            None => {
                let protocol = matches!(
                    msg,
                    MavMessage::COMMAND_ACK(_)
                        | MavMessage::PARAM_VALUE(_)
                        | MavMessage::MISSION_REQUEST_INT(_)
                        | MavMessage::MISSION_ITEM_INT(_)
                        | MavMessage::MISSION_COUNT(_)
                        | MavMessage::MISSION_ACK(_)
                );
                if !protocol {
                    self.events.push_back(GroundEvent::Other(Box::new(frame)));
                }
            }
        }
    }

    /// Sends a command; its outcome arrives as [`GroundEvent::Command`] with `request_id`.
    pub fn send_command(
        &mut self,
        now: Duration,
        request_id: RequestId,
        command: Command,
    ) -> Result<(), CommandSendError> {
        self.commands.send(now, request_id, self.vehicle, command)
    }

    /// Fetches the whole parameter table.
    pub fn param_list(&mut self, now: Duration) -> Result<(), ParamRequestError> {
        self.params.list(now, self.vehicle)
    }

    /// Reads one parameter.
    pub fn param_read(&mut self, now: Duration, name: &str) -> Result<(), ParamRequestError> {
        self.params.read(now, self.vehicle, name)
    }

    /// Sets one parameter.
    pub fn param_set(
        &mut self,
        now: Duration,
        name: &str,
        value: f32,
    ) -> Result<(), ParamRequestError> {
        self.params.set(now, self.vehicle, name, value)
    }

    /// Uploads the guidance plan.
    pub fn plan_upload(
        &mut self,
        now: Duration,
        items: Vec<PlanItem>,
    ) -> Result<(), PlanRequestError> {
        self.plan.upload(now, self.vehicle, items)
    }

    /// Downloads the plan the drone holds.
    pub fn plan_download(&mut self, now: Duration) -> Result<(), PlanRequestError> {
        self.plan.download(now, self.vehicle)
    }

    /// Uploads the keep-out fence ([`zones_to_fence`](crate::plan::zones_to_fence)).
    pub fn fence_upload(
        &mut self,
        now: Duration,
        items: Vec<FenceItem>,
    ) -> Result<(), PlanRequestError> {
        self.fence.upload(now, self.vehicle, items)
    }

    /// Downloads the fence the drone holds.
    pub fn fence_download(&mut self, now: Duration) -> Result<(), PlanRequestError> {
        self.fence.download(now, self.vehicle)
    }

    /// Holds the stick at `sticks` (streamed until released).
    pub fn manual_hold(&mut self, now: Duration, sticks: Sticks) {
        self.manual.hold(now, sticks);
    }

    /// Releases the stick.
    pub fn manual_release(&mut self) {
        self.manual.release();
    }

    /// Keeps (or stops keeping) the wire bytes of every frame accepted, for
    /// [`poll_accepted_frame`](Self::poll_accepted_frame): what a read-only forward passes on.
    pub fn keep_accepted_frames(&mut self, on: bool) {
        self.core.keep_accepted(on);
    }

    /// The wire bytes of the next frame accepted since [`keep_accepted_frames`]
    /// (Self::keep_accepted_frames) was switched on: checked, its signature verified when
    /// signing is on, and not a second copy heard over another radio.
    pub fn poll_accepted_frame(&mut self) -> Option<Vec<u8>> {
        self.core.poll_accepted()
    }

    /// Sends a frame as it is: one a forward's watcher sent and its filter lets through.
    pub fn send_raw_frame(&mut self, frame: Vec<u8>) {
        self.core.send_raw(frame);
    }

    /// Sends any other message now (e.g. for tools).
    pub fn send_message(&mut self, now: Duration, msg: &MavMessage) {
        self.core.send(now, msg);
    }

    /// Runs timers: heartbeats, link liveness, retries, manual streaming.
    pub fn handle_timeout(&mut self, now: Duration) {
        if self.core.handle_timeout(now) {
            let hb = MavMessage::HEARTBEAT(mc::HEARTBEAT_DATA {
                custom_mode: 0,
                mavtype: mc::MavType::MAV_TYPE_GCS,
                autopilot: mc::MavAutopilot::MAV_AUTOPILOT_INVALID,
                base_mode: mc::MavModeFlag::empty(),
                system_status: mc::MavState::MAV_STATE_ACTIVE,
                mavlink_version: 3,
            });
            self.core.send(now, &hb);
        }
        self.commands.handle_timeout(now);
        self.params.handle_timeout(now);
        self.plan.handle_timeout(now);
        self.fence.handle_timeout(now);
        self.manual.handle_timeout(now);
    }

    /// Earliest time [`handle_timeout`](Self::handle_timeout) must run.
    pub fn poll_timeout(&self) -> Option<Duration> {
        [
            Some(self.core.poll_timeout()),
            self.commands.poll_timeout(),
            self.params.poll_timeout(),
            self.plan.poll_timeout(),
            self.fence.poll_timeout(),
            self.manual.poll_timeout(),
        ]
        .into_iter()
        .flatten()
        .min()
    }

    fn flush(&mut self, now: Duration) {
        let target = self.vehicle.0;
        while let Some(m) = self.commands.poll_transmit() {
            self.core.send(now, &m);
        }
        while let Some(m) = self.params.poll_transmit() {
            self.core.send(now, &m);
        }
        while let Some(m) = self.plan.poll_transmit() {
            self.core.send(now, &m);
        }
        while let Some(m) = self.fence.poll_transmit() {
            self.core.send(now, &m);
        }
        while let Some(m) = self.manual.poll_transmit(now, target) {
            self.core.send(now, &m);
        }
    }

    /// Next frame to send (one MAVLink frame per call).
    pub fn poll_transmit(&mut self, now: Duration) -> Option<Vec<u8>> {
        self.flush(now);
        self.core.out.pop_front()
    }

    /// Next event.
    pub fn poll_event(&mut self) -> Option<GroundEvent> {
        while let Some(e) = self.core.events.pop_front() {
            self.events.push_back(GroundEvent::Link(e));
        }
        while let Some(e) = self.commands.poll_event() {
            self.events.push_back(GroundEvent::Command(e));
        }
        while let Some(e) = self.params.poll_event() {
            self.events.push_back(GroundEvent::Param(e));
        }
        while let Some(e) = self.plan.poll_event() {
            self.events.push_back(GroundEvent::Plan(e));
        }
        while let Some(e) = self.fence.poll_event() {
            self.events.push_back(GroundEvent::Fence(e));
        }
        self.events.pop_front()
    }

    /// Link quality now.
    pub fn link_stats(&mut self, now: Duration) -> LinkStats {
        self.core.stats(now)
    }

    /// Whether the drone's heartbeats are arriving.
    pub fn is_connected(&self) -> bool {
        self.core.connected
    }

    /// Switches MAVLink 2 signing on (`Some`, refusing unsigned and MAVLink 1 frames from now
    /// on) or off (`None`).
    pub fn set_signing(&mut self, now: Duration, signing: Option<SigningConfig>) {
        self.core.set_signing(now, signing);
    }
}
