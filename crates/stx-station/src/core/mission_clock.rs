//! The mission clock the pages show: the drone's own clock (s since its boot), read from the
//! time stamps of its telemetry and carried forward between them at the rate it has been
//! running against the station's clock — 1 for a real flight, 20 for a rehearsal at
//! `--sim-speed 20`. Plots, the T+ clock, countdowns and the log then run on the mission's time
//! at any speed (they ran on the station's wall clock while countdowns ran on mission seconds,
//! 20 times apart at 20×), and keep running through a silent link as the flight does.
//!
//! It never runs backwards: carried forward at a rate measured over bursty frames it may get
//! ahead of the next reading, and a clock that then stepped back would put a plot's newest point
//! after the time the page shows (a replay paused after a seek did just that). It waits there
//! for the drone's clock to catch up instead.

/// Shortest stretch of the station's clock over which the rate is measured, s.
const RATE_WINDOW_S: f64 = 2.0;
/// The rate is kept within these bounds (a real drone runs at 1).
const RATE_LIMITS: [f64; 2] = [0.01, 10_000.0];

/// The drone's clock against the station's.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct MissionClock {
    /// The newest reading: station clock, drone clock, s.
    last: Option<(f64, f64)>,
    /// Where the rate's current window began: station clock, drone clock, s.
    anchor: Option<(f64, f64)>,
    /// Drone seconds per station second, once measured.
    rate: Option<f64>,
    /// What the clock had reached when the newest reading came, if that was ahead of it, s.
    floor: Option<f64>,
}

impl MissionClock {
    /// The drone's clock read `drone_s` at the station's `now_s`.
    pub(crate) fn observe(&mut self, now_s: f64, drone_s: f64) {
        if self.last.is_some_and(|(_, d)| drone_s < d) {
            // Older than what was read (a late frame) or a reboot: the caller restarts the
            // clock on a reboot; a late frame says nothing new.
            return;
        }
        self.floor = self.at(now_s).filter(|&shown| shown > drone_s);
        self.last = Some((now_s, drone_s));
        match self.anchor {
            None => self.anchor = Some((now_s, drone_s)),
            Some((s0, d0)) if now_s - s0 >= RATE_WINDOW_S => {
                let rate = (drone_s - d0) / (now_s - s0);
                if rate.is_finite() {
                    self.rate = Some(rate.clamp(RATE_LIMITS[0], RATE_LIMITS[1]));
                }
                self.anchor = Some((now_s, drone_s));
            }
            Some(_) => {}
        }
    }

    /// Drone seconds per station second (1 until measured).
    pub(crate) fn rate(&self) -> f64 {
        self.rate.unwrap_or(1.0)
    }

    /// Forgets everything (the drone restarted: its clock began again).
    pub(crate) fn restart(&mut self) {
        *self = Self::default();
    }

    /// The mission's time at the station's `now_s`: the newest reading carried forward at the
    /// measured rate (1 until one is measured), never less than it has already shown; `None`
    /// before the drone is heard.
    pub(crate) fn at(&self, now_s: f64) -> Option<f64> {
        let (s, d) = self.last?;
        let carried = d + (now_s - s).max(0.0) * self.rate.unwrap_or(1.0);
        Some(self.floor.map_or(carried, |f| carried.max(f)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_clock_runs_at_the_rehearsals_speed_through_a_silent_link() {
        let mut c = MissionClock::default();
        assert_eq!(c.at(0.0), None);
        // A rehearsal at 20×: 5 drone seconds per quarter of a station second.
        for k in 0..=20 {
            let now = f64::from(k) * 0.25;
            c.observe(now, 100.0 + 20.0 * now);
        }
        // Then silence for 3 s of the station's clock: the flight went on 60 s.
        let t = c.at(8.0).expect("heard");
        assert!((t - (100.0 + 20.0 * 8.0)).abs() < 1e-9, "{t}");
    }

    #[test]
    fn a_real_flight_runs_at_one_and_a_late_frame_changes_nothing() {
        let mut c = MissionClock::default();
        for k in 0..=12 {
            let now = f64::from(k) * 0.25;
            c.observe(now, 500.0 + now);
        }
        c.observe(3.1, 400.0);
        let t = c.at(4.0).expect("heard");
        assert!((t - 504.0).abs() < 1e-9, "{t}");
        c.restart();
        assert_eq!(c.at(4.0), None);
    }

    #[test]
    fn a_reading_behind_the_carried_clock_holds_it_instead_of_stepping_back() {
        let mut c = MissionClock::default();
        // Frames in bursts: the rate measured over the first window is 10, the drone then
        // runs at 5.
        c.observe(0.0, 0.0);
        c.observe(2.0, 20.0);
        let ahead = c.at(3.0).expect("heard");
        assert!((ahead - 30.0).abs() < 1e-9, "{ahead}");
        // The next reading says 25 at 3 s: the clock stays where it was shown …
        c.observe(3.0, 25.0);
        let mut shown = ahead;
        for k in 0..=40 {
            let now = 3.0 + f64::from(k) * 0.05;
            let t = c.at(now).expect("heard");
            assert!(t >= shown, "stepped back from {shown} to {t} at {now} s");
            shown = t;
        }
        // … until the reading carried forward passes it (25 + 10 × 0.6 = 31 at 3.6 s).
        assert!((c.at(3.6).expect("heard") - 31.0).abs() < 1e-9);
        // A reboot forgets the floor with the rest.
        c.restart();
        c.observe(4.0, 1.0);
        assert_eq!(c.at(4.0), Some(1.0));
    }
}
