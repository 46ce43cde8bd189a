//! MCAP's top-level records walked one by one, with their offsets, telling a record cut by
//! the end of the file from a whole one — what the scan of a file without summary and the
//! recovery of a cut file need, and what `mcap`'s readers do not report. Record bodies are
//! parsed by `mcap` itself ([`mcap::parse_record`], [`mcap::read::ChunkReader`]).

use std::borrow::Cow;
use std::collections::HashMap;
use std::io::{self, Read};
use std::sync::Arc;

use mcap::records::{ChunkHeader, Record, op};
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use mcap::{Channel, McapError, Schema};

/// The largest chunk we decompress, B: stx writes chunks of about 1 MiB and other writers
/// not much more; a larger size in a header is corruption, not a reason to allocate it.
pub(crate) const MAX_CHUNK_BYTES: u64 = 256 * 1024 * 1024;

/// Bytes of a record's opcode and length.
const RECORD_PREFIX: u64 = 1 + 8;

/// One step of the walk.
pub(crate) enum Step {
    /// A whole record at `offset`.
    Whole {
        offset: u64,
        opcode: u8,
        body: Vec<u8>,
    },
    /// The file ends inside the record at `offset` of `declared_len` bytes (when its length
    /// could be read); `body` is what there is of it.
    Cut {
        opcode: Option<u8>,
        declared_len: u64,
        body: Vec<u8>,
    },
}

/// Walks the records of an MCAP stream after its start magic.
pub(crate) struct Walk<R> {
    reader: R,
    offset: u64,
    done: bool,
}

impl<R: Read> Walk<R> {
    /// Checks the start magic. `Ok(None)`: the stream is not MCAP (or is shorter than its
    /// magic).
    pub(crate) fn new(mut reader: R) -> io::Result<Option<Self>> {
        let mut magic = Vec::with_capacity(mcap::MAGIC.len());
        (&mut reader)
            .take(mcap::MAGIC.len() as u64)
            .read_to_end(&mut magic)?;
        if magic != mcap::MAGIC {
            return Ok(None);
        }
        Ok(Some(Self {
            reader,
            offset: mcap::MAGIC.len() as u64,
            done: false,
        }))
    }

    /// Where the walk is: the offset after the last whole record (the start of a cut one).
    pub(crate) fn offset(&self) -> u64 {
        self.offset
    }

    /// The next record; `None` at the end of the stream, and after a footer or a cut record.
    pub(crate) fn next_step(&mut self) -> io::Result<Option<Step>> {
        if self.done {
            return Ok(None);
        }
        let offset = self.offset;
        let mut prefix = Vec::with_capacity(RECORD_PREFIX as usize);
        (&mut self.reader)
            .take(RECORD_PREFIX)
            .read_to_end(&mut prefix)?;
        if prefix.is_empty() {
            self.done = true;
            return Ok(None);
        }
        let opcode = prefix[0];
        let Ok(len_bytes) = <[u8; 8]>::try_from(prefix.get(1..9).unwrap_or_default()) else {
            self.done = true;
            return Ok(Some(Step::Cut {
                opcode: Some(opcode),
                declared_len: 0,
                body: Vec::new(),
            }));
        };
        let len = u64::from_le_bytes(len_bytes);
        // Read through `take`: a corrupt length cannot make us allocate more than the file has.
        let mut body = Vec::new();
        (&mut self.reader).take(len).read_to_end(&mut body)?;
        if (body.len() as u64) < len {
            self.done = true;
            return Ok(Some(Step::Cut {
                opcode: Some(opcode),
                declared_len: len,
                body,
            }));
        }
        self.offset += RECORD_PREFIX + len;
        if opcode == op::FOOTER {
            self.done = true;
        }
        Ok(Some(Step::Whole {
            offset,
            opcode,
            body,
        }))
    }
}

