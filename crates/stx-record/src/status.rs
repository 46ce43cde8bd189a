//! What the file adapter tells its caller: bytes and messages written, messages lost, the
//! last problem, and while the disk fails the recording since when and when it is tried
//! again (then, once it works again, when it resumed) — polled by the station for its
//! dashboard, and logged once per kind of problem per interval so a full disk does not
//! flood the log.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::sync::{Mutex, PoisonError};
use std::time::{Duration, Instant};

use serde::Serialize;

/// Kinds of trouble a recorder meets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum IssueKind {
    /// The writer thread fell behind and its queue was full: messages dropped.
    QueueFull,
    /// The writer thread has stopped: messages dropped.
    Stopped,
    /// A recording file (or its directory) could not be created.
    Create,
    /// Writing to the file failed (e.g. the disk is full); the file is given up.
    Write,
    /// Syncing a finished file to disk failed.
    Sync,
    /// A message could not be encoded as JSON.
    Encode,
    /// The writer core refused a message.
    Core,
}

/// The last problem of one kind.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct RecorderIssue {
    /// Its kind.
    pub kind: IssueKind,
    /// What happened, last time.
    pub message: String,
    /// How many times problems of this kind happened since the recorder started.
    pub occurrences: u64,
}

/// Writing has been failing (a file could not be created or written): nothing is recorded
/// until a try succeeds. Times are from the snapshot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Failing {
    /// How long it has been failing, s.
    pub duration: Duration,
    /// When the next try is, from now, s (zero: under way).
    pub next_try_in: Duration,
    /// Tries that failed, the first failure included.
    pub failed_tries: u32,
    /// Messages lost since it began.
    pub messages_lost: u64,
}

/// The last time writing worked again after failing. Times are from the snapshot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Resumed {
    /// How long ago, s.
    pub ago: Duration,
    /// How long it had been failing, s.
    pub after: Duration,
    /// Messages lost while it was failing.
    pub messages_lost: u64,
}

/// A snapshot of a recorder's state.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct RecorderStatus {
    /// Bytes written to recording files, B.
    pub bytes_written: u64,
    /// Messages in chunks written to files.
    pub messages_written: u64,
    /// Messages dropped: queue full, writer stopped, or their chunk could not be written.
    pub messages_lost: u64,
    /// Files started and kept (a file removed for holding no message is not counted).
    pub files_started: u32,
    /// The file being written, if one is open.
    pub current_file: Option<PathBuf>,
    /// The most recent problem, if any.
    pub last_error: Option<RecorderIssue>,
    /// While writing fails: since when, and the next try.
    pub failing: Option<Failing>,
    /// When writing last worked again after failing.
    pub resumed: Option<Resumed>,
}

/// An outage as the writer thread reports it.
struct Outage {
    since: Instant,
    next_try: Instant,
    failed_tries: u32,
    /// `messages_lost` when it began.
    lost_before: u64,
}

struct ResumedAt {
    at: Instant,
    after: Duration,
    messages_lost: u64,
}

#[derive(Default)]
struct Issues {
    current_file: Option<PathBuf>,
    last: Option<RecorderIssue>,
    occurrences: HashMap<IssueKind, u64>,
    /// When each kind was last logged, and how many were not logged since.
    logged: HashMap<IssueKind, (Instant, u64)>,
    failing: Option<Outage>,
    resumed: Option<ResumedAt>,
}

/// Counters shared by the caller's handles and the writer thread.
pub(crate) struct Shared {
    bytes_written: AtomicU64,
    messages_written: AtomicU64,
    messages_lost: AtomicU64,
    files_started: AtomicU32,
    issues: Mutex<Issues>,
    log_every: Duration,
    origin: Instant,
    /// Commands in the writer's queue (added before sending, taken off as received).
    pub(crate) queued: std::sync::atomic::AtomicUsize,
    /// Messages dropped for a full queue and not yet reported ([`Shared::queue_full`]).
    queue_full_pending: AtomicU64,
    /// When a full queue was last reported, ms after `origin`, plus one (0: never).
    queue_full_reported: AtomicU64,
}

