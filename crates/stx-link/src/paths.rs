//! Several radios carrying one link (a primary and a backup telemetry radio to the same drone).
//!
//! Each radio is a *path* with its own frame decoder (a byte stream cannot be spliced with
//! another) and its own signing verifier (each radio's stream is checked for replays on its
//! own; a frame replayed from one radio into the other is refused there as soon as that radio
//! has carried anything newer, and within [`DUPLICATE_WINDOW`] it is a copy anyway).
//!
//! - Receiving: a frame heard on two radios is delivered once. A copy is recognised by sender,
//!   sequence number, message id and checksum, within [`DUPLICATE_WINDOW`] and while fewer
//!   than 256 frames from that sender have been delivered since: the sequence number comes
//!   round again after 256 frames, so at any rate a later frame with the same number is new.
//! - Sending: every frame goes out on one radio, the *transmit path*: the lowest-numbered
//!   path heard within the link timeout (the primary while it works), else the one heard last.
//!   Retries of the command, parameter and plan protocols are new sends, so a transfer that
//!   began on a radio that fell silent carries on over the other one.
//! - Statistics: per path ([`PathStats`]), next to the merged link's ([`crate::endpoint::LinkStats`]).

use std::collections::{HashMap, VecDeque};
use std::time::Duration;

use serde::{Deserialize, Serialize};

use crate::endpoint::senders::{SenderTable, account_sender, loss_pct};
use crate::frame::{DecoderStats, FrameDecoder, FrameHeader};

/// How long a frame is remembered to recognise its copy arriving over another radio.
pub const DUPLICATE_WINDOW: Duration = Duration::from_secs(2);

/// Most frames remembered for duplicate detection (bounds memory at any rate).
const MAX_REMEMBERED: usize = 8192;

/// Most arrival times kept for a path's rate.
const MAX_PATH_ARRIVALS: usize = 16_384;

/// Link quality of one radio.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PathStats {
    /// Path number (0 = primary).
    pub path: usize,
    /// Whether frames to the peer go out on this path now.
    pub transmitting: bool,
    /// Seconds since this path last delivered a frame (a copy counts: the radio works).
    pub last_heard_age_s: Option<f64>,
    /// Frames per second heard on this path over the rate window (copies included).
    pub messages_per_s: f64,
    /// Frames decoded on this path (copies included).
    pub frames_in: u64,
    /// Frames on this path that the other path had already delivered.
    pub duplicates: u64,
    /// Bytes received on this path.
    pub bytes_in: u64,
    /// Checksum failures on this path.
    pub crc_errors: u64,
    /// Frames refused by signing on this path.
    pub signature_failures: u64,
    /// Packet loss on this path alone, from its sequence-number gaps, %.
    pub packet_loss_pct: f64,
}

/// One radio's receive side.
#[derive(Debug)]
pub(crate) struct RadioPath {
    pub(crate) decoder: FrameDecoder,
    arrivals: VecDeque<Duration>,
    last_heard: Option<Duration>,
    senders: SenderTable,
    duplicates: u64,
}

impl RadioPath {
    pub(crate) fn new(decoder: FrameDecoder) -> Self {
        Self {
            decoder,
            arrivals: VecDeque::new(),
            last_heard: None,
            senders: HashMap::new(),
            duplicates: 0,
        }
    }

    /// A frame decoded on this path at `now` (before duplicate removal).
    pub(crate) fn heard(&mut self, now: Duration, header: &FrameHeader) {
        self.last_heard = Some(now);
        if self.arrivals.len() >= MAX_PATH_ARRIVALS {
            self.arrivals.pop_front();
        }
        self.arrivals.push_back(now);
        account_sender(&mut self.senders, header);
    }

    pub(crate) fn count_duplicate(&mut self) {
        self.duplicates += 1;
    }

    pub(crate) fn duplicates(&self) -> u64 {
        self.duplicates
    }

    fn heard_within(&self, now: Duration, timeout: Duration) -> bool {
        self.last_heard
            .is_some_and(|t| now.saturating_sub(t) < timeout)
    }

