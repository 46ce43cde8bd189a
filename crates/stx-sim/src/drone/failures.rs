//! Failure injection for rehearsals: what can go wrong with the link, the GPS and a servo,
//! from the scenario file's `[failures]` table and the command line.
//!
//! - Link drops (`link_drop_s` windows of mission time): the drone neither sends nor hears
//!   anything — [`crate::drone::Drone`] asks [`LinkFaults::drops_datagram`] for every
//!   datagram in (each `handle_bytes` call) and every frame out.
//! - Packet loss (`packet_loss_pct`): each datagram, in or out, is dropped with this
//!   probability, drawn from a generator seeded by the mission's seed, so a rehearsal is
//!   repeatable given the same traffic.
//! - GPS loss (`gps_loss_s` windows): the GPS receiver emits nothing (its windows are added to
//!   the sensor layer's dropout windows).
//! - A stuck servo (`stuck_servo`): from `at_s` on, one servo (main line, right or left brake)
//!   stays where it was, whatever it is commanded.
//!
//! All windows are in mission time (the simulation's clock, s from the drone's start), so a
//! rehearsal at any `--speed` fails at the same point of the flight.

use std::str::FromStr;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;
use stx_dynamics::state::Controls;

use crate::drone::config_error::MissionError;

/// One of the three servos.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Servo {
    /// Differential main line.
    Main,
    /// Right brake.
    Right,
    /// Left brake.
    Left,
}

/// A servo that sticks at its position from a time on.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StuckServo {
    /// Which servo.
    pub servo: Servo,
    /// From when, s of mission time.
    pub at_s: f64,
}

/// A command-line failure flag that does not parse.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FailureFlagError {
    /// A window is not `FROM..TO` with 0 ≤ FROM < TO.
    #[error("{text:?} is not a window FROM..TO in seconds of mission time with 0 ≤ FROM < TO")]
    Window { text: String },
    /// A stuck servo is not `main|right|left@T`.
    #[error("{text:?} is not SERVO@T with SERVO main, right or left and T ≥ 0 seconds")]
    StuckServo { text: String },
}

/// Parses a window `FROM..TO` (seconds of mission time), e.g. `100..160`.
pub fn parse_window(text: &str) -> Result<[f64; 2], FailureFlagError> {
    let err = || FailureFlagError::Window {
        text: text.to_string(),
    };
    let (from, to) = text.split_once("..").ok_or_else(err)?;
    let from: f64 = from.trim().parse().map_err(|_| err())?;
    let to: f64 = to.trim().parse().map_err(|_| err())?;
    if from >= 0.0 && to > from && to.is_finite() {
        Ok([from, to])
    } else {
        Err(err())
    }
}

impl FromStr for StuckServo {
    type Err = FailureFlagError;

    fn from_str(text: &str) -> Result<Self, FailureFlagError> {
        let err = || FailureFlagError::StuckServo {
            text: text.to_string(),
        };
        let (servo, at) = text.split_once('@').ok_or_else(err)?;
        let servo = match servo.trim() {
            "main" => Servo::Main,
            "right" => Servo::Right,
            "left" => Servo::Left,
            _ => return Err(err()),
        };
        let at_s: f64 = at.trim().parse().map_err(|_| err())?;
        if at_s >= 0.0 && at_s.is_finite() {
            Ok(Self { servo, at_s })
        } else {
            Err(err())
        }
    }
}

/// The `[failures]` table.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FailureConfig {
    /// Windows `[from, to]` of mission time, s, during which the link is down both ways.
    pub link_drop_s: Vec<[f64; 2]>,
    /// Share of datagrams lost at random each way, % (0…100).
    pub packet_loss_pct: f64,
    /// Windows `[from, to]` of mission time, s, during which the GPS emits nothing.
    pub gps_loss_s: Vec<[f64; 2]>,
    /// A servo that sticks.
    pub stuck_servo: Option<StuckServo>,
}

impl FailureConfig {
    /// Checks the windows, the loss percentage and the stuck servo's time.
    pub fn validate(&self) -> Result<(), MissionError> {
        let bad = |field: &str, value: String, rule| MissionError::Invalid {
            field: field.to_string(),
            value,
            rule,
        };
        for (field, windows) in [
            ("failures.link_drop_s", &self.link_drop_s),
            ("failures.gps_loss_s", &self.gps_loss_s),
        ] {
            for (i, &[from, to]) in windows.iter().enumerate() {
                if !(from >= 0.0 && to > from && to.is_finite()) {
                    return Err(bad(
                        &format!("{field}[{i}]"),
                        format!("[{from}, {to}]"),
                        "a window [from, to] with 0 ≤ from < to, seconds of mission time",
                    ));
                }
            }
        }
        if !(0.0..=100.0).contains(&self.packet_loss_pct) {
            return Err(bad(
                "failures.packet_loss_pct",
                self.packet_loss_pct.to_string(),
                "must be within 0…100 %",
            ));
        }
        if let Some(s) = self.stuck_servo
            && !(s.at_s >= 0.0 && s.at_s.is_finite())
        {
            return Err(bad(
                "failures.stuck_servo.at_s",
                s.at_s.to_string(),
                "must be a finite number ≥ 0",
            ));
        }
        Ok(())
    }

    /// Whether `time_s` lies in a link-drop window.
    pub fn link_down_at(&self, time_s: f64) -> bool {
        in_windows(&self.link_drop_s, time_s)
    }

    /// Whether `time_s` lies in a GPS-loss window.
    pub fn gps_lost_at(&self, time_s: f64) -> bool {
        in_windows(&self.gps_loss_s, time_s)
    }
}

