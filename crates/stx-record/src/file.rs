//! The file adapter: a writer thread that runs a [`RecorderCore`] and puts its bytes in
//! files, fed by a bounded queue so that recording never holds up the station.
//!
//! Callers write through a [`RecorderHandle`] (cheap to clone, one per producer). A message
//! that finds the queue full is dropped and counted; so is every message of a chunk the disk
//! refused. What went wrong is in [`RecorderHandle::status`] and in the log, once per kind of
//! problem per [`RecorderConfig::log_every`].
//!
//! When the disk refuses the recording (full, or any other I/O error) the writer thread
//! (`thread`) keeps what the file holds: it cuts the file back to its last whole chunk, so it
//! reads as a file cut there and `stx record recover` makes it whole, and closes it. A file
//! that holds no message of the flight (the disk refused its first bytes) is removed instead,
//! and its number used again. Nothing more is created until the next try, after
//! [`RecorderConfig::retry_after`], doubling after each try that fails up to
//! [`RecorderConfig::retry_max`] ([`crate::backoff`]); the messages of the meantime are
//! counted lost. A try that succeeds resumes in the next file, not the kept one: the core has
//! already handed out (and indexed, for the summary) the chunks the disk refused, so the kept
//! file cannot go on as one valid MCAP file unless every refused byte were held in memory for
//! as long as the disk stays full.
//!
//! Files ([`Directory`]) are named by the run's start (UTC) and number —
//! `stx-20261105T143012Z-001.mcap` — in the directory the caller chose, by default
//! [`recordings_dir`] of the station's state directory. Each chunk is one `write` to the OS,
//! so a killed process leaves whole chunks behind; files are synced when they end.

mod directory;
mod thread;

pub use directory::{Directory, RECORDINGS_DIR_NAME, recordings_dir, run_started_ms_from_name};

use std::io;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::sync::mpsc::{self, SyncSender, TrySendError};
use std::thread::JoinHandle;
use std::time::Duration;

use serde::Serialize;

use crate::backoff::Backoff;
use crate::channel::ChannelId;
use crate::status::{IssueKind, RecorderStatus, Shared};
use crate::writer::RecorderCore;

/// How the writer thread behaves.
#[derive(Debug, Clone, PartialEq)]
pub struct RecorderConfig {
    /// Messages the queue holds before new ones are dropped. At a few hundred messages a
    /// second, the default is more than 10 s of a stalled disk.
    pub queue_capacity: usize,
    /// After a file could not be created or written, how long before the first try, s. Each
    /// try that fails doubles the wait, up to [`RecorderConfig::retry_max`].
    pub retry_after: Duration,
    /// The longest wait between tries, s. The default, 2 min, uses space freed during a long
    /// outage within 2 minutes; the tries before it (5, 10, 20, 40, 80 s) use space that
    /// frees soon, sooner. Each try that fails leaves nothing behind.
    pub retry_max: Duration,
    /// A kind of problem is logged at most once per this interval, s (it is always counted).
    pub log_every: Duration,
}

impl Default for RecorderConfig {
    fn default() -> Self {
        Self {
            queue_capacity: 8192,
            retry_after: Duration::from_secs(5),
            retry_max: Duration::from_secs(120),
            log_every: Duration::from_secs(60),
        }
    }
}

/// Where the writer thread puts files: a directory ([`Directory`]), or in tests a sink that
/// fails on purpose.
pub trait Storage: Send + 'static {
    /// Creates file `part` (from 1) of the run; returns its path and the file.
    fn create(&mut self, part: u32) -> io::Result<(PathBuf, Box<dyn StorageFile>)>;
    /// Removes a file it created, closed (one that holds no message of the flight).
    fn remove(&mut self, path: &Path) -> io::Result<()>;
}

/// One file being written.
pub trait StorageFile: Send {
    /// Appends `data`.
    fn write_all(&mut self, data: &[u8]) -> io::Result<()>;
    /// Cuts the file back to its first `len` bytes: after a write the disk refused, which
    /// may have left part of its data.
    fn truncate(&mut self, len: u64) -> io::Result<()>;
    /// Makes what was written durable (the file is finished).
    fn sync(&mut self) -> io::Result<()>;
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
        let backoff = Backoff::new(config.retry_after, config.retry_max);
        let writer = thread::Writer::new(core, Box::new(storage), shared.clone(), backoff);
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
