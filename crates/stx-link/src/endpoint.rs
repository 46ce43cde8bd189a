//! The two ends of the link, each composing framing, signing and the micro-protocols behind
//! one sans-io surface: bytes and `now` in, events and bytes out.
//!
//! - [`GroundEndpoint`] (station): sends commands, parameter and plan requests and the
//!   joystick; receives telemetry; tracks whether the drone is connected.
//! - [`VehicleEndpoint`] (drone, simulated or not): sends telemetry and its status heartbeat;
//!   answers commands, parameters and plan transfers; turns MANUAL_CONTROL into sticks that go
//!   stale.
//!
//! Both send a HEARTBEAT every [`LinkConfig::heartbeat_period`] and declare the peer connected
//! on its first heartbeat and lost after [`LinkConfig::link_timeout`] without one, with a
//! [`LinkEvent`] on each change. [`LinkStats`] (serde-serialisable, for the dashboard) counts
//! traffic, errors, signing refusals, per-sender packet loss from sequence-number gaps, the
//! message rate over a sliding window and the age of the last message of each kind.
//!
//! Loss from sequence numbers: a frame up to [`MAX_LOSS_GAP`] ahead of the last one counts the
//! numbers skipped as lost; one at most [`MAX_REORDER_DEPTH`] behind is a late (reordered)
//! frame — it un-counts one loss, since it did arrive — and one further behind means the sender
//! restarted its sequence (a reboot, a second instance): counted as a restart, not as the
//! ~255 frames a naive modulo-256 difference would say were lost.
//!
//! Stream transports (TCP, serial) call [`handle_stream_end`](GroundEndpoint::handle_stream_end)
//! when a connection drops, so a frame cut off by it is counted as truncated rather than
//! waiting for bytes that will never come.
//!
//! The calling convention follows quinn-proto: after [`handle_bytes`](GroundEndpoint::handle_bytes)
//! or [`handle_timeout`](GroundEndpoint::handle_timeout), drain
//! [`poll_event`](GroundEndpoint::poll_event) and [`poll_transmit`](GroundEndpoint::poll_transmit),
//! then sleep until [`poll_timeout`](GroundEndpoint::poll_timeout). No sockets, clocks or
//! sleeps in here: `now` is a monotonic [`Duration`] from any fixed origin.

use std::collections::{BTreeMap, HashMap, VecDeque};
use std::time::Duration;

use mavlink::Message;
use mavlink::dialects::common as mc;
use mavlink::dialects::common::MavMessage;
use serde::{Deserialize, Serialize};

use crate::command::{
    Command, CommandClient, CommandConfig, CommandEvent, CommandResult, CommandSendError,
    CommandServer, IncomingCommand, IncomingId, RequestId,
};
use crate::frame::{
    DecoderPolicy, DecoderStats, Frame, FrameDecoder, FrameEncoder, FrameError, FrameHeader,
};
use crate::manual::{ManualEvent, ManualReceiver, ManualSender, Sticks};
use crate::param::{
    ParamChange, ParamClient, ParamConfig, ParamEvent, ParamRefusal, ParamRequestError, ParamSpec,
    ParamTable, ParamTableError, ParamValidator, RangeOnly,
};
use crate::paths::{Deduplicator, PathStats, RadioPath, signature_failures, transmit_path};
use crate::plan::{PlanClient, PlanConfig, PlanEvent, PlanItem, PlanRequestError, PlanServer};
use crate::signing::SigningConfig;
use crate::telemetry::{
    Severity, StatusTextAssembler, Telemetry, VehicleStatus, split_status_text,
};

/// Settings shared by both ends.
#[derive(Debug, Clone)]
pub struct LinkConfig {
    /// Our MAVLink system id.
    pub system_id: u8,
    /// Our MAVLink component id.
    pub component_id: u8,
    /// Time between our heartbeats (1 s is MAVLink's norm).
    pub heartbeat_period: Duration,
    /// Peer declared lost after this long without its heartbeat.
    pub link_timeout: Duration,
    /// Window over which the message rate is averaged.
    pub rate_window: Duration,
    /// Accept MAVLink 1 frames (never while signing is on).
    pub accept_v1: bool,
    /// MAVLink 2 signing; `None` = off.
    pub signing: Option<SigningConfig>,
    /// Radios (transports) carrying this link to the same peer, numbered from 0 in order of
    /// preference (0 is taken as 1). With more than one, see [`crate::paths`].
    pub paths: usize,
}

impl LinkConfig {
    /// Defaults for the ground station: system 255, component 190 (MAV_COMP_ID_MISSIONPLANNER).
    pub fn ground() -> Self {
        Self {
            system_id: 255,
            component_id: 190,
            ..Self::vehicle()
        }
    }