    pub(crate) fn stats(
        &mut self,
        path: usize,
        now: Duration,
        rate_window: Duration,
        transmitting: bool,
    ) -> PathStats {
        while self
            .arrivals
            .front()
            .is_some_and(|&t| now.saturating_sub(t) > rate_window)
        {
            self.arrivals.pop_front();
        }
        let d = self.decoder.stats();
        let (lost, received) = self
            .senders
            .values()
            .fold((0, 0), |(l, r), (_, s)| (l + s.lost, r + s.received));
        PathStats {
            path,
            transmitting,
            last_heard_age_s: self.last_heard.map(|t| now.saturating_sub(t).as_secs_f64()),
            messages_per_s: self.arrivals.len() as f64 / rate_window.as_secs_f64().max(1e-9),
            frames_in: d.frames_ok,
            duplicates: self.duplicates,
            bytes_in: d.bytes_in,
            crc_errors: d.crc_errors,
            signature_failures: signature_failures(d, self.decoder.signing_required()),
            packet_loss_pct: loss_pct(lost, received),
        }
    }
}

/// Frames refused by signing, from a decoder's counters.
pub(crate) fn signature_failures(d: &DecoderStats, signing_required: bool) -> u64 {
    d.bad_signatures
        + d.replays_refused
        + d.unsigned_refused
        + if signing_required { d.v1_refused } else { 0 }
}

/// What identifies a frame across radios.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct FrameKey {
    system_id: u8,
    component_id: u8,
    sequence: u8,
    message_id: u32,
    checksum: u16,
}

/// Frames from one sender after which its sequence number comes round again.
const SEQUENCE_PERIOD: u64 = 256;

/// Remembers recent frames to drop the second copy of each.
#[derive(Debug, Default)]
pub(crate) struct Deduplicator {
    /// When each remembered frame was delivered, and how many frames its sender had delivered
    /// before it.
    seen: HashMap<FrameKey, (Duration, u64)>,
    order: VecDeque<(Duration, FrameKey)>,
    delivered: HashMap<(u8, u8), u64>,
}

impl Deduplicator {
    /// Whether the frame with `header`, heard at `now`, was already delivered within
    /// [`DUPLICATE_WINDOW`]; if not it is remembered.
    pub(crate) fn is_copy(&mut self, now: Duration, header: &FrameHeader) -> bool {
        self.expire(now);
        let key = FrameKey {
            system_id: header.system_id,
            component_id: header.component_id,
            sequence: header.sequence,
            message_id: header.message_id,
            checksum: header.checksum,
        };
        let delivered = self
            .delivered
            .entry((header.system_id, header.component_id))
            .or_default();
        if let Some(&(_, index)) = self.seen.get(&key)
            && *delivered - index < SEQUENCE_PERIOD
        {
            return true;
        }
        let index = *delivered;
        *delivered += 1;
        if self.order.len() >= MAX_REMEMBERED
            && let Some((t, old)) = self.order.pop_front()
            && self.seen.get(&old).is_some_and(|&(at, _)| at == t)
        {
            self.seen.remove(&old);
        }
        self.seen.insert(key, (now, index));
        self.order.push_back((now, key));
        false
    }

    fn expire(&mut self, now: Duration) {
        while let Some(&(t, key)) = self.order.front() {
            if now.saturating_sub(t) <= DUPLICATE_WINDOW {
                break;
            }
            self.order.pop_front();
            if self.seen.get(&key).is_some_and(|&(at, _)| at == t) {
                self.seen.remove(&key);
            }
        }
    }
}

