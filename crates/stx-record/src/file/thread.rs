//! The writer thread: takes commands off the queue, runs them through the core, and applies
//! what the core hands out to files — and when the disk refuses, keeps what the file holds,
//! waits as the back-off says, and tries again (the rules are in the parent module's
//! documentation).
//!
//! Its states: no file (`Closed`), a file being written (`Open`), or writing failing
//! (`Failing`), where nothing is created until the next try. A try asks the core for a file
//! (the next number after a kept file, else the same number again) and applies it like any
//! other; the outage ends when a message reaches the disk, not when a file is created, so a
//! disk with room for a header and nothing more is still failing.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};

use super::{Command, Storage, StorageFile};
use crate::backoff::{Backoff, Outage};
use crate::channel::ChannelId;
use crate::status::{IssueKind, Shared};
use crate::writer::{Output, RecorderCore, WriteError};

/// How long the thread waits for a command when nothing is due.
const IDLE_WAIT: Duration = Duration::from_secs(1);

enum FileState {
    /// No file: before the first, or between one file's end and the next one's start.
    Closed,
    Open(OpenFile),
    /// Writing failed; nothing is created until the back-off's next try. `kept`: a file of
    /// the core's current number is on disk (cut where the disk refused), so the next try
    /// starts the next number; otherwise it starts the same number again.
    Failing {
        kept: bool,
    },
}

struct OpenFile {
    file: Box<dyn StorageFile>,
    path: PathBuf,
    /// Bytes written whole: where the file ends if it is given up, B.
    len: u64,
    /// Messages it holds.
    messages: u64,
}

pub(super) struct Writer {
    core: RecorderCore,
    storage: Box<dyn Storage>,
    file: FileState,
    shared: Arc<Shared>,
    backoff: Backoff,
    origin: Instant,
    /// A try is under way: the file the core starts is created.
    trying: bool,
}

impl Writer {
    pub(super) fn new(
        core: RecorderCore,
        storage: Box<dyn Storage>,
        shared: Arc<Shared>,
        backoff: Backoff,
    ) -> Self {
        Self {
            core,
            storage,
            file: FileState::Closed,
            shared,
            backoff,
            origin: Instant::now(),
            trying: false,
        }
    }

    fn now(&self) -> Duration {
        self.origin.elapsed()
    }

    pub(super) fn run(mut self, rx: Receiver<Command>) {
        loop {
            self.apply_outputs();
            self.retry_if_due();
            let received = rx.recv_timeout(self.wait());
            if matches!(
                received,
                Ok(Command::Message { .. } | Command::Encode { .. })
            ) {
                self.shared.queued.fetch_sub(1, Ordering::Relaxed);
            }
            match received {
                Ok(Command::Message {
                    channel,
                    log_time,
                    publish_time,
                    payload,
                }) => self.write(channel, log_time, publish_time, &payload),
                Ok(Command::Encode {
                    log_time,
                    publish_time,
                    encode,
                }) => {
                    for (channel, payload) in encode() {
                        self.write(channel, log_time, publish_time, &payload);
                    }
                }
                Ok(Command::Flush(ack)) => {
                    let now = self.now();
                    if let Err(e) = self.core.flush(now) {
                        self.shared.report(IssueKind::Core, e.to_string());
                    }
                    self.apply_outputs();
                    let _ = ack.send(());
                }
                Ok(Command::Finish) | Err(RecvTimeoutError::Disconnected) => {
                    // Messages other handles queued after the finish will not be written.
                    let late = rx
                        .try_iter()
                        .filter(|c| matches!(c, Command::Message { .. } | Command::Encode { .. }))
                        .count();
                    self.shared.lost(late as u64);
                    break;
                }
                Err(RecvTimeoutError::Timeout) => {
                    let now = self.now();
                    if let Err(e) = self.core.handle_timeout(now) {
                        self.shared.report(IssueKind::Core, e.to_string());
                    }
                }
            }
        }
        if let Err(e) = self.core.finish() {
            self.shared.report(IssueKind::Core, e.to_string());
        }
        self.apply_outputs();
    }

    /// Until the open chunk is due to close or the next try, whichever is first.
    fn wait(&self) -> Duration {
        let retry = match self.file {
            FileState::Failing { .. } => self.backoff.outage().map(|o| o.next_try),
            _ => None,
        };
        let now = self.now();
        self.core
            .poll_timeout()
            .into_iter()
            .chain(retry)
            .min()
            .map_or(IDLE_WAIT, |at| at.saturating_sub(now))
    }

    fn write(&mut self, channel: ChannelId, log_time: u64, publish_time: u64, payload: &[u8]) {
        let now = self.now();
        if let Err(e) = self
            .core
            .write(now, channel, log_time, publish_time, payload)
        {
            self.shared.lost(1);
            self.shared.report(IssueKind::Core, e.to_string());
            if matches!(e, WriteError::Mcap(_)) {
                let _ = self.core.start_new_file(now);
            }
        }
    }

    fn retry_if_due(&mut self) {
        let FileState::Failing { kept } = self.file else {
            return;
        };
        let now = self.now();
        if !self.backoff.due(now) {
            return;
        }
        self.trying = true;
        let started = if kept {
            self.core.start_new_file(now)
        } else {
            self.core.restart_file(now)
        };
        if let Err(e) = started {
            self.shared.report(IssueKind::Core, e.to_string());
        }
        self.apply_outputs();
        self.trying = false;
    }

