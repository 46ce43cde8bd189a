//! Where a replay is in its recording: a position that runs at a chosen speed from an anchor
//! on the caller's clock, and stops at pause and at the recording's end. Pure: the feeder
//! gives `now` (any monotonic clock), so pause, seek and speed are tested on a fake one.
//!
//! A seek (and the start) holds the position where it was put until the feeder has rebuilt
//! what the station shows there ([`ReplayClock::release`]): a replay that plays on resumes
//! from the place sought, however long the rebuild took, and the pages are told which seek
//! what they are shown belongs to ([`ReplayClock::shown_epoch`]).

use std::time::Duration;

use thiserror::Error;

/// The slowest replay, × real time.
pub const MIN_SPEED: f64 = 0.25;
/// The fastest replay, × real time.
pub const MAX_SPEED: f64 = 64.0;

/// A refused replay request.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ReplayError {
    /// The speed is out of range.
    #[error("speed {0} is not within {MIN_SPEED}–{MAX_SPEED}× real time")]
    Speed(f64),
    /// The position is outside the recording.
    #[error("position {0} ms is outside the recording ({1}–{2} ms)")]
    Position(i64, u64, u64),
}

/// The replay's position in recording time (ns since the Unix epoch, as MCAP log times).
#[derive(Debug, Clone, PartialEq)]
pub struct ReplayClock {
    start_ns: u64,
    end_ns: u64,
    /// Position at `anchor`.
    at_anchor_ns: u64,
    anchor: Duration,
    speed: f64,
    paused: bool,
    /// Bumped by every seek, so the feeder knows to start reading again from the position.
    epoch: u64,
    /// Waiting for the feeder to rebuild the station at the position (after the start or a
    /// seek): the position does not move.
    held: bool,
    /// The seek whose rebuild the feeder finished last: what the pages are shown.
    shown_epoch: u64,
}

impl ReplayClock {
    /// A replay of `[start_ns, end_ns]` from its start at `now`, playing at `speed`.
    pub fn new(start_ns: u64, end_ns: u64, speed: f64, now: Duration) -> Result<Self, ReplayError> {
        check_speed(speed)?;
        Ok(Self {
            start_ns,
            end_ns: end_ns.max(start_ns),
            at_anchor_ns: start_ns,
            anchor: now,
            speed,
            paused: false,
            epoch: 0,
            held: true,
            shown_epoch: 0,
        })
    }

    /// The position at `now`, ns (never past the end).
    pub fn position(&self, now: Duration) -> u64 {
        if self.paused || self.held {
            return self.at_anchor_ns;
        }
        let run = now.saturating_sub(self.anchor).as_secs_f64() * self.speed * 1e9;
        self.at_anchor_ns
            .saturating_add(run as u64)
            .min(self.end_ns)
    }

    /// The position at the last change (start, seek, pause, play, speed), ns: where a reader
    /// starting again reads from, so nothing between it and the position is skipped.
    pub fn anchor_position(&self) -> u64 {
        self.at_anchor_ns
    }

    /// The recording's first and last log times, ns.
    pub fn range(&self) -> (u64, u64) {
        (self.start_ns, self.end_ns)
    }

    /// × real time.
    pub fn speed(&self) -> f64 {
        self.speed
    }

    /// Paused (by request; a replay at its end is not paused, it is finished).
    pub fn paused(&self) -> bool {
        self.paused
    }

    /// At the end of the recording.
    pub fn finished(&self, now: Duration) -> bool {
        self.position(now) >= self.end_ns
    }

    /// How many seeks so far.
    pub fn epoch(&self) -> u64 {
        self.epoch
    }

    /// The seek (epoch) whose rebuild is done: what the station shows belongs to it.
    pub fn shown_epoch(&self) -> u64 {
        self.shown_epoch
    }

    /// Waiting for the station to be rebuilt at the position (the start or a seek).
    pub fn held(&self) -> bool {
        self.held
    }

    /// The feeder has rebuilt the station at the position for seek `epoch`: the position
    /// moves on from `now` (unless paused). False, and nothing changes, if another seek came
    /// since or it was released already.
    pub fn release(&mut self, now: Duration, epoch: u64) -> bool {
        if epoch != self.epoch || !self.held {
            return false;
        }
        self.held = false;
        self.shown_epoch = epoch;
        self.anchor = now;
        true
    }

    /// The real time at which the position reaches `log_ns` (`None` while paused or held, or
    /// if it is past the end).
    pub fn due_at(&self, log_ns: u64) -> Option<Duration> {
        if self.paused || self.held || log_ns > self.end_ns {
            return None;
        }
        let ahead_ns = log_ns.saturating_sub(self.at_anchor_ns) as f64 / self.speed;
        Some(self.anchor + Duration::from_nanos(ahead_ns as u64))
    }

    fn re_anchor(&mut self, now: Duration) {
        self.at_anchor_ns = self.position(now);
        self.anchor = now;
    }

    /// Stops at the position of `now`.
    pub fn pause(&mut self, now: Duration) {
        self.re_anchor(now);
        self.paused = true;
    }

