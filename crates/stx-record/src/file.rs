//! The file adapter: a writer thread that runs a [`RecorderCore`] and puts its bytes in
//! files, fed by a bounded queue so that recording never holds up the station.
//!
//! Callers write through a [`RecorderHandle`] (cheap to clone, one per producer). A message
//! that finds the queue full is dropped and counted; so is every message of a chunk the disk
//! refused. After a write error the file is given up (it stays readable up to its last whole
//! chunk, and `recover` makes a clean copy) and a new file is tried every
//! [`RecorderConfig::retry_after`], so a disk that frees up is used again. What went wrong is
//! in [`RecorderHandle::status`] and in the log, once per kind of problem per
//! [`RecorderConfig::log_every`].
//!
//! Files are named by the run's start (UTC) and part number —
//! `stx-20261105T143012Z-001.mcap`; a failed attempt uses up its number — in the directory
//! the caller chose, by default
//! [`recordings_dir`] of the station's state directory. Each chunk is one `write` to the OS,
//! so a killed process leaves whole chunks behind; files are synced when they end.

use std::fs::{File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, SyncSender, TrySendError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant, SystemTime};

use serde::Serialize;

use crate::channel::ChannelId;
use crate::status::{IssueKind, RecorderStatus, Shared};
use crate::writer::{Output, RecorderCore};

/// Name of the recordings directory inside the station's state directory.
pub const RECORDINGS_DIR_NAME: &str = "recordings";

/// Where recordings go by default: `recordings/` in the station's state directory (found
/// like the signing timestamp's: `stx_link::signing::persist::default_state_dir`).
pub fn recordings_dir(state_dir: &Path) -> PathBuf {
    state_dir.join(RECORDINGS_DIR_NAME)
}

/// How the writer thread behaves.
#[derive(Debug, Clone, PartialEq)]
pub struct RecorderConfig {
    /// Messages the queue holds before new ones are dropped. At a few hundred messages a
    /// second, the default is more than 10 s of a stalled disk.
    pub queue_capacity: usize,
    /// After a file could not be created or written, how long before a new one is tried, s.
    pub retry_after: Duration,
    /// A kind of problem is logged at most once per this interval, s (it is always counted).
    pub log_every: Duration,
}

impl Default for RecorderConfig {
    fn default() -> Self {
        Self {
            queue_capacity: 8192,
            retry_after: Duration::from_secs(5),
            log_every: Duration::from_secs(60),
        }
    }
}

/// Where the writer thread puts files: a directory ([`Directory`]), or in tests a sink that
/// fails on purpose.
pub trait Storage: Send + 'static {
    /// Creates file `part` (from 1) of the run; returns its path and the file.
    fn create(&mut self, part: u32) -> io::Result<(PathBuf, Box<dyn StorageFile>)>;
}

/// One file being written.
pub trait StorageFile: Send {
    /// Appends `data`.
    fn write_all(&mut self, data: &[u8]) -> io::Result<()>;
    /// Makes what was written durable (the file is finished).
    fn sync(&mut self) -> io::Result<()>;
}

impl StorageFile for File {
    fn write_all(&mut self, data: &[u8]) -> io::Result<()> {
        Write::write_all(self, data)
    }

    fn sync(&mut self) -> io::Result<()> {
        self.sync_data()
    }
}

/// Recording files in a directory (created when the first file is).
#[derive(Debug, Clone)]
pub struct Directory {
    dir: PathBuf,
    run_stamp: String,
}

impl Directory {
    /// Files in `dir` for a run started at `run_started` (wall clock, names the files).
    pub fn new(dir: impl Into<PathBuf>, run_started: SystemTime) -> Self {
        let t = time::OffsetDateTime::from(run_started);
        Self {
            dir: dir.into(),
            run_stamp: format!(
                "{:04}{:02}{:02}T{:02}{:02}{:02}Z",
                t.year(),
                u8::from(t.month()),
                t.day(),
                t.hour(),
                t.minute(),
                t.second()
            ),
        }
    }

