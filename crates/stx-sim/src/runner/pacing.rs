//! When each step of the simulation is due, in wall time: sans-io, on the caller's clock (a
//! [`Duration`] since the flight started), so the rule is tested without waiting.
//!
//! At `N` times real time step `k` (counted from the last re-anchoring) is due `k·period/N`
//! after the anchor. A step sent more than [`CATCH_UP_LIMIT`] after it was due re-anchors the
//! schedule at that instant: a slow stretch (a busy machine, a debugger) is not made up for by
//! a burst of steps afterwards. After the landing the schedule runs at real time from the
//! landing on, whatever the flight's speed.

use std::time::Duration;

use super::options::Speed;

/// Lateness beyond which the schedule restarts from now instead of catching up.
pub const CATCH_UP_LIMIT: Duration = Duration::from_secs(1);

/// The step schedule of one flight.
#[derive(Debug, Clone)]
pub struct Pacer {
    speed: Speed,
    period_s: f64,
    /// The anchor: an instant and the steps sent before it.
    anchor: (Duration, u64),
    sent: u64,
    landed: bool,
}

impl Pacer {
    /// Steps of `period_s` of mission time at `speed`, starting at `now`.
    pub fn new(speed: Speed, period_s: f64, now: Duration) -> Self {
        Self {
            speed,
            period_s,
            anchor: (now, 0),
            sent: 0,
            landed: false,
        }
    }

    /// The speed in force: the flight's, real time once landed.
    pub fn speed(&self) -> Speed {
        if self.landed {
            Speed::Times(1.0)
        } else {
            self.speed
        }
    }

    /// When the next step is due; `None`: at once (maximum speed).
    pub fn due(&self) -> Option<Duration> {
        match self.speed() {
            Speed::Max => None,
            Speed::Times(times) => {
                let steps = (self.sent - self.anchor.1 + 1) as f64;
                Some(self.anchor.0 + Duration::from_secs_f64(steps * self.period_s / times))
            }
        }
    }

    /// A step was sent at `now`.
    pub fn stepped(&mut self, now: Duration) {
        let due = self.due();
        self.sent += 1;
        if due.is_some_and(|due| now > due + CATCH_UP_LIMIT) {
            self.anchor = (now, self.sent);
        }
    }

    /// The drone landed at `now`: real time from here on.
    pub fn landed(&mut self, now: Duration) {
        self.landed = true;
        self.anchor = (now, self.sent);
    }

    /// Steps sent so far.
    pub fn sent(&self) -> u64 {
        self.sent
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PERIOD_S: f64 = 0.25;

    fn ms(v: u64) -> Duration {
        Duration::from_millis(v)
    }

    /// `due` is `expected` to the microsecond (the schedule is computed in floating point).
    fn at(due: Option<Duration>, expected: Duration) -> bool {
        due.is_some_and(|d| d.abs_diff(expected) < Duration::from_micros(1))
    }

    #[test]
    fn steps_come_every_period_over_the_speed() {
        let mut p = Pacer::new(Speed::Times(10.0), PERIOD_S, ms(1000));
        for k in 1..=5 {
            let due = p.due().expect("paced");
            assert!(at(Some(due), ms(1000 + 25 * k)), "{due:?}");
            p.stepped(due);
        }
        assert_eq!(p.sent(), 5);
        // Real time: a step every 250 ms.
        let mut p = Pacer::new(Speed::Times(1.0), PERIOD_S, Duration::ZERO);
        p.stepped(ms(250));
        assert!(at(p.due(), ms(500)), "{:?}", p.due());
    }

    #[test]
    fn a_step_late_by_more_than_a_second_reanchors_instead_of_catching_up() {
        let mut p = Pacer::new(Speed::Times(1.0), PERIOD_S, Duration::ZERO);
        // Slightly late: the schedule keeps its anchor and the next step comes early.
        p.stepped(ms(900));
        assert!(at(p.due(), ms(500)), "{:?}", p.due());
        // Sent 3 s after it was due: the next is a period after that, not at once.
        p.stepped(ms(3500));
        assert!(at(p.due(), ms(3750)), "{:?}", p.due());
    }

    #[test]
    fn at_max_speed_every_step_is_due_at_once_until_the_landing() {
        let mut p = Pacer::new(Speed::Max, PERIOD_S, Duration::ZERO);
        for k in 0..100 {
            assert_eq!(p.due(), None);
            p.stepped(ms(k));
        }
        p.landed(ms(100));
        assert_eq!(p.speed(), Speed::Times(1.0));
        assert!(at(p.due(), ms(350)), "{:?}", p.due());
        p.stepped(ms(350));
        assert!(at(p.due(), ms(600)), "{:?}", p.due());
    }
}
