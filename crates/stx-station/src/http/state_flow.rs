//! When a page may be sent its next `state`: flow control by the page's `state_ack`s.
//!
//! Why: the `watch` channel gives a page the newest state whenever its socket takes one, but a
//! socket takes far more than the page has read: the kernel's buffers on both ends and the
//! browser's own queue hold megabytes, so a busy page (three dashboards on a loaded laptop, a
//! phone) was shown states 10–20 s old while the station had moved on. A page that acknowledges
//! each state it handled is sent one only while fewer than [`IN_FLIGHT`] are unacknowledged; the
//! rest wait in the `watch` channel, where a newer one replaces them. A page says so as it
//! connects, or its flow would start with a backlog (every state sent before its first
//! acknowledgement came back). Pages that never acknowledge (relays, tools) are sent every state
//! as before.

use std::time::{Duration, Instant};

/// States a page that acknowledges may have unacknowledged: one it is handling and one on its
/// way, so it never waits a round trip for the next, and never has more queued.
pub const IN_FLIGHT: u32 = 2;
/// A page that stops acknowledging is still sent a state this long after the last one: a lost
/// or forgotten acknowledgement must not freeze it. Well below the 2 s without a state after
/// which the page shows everything STALE (`STATE_GAP_STALE_S` in `web/src/lib/staleness.ts`):
/// held for as long as that, the held state went out at the next 4 Hz tick after 2 s, and a
/// busy page paused on a replay flickered STALE while the station was fine (a local CI run,
/// 2026-12-02).
pub const HOLD_MAX: Duration = Duration::from_secs(1);

/// One page's flow of states.
#[derive(Debug, Default)]
pub struct StateFlow {
    /// The page has acknowledged at least one state: flow control is on.
    acking: bool,
    /// States sent and not acknowledged.
    unacked: u32,
    /// When the last state was sent.
    last_sent: Option<Instant>,
}

impl StateFlow {
    /// The flow of a page that said, as it connected, that it acknowledges every state
    /// (`?state_acks=true`): held from its first state on. Any other page's flow turns on
    /// with its first acknowledgement.
    pub fn acknowledged() -> Self {
        Self {
            acking: true,
            ..Self::default()
        }
    }

    /// Whether a state may be sent to the page at `now`.
    pub fn may_send(&self, now: Instant) -> bool {
        !self.acking
            || self.unacked < IN_FLIGHT
            || self.last_sent.is_none_or(|t| now >= t + HOLD_MAX)
    }

    /// When a held state may go anyway (`None`: nothing is held back).
    pub fn held_until(&self, now: Instant) -> Option<Instant> {
        if self.may_send(now) {
            None
        } else {
            self.last_sent.map(|t| t + HOLD_MAX)
        }
    }

    /// A state was sent at `now`.
    pub fn sent(&mut self, now: Instant) {
        self.unacked = self.unacked.saturating_add(1);
        self.last_sent = Some(now);
    }

    /// The page acknowledged a state. One more than were sent is dropped: a page cannot open its
    /// window wider by acknowledging in advance.
    pub fn acked(&mut self) {
        self.acking = true;
        self.unacked = self.unacked.saturating_sub(1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_page_that_never_acknowledges_is_sent_every_state() {
        let t = Instant::now();
        let mut f = StateFlow::default();
        for i in 0..100 {
            assert!(f.may_send(t), "state {i}");
            f.sent(t);
        }
        assert_eq!(f.held_until(t), None);
    }

    #[test]
    fn an_acknowledging_page_has_at_most_two_states_unacknowledged() {
        let t = Instant::now();
        let mut f = StateFlow::default();
        // The greeting's state and a few more went out before its first acknowledgement came.
        for _ in 0..4 {
            f.sent(t);
        }
        f.acked();
        assert!(!f.may_send(t), "3 unacknowledged");
        assert_eq!(f.held_until(t), Some(t + HOLD_MAX));
        f.acked();
        assert!(!f.may_send(t), "2 unacknowledged");
        f.acked();
        assert!(f.may_send(t), "1 unacknowledged");
        f.sent(t);
        assert!(!f.may_send(t));
        f.acked();
        f.acked();
        assert!(f.may_send(t));
    }

    #[test]
    fn a_page_that_said_it_acknowledges_is_held_from_its_first_states() {
        let t = Instant::now();
        let mut f = StateFlow::acknowledged();
        f.sent(t);
        assert!(f.may_send(t));
        f.sent(t);
        assert!(!f.may_send(t), "two states out before any acknowledgement");
        f.acked();
        assert!(f.may_send(t));
    }

    #[test]
    fn acknowledging_in_advance_does_not_open_the_window() {
        let t = Instant::now();
        let mut f = StateFlow::default();
        for _ in 0..10 {
            f.acked();
        }
        f.sent(t);
        assert!(f.may_send(t));
        f.sent(t);
        assert!(!f.may_send(t), "two sent, none acknowledged since");
    }

    #[test]
    fn a_page_that_stops_acknowledging_gets_a_state_every_hold_max() {
        let t = Instant::now();
        let mut f = StateFlow::default();
        f.sent(t);
        f.acked();
        f.sent(t);
        f.sent(t);
        assert!(!f.may_send(t + HOLD_MAX - Duration::from_millis(1)));
        assert!(f.may_send(t + HOLD_MAX));
        f.sent(t + HOLD_MAX);
        assert!(!f.may_send(t + HOLD_MAX + Duration::from_millis(1)));
        assert_eq!(f.held_until(t + HOLD_MAX), Some(t + HOLD_MAX * 2));
    }

    #[test]
    fn a_held_page_hears_from_the_station_before_it_would_call_the_station_silent() {
        // The page's threshold, read from its source so the two cannot drift apart.
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../web/src/lib/staleness.ts"
        );
        let source = std::fs::read_to_string(path).expect("the page's staleness rules");
        let gap_s: f64 = source
            .lines()
            .find_map(|l| l.strip_prefix("export const STATE_GAP_STALE_S = "))
            .and_then(|v| v.trim_end_matches(';').trim().parse().ok())
            .expect("STATE_GAP_STALE_S = <seconds>;");
        // A held state goes at the first 4 Hz tick after HOLD_MAX; half a second more for a
        // loaded machine's delivery and the page's own handling.
        let worst_gap_s = HOLD_MAX.as_secs_f64() + 0.25 + 0.5;
        assert!(
            worst_gap_s < gap_s,
            "held {worst_gap_s} s, the page calls {gap_s} s silent"
        );
    }
}