    /// The name of file `part` (`stx-20261105T143012Z-001.mcap`).
    pub fn file_name(&self, part: u32) -> String {
        format!("stx-{}-{part:03}.mcap", self.run_stamp)
    }
}

/// When the run that wrote the file `name` started, as its name says (the names
/// [`Directory::file_name`] gives), Unix milliseconds; `None` for any other name. A file
/// just begun holds no message yet that could say so.
pub fn run_started_ms_from_name(name: &str) -> Option<u64> {
    let stamp = name.strip_prefix("stx-")?.get(..16)?;
    let digits = |range: std::ops::Range<usize>| stamp.get(range)?.parse::<u32>().ok();
    if stamp.as_bytes().get(8) != Some(&b'T') || stamp.as_bytes().get(15) != Some(&b'Z') {
        return None;
    }
    let month = time::Month::try_from(u8::try_from(digits(4..6)?).ok()?).ok()?;
    let date = time::Date::from_calendar_date(
        i32::try_from(digits(0..4)?).ok()?,
        month,
        u8::try_from(digits(6..8)?).ok()?,
    )
    .ok()?;
    let at = date
        .with_hms(
            u8::try_from(digits(9..11)?).ok()?,
            u8::try_from(digits(11..13)?).ok()?,
            u8::try_from(digits(13..15)?).ok()?,
        )
        .ok()?
        .assume_utc();
    u64::try_from(at.unix_timestamp()).ok().map(|s| s * 1000)
}

impl Storage for Directory {
    fn create(&mut self, part: u32) -> io::Result<(PathBuf, Box<dyn StorageFile>)> {
        std::fs::create_dir_all(&self.dir)?;
        let base = self.file_name(part);
        // Two runs started within the same second: never overwrite, add a counter.
        for attempt in 0..100 {
            let name = if attempt == 0 {
                base.clone()
            } else {
                base.replace(".mcap", &format!("-{attempt}.mcap"))
            };
            let path = self.dir.join(name);
            match OpenOptions::new().write(true).create_new(true).open(&path) {
                Ok(file) => return Ok((path, Box::new(file))),
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
                Err(e) => return Err(e),
            }
        }
        Err(io::Error::new(
            io::ErrorKind::AlreadyExists,
            format!("{base}: 100 files of that name exist"),
        ))
    }
}

/// Messages made on the writer's thread: see [`RecorderHandle::write_later`].
pub type Encode = Box<dyn FnOnce() -> Vec<(ChannelId, Vec<u8>)> + Send>;

enum Command {
    Message {
        channel: ChannelId,
        log_time: u64,
        publish_time: u64,
        payload: Vec<u8>,
    },
    Encode {
        log_time: u64,
        publish_time: u64,
        encode: Encode,
    },
    Flush(SyncSender<()>),
    Finish,
}

/// A producer's way into a running [`Recorder`]. Never blocks.
#[derive(Clone)]
pub struct RecorderHandle {
    tx: SyncSender<Command>,
    shared: Arc<Shared>,
    /// The queue's capacity: [`RecorderHandle::drop_if_full`] compares `Shared::queued` with it.
    capacity: usize,
}

impl RecorderHandle {
    /// Queues `payload` (JSON following the channel's schema) for `channel`, logged at
    /// `log_time` and published at `publish_time` (ns since the Unix epoch). `false`: it was
    /// dropped (queue full or writer stopped), and counted lost.
    pub fn write(
        &self,
        channel: ChannelId,
        log_time: u64,
        publish_time: u64,
        payload: Vec<u8>,
    ) -> bool {
        self.send(Command::Message {
            channel,
            log_time,
            publish_time,
            payload,
        })
    }

    /// Queues `encode`, which the writer's thread runs to make the messages (channel and
    /// JSON payload each), logged at `log_time` and published at `publish_time`. The caller
    /// pays a move instead of the encoding: the link's hot path records this way. `false`:
    /// dropped (queue full or writer stopped), counted as one lost message.
    pub fn write_later(
        &self,
        log_time: u64,
        publish_time: u64,
        encode: impl FnOnce() -> Vec<(ChannelId, Vec<u8>)> + Send + 'static,
    ) -> bool {
        if self.drop_if_full() {
            return false;
        }
        self.send(Command::Encode {
            log_time,
            publish_time,
            encode: Box::new(encode),
        })
    }

