//! When to try the disk again after it failed the recording: exponential back-off, sans-io.
//!
//! A full disk rarely frees itself within seconds, and every try costs a file created and
//! removed; yet space the operator frees should be used soon. So the first try comes after
//! [`Backoff::first`], each try that fails doubles the wait, up to [`Backoff::max`]; the
//! stretch of failures (an [`Outage`]) ends when a message reaches the disk again, and the
//! next failure starts over from the first wait. The writer thread ([`crate::file`]) keeps
//! one of these and passes its own clock's `now`.

use std::time::Duration;

/// A stretch of time in which the recording could not be written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Outage {
    /// When the first failure happened (the caller's clock).
    pub since: Duration,
    /// Tries that failed, the first failure included.
    pub failed_tries: u32,
    /// When the next try is due (the caller's clock).
    pub next_try: Duration,
}

/// Exponential back-off between tries: see the module documentation.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Backoff {
    first: Duration,
    max: Duration,
    outage: Option<Outage>,
}

impl Backoff {
    /// Waits `first` after the first failure, doubling after each failed try up to `max`
    /// (`max` below `first` is taken as `first`).
    pub fn new(first: Duration, max: Duration) -> Self {
        Self {
            first,
            max: max.max(first),
            outage: None,
        }
    }

    /// The wait after the first failure.
    pub fn first(&self) -> Duration {
        self.first
    }

    /// The longest wait.
    pub fn max(&self) -> Duration {
        self.max
    }

    /// The wait after the `failed_tries`-th failure in a row (from 1).
    pub fn wait_after(&self, failed_tries: u32) -> Duration {
        let doublings = failed_tries.saturating_sub(1).min(31);
        self.first.saturating_mul(1 << doublings).min(self.max)
    }

    /// A try failed at `now` (the first failure starts an outage); returns the outage, with
    /// when to try next.
    pub fn failed(&mut self, now: Duration) -> Outage {
        let outage = match self.outage {
            None => Outage {
                since: now,
                failed_tries: 1,
                next_try: now + self.first,
            },
            Some(o) => {
                let failed_tries = o.failed_tries.saturating_add(1);
                Outage {
                    failed_tries,
                    next_try: now + self.wait_after(failed_tries),
                    ..o
                }
            }
        };
        self.outage = Some(outage);
        outage
    }

    /// Writing works again: ends the outage, which is returned (`None` if there was none).
    pub fn succeeded(&mut self) -> Option<Outage> {
        self.outage.take()
    }

    /// The outage under way, if any.
    pub fn outage(&self) -> Option<Outage> {
        self.outage
    }

    /// `true` when an outage is under way and its next try is due at `now`.
    pub fn due(&self, now: Duration) -> bool {
        self.outage.is_some_and(|o| now >= o.next_try)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const S: Duration = Duration::from_secs(1);

    #[test]
    fn the_wait_doubles_from_the_first_to_the_cap_and_a_success_starts_over() {
        let mut b = Backoff::new(5 * S, 120 * S);
        let mut now = 100 * S;
        let mut waits = Vec::new();
        for _ in 0..8 {
            let o = b.failed(now);
            assert_eq!(o.since, 100 * S, "the outage began at the first failure");
            waits.push((o.next_try - now).as_secs());
            assert!(!b.due(o.next_try - Duration::from_millis(1)));
            assert!(b.due(o.next_try));
            now = o.next_try;
        }
        assert_eq!(waits, [5, 10, 20, 40, 80, 120, 120, 120]);
        assert_eq!(b.outage().map(|o| o.failed_tries), Some(8));
        let ended = b.succeeded().expect("an outage ended");
        assert_eq!(ended.failed_tries, 8);
        assert_eq!(b.outage(), None);
        assert!(!b.due(now + 1000 * S), "nothing to try without an outage");
        // The next failure waits the first wait again, and starts a new outage.
        let o = b.failed(now);
        assert_eq!((o.since, o.next_try - now, o.failed_tries), (now, 5 * S, 1));
    }

    #[test]
    fn a_wait_never_overflows_however_long_the_outage() {
        let b = Backoff::new(5 * S, 120 * S);
        assert_eq!(b.wait_after(u32::MAX), 120 * S);
        let unbounded = Backoff::new(5 * S, Duration::MAX);
        assert_eq!(unbounded.wait_after(40), 5 * S * (1 << 31));
        assert_eq!(
            Backoff::new(5 * S, S).max(),
            5 * S,
            "a cap below the first wait"
        );
    }
}