/// The path frames go out on: the lowest-numbered one heard within `timeout`, else the one
/// heard last, else the primary.
pub(crate) fn transmit_path(paths: &[RadioPath], now: Duration, timeout: Duration) -> usize {
    if let Some(i) = paths.iter().position(|p| p.heard_within(now, timeout)) {
        return i;
    }
    paths
        .iter()
        .enumerate()
        .filter_map(|(i, p)| p.last_heard.map(|t| (t, i)))
        .max()
        .map_or(0, |(_, i)| i)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::{DecoderPolicy, WireVersion};

    fn header(sequence: u8, checksum: u16) -> FrameHeader {
        FrameHeader {
            version: WireVersion::V2,
            system_id: 1,
            component_id: 1,
            sequence,
            message_id: 30,
            payload_len: 28,
            signature: None,
            checksum,
        }
    }

    fn path() -> RadioPath {
        RadioPath::new(FrameDecoder::new(DecoderPolicy::default()))
    }

    const S: fn(f64) -> Duration = Duration::from_secs_f64;

    #[test]
    fn a_second_copy_within_the_window_is_recognised_and_a_new_frame_is_not() {
        let mut d = Deduplicator::default();
        assert!(!d.is_copy(S(0.0), &header(7, 0xBEEF)));
        assert!(
            d.is_copy(S(0.4), &header(7, 0xBEEF)),
            "same frame, other radio"
        );
        assert!(
            !d.is_copy(S(0.5), &header(7, 0xCAFE)),
            "same sequence, other content: a new frame"
        );
        assert!(!d.is_copy(S(0.5), &header(8, 0xBEEF)), "next sequence");
        // After the window the sequence has wrapped: the same key is a new frame.
        assert!(!d.is_copy(S(0.0) + DUPLICATE_WINDOW + S(0.1), &header(7, 0xBEEF)));
    }

    #[test]
    fn at_a_high_rate_the_same_frame_a_sequence_round_later_is_new() {
        let mut d = Deduplicator::default();
        // 256 frames in 0.1 s: the sequence comes round well inside the time window, and a
        // heartbeat repeats byte for byte.
        for i in 0..=256_u32 {
            let sequence = (i % 256) as u8;
            let h = if i == 0 || i == 256 {
                header(sequence, 0xAAAA)
            } else {
                FrameHeader {
                    message_id: 1,
                    ..header(sequence, i as u16)
                }
            };
            let now = S(f64::from(i) * 0.1 / 256.0);
            assert!(!d.is_copy(now, &h), "frame {i} is new");
            if i == 254 {
                // 255 frames on, the sequence has not come round: still the first one's copy.
                assert!(
                    d.is_copy(now, &header(0, 0xAAAA)),
                    "the first frame's copy, late"
                );
            }
        }
    }

    #[test]
    fn memory_stays_bounded_at_any_rate() {
        let mut d = Deduplicator::default();
        for i in 0..(3 * MAX_REMEMBERED as u32) {
            let h = FrameHeader {
                message_id: i,
                ..header(0, 0)
            };
            assert!(!d.is_copy(S(0.0), &h));
        }
        assert!(d.order.len() <= MAX_REMEMBERED && d.seen.len() <= MAX_REMEMBERED);
    }

    #[test]
    fn frames_go_out_on_the_primary_while_it_is_heard_and_on_the_backup_when_it_is_silent() {
        let timeout = S(3.0);
        let mut paths = vec![path(), path()];
        assert_eq!(
            transmit_path(&paths, S(0.0), timeout),
            0,
            "nothing heard yet"
        );
        paths[1].heard(S(1.0), &header(0, 0));
        assert_eq!(
            transmit_path(&paths, S(1.0), timeout),
            1,
            "only the backup heard"
        );
        paths[0].heard(S(2.0), &header(1, 0));
        assert_eq!(transmit_path(&paths, S(2.5), timeout), 0, "primary back");
        paths[1].heard(S(4.0), &header(2, 0));
        assert_eq!(
            transmit_path(&paths, S(5.5), timeout),
            1,
            "primary silent for 3.5 s, backup heard 1.5 s ago"
        );
        assert_eq!(
            transmit_path(&paths, S(60.0), timeout),
            1,
            "both silent: the one heard last"
        );
    }

    #[test]
    fn a_path_counts_its_own_loss() {
        let mut p = path();
        for seq in [0_u8, 1, 2, 5, 6] {
            p.heard(S(0.0), &header(seq, 0));
        }
        let s = p.stats(0, S(0.0), S(5.0), true);
        // 2 missing of 7.
        assert!(
            (s.packet_loss_pct - 100.0 * 2.0 / 7.0).abs() < 1e-9,
            "{s:?}"
        );
        assert_eq!(s.last_heard_age_s, Some(0.0));
    }
}