/// A chunk's records, decompressed; `error` says why reading stopped early, if it did.
pub(crate) struct ChunkContents {
    pub(crate) header: Option<ChunkHeader>,
    pub(crate) records: Vec<Record<'static>>,
    pub(crate) error: Option<McapError>,
}

/// Decodes chunk records with one `mcap` sans-io reader kept across chunks, so its
/// decompressors are made once, not once a chunk.
pub(crate) struct ChunkDecoder {
    reader: LinearReader,
}

impl ChunkDecoder {
    pub(crate) fn new() -> Self {
        Self {
            reader: Self::fresh(),
        }
    }

    fn fresh() -> LinearReader {
        LinearReader::new_with_options(
            LinearReaderOptions::default()
                .with_skip_start_magic(true)
                .with_skip_end_magic(true)
                .with_validate_chunk_crcs(true)
                .with_record_length_limit(MAX_CHUNK_BYTES as usize),
        )
    }

    /// The records of a whole chunk record's `body`, its CRC checked. With an `error`, the
    /// records are not to be trusted (the CRC is checked after they decompress).
    pub(crate) fn whole(&mut self, body: &[u8]) -> ChunkContents {
        let header = parse_chunk_header(body);
        // The compressed data must fill the record exactly, or the reader would run on into
        // whatever we feed it next.
        match header {
            Some((header, data_start))
                if data_start as u64 + header.compressed_size == body.len() as u64 =>
            {
                self.decode(header, body.len() as u64, body, true)
            }
            Some((header, _)) => ChunkContents {
                header: Some(header),
                records: Vec::new(),
                error: Some(McapError::BadChunkLength {
                    header: body.len() as u64,
                    available: body.len() as u64,
                }),
            },
            None => ChunkContents {
                header: None,
                records: Vec::new(),
                error: Some(McapError::UnexpectedEof),
            },
        }
    }

    /// What can be read from the first `body.len()` bytes of a chunk record of `declared_len`
    /// bytes: the records that decompress whole from the bytes present (a true prefix of the
    /// chunk, though its CRC, which covers the whole chunk, cannot be checked).
    pub(crate) fn cut(&mut self, declared_len: u64, body: &[u8]) -> ChunkContents {
        match parse_chunk_header(body) {
            Some((header, _)) => self.decode(header, declared_len, body, false),
            None => ChunkContents {
                header: None,
                records: Vec::new(),
                error: Some(McapError::UnexpectedEof),
            },
        }
    }

    fn decode(
        &mut self,
        header: ChunkHeader,
        declared_len: u64,
        body: &[u8],
        whole: bool,
    ) -> ChunkContents {
        let mut contents = ChunkContents {
            header: Some(header.clone()),
            records: Vec::new(),
            error: None,
        };
        if header.uncompressed_size > MAX_CHUNK_BYTES {
            contents.error = Some(McapError::ChunkTooLarge(header.uncompressed_size));
            return contents;
        }
        let mut prefix = [0u8; RECORD_PREFIX as usize];
        prefix[0] = op::CHUNK;
        prefix[1..].copy_from_slice(&declared_len.to_le_bytes());
        for part in [&prefix[..], body] {
            self.reader.insert(part.len()).copy_from_slice(part);
            self.reader.notify_read(part.len());
        }
        // Records until the reader asks for more: the chunk is done (whole), or the bytes
        // present are used up (cut).
        while let Some(event) = self.reader.next_event() {
            match event {
                Ok(LinearReadEvent::Record { data, opcode }) => {
                    match mcap::parse_record(opcode, data) {
                        Ok(record) => contents.records.push(record.into_owned()),
                        Err(e) => {
                            contents.error = Some(e);
                            break;
                        }
                    }
                }
                Ok(LinearReadEvent::ReadRequest(_)) => break,
                Err(e) => {
                    contents.error = Some(e);
                    break;
                }
            }
        }
        if contents.error.is_some() || !whole {
            // Mid-chunk or failed: the next chunk needs a reader in a known state.
            self.reader = Self::fresh();
        }
        contents
    }
}

