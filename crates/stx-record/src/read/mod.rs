//! Reading a recording: what it holds, from its summary (an index read at the end of the
//! file, not a scan) when the file is whole, or from one pass over it when it is not; and
//! its messages in log-time order from any time, through the chunk indexes, so a seek reads
//! only the chunks after it. A file without summary is indexed by one pass over it (`scan`).

use std::collections::HashMap;
use std::fs::File;
use std::io::{self, Read, Seek, SeekFrom};
use std::path::Path;
use std::sync::Arc;

use mcap::records::{Metadata, Record, op};
use mcap::sans_io::{
    IndexedReadEvent, IndexedReader, IndexedReaderOptions, SummaryReadEvent, SummaryReader,
    SummaryReaderOptions,
};
use mcap::{McapError, Summary};

use crate::info::RecordingInfo;
use crate::records::MAX_CHUNK_BYTES;
use scan::scan;

mod error;
mod scan;

pub use error::ReadError;

/// Where a recording's index came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IndexSource {
    /// The file's own summary: the file is whole.
    Summary,
    /// A pass over the file, which has no (readable) summary.
    Scan {
        /// Where the file stops short of a whole data section (the offset of the record it
        /// ends inside, or its length); `None` when only the summary is unreadable.
        cut_at: Option<u64>,
        /// Whole chunks that could not be read, skipped.
        bad_chunks: u32,
    },
}

/// One channel of a recording.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ChannelInfo {
    /// MCAP channel id (what [`RecordedMessage::channel_id`] refers to).
    pub id: u16,
    /// Topic.
    pub topic: Arc<str>,
    /// Schema name (empty when the channel has no schema).
    pub schema_name: String,
    /// Schema encoding (`jsonschema` for stx's channels).
    pub schema_encoding: String,
    /// Message encoding (`json` for stx's channels).
    pub message_encoding: String,
    /// Messages on the channel.
    pub message_count: u64,
}

/// A message read back.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RecordedMessage {
    /// MCAP channel id.
    pub channel_id: u16,
    /// The channel's topic.
    pub topic: Arc<str>,
    /// Sequence number on its channel.
    pub sequence: u32,
    /// Log time, ns since the Unix epoch.
    pub log_time: u64,
    /// Publish time, ns since the Unix epoch.
    pub publish_time: u64,
    /// The payload (JSON for stx's channels).
    pub data: Vec<u8>,
}

/// An open recording.
pub struct Recording<R> {
    source: R,
    summary: Summary,
    channels: Vec<ChannelInfo>,
    topics: HashMap<u16, Arc<str>>,
    metadata: Vec<Metadata>,
    index: IndexSource,
}

impl Recording<File> {
    /// Opens the recording at `path`.
    pub fn open(path: &Path) -> Result<Self, ReadError> {
        Self::from_reader(File::open(path)?)
    }
}

impl<R: Read + Seek> Recording<R> {
    /// Reads the index of the recording in `source`: its summary if it has one, else a scan.
    pub fn from_reader(mut source: R) -> Result<Self, ReadError> {
        let len = source.seek(SeekFrom::End(0))?;
        // Any failure to read a summary (cut file, no footer, bad CRC) means: scan.
        let indexed = read_summary(&mut source, len).ok().flatten().filter(|s| {
            s.stats
                .as_ref()
                .is_some_and(|st| st.message_count == 0 || !s.chunk_indexes.is_empty())
        });
        let (summary, metadata, index) = match indexed {
            Some(summary) => {
                // An index pointing past the end of the file is corruption, caught here
                // rather than as a short read in the middle of a replay.
                for chunk in &summary.chunk_indexes {
                    let end = chunk.chunk_start_offset.checked_add(chunk.chunk_length);
                    if end.is_none_or(|end| end > len) {
                        return Err(ReadError::Corrupt {
                            offset: chunk.chunk_start_offset,
                            source: McapError::BadIndex,
                        });
                    }
                }
                let metadata = read_metadata(&mut source, &summary, len)?;
                (summary, metadata, IndexSource::Summary)
            }
            None => {
                source.seek(SeekFrom::Start(0))?;
                let scanned = scan(io::BufReader::new(&mut source))?;
                let index = IndexSource::Scan {
                    cut_at: scanned.cut_at,
                    bad_chunks: scanned.bad_chunks,
                };
                (scanned.summary, scanned.metadata, index)
            }
        };
        let counts = summary
            .stats
            .as_ref()
            .map(|s| s.channel_message_counts.clone())
            .unwrap_or_default();
        let mut channels: Vec<ChannelInfo> = summary
            .channels
            .values()
            .map(|c| ChannelInfo {
                id: c.id,
                topic: Arc::from(c.topic.as_str()),
                schema_name: c
                    .schema
                    .as_ref()
                    .map(|s| s.name.clone())
                    .unwrap_or_default(),
                schema_encoding: c
                    .schema
                    .as_ref()
                    .map(|s| s.encoding.clone())
                    .unwrap_or_default(),
                message_encoding: c.message_encoding.clone(),
                message_count: counts.get(&c.id).copied().unwrap_or(0),
            })
            .collect();
        channels.sort_by_key(|c| c.id);
        let topics = channels.iter().map(|c| (c.id, c.topic.clone())).collect();
        Ok(Self {
            source,
            summary,
            channels,
            topics,
            metadata,
            index,
        })
    }

    /// The schema (for stx's channels a JSON Schema) of the channel on `topic`.
    pub fn schema(&self, topic: &str) -> Option<&[u8]> {
        self.summary
            .channels
            .values()
            .find(|c| c.topic == topic)
            .and_then(|c| c.schema.as_ref())
            .map(|s| &s.data[..])
    }