/// A full queue is reported at most this often, ms.
const QUEUE_FULL_REPORT_MS: u64 = 100;

impl Shared {
    pub(crate) fn new(log_every: Duration) -> Self {
        Self {
            bytes_written: AtomicU64::new(0),
            messages_written: AtomicU64::new(0),
            messages_lost: AtomicU64::new(0),
            files_started: AtomicU32::new(0),
            issues: Mutex::new(Issues::default()),
            log_every,
            origin: Instant::now(),
            queued: std::sync::atomic::AtomicUsize::new(0),
            queue_full_pending: AtomicU64::new(0),
            queue_full_reported: AtomicU64::new(0),
        }
    }

    pub(crate) fn written(&self, bytes: u64, messages: u64) {
        self.bytes_written.fetch_add(bytes, Ordering::Relaxed);
        self.messages_written.fetch_add(messages, Ordering::Relaxed);
    }

    pub(crate) fn lost(&self, messages: u64) {
        self.messages_lost.fetch_add(messages, Ordering::Relaxed);
    }

    pub(crate) fn file_opened(&self, path: PathBuf) {
        self.files_started.fetch_add(1, Ordering::Relaxed);
        self.issues().current_file = Some(path);
    }

    pub(crate) fn file_closed(&self) {
        self.issues().current_file = None;
    }

    /// The file just closed was removed: its `bytes` (written, but of no message) and the
    /// file itself no longer count.
    pub(crate) fn file_removed(&self, bytes: u64) {
        self.files_started.fetch_sub(1, Ordering::Relaxed);
        self.bytes_written.fetch_sub(bytes, Ordering::Relaxed);
        self.file_closed();
    }

    /// Writing failed (again): it has been failing since `since`, and is tried next at
    /// `next_try`.
    pub(crate) fn failing(&self, since: Instant, next_try: Instant, failed_tries: u32) {
        let lost = self.messages_lost.load(Ordering::Relaxed);
        let mut issues = self.issues();
        let lost_before = issues.failing.as_ref().map_or(lost, |o| o.lost_before);
        issues.failing = Some(Outage {
            since,
            next_try,
            failed_tries,
            lost_before,
        });
    }

    /// Writing works again at `at`: returns the messages lost while it failed.
    pub(crate) fn resumed(&self, at: Instant) -> u64 {
        let lost = self.messages_lost.load(Ordering::Relaxed);
        let mut issues = self.issues();
        let Some(outage) = issues.failing.take() else {
            return 0;
        };
        let messages_lost = lost.saturating_sub(outage.lost_before);
        issues.resumed = Some(ResumedAt {
            at,
            after: at.saturating_duration_since(outage.since),
            messages_lost,
        });
        messages_lost
    }

    /// A message dropped because the writer's queue is full: counted at once, reported (the
    /// problem, its count, the log) at most every [`QUEUE_FULL_REPORT_MS`], so a writer far
    /// behind costs the link's hot path two atomic additions a message, not a lock or a clock.
    pub(crate) fn queue_full(&self) {
        let pending = self.queue_full_pending.fetch_add(1, Ordering::Relaxed) + 1;
        // The clock is read on the first drop after a report and then every 256th: soon
        // enough to report, and no clock read for most drops.
        if pending % 256 != 1 {
            return;
        }
        let now = self.origin.elapsed().as_millis() as u64 + 1;
        let last = self.queue_full_reported.load(Ordering::Relaxed);
        if last != 0 && now < last + QUEUE_FULL_REPORT_MS {
            return;
        }
        if self
            .queue_full_reported
            .compare_exchange(last, now, Ordering::Relaxed, Ordering::Relaxed)
            .is_err()
        {
            return;
        }
        let n = self.queue_full_pending.swap(0, Ordering::Relaxed);
        self.report_times(IssueKind::QueueFull, "the writer is behind: queue full", n);
    }

