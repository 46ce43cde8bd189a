//! The writer core: messages and `now` in, the bytes of MCAP files out, and when to start a
//! new file. No file, no thread, no clock: the adapter ([`crate::file`]) or a test drives it.
//!
//! The core keeps `mcap`'s writer in its buffered mode over an in-memory sink, so a chunk
//! leaves as one piece of bytes when it closes; nothing of an open chunk is ever on disk,
//! and a file cut anywhere ends at worst with one partial chunk that a reader skips.
//! Chunks close when they hold [`CoreOptions::chunk_bytes`] or have been open
//! [`CoreOptions::chunk_max_age`] — the second bounds what a killed process loses. The
//! adapter calls [`RecorderCore::handle_timeout`] at [`RecorderCore::poll_timeout`] so a
//! quiet recorder closes its chunk too.
//!
//! Each file starts with the MCAP header, the metadata record ([`RecordingInfo`]) and a chunk
//! naming every channel, so even a file cut in its first second says what it records.

use std::collections::{BTreeMap, VecDeque};
use std::io::Write;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

use mcap::records::MessageHeader;
use mcap::write::NoSeek;
use thiserror::Error;

use crate::channel::{ChannelError, ChannelId, ChannelSpec, MESSAGE_ENCODING, SCHEMA_ENCODING};
use crate::info::RecordingInfo;

/// Chunk compression.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Compression {
    /// zstd: JSON telemetry shrinks several times; the default.
    Zstd,
    /// lz4: faster, larger.
    Lz4,
    /// None (for tests and inspection with a hex editor).
    None,
}

/// When chunks close and files rotate.
#[derive(Debug, Clone, PartialEq)]
pub struct CoreOptions {
    /// Uncompressed bytes after which a chunk closes, B. Larger chunks compress better; at
    /// stx's rates the age limit closes them first.
    pub chunk_bytes: u64,
    /// How long a chunk stays open at most: the data a killed process can lose, s.
    pub chunk_max_age: Duration,
    /// Start a new file once this one holds this many bytes, B (checked as chunks close, so a
    /// file may pass it by one chunk). `None`: no limit.
    pub max_file_bytes: Option<u64>,
    /// Start a new file once this one has been open this long, s (checked as chunks close).
    /// `None`: no limit.
    pub max_file_duration: Option<Duration>,
    /// Chunk compression.
    pub compression: Compression,
    /// zstd's level (1–19; 0: zstd's default, 3). A one-second chunk is small and gives the
    /// compressor little to work with; level 9 takes about 6 % off a flight's file against
    /// the default and compresses tens of MB/s, far above a station's rates, even when a
    /// rehearsal flies at 100×.
    pub compression_level: u32,
}

impl Default for CoreOptions {
    fn default() -> Self {
        Self {
            chunk_bytes: 1024 * 1024,
            chunk_max_age: Duration::from_secs(1),
            // A 3-hour flight stays in one file; a station left running for days does not
            // grow one file without end.
            max_file_bytes: Some(1024 * 1024 * 1024),
            max_file_duration: Some(Duration::from_secs(12 * 3600)),
            compression: Compression::Zstd,
            compression_level: 9,
        }
    }
}

/// What the adapter must do, in order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Output {
    /// Open the run's file number `part` (from 1); the bytes that follow are its.
    StartFile {
        /// File number within the run, from 1.
        part: u32,
    },
    /// Append `data` to the current file. It holds `messages` messages (a closed chunk's;
    /// 0 for the header, metadata and summary), which the adapter counts written or lost.
    Bytes {
        /// The bytes.
        data: Vec<u8>,
        /// Messages in `data`.
        messages: u64,
    },
    /// The current file is whole (the last bytes were its summary and footer): close it.
    EndFile,
    /// `messages` accepted earlier will be in no file: the MCAP writer failed with their
    /// chunk open. The adapter counts them lost.
    Lost {
        /// Messages lost.
        messages: u64,
    },
}