    /// Defaults for the drone: system 1, component 1 (autopilot).
    pub fn vehicle() -> Self {
        Self {
            system_id: 1,
            component_id: 1,
            heartbeat_period: Duration::from_secs(1),
            link_timeout: Duration::from_millis(3500),
            rate_window: Duration::from_secs(5),
            accept_v1: true,
            signing: None,
            paths: 1,
        }
    }

    /// Sets signing.
    pub fn with_signing(mut self, signing: Option<SigningConfig>) -> Self {
        self.signing = signing;
        self
    }

    /// Sets the number of radios carrying the link.
    pub fn with_paths(mut self, paths: usize) -> Self {
        self.paths = paths.max(1);
        self
    }
}

/// Link-level events of either end.
#[derive(Debug, Clone, PartialEq)]
pub enum LinkEvent {
    /// The peer's first heartbeat, or the first after it was lost.
    Connected { system_id: u8, component_id: u8 },
    /// No heartbeat from the peer for the link timeout.
    Lost { system_id: u8, since_last: Duration },
    /// A frame was dropped (also counted in [`LinkStats`]).
    FrameError(FrameError),
    /// Our signing timestamp high-water mark moved: persist it (see
    /// [`crate::signing::Signer::take_value_to_persist`]).
    PersistSigningTimestamp(u64),
}

/// Loss accounting for one sender (system, component).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct SenderStats {
    /// Sender system id.
    pub system_id: u8,
    /// Sender component id.
    pub component_id: u8,
    /// Frames received.
    pub received: u64,
    /// Frames missing, from sequence-number gaps (less those that arrived late).
    pub lost: u64,
    /// Frames repeating the previous sequence number (a copy heard over a second radio is
    /// removed before this count).
    pub duplicates: u64,
    /// Frames that arrived after a later one (at most [`MAX_REORDER_DEPTH`] behind).
    pub reordered: u64,
    /// Times the sender's sequence jumped back further: it restarted (not counted as loss).
    pub restarts: u64,
    /// `lost / (lost + received)`, %.
    pub loss_pct: f64,
}

/// Largest forward jump of a sender's sequence number counted as loss (half the 8-bit range:
/// beyond it the frame is more likely behind than that far ahead).
pub const MAX_LOSS_GAP: u8 = 128;

/// Deepest a frame may be behind the sender's latest and count as reordered; further behind is
/// a restart of the sender's sequence.
pub const MAX_REORDER_DEPTH: u8 = 16;

impl SenderStats {
    /// Accounts a frame with `sequence` after the last one `last` (see the module
    /// documentation); returns the sequence to remember as the latest.
    fn account(&mut self, last: u8, sequence: u8) -> u8 {
        self.received += 1;
        let ahead = sequence.wrapping_sub(last);
        let behind = last.wrapping_sub(sequence);
        if ahead == 0 {
            self.duplicates += 1;
            last
        } else if ahead <= MAX_LOSS_GAP {
            self.lost += u64::from(ahead - 1);
            sequence
        } else if behind <= MAX_REORDER_DEPTH {
            self.reordered += 1;
            self.lost = self.lost.saturating_sub(1);
            last
        } else {
            self.restarts += 1;
            sequence
        }
    }
}

/// Each sender's last sequence number and loss figures.
pub(crate) type SenderTable = HashMap<(u8, u8), (u8, SenderStats)>;

/// `lost / (lost + received)`, %; 0 before anything was expected.
pub(crate) fn loss_pct(lost: u64, received: u64) -> f64 {
    match lost + received {
        0 => 0.0,
        expected => 100.0 * lost as f64 / expected as f64,
    }
}

/// Accounts the frame with header `h` to its sender in `senders`.
pub(crate) fn account_sender(senders: &mut SenderTable, h: &FrameHeader) {
    let key = (h.system_id, h.component_id);
    match senders.get_mut(&key) {
        Some((last_seq, s)) => *last_seq = s.account(*last_seq, h.sequence),
        None => {
            let first = SenderStats {
                system_id: h.system_id,
                component_id: h.component_id,
                received: 1,
                ..Default::default()
            };
            senders.insert(key, (h.sequence, first));
        }
    }
}

