//! Packet loss per sender (system, component), from the sequence numbers of its frames.
//!
//! A frame up to [`MAX_LOSS_GAP`] ahead of the sender's last one counts the numbers skipped as
//! lost; one at most [`MAX_REORDER_DEPTH`] behind is a late (reordered) frame — it un-counts
//! one loss, since it did arrive — and one further behind means the sender restarted its
//! sequence (a reboot, a second instance): counted as a restart, not as the ~255 frames a
//! naive modulo-256 difference would say were lost.
//!
//! The merged link ([`super::LinkStats::senders`]) and each radio
//! ([`crate::paths::PathStats::packet_loss_pct`]) keep a [`SenderTable`] of their own.

use std::collections::HashMap;

use serde::{Deserialize, Serialize};

use crate::frame::FrameHeader;

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