/// Why the core refused a call.
#[derive(Debug, Error)]
pub enum WriteError {
    /// A [`ChannelId`] from another recorder.
    #[error("channel {0:?} is not registered here")]
    UnknownChannel(ChannelId),
    /// [`RecorderCore::finish`] was called.
    #[error("the recording is finished")]
    Finished,
    /// A channel could not be registered.
    #[error(transparent)]
    Channel(#[from] ChannelError),
    /// The MCAP writer failed (it writes to memory, so this is a limit, not I/O). The file
    /// in progress should be given up: [`RecorderCore::start_new_file`].
    #[error("MCAP writer: {0}")]
    Mcap(#[from] mcap::McapError),
}

/// The sink the MCAP writer writes to: bytes wait here until the core hands them out.
/// Shared because the writer owns its sink and offers no way back to it.
#[derive(Clone, Default)]
struct SharedBuf(Arc<Mutex<Vec<u8>>>);

impl SharedBuf {
    fn take(&self) -> Vec<u8> {
        std::mem::take(&mut *self.0.lock().unwrap_or_else(PoisonError::into_inner))
    }
}

impl Write for SharedBuf {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .extend_from_slice(buf);
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

type McapWriter = mcap::Writer<NoSeek<SharedBuf>>;

struct Channel {
    spec: ChannelSpec,
    /// Id of the channel in the current file's writer.
    mcap_id: u16,
    /// MCAP sequence number of the next message (per channel, across files).
    sequence: u32,
}

/// The chunk being filled.
struct OpenChunk {
    opened: Duration,
    /// Uncompressed record bytes so far (an estimate of what `mcap` counts), B.
    bytes: u64,
    messages: u64,
}

/// Bytes of a message record before its payload: opcode, length, channel id, sequence,
/// log time, publish time.
const MESSAGE_RECORD_OVERHEAD: u64 = 1 + 8 + 2 + 4 + 8 + 8;

/// Counts since the core started.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CoreStats {
    /// Messages accepted.
    pub messages: u64,
    /// Chunks closed.
    pub chunks: u64,
    /// Files started (a file started again under its number counts again).
    pub files: u32,
}

/// The sans-io recorder: see the module documentation.
pub struct RecorderCore {
    options: CoreOptions,
    info: RecordingInfo,
    channels: Vec<Channel>,
    sink: SharedBuf,
    writer: Option<McapWriter>,
    part: u32,
    file_started: Duration,
    file_bytes: u64,
    chunk: Option<OpenChunk>,
    output: VecDeque<Output>,
    stats: CoreStats,
}

impl RecorderCore {
    /// A recorder starting file 1 at `now` (any monotonic clock; the adapter's starts at zero).
    pub fn new(
        options: CoreOptions,
        info: RecordingInfo,
        now: Duration,
    ) -> Result<Self, WriteError> {
        let mut core = Self {
            options,
            info,
            channels: Vec::new(),
            sink: SharedBuf::default(),
            writer: None,
            part: 0,
            file_started: now,
            file_bytes: 0,
            chunk: None,
            output: VecDeque::new(),
            stats: CoreStats::default(),
        };
        core.start_file(now)?;
        Ok(core)
    }

    /// Registers a channel; its records go into the current chunk, and into every later file.
    pub fn add_channel(
        &mut self,
        now: Duration,
        spec: ChannelSpec,
    ) -> Result<ChannelId, WriteError> {
        if self.channels.iter().any(|c| c.spec.topic() == spec.topic()) {
            return Err(ChannelError::DuplicateTopic {
                topic: spec.topic().to_owned(),
            }
            .into());
        }
        let index = u16::try_from(self.channels.len()).map_err(|_| ChannelError::TooMany {
            max: u16::MAX as usize,
        })?;
        let writer = self.writer.as_mut().ok_or(WriteError::Finished)?;
        let mcap_id = register(writer, &spec)?;
        let record_bytes = (spec.topic().len() + spec.schema_text().len() + 64) as u64;
        self.chunk
            .get_or_insert(OpenChunk {
                opened: now,
                bytes: 0,
                messages: 0,
            })
            .bytes += record_bytes;
        self.channels.push(Channel {
            spec,
            mcap_id,
            sequence: 0,
        });
        Ok(ChannelId(index))
    }

    /// Records `payload` (JSON following the channel's schema) on `channel`, logged at
    /// `log_time` and published at `publish_time` (both nanoseconds since the Unix epoch).
    pub fn write(
        &mut self,
        now: Duration,
        channel: ChannelId,
        log_time: u64,
        publish_time: u64,
        payload: &[u8],
    ) -> Result<(), WriteError> {
        if usize::from(channel.0) >= self.channels.len() {
            return Err(WriteError::UnknownChannel(channel));
        }
        // A chunk past its age closes before it takes more, even if the adapter was late.
        // (This may rotate the file, which renumbers channels: look the id up after.)
        self.handle_timeout(now)?;
        let ch = &mut self.channels[usize::from(channel.0)];
        let header = MessageHeader {
            channel_id: ch.mcap_id,
            sequence: ch.sequence,
            log_time,
            publish_time,
        };
        let writer = self.writer.as_mut().ok_or(WriteError::Finished)?;
        writer.write_to_known_channel(&header, payload)?;
        ch.sequence = ch.sequence.wrapping_add(1);
        self.stats.messages += 1;
        let chunk = self.chunk.get_or_insert(OpenChunk {
            opened: now,
            bytes: 0,
            messages: 0,
        });
        chunk.bytes += MESSAGE_RECORD_OVERHEAD + payload.len() as u64;
        chunk.messages += 1;
        if chunk.bytes >= self.options.chunk_bytes {
            self.close_chunk(now)?;
        }
        Ok(())
    }

    /// Closes the open chunk if it is due (and rotates the file if that is due).
    pub fn handle_timeout(&mut self, now: Duration) -> Result<(), WriteError> {
        match &self.chunk {
            Some(c) if now.saturating_sub(c.opened) >= self.options.chunk_max_age => {
                self.close_chunk(now)
            }
            _ => Ok(()),
        }
    }

    /// When [`Self::handle_timeout`] must next be called; `None` while no chunk is open.
    pub fn poll_timeout(&self) -> Option<Duration> {
        self.chunk
            .as_ref()
            .map(|c| c.opened + self.options.chunk_max_age)
    }

    /// Closes the open chunk now (e.g. before a planned stop, or when the operator asks).
    pub fn flush(&mut self, now: Duration) -> Result<(), WriteError> {
        if self.chunk.is_some() {
            self.close_chunk(now)?;
        }
        Ok(())
    }

    /// Ends the current file and starts the next: what the adapter asks for after the disk
    /// failed it, so later data go to a file that is whole.
    pub fn start_new_file(&mut self, now: Duration) -> Result<(), WriteError> {
        if self.writer.is_none() {
            return Err(WriteError::Finished);
        }
        // A writer that failed cannot write its summary; the file is given up either way.
        let ended = self.end_file();
        self.start_file(now)?;
        ended
    }

    /// Ends the current file and starts it again under the same number: what the adapter asks
    /// for when it removed what it had of the file (it held no message, e.g. a full disk
    /// refused its first bytes), so the run's file numbers keep no gap.
    pub fn restart_file(&mut self, now: Duration) -> Result<(), WriteError> {
        if self.writer.is_none() {
            return Err(WriteError::Finished);
        }
        let ended = self.end_file();
        self.part = self.part.saturating_sub(1);
        self.start_file(now)?;
        ended
    }

    /// Closes the open chunk and writes the file's summary; the core accepts nothing more.
    pub fn finish(&mut self) -> Result<(), WriteError> {
        if self.writer.is_none() {
            return Ok(());
        }
        self.end_file()
    }

    /// The next thing the adapter must do, in order; `None` when there is nothing to do.
    pub fn poll_output(&mut self) -> Option<Output> {
        self.output.pop_front()
    }

    /// Counts since the core started.
    pub fn stats(&self) -> CoreStats {
        self.stats
    }

    /// The current file's number within the run, from 1.
    pub fn part(&self) -> u32 {
        self.part
    }

    fn mcap_options(&self) -> mcap::WriteOptions {
        let compression = match self.options.compression {
            Compression::Zstd => Some(mcap::Compression::Zstd),
            Compression::Lz4 => Some(mcap::Compression::Lz4),
            Compression::None => None,
        };
        mcap::WriteOptions::new()
            .compression(compression)
            .compression_level(self.options.compression_level)
            .library(concat!(
                "stx-record/",
                env!("CARGO_PKG_VERSION"),
                "; ",
                "mcap-rust"
            ))
            // The core closes chunks itself, so it knows when (and what) bytes leave.
            .chunk_size(None)
            // Chunks are assembled in memory and leave whole; nothing seeks back.
            .disable_seeking(true)
            // No compression threads: the core stays a plain value on its caller's thread.
            .compression_threads(0)
            // Per-message indexes inside each chunk (16 B a message, uncompressed) would be a
            // quarter of a flight's file; readers find messages from the chunk indexes, as
            // for a cut file (`read::scan`), and every MCAP reader handles their absence.
            .emit_message_indexes(false)
    }

    fn start_file(&mut self, now: Duration) -> Result<(), WriteError> {
        self.part += 1;
        self.stats.files += 1;
        self.output.push_back(Output::StartFile { part: self.part });
        self.sink = SharedBuf::default();
        self.file_started = now;
        self.file_bytes = 0;
        self.chunk = None;
        let mut writer = self.mcap_options().create(NoSeek::new(self.sink.clone()))?;
        writer.write_metadata(&self.info.to_metadata(self.part))?;
        for ch in &mut self.channels {
            ch.mcap_id = register(&mut writer, &ch.spec)?;
        }
        // The channels' chunk leaves at once, so the file names its channels from the start.
        writer.flush()?;
        self.writer = Some(writer);
        self.emit(0);
        Ok(())
    }

    fn close_chunk(&mut self, now: Duration) -> Result<(), WriteError> {
        let messages = self.chunk.take().map_or(0, |c| c.messages);
        let writer = self.writer.as_mut().ok_or(WriteError::Finished)?;
        if let Err(e) = writer.flush() {
            self.output.push_back(Output::Lost { messages });
            return Err(e.into());
        }
        self.stats.chunks += 1;
        self.emit(messages);
        let too_big = self
            .options
            .max_file_bytes
            .is_some_and(|max| self.file_bytes >= max);
        let too_old = self
            .options
            .max_file_duration
            .is_some_and(|max| now.saturating_sub(self.file_started) >= max);
        if too_big || too_old {
            self.end_file()?;
            self.start_file(now)?;
        }
        Ok(())
    }

    fn end_file(&mut self) -> Result<(), WriteError> {
        let messages = self.chunk.take().map_or(0, |c| c.messages);
        let result = match self.writer.take() {
            Some(mut writer) => writer.finish().map(|_| ()).map_err(WriteError::from),
            None => Ok(()),
        };
        if result.is_ok() {
            self.emit(messages);
        } else {
            // Whatever the failed writer left is no file; its open chunk is lost.
            self.emit(0);
            self.output.push_back(Output::Lost { messages });
        }
        self.output.push_back(Output::EndFile);
        result
    }

    /// Hands out what the writer has written since the last call.
    fn emit(&mut self, messages: u64) {
        let data = self.sink.take();
        if !data.is_empty() || messages > 0 {
            self.file_bytes += data.len() as u64;
            self.output.push_back(Output::Bytes { data, messages });
        }
    }
}

fn register(writer: &mut McapWriter, spec: &ChannelSpec) -> Result<u16, mcap::McapError> {
    let schema_id = writer.add_schema(
        spec.schema_name(),
        SCHEMA_ENCODING,
        spec.schema_text().as_bytes(),
    )?;
    writer.add_channel(schema_id, spec.topic(), MESSAGE_ENCODING, &BTreeMap::new())
}

#[cfg(test)]
mod tests;