/// Link quality, for the dashboard and recordings.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct LinkStats {
    /// Whether the peer's heartbeats are arriving.
    pub connected: bool,
    /// Seconds since the peer's last heartbeat.
    pub last_heartbeat_age_s: Option<f64>,
    /// Messages received per second over the rate window.
    pub messages_per_s: f64,
    /// Frames received and delivered.
    pub frames_in: u64,
    /// Frames sent.
    pub frames_out: u64,
    /// Bytes received.
    pub bytes_in: u64,
    /// Bytes sent.
    pub bytes_out: u64,
    /// Checksum failures.
    pub crc_errors: u64,
    /// Frames with a good CRC that did not parse.
    pub parse_errors: u64,
    /// Frames with a message id outside the dialect.
    pub unknown_message_ids: u64,
    /// Frames refused by signing: bad signature, replay, unsigned or MAVLink 1 while signing.
    pub signature_failures: u64,
    /// Bytes not part of any delivered frame.
    pub bytes_discarded: u64,
    /// Packet loss over all senders, %.
    pub packet_loss_pct: f64,
    /// Per-sender loss.
    pub senders: Vec<SenderStats>,
    /// Seconds since the last message of each kind, by MAVLink message name.
    pub last_message_age_s: BTreeMap<String, f64>,
    /// Every decoder counter (all paths together).
    pub decoder: DecoderStats,
    /// Frames dropped as the second copy of one heard over another radio.
    pub duplicates_dropped: u64,
    /// Each radio's own figures (one entry per path).
    pub paths: Vec<PathStats>,
}

/// Most arrival times kept for the rate window.
const MAX_RATE_SAMPLES: usize = 65_536;

/// Framing, signing, heartbeats, liveness and statistics shared by both ends.
#[derive(Debug)]
struct LinkCore {
    config: LinkConfig,
    /// One per radio; at least one.
    paths: Vec<RadioPath>,
    copies: Deduplicator,
    encoder: FrameEncoder,
    out: VecDeque<Vec<u8>>,
    events: VecDeque<LinkEvent>,
    next_heartbeat: Duration,
    peer: Option<(u8, u8)>,
    last_peer_heartbeat: Option<Duration>,
    connected: bool,
    arrivals: VecDeque<Duration>,
    senders: SenderTable,
    last_by_kind: HashMap<u32, (&'static str, Duration)>,
    frames_out: u64,
    bytes_out: u64,
}

impl LinkCore {
    fn new(config: LinkConfig, now: Duration) -> Self {
        let paths = (0..config.paths.max(1))
            .map(|_| {
                let mut decoder = FrameDecoder::new(DecoderPolicy {
                    accept_v1: config.accept_v1,
                });
                if let Some(s) = &config.signing {
                    decoder.set_verifier(Some(s.build(now).1));
                }
                RadioPath::new(decoder)
            })
            .collect();
        let mut encoder = FrameEncoder::new(config.system_id, config.component_id);
        if let Some(s) = &config.signing {
            encoder.set_signer(Some(s.build(now).0));
        }
        let mut core = Self {
            config,
            paths,
            copies: Deduplicator::default(),
            encoder,
            out: VecDeque::new(),
            events: VecDeque::new(),
            next_heartbeat: now,
            peer: None,
            last_peer_heartbeat: None,
            connected: false,
            arrivals: VecDeque::new(),
            senders: HashMap::new(),
            last_by_kind: HashMap::new(),
            frames_out: 0,
            bytes_out: 0,
        };
        core.check_persist();
        core
    }

    /// Switches signing on (`Some`) or off (`None`) at `now`.
    fn set_signing(&mut self, now: Duration, signing: Option<SigningConfig>) {
        match &signing {
            Some(s) => {
                self.encoder.set_signer(Some(s.build(now).0));
                for path in &mut self.paths {
                    path.decoder.set_verifier(Some(s.build(now).1));
                }
            }
            None => {
                self.encoder.set_signer(None);
                for path in &mut self.paths {
                    path.decoder.set_verifier(None);
                }
            }
        }
        tracing::info!(on = signing.is_some(), "signing switched");
        self.config.signing = signing;
        self.check_persist();
    }

    /// The signing timestamp high-water mark in force (`None`: signing off).
    fn signing_mark(&self) -> Option<u64> {
        self.encoder.signer().map(|s| s.value_to_persist())
    }

    fn check_persist(&mut self) {
        if let Some(v) = self
            .encoder
            .signer_mut()
            .and_then(|s| s.take_value_to_persist())
        {
            self.events.push_back(LinkEvent::PersistSigningTimestamp(v));
        }
    }

    fn send(&mut self, now: Duration, msg: &MavMessage) {
        let bytes = self.encoder.encode(now, msg);
        self.frames_out += 1;
        self.bytes_out += bytes.len() as u64;
        self.out.push_back(bytes);
        self.check_persist();
    }

