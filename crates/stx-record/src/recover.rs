//! Recovery: a clean, finished copy of a recording cut at any byte (the station killed, the
//! disk full), holding every whole chunk up to the cut and every message that can still be
//! read from the chunk the cut fell in.
//!
//! Whole chunks are copied only if their CRC checks; a whole chunk that fails is skipped and
//! counted, never half-copied. The chunk the cut fell in has no whole CRC to check: its
//! messages that decompress whole from the bytes present are copied (compressed data
//! decode as a true prefix), and counted apart. Channel and schema ids, sequence numbers
//! and times are kept, so the copy is the same recording with its summary.

use std::borrow::Cow;
use std::fs::File;
use std::io::{self, BufReader, BufWriter, Read, Seek, Write};
use std::path::Path;

use mcap::records::{Record, op};
use mcap::{Attachment, McapError, Message, Writer};
use thiserror::Error;

use crate::records::{Catalog, ChunkContents, ChunkDecoder, Step, Walk};

/// Why a recovery failed.
#[derive(Debug, Error)]
pub enum RecoverError {
    /// The input does not start with MCAP's magic bytes.
    #[error("not an MCAP file (no MCAP magic at its start)")]
    NotMcap,
    /// The input could not be read.
    #[error("reading the recording: {0}")]
    Read(#[source] io::Error),
    /// The copy could not be written.
    #[error("writing the recovered copy: {0}")]
    Write(#[source] McapError),
}

/// What a recovery found and kept.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct RecoverReport {
    /// Whole chunks copied.
    pub chunks: u64,
    /// Whole chunks skipped because they did not read (bad CRC or compression).
    pub bad_chunks: u64,
    /// Messages copied.
    pub messages: u64,
    /// Of those, messages read from the chunk the cut fell in.
    pub from_cut_chunk: u64,
    /// Messages skipped because their channel was never defined.
    pub orphan_messages: u64,
    /// Metadata records copied.
    pub metadata: u64,
    /// Where the input stops short of a whole data section: the offset of the record it ends
    /// inside, or its length if it ends between records. `None`: the data section was whole
    /// (the input reached its data-end record).
    pub cut_at: Option<u64>,
}

/// Copies what can be read of the recording in `input` to `output`, finished.
pub fn recover<R: Read, W: Write + Seek>(
    input: R,
    output: W,
) -> Result<RecoverReport, RecoverError> {
    let mut walk = Walk::new(input)
        .map_err(RecoverError::Read)?
        .ok_or(RecoverError::NotMcap)?;
    let options = mcap::WriteOptions::new()
        .library(concat!(
            "stx-record/",
            env!("CARGO_PKG_VERSION"),
            " recover"
        ))
        .compression_threads(0);
    let mut copy = Copy {
        writer: None,
        options: Some((options, output)),
        catalog: Catalog::default(),
        report: RecoverReport::default(),
    };
    let mut data_end = false;
    let mut decoder = ChunkDecoder::new();
    while let Some(step) = walk.next_step().map_err(RecoverError::Read)? {
        match step {
            Step::Whole { opcode, body, .. } if opcode == op::CHUNK => {
                let contents = decoder.whole(&body);
                if contents.error.is_some() {
                    copy.report.bad_chunks += 1;
                } else {
                    copy.report.chunks += 1;
                    copy.chunk(contents, false)?;
                }
            }
            Step::Whole { opcode, .. } if opcode == op::DATA_END => {
                data_end = true;
                break;
            }
            Step::Whole { opcode, body, .. } => match mcap::parse_record(opcode, &body) {
                Ok(record) => copy.record(record)?,
                // A malformed record outside chunks carries no messages: skip it.
                Err(_) => continue,
            },
            Step::Cut {
                opcode,
                declared_len,
                body,
            } => {
                if opcode == Some(op::CHUNK) {
                    copy.chunk(decoder.cut(declared_len, &body), true)?;
                }
            }
        }
    }
    if !data_end {
        copy.report.cut_at = Some(walk.offset());
    }
    let writer = copy.writer()?;
    writer.finish().map_err(RecoverError::Write)?;
    Ok(copy.report)
}

/// [`recover`] from the file `input` to a new file `output` (replaced if it exists).
pub fn recover_file(input: &Path, output: &Path) -> Result<RecoverReport, RecoverError> {
    let reader = BufReader::new(File::open(input).map_err(RecoverError::Read)?);
    let file = File::create(output).map_err(|e| RecoverError::Write(e.into()))?;
    let report = {
        let mut out = BufWriter::new(file);
        let report = recover(reader, &mut out)?;
        out.flush().map_err(|e| RecoverError::Write(e.into()))?;
        out.into_inner()
            .map_err(|e| RecoverError::Write(e.into_error().into()))?
            .sync_all()
            .map_err(|e| RecoverError::Write(e.into()))?;
        report
    };
    Ok(report)
}

struct Copy<W: Write + Seek> {
    writer: Option<Writer<W>>,
    /// What the writer will be made of, until the input's header (or first record) is seen.
    options: Option<(mcap::WriteOptions, W)>,
    catalog: Catalog,
    report: RecoverReport,
}

impl<W: Write + Seek> Copy<W> {
    fn writer(&mut self) -> Result<&mut Writer<W>, RecoverError> {
        if self.writer.is_none() {
            self.start("")?;
        }
        self.writer
            .as_mut()
            .ok_or(RecoverError::Write(McapError::AttemptedWriteAfterFailure))
    }

    fn start(&mut self, profile: &str) -> Result<(), RecoverError> {
        if let Some((options, output)) = self.options.take() {
            let writer = options
                .profile(profile)
                .create(output)
                .map_err(RecoverError::Write)?;
            self.writer = Some(writer);
        }
        Ok(())
    }

    fn chunk(&mut self, contents: ChunkContents, cut: bool) -> Result<(), RecoverError> {
        for record in contents.records {
            let before = self.report.messages;
            self.record(record)?;
            if cut {
                self.report.from_cut_chunk += self.report.messages - before;
            }
        }
        Ok(())
    }

    fn record(&mut self, record: Record<'_>) -> Result<(), RecoverError> {
        match record {
            Record::Header(h) => self.start(&h.profile)?,
            Record::Schema { .. } | Record::Channel(_) => self.catalog.note(&record),
            Record::Message { header, data } => {
                let Some(channel) = self.catalog.channels.get(&header.channel_id).cloned() else {
                    self.report.orphan_messages += 1;
                    return Ok(());
                };
                let message = Message {
                    channel,
                    sequence: header.sequence,
                    log_time: header.log_time,
                    publish_time: header.publish_time,
                    data: Cow::Borrowed(&data),
                };
                self.writer()?
                    .write(&message)
                    .map_err(RecoverError::Write)?;
                self.report.messages += 1;
            }
            Record::Metadata(m) => {
                self.writer()?
                    .write_metadata(&m)
                    .map_err(RecoverError::Write)?;
                self.report.metadata += 1;
            }
            Record::Attachment { header, data, .. } => {
                let attachment = Attachment {
                    log_time: header.log_time,
                    create_time: header.create_time,
                    name: header.name,
                    media_type: header.media_type,
                    data,
                };
                self.writer()?
                    .attach(&attachment)
                    .map_err(RecoverError::Write)?;
            }
            // Indexes and statistics are rebuilt by the writer; chunks never nest.
            _ => {}
        }
        Ok(())
    }
}
