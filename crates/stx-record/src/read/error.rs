//! Why a recording could not be read.

use std::io;

use mcap::McapError;
use thiserror::Error;

/// Why a recording could not be read.
#[derive(Debug, Error)]
pub enum ReadError {
    /// The file could not be read.
    #[error("reading the recording: {0}")]
    Io(#[from] io::Error),
    /// The file does not start with MCAP's magic bytes.
    #[error("not an MCAP file (no MCAP magic at its start)")]
    NotMcap,
    /// A message outside any chunk: this reader seeks through chunks only.
    #[error("message outside a chunk at byte {offset}: rewrite the file with `stx record recover`")]
    NotChunked {
        /// Offset of the message record.
        offset: u64,
    },
    /// A record that does not parse.
    #[error("malformed record at byte {offset}: {source}")]
    Corrupt {
        /// Offset of the record.
        offset: u64,
        /// What `mcap` said.
        source: McapError,
    },
    /// `mcap` refused the file's index or a chunk.
    #[error("MCAP: {0}")]
    Mcap(#[from] McapError),
}
