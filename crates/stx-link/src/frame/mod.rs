//! MAVLink framing: bytes in, decoded messages with their headers out, and back.
//!
//! Radios and serial lines deliver frames cut anywhere, glued together, corrupted, or mixed
//! with noise; this module is the one place that turns such a byte stream into messages, so
//! everything above it sees only whole, checked messages.
//!
//! [`FrameDecoder`] is sans-io: [`FrameDecoder::push`] any chunk, then call
//! [`FrameDecoder::poll`] until it returns `None`. Each call yields either a [`Frame`] (header
//! plus [`MavMessage`](crate::MavMessage)) or a [`FrameError`] saying why a candidate frame was dropped. After a
//! bad checksum it resynchronises on the next magic byte after the failed candidate's start,
//! so a valid frame hidden inside a corrupted one is still found. Nothing is silently
//! swallowed: [`DecoderStats`] counts CRC errors, unknown message ids, parse errors, bytes
//! discarded between frames, MAVLink 1 frames (accepted or refused), signing refusals and
//! truncated frames at end of stream. Lengths read from the wire are bounded by the format
//! (one byte, at most 255) and by [`MAX_FRAME_LEN`]; no wire value is used to index without a
//! checked access.
//!
//! [`FrameEncoder`] serialises messages into MAVLink 2 frames with our system/component ids
//! and a wrapping sequence number, signed when a [`Signer`](crate::signing::Signer) is set.
//!
//! ## Files
//! - `format.rs`: the wire constants, [`FrameHeader`] and [`Frame`].
//! - `crc.rs`: the MAVLink checksum and each message's CRC_EXTRA.
//! - `decoder.rs`: [`FrameDecoder`], its [`FrameError`]s, [`DecoderStats`] and
//!   [`DecoderPolicy`].
//! - `encoder.rs`: [`FrameEncoder`] and [`encode_frame_into`].

mod crc;
mod decoder;
mod encoder;
mod format;

pub use crc::{crc_mavlink, known_extra_crc};
pub use decoder::{DecoderPolicy, DecoderStats, FrameDecoder, FrameError};
pub use encoder::{FrameEncoder, FrameIds, encode_frame_into};
pub use format::{
    Frame, FrameHeader, IFLAG_SIGNED, MAGIC_V1, MAGIC_V2, MAX_FRAME_LEN, SignatureBlock,
    V1_HEADER_LEN, V2_HEADER_LEN, WireVersion,
};

#[cfg(test)]
mod tests;