    /// Decodes `bytes` received on `path`, returning the frames for the endpoint to
    /// dispatch.
    fn ingest(&mut self, path: usize, now: Duration, bytes: &[u8]) -> Vec<Frame> {
        let Some(p) = self.paths.get_mut(path) else {
            tracing::warn!(
                path,
                paths = self.paths.len(),
                "bytes on a path that does not exist dropped"
            );
            return Vec::new();
        };
        p.decoder.push(bytes);
        self.drain_decoder(path, now)
    }

    /// The connection carrying `path`'s byte stream ended: what is buffered can no longer
    /// complete. Returns the frames still found behind a cut-off candidate.
    fn stream_end(&mut self, path: usize, now: Duration) -> Vec<Frame> {
        let Some(p) = self.paths.get_mut(path) else {
            return Vec::new();
        };
        p.decoder.finish();
        self.drain_decoder(path, now)
    }

    fn drain_decoder(&mut self, path: usize, now: Duration) -> Vec<Frame> {
        let mut frames = Vec::new();
        let several = self.paths.len() > 1;
        while let Some(p) = self.paths.get_mut(path)
            && let Some(r) = p.decoder.poll(now)
        {
            match r {
                Ok(frame) => {
                    if several {
                        p.heard(now, &frame.header);
                        if self.copies.is_copy(now, &frame.header) {
                            p.count_duplicate();
                            continue;
                        }
                    }
                    self.account(now, &frame.header, &frame.message);
                    frames.push(frame);
                }
                Err(e) => {
                    tracing::debug!(error = %e, "frame dropped");
                    self.events.push_back(LinkEvent::FrameError(e));
                }
            }
        }
        frames
    }

    fn account(&mut self, now: Duration, h: &FrameHeader, msg: &MavMessage) {
        if self.arrivals.len() >= MAX_RATE_SAMPLES {
            self.arrivals.pop_front();
        }
        self.arrivals.push_back(now);
        self.prune_arrivals(now);
        self.last_by_kind
            .insert(h.message_id, (msg.message_name(), now));
        account_sender(&mut self.senders, h);
    }

    fn prune_arrivals(&mut self, now: Duration) {
        while self
            .arrivals
            .front()
            .is_some_and(|&t| now.saturating_sub(t) > self.config.rate_window)
        {
            self.arrivals.pop_front();
        }
    }

    /// A heartbeat from the peer we track.
    fn peer_heartbeat(&mut self, now: Duration, from: (u8, u8)) {
        self.last_peer_heartbeat = Some(now);
        self.peer = Some(from);
        if !self.connected {
            self.connected = true;
            tracing::info!(system_id = from.0, "link connected");
            self.events.push_back(LinkEvent::Connected {
                system_id: from.0,
                component_id: from.1,
            });
        }
    }

    /// Heartbeat and liveness timers; returns whether a heartbeat is due.
    fn handle_timeout(&mut self, now: Duration) -> bool {
        if self.connected
            && let (Some(last), Some(peer)) = (self.last_peer_heartbeat, self.peer)
        {
            let since_last = now.saturating_sub(last);
            if since_last >= self.config.link_timeout {
                self.connected = false;
                tracing::warn!(system_id = peer.0, ?since_last, "link lost");
                self.events.push_back(LinkEvent::Lost {
                    system_id: peer.0,
                    since_last,
                });
            }
        }
        if now >= self.next_heartbeat {
            self.next_heartbeat = if now >= self.next_heartbeat + self.config.heartbeat_period {
                now + self.config.heartbeat_period
            } else {
                self.next_heartbeat + self.config.heartbeat_period
            };
            return true;
        }
        false
    }

    fn poll_timeout(&self) -> Duration {
        let mut t = self.next_heartbeat;
        if self.connected
            && let Some(last) = self.last_peer_heartbeat
        {
            t = t.min(last + self.config.link_timeout);
        }
        t
    }

    /// The path frames go out on now (see [`crate::paths`]).
    fn transmit_path(&self, now: Duration) -> usize {
        if self.paths.len() == 1 {
            return 0;
        }
        transmit_path(&self.paths, now, self.config.link_timeout)
    }