    /// `true` when the queue is full: one message is counted lost, and the caller should not
    /// build it. A writer far behind then costs the link's hot path a load and two atomic
    /// additions a message, no allocation.
    pub fn drop_if_full(&self) -> bool {
        if self.shared.queued.load(Ordering::Relaxed) < self.capacity {
            return false;
        }
        self.shared.lost(1);
        self.shared.queue_full();
        true
    }

    fn send(&self, command: Command) -> bool {
        self.shared.queued.fetch_add(1, Ordering::Relaxed);
        let sent = self.tx.try_send(command);
        if sent.is_err() {
            self.shared.queued.fetch_sub(1, Ordering::Relaxed);
        }
        match sent {
            Ok(()) => true,
            Err(TrySendError::Full(_)) => {
                self.shared.lost(1);
                self.shared.queue_full();
                false
            }
            Err(TrySendError::Disconnected(_)) => {
                self.shared.lost(1);
                self.shared
                    .report(IssueKind::Stopped, "the writer thread has stopped");
                false
            }
        }
    }

    /// Encodes `value` as JSON (on the caller's thread) and queues it, logged and published
    /// at `log_time`. `false`: dropped and counted lost.
    pub fn write_json<T: Serialize + ?Sized>(
        &self,
        channel: ChannelId,
        log_time: u64,
        value: &T,
    ) -> bool {
        match serde_json::to_vec(value) {
            Ok(payload) => self.write(channel, log_time, log_time, payload),
            Err(e) => {
                self.shared.lost(1);
                self.shared.report(IssueKind::Encode, e.to_string());
                false
            }
        }
    }

    /// Closes the open chunk and waits, at most `timeout`, until it is written. `false`: the
    /// queue was full, the writer stopped, or it did not answer in time.
    pub fn flush(&self, timeout: Duration) -> bool {
        let (ack_tx, ack_rx) = mpsc::sync_channel(1);
        self.tx.try_send(Command::Flush(ack_tx)).is_ok() && ack_rx.recv_timeout(timeout).is_ok()
    }

    /// Counters and the last problem.
    pub fn status(&self) -> RecorderStatus {
        self.shared.snapshot()
    }
}

/// A writer thread recording to files. Finish it with [`Recorder::finish`] (dropping it
/// finishes too) so the last file gets its summary.
pub struct Recorder {
    handle: RecorderHandle,
    thread: Option<JoinHandle<()>>,
}

impl Recorder {
    /// Starts the writer thread on `core` (with its channels registered; its clock starts at
    /// zero now) writing to `storage`.
    pub fn spawn(
        core: RecorderCore,
        storage: impl Storage,
        config: RecorderConfig,
    ) -> io::Result<Self> {
        let (tx, rx) = mpsc::sync_channel(config.queue_capacity.max(1));
        let shared = Arc::new(Shared::new(config.log_every));
        let writer = Writer {
            core,
            storage: Box::new(storage),
            file: FileState::Closed,
            shared: shared.clone(),
            retry_after: config.retry_after,
            origin: Instant::now(),
        };
        let thread = std::thread::Builder::new()
            .name("stx-record".into())
            .spawn(move || writer.run(rx))?;
        Ok(Self {
            handle: RecorderHandle {
                tx,
                shared,
                capacity: config.queue_capacity.max(1),
            },
            thread: Some(thread),
        })
    }

    /// A handle for producers.
    pub fn handle(&self) -> RecorderHandle {
        self.handle.clone()
    }

    /// Counters and the last problem.
    pub fn status(&self) -> RecorderStatus {
        self.handle.status()
    }

    /// Writes what is open, the file's summary, and stops the thread; the final status.
    pub fn finish(mut self) -> RecorderStatus {
        self.stop();
        self.handle.status()
    }

