//! The link core both ends share: framing and signing over one or several radios, our
//! heartbeat timer, the peer's liveness and the statistics ([`LinkStats`]). The ground and
//! vehicle endpoints each own one and add their protocols on top.

use std::collections::{BTreeMap, HashMap, VecDeque};
use std::time::Duration;

use mavlink::Message;
use mavlink::dialects::common::MavMessage;

use super::senders::{SenderStats, SenderTable, account_sender, loss_pct};
use super::stats::LinkStats;
use crate::frame::{
    DecoderPolicy, DecoderStats, Frame, FrameDecoder, FrameEncoder, FrameError, FrameHeader,
    FrameIds, encode_frame_into,
};
use crate::paths::{Deduplicator, PathStats, RadioPath, signature_failures, transmit_path};
use crate::signing::SigningConfig;

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

/// Most arrival times kept for the rate window.
const MAX_RATE_SAMPLES: usize = 65_536;

/// Framing, signing, heartbeats, liveness and statistics shared by both ends.
#[derive(Debug)]
pub(super) struct LinkCore {
    pub(super) config: LinkConfig,
    /// One per radio; at least one.
    paths: Vec<RadioPath>,
    copies: Deduplicator,
    encoder: FrameEncoder,
    /// Sequence of each other component of our system that speaks through this link (a
    /// body's IMU): MAVLink counts sequences per component, and a receiver counts gaps so.
    other_sequences: HashMap<u8, u8>,
    pub(super) out: VecDeque<Vec<u8>>,
    pub(super) events: VecDeque<LinkEvent>,
    next_heartbeat: Duration,
    peer: Option<(u8, u8)>,
    last_peer_heartbeat: Option<Duration>,
    pub(super) connected: bool,
    arrivals: VecDeque<Duration>,
    senders: SenderTable,
    /// Last arrival of each message kind from each component: a body IMU's ATTITUDE must not
    /// keep the autopilot's fresh in the ages the operators watch.
    last_by_kind: HashMap<(u8, u32), (&'static str, Duration)>,
    frames_out: u64,
    bytes_out: u64,
    /// The wire bytes of each frame accepted (checked, signature verified, not a copy from
    /// another radio), kept only while someone forwards them (`None`: nobody does).
    accepted: Option<VecDeque<Vec<u8>>>,
}

/// Accepted frames kept for forwarding between two polls; beyond, the oldest go.
const MAX_ACCEPTED_KEPT: usize = 4096;

impl LinkCore {
    pub(super) fn new(config: LinkConfig, now: Duration) -> Self {
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
            other_sequences: HashMap::new(),
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
            accepted: None,
        };
        core.check_persist();
        core
    }

    /// Starts (or stops) keeping the wire bytes of accepted frames for [`Self::poll_accepted`].
    pub(super) fn keep_accepted(&mut self, on: bool) {
        self.accepted = on.then(VecDeque::new);
    }

    /// The wire bytes of the next accepted frame kept.
    pub(super) fn poll_accepted(&mut self) -> Option<Vec<u8>> {
        self.accepted.as_mut()?.pop_front()
    }

    /// Queues a frame to send as it is (not encoded by us: a watcher's, passed on).
    pub(super) fn send_raw(&mut self, frame: Vec<u8>) {
        self.frames_out += 1;
        self.bytes_out += frame.len() as u64;
        self.out.push_back(frame);
    }