fn in_windows(windows: &[[f64; 2]], time_s: f64) -> bool {
    windows
        .iter()
        .any(|&[from, to]| (from..=to).contains(&time_s))
}

/// Stream of the packet-loss generator (the sensors use 1–13).
const PACKET_LOSS_STREAM: u64 = 31;

/// The link's failures as the adapter applies them to datagrams.
#[derive(Debug, Clone)]
pub struct LinkFaults {
    windows: Vec<[f64; 2]>,
    loss_probability: f64,
    rng: ChaCha8Rng,
    /// Datagrams dropped because the link was down.
    pub dropped_down: u64,
    /// Datagrams dropped at random.
    pub dropped_random: u64,
}

impl LinkFaults {
    /// The link failures of `config`, random loss seeded by `seed`.
    pub fn new(config: &FailureConfig, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(PACKET_LOSS_STREAM);
        Self {
            windows: config.link_drop_s.clone(),
            loss_probability: config.packet_loss_pct / 100.0,
            rng,
            dropped_down: 0,
            dropped_random: 0,
        }
    }

    /// Whether the link is down at `time_s` of mission time.
    pub fn down_at(&self, time_s: f64) -> bool {
        in_windows(&self.windows, time_s)
    }

    /// Whether the datagram in or out at `time_s` of mission time is lost (counted).
    pub fn drops_datagram(&mut self, time_s: f64) -> bool {
        if self.down_at(time_s) {
            self.dropped_down += 1;
            return true;
        }
        if self.loss_probability > 0.0 && self.rng.random::<f64>() < self.loss_probability {
            self.dropped_random += 1;
            return true;
        }
        false
    }
}

/// A stuck servo at run time: remembers where the servo was when it stuck.
#[derive(Debug, Clone)]
pub struct ServoFault {
    stuck: Option<StuckServo>,
    held: Option<f64>,
}

impl ServoFault {
    /// The fault of `config` (none if absent).
    pub fn new(stuck: Option<StuckServo>) -> Self {
        Self { stuck, held: None }
    }

    /// Whether the servo is stuck at `time_s`.
    pub fn active_at(&self, time_s: f64) -> bool {
        self.stuck.is_some_and(|s| time_s >= s.at_s)
    }

    /// The servo that sticks, if any.
    pub fn servo(&self) -> Option<Servo> {
        self.stuck.map(|s| s.servo)
    }

    /// The commands the servos get at `time_s`: `commanded`, except that a stuck servo is
    /// commanded to stay where it was (`position`, the servos' actual positions) when it stuck.
    /// Returns whether the fault took effect at this call (for the operator's log).
    pub fn apply(
        &mut self,
        time_s: f64,
        commanded: Controls,
        position: Controls,
    ) -> (Controls, bool) {
        let Some(stuck) = self.stuck.filter(|s| time_s >= s.at_s) else {
            return (commanded, false);
        };
        let pick = |c: &Controls| match stuck.servo {
            Servo::Main => c.main_line_m,
            Servo::Right => c.brake_right,
            Servo::Left => c.brake_left,
        };
        let started = self.held.is_none();
        let held = *self.held.get_or_insert(pick(&position));
        let mut out = commanded;
        match stuck.servo {
            Servo::Main => out.main_line_m = held,
            Servo::Right => out.brake_right = held,
            Servo::Left => out.brake_left = held,
        }
        (out, started)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_parse_and_refuse_nonsense() {
        assert_eq!(parse_window("10..20.5"), Ok([10.0, 20.5]));
        assert!(parse_window("20..10").is_err());
        assert!(parse_window("-1..10").is_err());
        assert!(parse_window("10:20").is_err());
        assert!(parse_window("10").is_err());
        assert_eq!(
            "right@12".parse::<StuckServo>(),
            Ok(StuckServo {
                servo: Servo::Right,
                at_s: 12.0
            })
        );
        assert!("up@12".parse::<StuckServo>().is_err());
        assert!("main@-3".parse::<StuckServo>().is_err());
        assert!("main".parse::<StuckServo>().is_err());
    }

    #[test]
    fn packet_loss_is_seeded_and_near_its_rate() {
        let config = FailureConfig {
            packet_loss_pct: 20.0,
            link_drop_s: vec![[100.0, 200.0]],
            ..Default::default()
        };
        let mut a = LinkFaults::new(&config, 7);
        let mut b = LinkFaults::new(&config, 7);
        let drops_a: Vec<bool> = (0..10_000).map(|_| a.drops_datagram(1.0)).collect();
        let drops_b: Vec<bool> = (0..10_000).map(|_| b.drops_datagram(1.0)).collect();
        assert_eq!(drops_a, drops_b);
        let rate = a.dropped_random as f64 / 10_000.0;
        assert!((rate - 0.2).abs() < 0.02, "{rate}");
        assert!(a.drops_datagram(150.0));
        assert_eq!(a.dropped_down, 1);
    }

    #[test]
    fn a_stuck_servo_holds_where_it_was() {
        let mut fault = ServoFault::new(Some(StuckServo {
            servo: Servo::Left,
            at_s: 5.0,
        }));
        let cmd = Controls {
            main_line_m: 0.01,
            brake_right: 0.2,
            brake_left: 0.9,
        };
        let pos = Controls {
            brake_left: 0.3,
            ..cmd
        };
        assert_eq!(fault.apply(4.0, cmd, pos), (cmd, false));
        let (out, started) = fault.apply(5.0, cmd, pos);
        assert!(started);
        assert_eq!(out.brake_left, 0.3);
        assert_eq!(out.brake_right, 0.2);
        let (out, started) = fault.apply(6.0, cmd, Controls::default());
        assert!(!started);
        assert_eq!(out.brake_left, 0.3);
    }
}
