//! Manual control: the operator's joystick streamed as MANUAL_CONTROL, and its safe reception
//! on the drone.
//!
//! [`ManualSender`] (ground) sends the held stick at a steady rate (10 Hz by default) and stops
//! as soon as it is released: silence is how the drone learns the operator let go.
//! [`ManualReceiver`] (vehicle) turns each message into [`Sticks`] and declares them stale
//! after a timeout (0.5 s by default) without a message. It never hands out a value older than
//! the timeout, even if [`ManualReceiver::handle_timeout`] is called late:
//! [`ManualReceiver::sticks`] checks the age itself. The [`ManualEvent::Stale`] event lets the
//! application fall back to an autonomous mode.
//!
//! Wire: x, y, z, r normalised −1…1 ↔ −1000…1000; buttons 0–15 in `buttons`, 16–31 in the
//! `buttons2` extension. An axis at `INT16_MAX` (MAVLink's "invalid") reads as 0.

use std::time::Duration;

use mavlink::dialects::common as mc;
use mavlink::dialects::common::MavMessage;
use serde::{Deserialize, Serialize};

/// Stick and button state.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Sticks {
    /// Pitch axis (forward +), −1…1.
    pub x: f64,
    /// Roll axis (right +), −1…1; for the parafoil the main-line differential.
    pub y: f64,
    /// Thrust axis, −1…1 (the parafoil uses it for symmetric brakes).
    pub z: f64,
    /// Yaw axis (right +), −1…1.
    pub r: f64,
    /// Buttons 0–31, bit set = pressed.
    pub buttons: u32,
}

fn axis_to_wire(v: f64) -> i16 {
    if v.is_nan() {
        0
    } else {
        (v.clamp(-1.0, 1.0) * 1000.0).round() as i16
    }
}
fn axis_from_wire(v: i16) -> f64 {
    if v == i16::MAX {
        0.0
    } else {
        (f64::from(v) / 1000.0).clamp(-1.0, 1.0)
    }
}

impl Sticks {
    /// The MANUAL_CONTROL for `target_system`.
    pub fn to_mavlink(&self, target_system: u8) -> MavMessage {
        MavMessage::MANUAL_CONTROL(mc::MANUAL_CONTROL_DATA {
            x: axis_to_wire(self.x),
            y: axis_to_wire(self.y),
            z: axis_to_wire(self.z),
            r: axis_to_wire(self.r),
            buttons: (self.buttons & 0xFFFF) as u16,
            target: target_system,
            buttons2: (self.buttons >> 16) as u16,
            ..Default::default()
        })
    }

    /// The sticks a MANUAL_CONTROL carries.
    pub fn from_mavlink(m: &mc::MANUAL_CONTROL_DATA) -> Sticks {
        Sticks {
            x: axis_from_wire(m.x),
            y: axis_from_wire(m.y),
            z: axis_from_wire(m.z),
            r: axis_from_wire(m.r),
            buttons: u32::from(m.buttons) | u32::from(m.buttons2) << 16,
        }
    }
}

/// Ground side: streams the held stick.
#[derive(Debug)]
pub struct ManualSender {
    /// Time between messages while held (100 ms = 10 Hz).
    pub period: Duration,
    held: Option<Sticks>,
    next_send: Duration,
    due: bool,
}

impl ManualSender {
    /// A sender streaming every `period` while held.
    pub fn new(period: Duration) -> Self {
        Self {
            period,
            held: None,
            next_send: Duration::ZERO,
            due: false,
        }
    }

    /// Updates the held stick; the first value of a hold is sent at once.
    pub fn hold(&mut self, now: Duration, sticks: Sticks) {
        if self.held.is_none() {
            self.due = true;
            self.next_send = now;
        }
        self.held = Some(sticks);
    }

    /// Releases the stick: nothing more is sent.
    pub fn release(&mut self) {
        self.held = None;
        self.due = false;
    }

    /// Whether a stick is held.
    pub fn is_held(&self) -> bool {
        self.held.is_some()
    }

    /// Marks a message due when its time came.
    pub fn handle_timeout(&mut self, now: Duration) {
        if self.held.is_some() && now >= self.next_send {
            self.due = true;
        }
    }

    /// When the next message is due.
    pub fn poll_timeout(&self) -> Option<Duration> {
        self.held.map(|_| self.next_send)
    }

    /// The MANUAL_CONTROL to send now, if one is due.
    pub fn poll_transmit(&mut self, now: Duration, target_system: u8) -> Option<MavMessage> {
        let sticks = self.held?;
        if !self.due && now < self.next_send {
            return None;
        }
        self.due = false;
        // Keep a steady cadence; after a long gap restart it from now.
        self.next_send = if now >= self.next_send + self.period {
            now + self.period
        } else {
            self.next_send + self.period
        };
        Some(sticks.to_mavlink(target_system))
    }
}