    /// Notes a problem; logs it unless one of its kind was logged within `log_every`.
    pub(crate) fn report(&self, kind: IssueKind, message: impl AsRef<str> + Into<String>) {
        self.report_times(kind, message, 1);
    }

    /// `message` is only copied when it differs from the last one.
    fn report_times(&self, kind: IssueKind, message: impl AsRef<str> + Into<String>, times: u64) {
        let now = Instant::now();
        let mut issues = self.issues();
        let occurrences = {
            let n = issues.occurrences.entry(kind).or_insert(0);
            *n += times;
            *n
        };
        let due = match issues.logged.get_mut(&kind) {
            Some((at, quiet)) if now.duration_since(*at) < self.log_every => {
                *quiet += 1;
                None
            }
            Some((at, quiet)) => {
                let silenced = *quiet;
                *at = now;
                *quiet = 0;
                Some(silenced)
            }
            None => {
                issues.logged.insert(kind, (now, 0));
                Some(0)
            }
        };
        if let Some(silenced) = due {
            tracing::warn!(
                ?kind,
                occurrences,
                not_logged_since_last = silenced,
                "recording: {}",
                message.as_ref()
            );
        }
        match &mut issues.last {
            Some(last) if last.kind == kind && last.message == message.as_ref() => {
                last.occurrences = occurrences;
            }
            last => {
                *last = Some(RecorderIssue {
                    kind,
                    message: message.into(),
                    occurrences,
                });
            }
        }
    }

    pub(crate) fn snapshot(&self) -> RecorderStatus {
        let issues = self.issues();
        let mut last_error = issues.last.clone();
        // Drops since the last report of a full queue count too.
        if let Some(last) = &mut last_error
            && last.kind == IssueKind::QueueFull
        {
            last.occurrences += self.queue_full_pending.load(Ordering::Relaxed);
        }
        let now = Instant::now();
        let messages_lost = self.messages_lost.load(Ordering::Relaxed);
        RecorderStatus {
            bytes_written: self.bytes_written.load(Ordering::Relaxed),
            messages_written: self.messages_written.load(Ordering::Relaxed),
            messages_lost,
            files_started: self.files_started.load(Ordering::Relaxed),
            current_file: issues.current_file.clone(),
            last_error,
            failing: issues.failing.as_ref().map(|o| Failing {
                duration: now.saturating_duration_since(o.since),
                next_try_in: o.next_try.saturating_duration_since(now),
                failed_tries: o.failed_tries,
                messages_lost: messages_lost.saturating_sub(o.lost_before),
            }),
            resumed: issues.resumed.as_ref().map(|r| Resumed {
                ago: now.saturating_duration_since(r.at),
                after: r.after,
                messages_lost: r.messages_lost,
            }),
        }
    }

    fn issues(&self) -> std::sync::MutexGuard<'_, Issues> {
        self.issues.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_problem_is_counted_and_the_last_kept() {
        let shared = Shared::new(Duration::from_secs(3600));
        for i in 0..5 {
            shared.report(IssueKind::Write, format!("disk full {i}"));
        }
        shared.report(IssueKind::QueueFull, "queue full");
        shared.report(IssueKind::Write, "disk full again");
        let status = shared.snapshot();
        let last = status.last_error.unwrap();
        assert_eq!(last.kind, IssueKind::Write);
        assert_eq!(last.occurrences, 6);
        assert_eq!(last.message, "disk full again");
    }

    #[test]
    fn every_drop_of_a_full_queue_is_counted_though_few_are_reported() {
        let shared = Shared::new(Duration::from_secs(3600));
        for _ in 0..1000 {
            shared.lost(1);
            shared.queue_full();
        }
        let status = shared.snapshot();
        assert_eq!(status.messages_lost, 1000);
        let last = status.last_error.unwrap();
        assert_eq!(last.kind, IssueKind::QueueFull);
        assert_eq!(last.occurrences, 1000);
        // Reported once (the first drop); the rest wait for the next report.
        assert_eq!(shared.issues().occurrences[&IssueKind::QueueFull], 1);
    }
}
