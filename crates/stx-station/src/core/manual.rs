//! The operator's sticks: each `manual` message from a page holds the sticks on the link
//! (MANUAL_CONTROL streamed by the endpoint), a release or [`MANUAL_SILENCE_S`] without a
//! message stops them, so a page that dies does not leave the drone flying on its last input.

use stx_link::manual::Sticks;

use super::StationCore;
use super::actions::{APPLY_WITHIN_S, LinkOp, Purpose};

/// Sticks silent this long stop the uplink of MANUAL_CONTROL, s. A stick position is not
/// sent later than this after it arrived either: by then it is stale.
pub const MANUAL_SILENCE_S: f64 = 0.5;

fn clamp(v: f64) -> f64 {
    if v.is_finite() {
        v.clamp(-1.0, 1.0)
    } else {
        0.0
    }
}

impl StationCore {
    /// An operator's sticks (each axis clamped to −1…1, anything not a number read as 0).
    pub fn manual_hold(&mut self, now_s: f64, sticks: Sticks) {
        let sticks = Sticks {
            x: clamp(sticks.x),
            y: clamp(sticks.y),
            z: clamp(sticks.z),
            r: clamp(sticks.r),
            buttons: sticks.buttons,
        };
        self.manual_last_s = Some(now_s);
        self.outbox.issue(
            now_s,
            LinkOp::ManualHold(sticks),
            Purpose::Manual,
            MANUAL_SILENCE_S,
        );
    }

    /// The operator let go of the dead-man (or the page lost focus): stop now.
    pub fn manual_release(&mut self, now_s: f64) {
        self.manual_last_s = None;
        self.outbox.issue(
            now_s,
            LinkOp::ManualRelease,
            Purpose::Manual,
            APPLY_WITHIN_S,
        );
    }

    /// Stops sticks that went silent.
    pub(crate) fn manual_timeout(&mut self, now_s: f64) {
        if self
            .manual_last_s
            .is_some_and(|t| now_s - t > MANUAL_SILENCE_S)
        {
            self.manual_release(now_s);
        }
    }
}