/// What the vehicle side reports.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ManualEvent {
    /// Fresh stick values.
    Sticks(Sticks),
    /// No stick message for the timeout: stop using manual input.
    Stale { since_last: Duration },
}

/// Vehicle side: fresh sticks or nothing.
#[derive(Debug)]
pub struct ManualReceiver {
    /// Our system id (messages for other targets are ignored; 0 = any).
    pub system_id: u8,
    /// Age after which sticks are stale.
    pub timeout: Duration,
    last: Option<(Sticks, Duration)>,
    stale_reported: bool,
    events: std::collections::VecDeque<ManualEvent>,
}

impl ManualReceiver {
    /// A receiver declaring sticks stale after `timeout`.
    pub fn new(system_id: u8, timeout: Duration) -> Self {
        Self {
            system_id,
            timeout,
            last: None,
            stale_reported: true,
            events: Default::default(),
        }
    }

    /// Feeds a received message. Returns whether it was a MANUAL_CONTROL for us.
    pub fn handle_message(&mut self, now: Duration, msg: &MavMessage) -> bool {
        let MavMessage::MANUAL_CONTROL(m) = msg else {
            return false;
        };
        if m.target != 0 && m.target != self.system_id {
            return false;
        }
        let sticks = Sticks::from_mavlink(m);
        self.last = Some((sticks, now));
        self.stale_reported = false;
        self.events.push_back(ManualEvent::Sticks(sticks));
        true
    }

    /// The current sticks, `None` when stale or never received.
    pub fn sticks(&self, now: Duration) -> Option<Sticks> {
        let (s, at) = self.last?;
        (now.saturating_sub(at) < self.timeout).then_some(s)
    }

    /// Reports staleness when the timeout passed.
    pub fn handle_timeout(&mut self, now: Duration) {
        if let Some((_, at)) = self.last {
            let age = now.saturating_sub(at);
            if age >= self.timeout && !self.stale_reported {
                self.stale_reported = true;
                tracing::warn!(age_ms = age.as_millis() as u64, "manual control stale");
                self.events
                    .push_back(ManualEvent::Stale { since_last: age });
            }
        }
    }

    /// When the sticks turn stale.
    pub fn poll_timeout(&self) -> Option<Duration> {
        match self.last {
            Some((_, at)) if !self.stale_reported => Some(at + self.timeout),
            _ => None,
        }
    }

    /// Next event.
    pub fn poll_event(&mut self) -> Option<ManualEvent> {
        self.events.pop_front()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sticks_round_trip_with_buttons2() {
        let s = Sticks {
            x: -1.0,
            y: 0.25,
            z: 0.999,
            r: 1.0,
            buttons: 0x8001_0003,
        };
        let MavMessage::MANUAL_CONTROL(m) = s.to_mavlink(1) else {
            panic!()
        };
        assert_eq!(Sticks::from_mavlink(&m), s);
    }

    #[test]
    fn sender_streams_at_rate_and_stops_on_release() {
        let mut tx = ManualSender::new(Duration::from_millis(100));
        let mut sent = Vec::new();
        tx.hold(Duration::ZERO, Sticks::default());
        for ms in (0..=1000).step_by(10) {
            let now = Duration::from_millis(ms);
            if ms == 500 {
                tx.release();
            }
            tx.handle_timeout(now);
            if tx.poll_transmit(now, 1).is_some() {
                sent.push(ms);
            }
        }
        assert_eq!(sent, vec![0, 100, 200, 300, 400]);
    }

    #[test]
    fn receiver_never_holds_a_value_past_the_timeout() {
        let mut rx = ManualReceiver::new(1, Duration::from_millis(500));
        let s = Sticks {
            y: 0.7,
            ..Default::default()
        };
        rx.handle_message(Duration::ZERO, &s.to_mavlink(1));
        assert_eq!(rx.sticks(Duration::from_millis(499)), Some(s));
        // Even without handle_timeout being called:
        assert_eq!(rx.sticks(Duration::from_millis(500)), None);
        assert_eq!(rx.poll_timeout(), Some(Duration::from_millis(500)));
        rx.handle_timeout(Duration::from_millis(500));
        assert_eq!(rx.poll_event(), Some(ManualEvent::Sticks(s)));
        assert_eq!(
            rx.poll_event(),
            Some(ManualEvent::Stale {
                since_last: Duration::from_millis(500)
            })
        );
        rx.handle_timeout(Duration::from_millis(900));
        assert_eq!(rx.poll_event(), None);
    }
}