/// The schemas and channels met so far, linked as `mcap`'s messages want them.
#[derive(Default)]
pub(crate) struct Catalog {
    pub(crate) schemas: HashMap<u16, Arc<Schema<'static>>>,
    pub(crate) channels: HashMap<u16, Arc<Channel<'static>>>,
}

impl Catalog {
    /// Takes note of `record` if it is a schema or a channel (a channel whose schema is
    /// unknown keeps none).
    pub(crate) fn note(&mut self, record: &Record<'_>) {
        match record {
            Record::Schema { header, data } => {
                self.schemas.insert(
                    header.id,
                    Arc::new(Schema {
                        id: header.id,
                        name: header.name.clone(),
                        encoding: header.encoding.clone(),
                        data: Cow::Owned(data.to_vec()),
                    }),
                );
            }
            Record::Channel(c) => {
                self.channels.insert(
                    c.id,
                    Arc::new(Channel {
                        id: c.id,
                        topic: c.topic.clone(),
                        schema: self.schemas.get(&c.schema_id).cloned(),
                        message_encoding: c.message_encoding.clone(),
                        metadata: c.metadata.clone(),
                    }),
                );
            }
            _ => {}
        }
    }
}

/// A chunk record's header, parsed by hand because `mcap` parses only whole records; the
/// offset of its compressed data in `body`. `None` if `body` is shorter than the header.
fn parse_chunk_header(body: &[u8]) -> Option<(ChunkHeader, usize)> {
    let u64_at = |at: usize| -> Option<u64> {
        Some(u64::from_le_bytes(body.get(at..at + 8)?.try_into().ok()?))
    };
    let u32_at = |at: usize| -> Option<u32> {
        Some(u32::from_le_bytes(body.get(at..at + 4)?.try_into().ok()?))
    };
    let message_start_time = u64_at(0)?;
    let message_end_time = u64_at(8)?;
    let uncompressed_size = u64_at(16)?;
    let uncompressed_crc = u32_at(24)?;
    let name_len = usize::try_from(u32_at(28)?).ok()?;
    let name_end = 32usize.checked_add(name_len)?;
    let compression = String::from_utf8(body.get(32..name_end)?.to_vec()).ok()?;
    let compressed_size = u64_at(name_end)?;
    Some((
        ChunkHeader {
            message_start_time,
            message_end_time,
            uncompressed_size,
            uncompressed_crc,
            compression,
            compressed_size,
        },
        name_end + 8,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stream_that_is_not_mcap_is_refused() {
        assert!(Walk::new(&b"hello world, not mcap"[..]).unwrap().is_none());
        assert!(Walk::new(&b""[..]).unwrap().is_none());
    }

    #[test]
    fn a_record_cut_in_its_length_or_body_is_cut() {
        let mut bytes = mcap::MAGIC.to_vec();
        bytes.extend([op::METADATA, 5, 0, 0]);
        let mut walk = Walk::new(&bytes[..]).unwrap().unwrap();
        assert!(matches!(walk.next_step().unwrap(), Some(Step::Cut { .. })));
        assert_eq!(walk.offset(), 8);
        assert!(walk.next_step().unwrap().is_none());

        let mut bytes = mcap::MAGIC.to_vec();
        bytes.push(op::METADATA);
        bytes.extend(1000u64.to_le_bytes());
        bytes.extend([1, 2, 3]);
        let mut walk = Walk::new(&bytes[..]).unwrap().unwrap();
        match walk.next_step().unwrap() {
            Some(Step::Cut { body, .. }) => assert_eq!(body, [1, 2, 3]),
            _ => panic!("not cut"),
        }
    }

    #[test]
    fn a_chunk_header_cut_short_reads_nothing() {
        let contents = ChunkDecoder::new().cut(1000, &[0; 20]);
        assert!(contents.records.is_empty());
        assert!(contents.error.is_some());
    }
}