    /// The channels, by id.
    pub fn channels(&self) -> &[ChannelInfo] {
        &self.channels
    }

    /// The channel on `topic`, if any.
    pub fn channel(&self, topic: &str) -> Option<&ChannelInfo> {
        self.channels.iter().find(|c| &*c.topic == topic)
    }

    /// Messages in the recording (in its readable chunks, for a scanned file).
    pub fn message_count(&self) -> u64 {
        self.summary.stats.as_ref().map_or(0, |s| s.message_count)
    }

    /// Log times of the first and last message, ns since the Unix epoch; `None` when empty.
    pub fn time_range(&self) -> Option<(u64, u64)> {
        self.summary
            .stats
            .as_ref()
            .filter(|s| s.message_count > 0)
            .map(|s| (s.message_start_time, s.message_end_time))
    }

    /// Chunks indexed (and so readable).
    pub fn chunk_count(&self) -> usize {
        self.summary.chunk_indexes.len()
    }

    /// The metadata records.
    pub fn metadata(&self) -> &[Metadata] {
        &self.metadata
    }

    /// stx's metadata record, and the file's part number in its run.
    pub fn info(&self) -> Option<(RecordingInfo, u32)> {
        self.metadata.iter().find_map(RecordingInfo::from_metadata)
    }

    /// Whether the index is the file's own summary or a scan.
    pub fn index(&self) -> IndexSource {
        self.index
    }

    /// Every message, in log-time order.
    pub fn messages(&mut self) -> Result<Messages<'_, R>, ReadError> {
        self.messages_from(0)
    }

    /// The messages logged at or after `start` (ns since the Unix epoch), in log-time order.
    /// Only the chunks that can hold them are read.
    pub fn messages_from(&mut self, start: u64) -> Result<Messages<'_, R>, ReadError> {
        let mut options = IndexedReaderOptions::new().starting_at(start);
        options.record_length_limit = usize::try_from(MAX_CHUNK_BYTES).ok();
        let reader = IndexedReader::new_with_options(&self.summary, options)?;
        Ok(Messages {
            source: &mut self.source,
            topics: &self.topics,
            reader,
            buf: Vec::new(),
            done: false,
        })
    }
}

/// Messages of a [`Recording`] in log-time order; stops after the first error.
pub struct Messages<'a, R> {
    source: &'a mut R,
    topics: &'a HashMap<u16, Arc<str>>,
    reader: IndexedReader,
    buf: Vec<u8>,
    done: bool,
}

impl<R: Read + Seek> Iterator for Messages<'_, R> {
    type Item = Result<RecordedMessage, ReadError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        loop {
            let event = match self.reader.next_event() {
                None => {
                    self.done = true;
                    return None;
                }
                Some(Err(e)) => {
                    self.done = true;
                    return Some(Err(e.into()));
                }
                Some(Ok(event)) => event,
            };
            let (offset, length) = match event {
                IndexedReadEvent::Message { header, data } => {
                    let topic = self
                        .topics
                        .get(&header.channel_id)
                        .cloned()
                        .unwrap_or_else(|| Arc::from(""));
                    return Some(Ok(RecordedMessage {
                        channel_id: header.channel_id,
                        topic,
                        sequence: header.sequence,
                        log_time: header.log_time,
                        publish_time: header.publish_time,
                        data: data.to_vec(),
                    }));
                }
                IndexedReadEvent::ReadChunkRequest { offset, length } => (offset, length),
            };
            if let Err(e) = self.load_chunk(offset, length) {
                self.done = true;
                return Some(Err(e));
            }
        }
    }
}

impl<R: Read + Seek> Messages<'_, R> {
    fn load_chunk(&mut self, offset: u64, length: usize) -> Result<(), ReadError> {
        self.source.seek(SeekFrom::Start(offset))?;
        self.buf.resize(length, 0);
        self.source.read_exact(&mut self.buf)?;
        self.reader.insert_chunk_record_data(offset, &self.buf)?;
        Ok(())
    }
}

/// The summary at the end of `source` (`len` bytes), through `mcap`'s sans-io reader.
fn read_summary<R: Read + Seek>(source: &mut R, len: u64) -> Result<Option<Summary>, ReadError> {
    let options = SummaryReaderOptions::default().with_file_size(len);
    let mut reader = SummaryReader::new_with_options(options);
    while let Some(event) = reader.next_event() {
        match event? {
            SummaryReadEvent::ReadRequest(n) => {
                let got = source.read(reader.insert(n))?;
                reader.notify_read(got);
            }
            SummaryReadEvent::SeekRequest(to) => {
                let pos = source.seek(to)?;
                reader.notify_seeked(pos);
            }
        }
    }
    Ok(reader.finish())
}

/// The metadata records the summary points at.
fn read_metadata<R: Read + Seek>(
    source: &mut R,
    summary: &Summary,
    len: u64,
) -> Result<Vec<Metadata>, ReadError> {
    let mut out = Vec::new();
    for index in &summary.metadata_indexes {
        let offset = index.offset;
        if index.length < 9 || offset.saturating_add(index.length) > len {
            return Err(ReadError::Corrupt {
                offset,
                source: McapError::BadIndex,
            });
        }
        source.seek(SeekFrom::Start(offset))?;
        let mut record = Vec::new();
        (&mut *source).take(index.length).read_to_end(&mut record)?;
        if record.first() != Some(&op::METADATA) {
            return Err(ReadError::Corrupt {
                offset,
                source: McapError::BadIndex,
            });
        }
        match mcap::parse_record(op::METADATA, &record[9..]) {
            Ok(Record::Metadata(m)) => out.push(m),
            Ok(_) => {}
            Err(source) => return Err(ReadError::Corrupt { offset, source }),
        }
    }
    Ok(out)
}
