//! The replay's clock shared between the HTTP handlers (pause, seek, speed) and the feeder
//! thread, which a change wakes. A std mutex and condition variable: the feeder is a plain
//! thread reading a file, and the handlers hold the lock only to read or set the clock.
//! Also, for a replay "as recorded", what the recording has shown up to the position
//! ([`RecordedTimeline`]), which the feeder keeps and the pages read.

use std::sync::{Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use serde_json::Value;

use super::{RecordedTimeline, ReplayClock, ReplayError, ReplayMode};
use crate::messages::ReplayView;
use crate::requests::ReplayBody;

/// A replay's shared state.
pub struct ReplayControl {
    file: String,
    mode: ReplayMode,
    origin: Instant,
    clock: Mutex<ReplayClock>,
    changed: Condvar,
    recorded: Mutex<RecordedTimeline>,
}

impl ReplayControl {
    /// The replay of `file` (as shown to operators) over `[start_ns, end_ns]` at `speed`.
    pub fn new(
        file: String,
        mode: ReplayMode,
        start_ns: u64,
        end_ns: u64,
        speed: f64,
    ) -> Result<Self, ReplayError> {
        Ok(Self {
            file,
            mode,
            origin: Instant::now(),
            clock: Mutex::new(ReplayClock::new(start_ns, end_ns, speed, Duration::ZERO)?),
            changed: Condvar::new(),
            recorded: Mutex::new(RecordedTimeline::default()),
        })
    }

    /// Now on the control's clock.
    pub fn now(&self) -> Duration {
        self.origin.elapsed()
    }

    /// The mode.
    pub fn mode(&self) -> ReplayMode {
        self.mode
    }

    /// The clock, for a moment.
    pub fn clock(&self) -> MutexGuard<'_, ReplayClock> {
        self.clock.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The replay's mission time: seconds from the recording's start to the position. A
    /// replay station's core runs on it, so a pause stops its clock and a seek moves it.
    pub fn mission_s(&self) -> f64 {
        let now = self.now();
        let c = self.clock();
        (c.position(now) - c.range().0) as f64 / 1e9
    }

    /// The station is being rebuilt at a new position: what it holds is neither the old
    /// place's nor the new one's, and is not shown.
    pub fn seeking(&self) -> bool {
        self.clock().held()
    }

    /// The seek what the station shows belongs to.
    pub fn shown_epoch(&self) -> u64 {
        self.clock().shown_epoch()
    }

    /// The feeder has rebuilt the station for seek `epoch`: the replay moves on from there.
    pub fn release(&self, epoch: u64) -> bool {
        let now = self.now();
        let released = self.clock().release(now, epoch);
        self.changed.notify_all();
        released
    }

    /// Waits at most `timeout` for a change of the clock (the feeder's sleep).
    pub fn wait(&self, timeout: Duration) {
        let guard = self.clock();
        let _ = self.changed.wait_timeout(guard, timeout);
    }

    /// Applies an operator's request: pause or play, then speed, then position.
    pub fn apply(&self, body: &ReplayBody) -> Result<ReplayView, ReplayError> {
        let now = self.now();
        {
            let mut c = self.clock();
            // Check everything before changing anything.
            let mut trial = c.clone();
            if let Some(speed) = body.speed {
                trial.set_speed(now, speed)?;
            }
            if let Some(ms) = body.position_ms {
                trial.seek(now, ms)?;
            }
            match body.paused {
                Some(true) => trial.pause(now),
                Some(false) => trial.play(now),
                None => {}
            }
            *c = trial;
        }
        self.changed.notify_all();
        Ok(self.view())
    }

    /// What the pages show.
    pub fn view(&self) -> ReplayView {
        let now = self.now();
        let c = self.clock();
        let (start, end) = c.range();
        ReplayView {
            file: self.file.clone(),
            mode: self.mode,
            start_ms: start / 1_000_000,
            duration_ms: (end - start) / 1_000_000,
            position_ms: (c.position(now) - start) / 1_000_000,
            speed: c.speed(),
            paused: c.paused(),
            finished: c.finished(now),
            epoch: c.shown_epoch(),
            seeking: c.held(),
        }
    }

    /// What a replay "as recorded" has shown up to its position (kept by the feeder).
    pub fn recorded(&self) -> MutexGuard<'_, RecordedTimeline> {
        self.recorded.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The newest recorded `state` at the position, as the pages get it: with this replay's
    /// view and without the live station's recording figures; `None` before the first.
    pub fn recorded_state(&self) -> Option<Value> {
        let mut state = self.recorded().latest()?.clone();
        if let Some(map) = state.as_object_mut() {
            map.insert("recording".into(), Value::Null);
            map.insert(
                "replay".into(),
                serde_json::to_value(self.view()).unwrap_or_default(),
            );
        }
        Some(state)
    }

    /// The `history` message of a replay "as recorded" at its position.
    pub fn recorded_history(&self) -> Value {
        // The epoch read under the timeline's lock, under which the feeder swaps the
        // timeline and releases the clock: the two agree.
        let timeline = self.recorded();
        timeline.history(self.shown_epoch())
    }
}