    fn stats(&mut self, now: Duration) -> LinkStats {
        self.prune_arrivals(now);
        let d: DecoderStats = self.paths.iter().map(|p| p.decoder.stats()).sum();
        let signing_required = self
            .paths
            .first()
            .is_some_and(|p| p.decoder.signing_required());
        let duplicates_dropped: u64 = self.paths.iter().map(RadioPath::duplicates).sum();
        let window = self.config.rate_window.as_secs_f64().max(1e-9);
        let mut senders: Vec<SenderStats> = self
            .senders
            .values()
            .map(|(_, s)| SenderStats {
                loss_pct: loss_pct(s.lost, s.received),
                ..*s
            })
            .collect();
        senders.sort_by_key(|s| (s.system_id, s.component_id));
        let (lost, received) = senders
            .iter()
            .fold((0, 0), |(l, r), s| (l + s.lost, r + s.received));
        let packet_loss_pct = loss_pct(lost, received);
        let signature_failures = signature_failures(&d, signing_required);
        let messages_per_s = self.arrivals.len() as f64 / window;
        let paths = if self.paths.len() == 1 {
            // One radio: its figures are the link's.
            vec![PathStats {
                path: 0,
                transmitting: true,
                last_heard_age_s: self
                    .last_by_kind
                    .values()
                    .map(|(_, t)| now.saturating_sub(*t).as_secs_f64())
                    .reduce(f64::min),
                messages_per_s,
                frames_in: d.frames_ok,
                duplicates: 0,
                bytes_in: d.bytes_in,
                crc_errors: d.crc_errors,
                signature_failures,
                packet_loss_pct,
            }]
        } else {
            let transmitting = self.transmit_path(now);
            let window = self.config.rate_window;
            self.paths
                .iter_mut()
                .enumerate()
                .map(|(i, p)| p.stats(i, now, window, i == transmitting))
                .collect()
        };
        LinkStats {
            connected: self.connected,
            last_heartbeat_age_s: self
                .last_peer_heartbeat
                .map(|t| now.saturating_sub(t).as_secs_f64()),
            messages_per_s,
            frames_in: d.frames_ok - duplicates_dropped,
            frames_out: self.frames_out,
            bytes_in: d.bytes_in,
            bytes_out: self.bytes_out,
            crc_errors: d.crc_errors,
            parse_errors: d.parse_errors,
            unknown_message_ids: d.unknown_message_ids,
            signature_failures,
            bytes_discarded: d.bytes_discarded,
            packet_loss_pct,
            senders,
            last_message_age_s: self
                .last_by_kind
                .values()
                .map(|(name, t)| ((*name).to_string(), now.saturating_sub(*t).as_secs_f64()))
                .collect(),
            decoder: d,
            duplicates_dropped,
            paths,
        }
    }
}

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
    /// A telemetry item from the drone.
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
    /// Any other message from anyone (for recording and other tools).
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
        let msg = &frame.message;
        if from.0 == self.vehicle.0 {
            if let MavMessage::HEARTBEAT(h) = msg
                && h.mavtype != mc::MavType::MAV_TYPE_GCS
            {
                self.core.peer_heartbeat(now, from);
            }
            let our = self.core.config.system_id;
            self.commands.handle_message(now, from.0, our, msg);
            self.params.handle_message(now, from.0, msg);
            self.plan.handle_message(now, from.0, msg);
        }
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
                if !protocol || from.0 != self.vehicle.0 {
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

    /// Holds the stick at `sticks` (streamed until released).
    pub fn manual_hold(&mut self, now: Duration, sticks: Sticks) {
        self.manual.hold(now, sticks);
    }

    /// Releases the stick.
    pub fn manual_release(&mut self) {
        self.manual.release();
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
        self.manual.handle_timeout(now);
    }

    /// Earliest time [`handle_timeout`](Self::handle_timeout) must run.
    pub fn poll_timeout(&self) -> Option<Duration> {
        [
            Some(self.core.poll_timeout()),
            self.commands.poll_timeout(),
            self.params.poll_timeout(),
            self.plan.poll_timeout(),
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
}

impl Default for VehicleConfig {
    fn default() -> Self {
        use stx_gnc::mission::{FlightMode, FlightStage, GuidancePhase};
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
                state: crate::telemetry::SystemState::Standby,
            },
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
    params: ParamTable,
    plan: PlanServer,
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
            manual: ManualReceiver::new(sys, config.manual_timeout),
            commands,
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
                    self.commands.handle_message(now, from, msg)
                        || self.params.handle_message_with(msg, validator)
                        || self.plan.handle_message(now, from, msg)
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
        self.manual.handle_timeout(now);
    }

    /// Earliest time [`handle_timeout`](Self::handle_timeout) must run.
    pub fn poll_timeout(&self) -> Option<Duration> {
        [
            Some(self.core.poll_timeout()),
            self.plan.poll_timeout(),
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
        while let Some(m) = self.params.poll_transmit() {
            self.core.send(now, &m);
        }
        while let Some((severity, text)) = self.params.poll_text() {
            self.send_status_text(now, severity, &text);
        }
        while let Some(m) = self.plan.poll_transmit() {
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
