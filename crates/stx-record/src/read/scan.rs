//! The index of a file that has none (the station was killed before writing the summary):
//! one pass over its records builds what the summary would have said — channels, schemas,
//! message counts, time range and chunk indexes — so reading and seeking work the same way
//! afterwards. Only whole chunks are indexed; a chunk cut by the end of the file is left to
//! `recover`.

use std::collections::BTreeMap;
use std::io::Read;

use mcap::records::{ChunkIndex, Metadata, Record, Statistics, op};
use mcap::{McapError, Summary};

use super::error::ReadError;
use crate::records::{Catalog, ChunkDecoder, Step, Walk};

/// What the scan found.
pub(crate) struct Scanned {
    pub(crate) summary: Summary,
    pub(crate) metadata: Vec<Metadata>,
    /// Where the file stops short of a whole data section (the offset of the record it ends
    /// inside, or its length); `None` when the data section is whole.
    pub(crate) cut_at: Option<u64>,
    /// Whole chunks that could not be read (bad CRC, bad compression), skipped.
    pub(crate) bad_chunks: u32,
}

pub(crate) fn scan(reader: impl Read) -> Result<Scanned, ReadError> {
    let mut walk = Walk::new(reader)?.ok_or(ReadError::NotMcap)?;
    let mut catalog = Catalog::default();
    let mut decoder = ChunkDecoder::new();
    let mut chunk_indexes = Vec::new();
    let mut metadata = Vec::new();
    let mut counts: BTreeMap<u16, u64> = BTreeMap::new();
    let mut bounds: Option<(u64, u64)> = None;
    let mut data_end = false;
    let mut bad_chunks = 0;
    while let Some(step) = walk.next_step()? {
        let (offset, opcode, body) = match step {
            Step::Whole {
                offset,
                opcode,
                body,
            } => (offset, opcode, body),
            Step::Cut { .. } => break,
        };
        match opcode {
            op::CHUNK => {
                let contents = decoder.whole(&body);
                let Some(header) = contents.header.filter(|_| contents.error.is_none()) else {
                    bad_chunks += 1;
                    continue;
                };
                let mut messages = 0;
                for record in &contents.records {
                    catalog.note(record);
                    if let Record::Message { header, .. } = record {
                        messages += 1;
                        *counts.entry(header.channel_id).or_default() += 1;
                        let t = header.log_time;
                        bounds = Some(bounds.map_or((t, t), |(a, b)| (a.min(t), b.max(t))));
                    }
                }
                if messages > 0 {
                    chunk_indexes.push(ChunkIndex {
                        message_start_time: header.message_start_time,
                        message_end_time: header.message_end_time,
                        chunk_start_offset: offset,
                        chunk_length: 1 + 8 + body.len() as u64,
                        // The reader decodes whole chunks; it needs no message indexes.
                        message_index_offsets: BTreeMap::new(),
                        message_index_length: 0,
                        compression: header.compression,
                        compressed_size: header.compressed_size,
                        uncompressed_size: header.uncompressed_size,
                    });
                }
            }
            op::SCHEMA | op::CHANNEL => catalog.note(&parse(offset, opcode, &body)?),
            op::METADATA => {
                if let Record::Metadata(m) = parse(offset, opcode, &body)? {
                    metadata.push(m);
                }
            }
            op::MESSAGE => return Err(ReadError::NotChunked { offset }),
            // The data section ends here; what follows is a summary that did not read.
            op::DATA_END => {
                data_end = true;
                break;
            }
            _ => {}
        }
    }
    let cut_at = (!data_end).then(|| walk.offset());
    let (message_start_time, message_end_time) = bounds.unwrap_or((0, 0));
    let stats = Statistics {
        message_count: counts.values().sum(),
        schema_count: u16::try_from(catalog.schemas.len()).unwrap_or(u16::MAX),
        channel_count: catalog.channels.len() as u32,
        attachment_count: 0,
        metadata_count: metadata.len() as u32,
        chunk_count: chunk_indexes.len() as u32,
        message_start_time,
        message_end_time,
        channel_message_counts: counts,
    };
    Ok(Scanned {
        summary: Summary {
            stats: Some(stats),
            channels: catalog.channels,
            schemas: catalog.schemas,
            chunk_indexes,
            attachment_indexes: Vec::new(),
            metadata_indexes: Vec::new(),
        },
        metadata,
        cut_at,
        bad_chunks,
    })
}

fn parse(offset: u64, opcode: u8, body: &[u8]) -> Result<Record<'static>, ReadError> {
    mcap::parse_record(opcode, body)
        .map(Record::into_owned)
        .map_err(|source: McapError| ReadError::Corrupt { offset, source })
}