    fn stop(&mut self) {
        if let Some(thread) = self.thread.take() {
            // Blocking is right here: the station is stopping and wants its file whole.
            let _ = self.handle.tx.send(Command::Finish);
            if thread.join().is_err() {
                self.handle
                    .shared
                    .report(IssueKind::Stopped, "the writer thread panicked");
            }
        }
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        self.stop();
    }
}

enum FileState {
    Closed,
    Open(Box<dyn StorageFile>),
    /// Given up at `since` (adapter clock); a new file is tried after `retry_after`.
    Broken {
        since: Duration,
    },
}

struct Writer {
    core: RecorderCore,
    storage: Box<dyn Storage>,
    file: FileState,
    shared: Arc<Shared>,
    retry_after: Duration,
    origin: Instant,
}

impl Writer {
    fn now(&self) -> Duration {
        self.origin.elapsed()
    }

    fn run(mut self, rx: Receiver<Command>) {
        loop {
            self.apply_outputs();
            self.retry_if_due();
            let now = self.now();
            let wait = match self.core.poll_timeout() {
                Some(deadline) => deadline.saturating_sub(now),
                None => self.retry_after,
            };
            let received = rx.recv_timeout(wait);
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

    fn write(&mut self, channel: ChannelId, log_time: u64, publish_time: u64, payload: &[u8]) {
        let now = self.now();
        if let Err(e) = self
            .core
            .write(now, channel, log_time, publish_time, payload)
        {
            self.shared.lost(1);
            self.shared.report(IssueKind::Core, e.to_string());
            if matches!(e, crate::writer::WriteError::Mcap(_)) {
                let _ = self.core.start_new_file(now);
            }
        }
    }

    fn retry_if_due(&mut self) {
        let now = self.now();
        if let FileState::Broken { since } = self.file
            && now.saturating_sub(since) >= self.retry_after
        {
            if let Err(e) = self.core.start_new_file(now) {
                self.shared.report(IssueKind::Core, e.to_string());
            }
            self.apply_outputs();
        }
    }

    fn apply_outputs(&mut self) {
        while let Some(output) = self.core.poll_output() {
            match output {
                Output::StartFile { part } => self.open(part),
                Output::Bytes { data, messages } => self.append(&data, messages),
                Output::EndFile => self.close(),
                Output::Lost { messages } => self.shared.lost(messages),
            }
        }
    }

    fn open(&mut self, part: u32) {
        self.close();
        match self.storage.create(part) {
            Ok((path, file)) => {
                self.shared.file_opened(path);
                self.file = FileState::Open(file);
            }
            Err(e) => {
                self.shared.report(
                    IssueKind::Create,
                    format!("cannot create recording file {part}: {e}"),
                );
                self.file = FileState::Broken { since: self.now() };
            }
        }
    }

    fn append(&mut self, data: &[u8], messages: u64) {
        let FileState::Open(file) = &mut self.file else {
            self.shared.lost(messages);
            return;
        };
        match file.write_all(data) {
            Ok(()) => self.shared.written(data.len() as u64, messages),
            Err(e) => {
                self.shared.lost(messages);
                self.shared
                    .report(IssueKind::Write, format!("writing the recording: {e}"));
                self.shared.file_closed();
                self.file = FileState::Broken { since: self.now() };
            }
        }
    }

    fn close(&mut self) {
        if let FileState::Open(file) = &mut self.file {
            if let Err(e) = file.sync() {
                self.shared
                    .report(IssueKind::Sync, format!("syncing the recording: {e}"));
            }
            self.shared.file_closed();
            self.file = FileState::Closed;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_name_says_when_its_run_started() {
        let started = SystemTime::UNIX_EPOCH + Duration::from_secs(1_795_000_212);
        let name = Directory::new("/tmp", started).file_name(2);
        assert_eq!(run_started_ms_from_name(&name), Some(1_795_000_212_000));
        let counted = name.replace(".mcap", "-1.mcap");
        assert_eq!(run_started_ms_from_name(&counted), Some(1_795_000_212_000));
        for other in [
            "flight.mcap",
            "stx-2026.mcap",
            "stx-20261399T000000Z-001.mcap",
        ] {
            assert_eq!(run_started_ms_from_name(other), None, "{other}");
        }
    }
}