    fn apply_outputs(&mut self) {
        while let Some(output) = self.core.poll_output() {
            match output {
                Output::StartFile { part } => self.start(part),
                Output::Bytes { data, messages } => self.append(&data, messages),
                Output::EndFile => self.end(),
                Output::Lost { messages } => self.shared.lost(messages),
            }
        }
    }

    fn start(&mut self, part: u32) {
        self.end();
        if let FileState::Failing { kept } = &mut self.file
            && !self.trying
        {
            // The core moved on to a new file (it rotated) while the disk fails: nothing of
            // that file is on disk, and the next try starts it.
            *kept = false;
            return;
        }
        match self.storage.create(part) {
            Ok((path, file)) => {
                if self.backoff.outage().is_none() {
                    tracing::info!(file = %path.display(), "recording to a new file");
                }
                self.shared.file_opened(path.clone());
                self.file = FileState::Open(OpenFile {
                    file,
                    path,
                    len: 0,
                    messages: 0,
                });
            }
            Err(e) => {
                self.shared.report(
                    IssueKind::Create,
                    format!("cannot create recording file {part}: {e}"),
                );
                self.failed(false);
            }
        }
    }

    fn append(&mut self, data: &[u8], messages: u64) {
        let FileState::Open(open) = &mut self.file else {
            self.shared.lost(messages);
            return;
        };
        match open.file.write_all(data) {
            Ok(()) => {
                open.len += data.len() as u64;
                open.messages += messages;
                self.shared.written(data.len() as u64, messages);
                if messages > 0
                    && let Some(outage) = self.backoff.succeeded()
                {
                    self.resumed(outage);
                }
            }
            Err(e) => {
                self.shared
                    .report(IssueKind::Write, format!("writing the recording: {e}"));
                self.give_up();
                // Counted after the outage began, so it counts them too.
                self.shared.lost(messages);
            }
        }
    }

    /// The core ended the file (rotation, or the recording finished).
    fn end(&mut self) {
        let open = match std::mem::replace(&mut self.file, FileState::Closed) {
            FileState::Open(open) => open,
            other => {
                self.file = other;
                return;
            }
        };
        if open.messages == 0 && self.backoff.outage().is_some() {
            // A try that ended before any message reached it holds nothing of the flight.
            self.remove(open);
            return;
        }
        let OpenFile { mut file, .. } = open;
        if let Err(e) = file.sync() {
            self.shared
                .report(IssueKind::Sync, format!("syncing the recording: {e}"));
        }
        self.shared.file_closed();
    }

    /// The disk refused the file's bytes: the file is cut back to its last whole write and
    /// kept, or removed if it holds no message; writing fails until a try succeeds.
    fn give_up(&mut self) {
        let FileState::Open(mut open) = std::mem::replace(&mut self.file, FileState::Closed) else {
            return;
        };
        if open.messages == 0 {
            if self.backoff.outage().is_none() {
                tracing::warn!(file = %open.path.display(), "recording: the file held no message; removed");
            }
            self.remove(open);
            self.failed(false);
            return;
        }
        // The log, not the problem the page shows: the disk's refusal is the problem.
        if let Err(e) = open.file.truncate(open.len) {
            tracing::warn!(file = %open.path.display(), "recording: cannot cut the file back to its last whole chunk: {e}");
        }
        if let Err(e) = open.file.sync() {
            tracing::warn!(file = %open.path.display(), "recording: cannot sync the file: {e}");
        }
        tracing::warn!(
            file = %open.path.display(),
            messages = open.messages,
            bytes = open.len,
            "recording: the file is kept as far as it was written; `stx record recover` \
             makes it whole"
        );
        self.shared.file_closed();
        self.failed(true);
    }

    /// Removes a file that holds no message of the flight, so a disk that refuses the
    /// recording leaves no empty or header-only files behind.
    fn remove(&mut self, open: OpenFile) {
        let OpenFile {
            file, path, len, ..
        } = open;
        drop(file);
        match self.storage.remove(&path) {
            Ok(()) => self.shared.file_removed(len),
            Err(e) => {
                tracing::warn!(file = %path.display(), "recording: cannot remove a file that holds no message: {e}");
                self.shared.file_closed();
            }
        }
    }

    /// A try failed (or the first failure): when to try next, said in the status and, for
    /// the first failure, in the log.
    fn failed(&mut self, kept: bool) {
        let now = self.now();
        let first = self.backoff.outage().is_none();
        let outage = self.backoff.failed(now);
        self.file = FileState::Failing { kept };
        self.shared.failing(
            self.origin + outage.since,
            self.origin + outage.next_try,
            outage.failed_tries,
        );
        let next_s = outage.next_try.saturating_sub(now).as_secs_f64();
        if first {
            tracing::warn!(
                "recording failing: nothing is recorded until the disk takes it again; next \
                 try in {next_s:.0} s, the wait doubling after each failed try up to {:.0} s",
                self.backoff.max().as_secs_f64()
            );
        } else {
            tracing::debug!(
                failed_tries = outage.failed_tries,
                "recording: try failed; next in {next_s:.0} s"
            );
        }
    }

    fn resumed(&mut self, outage: Outage) {
        let now = self.now();
        let lost = self.shared.resumed(self.origin + now);
        let file = match &self.file {
            FileState::Open(open) => Some(open.path.display()),
            _ => None,
        };
        tracing::info!(
            file = file.map(tracing::field::display),
            failed_tries = outage.failed_tries,
            messages_lost = lost,
            "recording resumed after {:.0} s failing",
            now.saturating_sub(outage.since).as_secs_f64()
        );
    }
}