    /// Switches signing on (`Some`) or off (`None`) at `now`.
    pub(super) fn set_signing(&mut self, now: Duration, signing: Option<SigningConfig>) {
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
    pub(super) fn signing_mark(&self) -> Option<u64> {
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

    pub(super) fn send(&mut self, now: Duration, msg: &MavMessage) {
        let bytes = self.encoder.encode(now, msg);
        self.frames_out += 1;
        self.bytes_out += bytes.len() as u64;
        self.out.push_back(bytes);
        self.check_persist();
    }

    /// Sends `msg` as component `component_id` of our system (signed as our own frames are).
    pub(super) fn send_from(&mut self, now: Duration, component_id: u8, msg: &MavMessage) {
        if component_id == self.config.component_id {
            return self.send(now, msg);
        }
        let sequence = self.other_sequences.entry(component_id).or_insert(0);
        let ids = FrameIds {
            system_id: self.config.system_id,
            component_id,
            sequence: *sequence,
        };
        *sequence = sequence.wrapping_add(1);
        let mut bytes = Vec::with_capacity(64);
        encode_frame_into(now, msg, ids, self.encoder.signer_mut(), &mut bytes);
        self.frames_out += 1;
        self.bytes_out += bytes.len() as u64;
        self.out.push_back(bytes);
        self.check_persist();
    }

    /// Decodes `bytes` received on `path`, returning the frames for the endpoint to
    /// dispatch.
    pub(super) fn ingest(&mut self, path: usize, now: Duration, bytes: &[u8]) -> Vec<Frame> {
        if !self.push(path, bytes) {
            return Vec::new();
        }
        self.drain_decoder(path, now, |_| false).0
    }

    /// Decodes one whole datagram received on `path`. MAVLink over UDP never splits a frame
    /// across datagrams, so a candidate left incomplete at the datagram's end is dropped as
    /// truncated rather than completed by the next datagram, which may come from another
    /// sender: every frame returned lies wholly in this datagram. Also returns whether any
    /// frame passed `from_peer` (copies already delivered over another radio included: they
    /// show this radio reaches the peer as well as a first copy does).
    pub(super) fn ingest_datagram(
        &mut self,
        path: usize,
        now: Duration,
        datagram: &[u8],
        from_peer: impl Fn(&Frame) -> bool,
    ) -> (Vec<Frame>, bool) {
        if !self.push(path, datagram) {
            return (Vec::new(), false);
        }
        if let Some(p) = self.paths.get_mut(path) {
            p.decoder.finish();
        }
        self.drain_decoder(path, now, from_peer)
    }

    /// Appends `bytes` to `path`'s decoder; `false` (and a warning) if there is no such path.
    fn push(&mut self, path: usize, bytes: &[u8]) -> bool {
        let Some(p) = self.paths.get_mut(path) else {
            tracing::warn!(
                path,
                paths = self.paths.len(),
                "bytes on a path that does not exist dropped"
            );
            return false;
        };
        p.decoder.push(bytes);
        true
    }

    /// The connection carrying `path`'s byte stream ended: what is buffered can no longer
    /// complete. Returns the frames still found behind a cut-off candidate.
    pub(super) fn stream_end(&mut self, path: usize, now: Duration) -> Vec<Frame> {
        let Some(p) = self.paths.get_mut(path) else {
            return Vec::new();
        };
        p.decoder.finish();
        self.drain_decoder(path, now, |_| false).0
    }

    /// The frames `path`'s decoder has ready, and whether any of them passed `from_peer`.
    fn drain_decoder(
        &mut self,
        path: usize,
        now: Duration,
        from_peer: impl Fn(&Frame) -> bool,
    ) -> (Vec<Frame>, bool) {
        let mut frames = Vec::new();
        let mut peer_heard = false;
        let several = self.paths.len() > 1;
        while let Some(p) = self.paths.get_mut(path)
            && let Some(r) = p.decoder.poll(now)
        {
            match r {
                Ok(frame) => {
                    peer_heard |= from_peer(&frame);
                    if several {
                        p.heard(now, &frame.header);
                        if self.copies.is_copy(now, &frame.header) {
                            p.count_duplicate();
                            continue;
                        }
                    }
                    let raw = self
                        .accepted
                        .is_some()
                        .then(|| p.decoder.last_frame_bytes().to_vec());
                    self.account(now, &frame.header, &frame.message);
                    if let (Some(kept), Some(raw)) = (&mut self.accepted, raw) {
                        if kept.len() >= MAX_ACCEPTED_KEPT {
                            kept.pop_front();
                        }
                        kept.push_back(raw);
                    }
                    frames.push(frame);
                }
                Err(e) => {
                    tracing::debug!(error = %e, "frame dropped");
                    self.events.push_back(LinkEvent::FrameError(e));
                }
            }
        }
        (frames, peer_heard)
    }

    fn account(&mut self, now: Duration, h: &FrameHeader, msg: &MavMessage) {
        if self.arrivals.len() >= MAX_RATE_SAMPLES {
            self.arrivals.pop_front();
        }
        self.arrivals.push_back(now);
        self.prune_arrivals(now);
        self.last_by_kind
            .insert((h.component_id, h.message_id), (msg.message_name(), now));
        account_sender(&mut self.senders, h);
    }

    /// Seconds since the last message of each kind by name: the heartbeat peer's components
    /// under the plain name, any other component's as `NAME@COMPONENT` (a body's own IMU).
    /// Before a peer is heard every component goes under the plain name, freshest kept.
    fn ages_by_name(&self, now: Duration) -> BTreeMap<String, f64> {
        let main = self.peer.map(|p| p.1);
        let mut ages = BTreeMap::new();
        for ((component, _), (name, t)) in &self.last_by_kind {
            let key = if main.is_none_or(|m| m == *component) {
                (*name).to_string()
            } else {
                format!("{name}@{component}")
            };
            let age = now.saturating_sub(*t).as_secs_f64();
            ages.entry(key)
                .and_modify(|a: &mut f64| *a = a.min(age))
                .or_insert(age);
        }
        ages
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

    /// The (system, component) of the peer whose heartbeats we track, once one was heard.
    pub(super) fn peer(&self) -> Option<(u8, u8)> {
        self.peer
    }

    /// A heartbeat from the peer we track.
    pub(super) fn peer_heartbeat(&mut self, now: Duration, from: (u8, u8)) {
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
    pub(super) fn handle_timeout(&mut self, now: Duration) -> bool {
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

    pub(super) fn poll_timeout(&self) -> Duration {
        let mut t = self.next_heartbeat;
        if self.connected
            && let Some(last) = self.last_peer_heartbeat
        {
            t = t.min(last + self.config.link_timeout);
        }
        t
    }

    /// The path frames go out on now (see [`crate::paths`]).
    pub(super) fn transmit_path(&self, now: Duration) -> usize {
        if self.paths.len() == 1 {
            return 0;
        }
        transmit_path(&self.paths, now, self.config.link_timeout)
    }

    pub(super) fn stats(&mut self, now: Duration) -> LinkStats {
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
            last_message_age_s: self.ages_by_name(now),
            decoder: d,
            duplicates_dropped,
            paths,
        }
    }
}
