//! [`LinkStats`]: the quality of the link as both ends report it, for the dashboard and
//! recordings (serde-serialisable); built by the link core from its decoders, its radios
//! ([`PathStats`]) and its senders ([`SenderStats`]).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::senders::SenderStats;
use crate::frame::DecoderStats;
use crate::paths::PathStats;

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