    /// Plays on from where it is.
    pub fn play(&mut self, now: Duration) {
        self.re_anchor(now);
        self.paused = false;
    }

    /// Plays at `speed` from where it is.
    pub fn set_speed(&mut self, now: Duration, speed: f64) -> Result<(), ReplayError> {
        check_speed(speed)?;
        self.re_anchor(now);
        self.speed = speed;
        Ok(())
    }

    /// Jumps to `offset_ms` after the recording's start (paused or playing as before), held
    /// there until the feeder has rebuilt the station at it ([`ReplayClock::release`]).
    pub fn seek(&mut self, now: Duration, offset_ms: i64) -> Result<(), ReplayError> {
        let span_ms = (self.end_ns - self.start_ns) / 1_000_000;
        if offset_ms < 0 || offset_ms as u64 > span_ms {
            return Err(ReplayError::Position(offset_ms, 0, span_ms));
        }
        self.at_anchor_ns = self.start_ns + offset_ms as u64 * 1_000_000;
        self.anchor = now;
        self.epoch += 1;
        self.held = true;
        Ok(())
    }
}

fn check_speed(speed: f64) -> Result<(), ReplayError> {
    if (MIN_SPEED..=MAX_SPEED).contains(&speed) {
        Ok(())
    } else {
        Err(ReplayError::Speed(speed))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const S: u64 = 1_000_000_000;

    fn at(s: f64) -> Duration {
        Duration::from_secs_f64(s)
    }

    #[test]
    fn plays_at_its_speed_pauses_and_stops_at_the_end() {
        let mut c = ReplayClock::new(100 * S, 200 * S, 2.0, at(0.0)).unwrap();
        assert_eq!(
            c.position(at(10.0)),
            100 * S,
            "held until the feeder is ready"
        );
        assert!(c.release(at(10.0), 0));
        assert_eq!(c.position(at(10.0)), 100 * S);
        assert_eq!(c.position(at(15.0)), 110 * S, "2× for 5 s");
        c.pause(at(15.0));
        assert_eq!(c.position(at(40.0)), 110 * S, "paused");
        assert_eq!(c.due_at(120 * S), None, "nothing is due while paused");
        c.play(at(40.0));
        assert_eq!(c.due_at(120 * S), Some(at(45.0)));
        assert_eq!(c.position(at(1000.0)), 200 * S, "never past the end");
        assert!(c.finished(at(1000.0)));
    }

    #[test]
    fn speed_changes_keep_the_position_and_are_bounded() {
        let mut c = ReplayClock::new(0, 3600 * S, 1.0, at(0.0)).unwrap();
        c.release(at(0.0), 0);
        c.set_speed(at(10.0), 64.0).unwrap();
        assert_eq!(c.position(at(10.0)), 10 * S);
        assert_eq!(c.position(at(11.0)), 74 * S);
        assert_eq!(c.set_speed(at(11.0), 65.0), Err(ReplayError::Speed(65.0)));
        assert_eq!(c.set_speed(at(11.0), 0.2), Err(ReplayError::Speed(0.2)));
        assert!(c.set_speed(at(11.0), MIN_SPEED).is_ok());
        assert!(ReplayClock::new(0, 1, f64::NAN, at(0.0)).is_err());
    }

    #[test]
    fn a_seek_moves_the_position_and_counts_and_a_bad_one_is_refused() {
        let mut c = ReplayClock::new(50 * S, 150 * S, 1.0, at(0.0)).unwrap();
        c.release(at(0.0), 0);
        c.pause(at(3.0));
        c.seek(at(4.0), 60_000).unwrap();
        assert_eq!(
            c.position(at(9.0)),
            110 * S,
            "still paused, at the new place"
        );
        assert_eq!(c.epoch(), 1);
        assert!(matches!(
            c.seek(at(4.0), 100_001),
            Err(ReplayError::Position(..))
        ));
        assert!(matches!(
            c.seek(at(4.0), -1),
            Err(ReplayError::Position(..))
        ));
        assert_eq!(c.epoch(), 1, "a refused seek changes nothing");
    }

    #[test]
    fn a_seek_holds_the_position_until_the_rebuild_for_it_is_done() {
        let mut c = ReplayClock::new(0, 100 * S, 2.0, at(0.0)).unwrap();
        c.release(at(0.0), 0);
        c.seek(at(5.0), 40_000).unwrap();
        c.seek(at(6.0), 30_000).unwrap();
        assert!(c.held());
        assert_eq!(
            c.position(at(9.0)),
            30 * S,
            "held while the station is rebuilt"
        );
        assert_eq!(c.due_at(31 * S), None);
        assert!(
            !c.release(at(9.0), 1),
            "the rebuild for an older seek does not release it"
        );
        assert_eq!((c.held(), c.shown_epoch()), (true, 0));
        assert!(c.release(at(10.0), 2));
        assert_eq!((c.held(), c.shown_epoch()), (false, 2));
        assert!(!c.release(at(10.5), 2), "once");
        assert_eq!(
            c.position(at(11.0)),
            32 * S,
            "plays on from the place sought"
        );
    }
}
