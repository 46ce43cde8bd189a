//! The replay's clock shared between the HTTP handlers (pause, seek, speed) and the feeder
//! thread, which a change wakes. A std mutex and condition variable: the feeder is a plain
//! thread reading a file, and the handlers hold the lock only to read or set the clock.

use std::sync::{Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use super::{ReplayClock, ReplayError, ReplayMode};
use crate::messages::ReplayView;
use crate::requests::ReplayBody;

/// A replay's shared state.
pub struct ReplayControl {
    file: String,
    mode: ReplayMode,
    origin: Instant,
    clock: Mutex<ReplayClock>,
    changed: Condvar,
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
        }
    }
}
