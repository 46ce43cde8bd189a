//! The MAVLink wire format: start bytes, header lengths and the largest frame, and what a
//! decoded frame is ([`Frame`]: its [`FrameHeader`] and the message).

use mavlink::dialects::common::MavMessage;

use crate::signing::SIGNATURE_BLOCK_LEN;

/// MAVLink 1 start byte.
pub const MAGIC_V1: u8 = 0xFE;
/// MAVLink 2 start byte.
pub const MAGIC_V2: u8 = 0xFD;
/// MAVLink 2 header length, magic included.
pub const V2_HEADER_LEN: usize = 10;
/// MAVLink 1 header length, magic included.
pub const V1_HEADER_LEN: usize = 6;
/// Incompatibility flag of a signed MAVLink 2 frame.
pub const IFLAG_SIGNED: u8 = 0x01;
/// Longest possible frame: MAVLink 2 header, 255-byte payload, CRC, signature block.
pub const MAX_FRAME_LEN: usize = V2_HEADER_LEN + 255 + 2 + SIGNATURE_BLOCK_LEN;

/// Which MAVLink framing a frame used.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum WireVersion {
    /// MAVLink 1 (magic 0xFE).
    V1,
    /// MAVLink 2 (magic 0xFD).
    V2,
}

/// The 13-byte signature block of a signed MAVLink 2 frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SignatureBlock {
    /// Link id of the sender's channel.
    pub link_id: u8,
    /// Sender's timestamp, 10 µs units since 2015-01-01 UTC.
    pub timestamp_10us: u64,
}

/// Header fields of a decoded frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameHeader {
    /// Framing used.
    pub version: WireVersion,
    /// Sender system id.
    pub system_id: u8,
    /// Sender component id.
    pub component_id: u8,
    /// Sender's packet sequence number (wraps at 256).
    pub sequence: u8,
    /// Message id.
    pub message_id: u32,
    /// Payload length on the wire (after MAVLink 2 zero truncation).
    pub payload_len: u8,
    /// Signature block, for signed frames (verified only when signing is on).
    pub signature: Option<SignatureBlock>,
    /// The frame's CRC as received (checked): with the sender and sequence it tells a second
    /// copy of a frame, heard over another radio, from a new frame.
    pub checksum: u16,
}

impl FrameHeader {
    /// Whether the frame carried a signature.
    pub fn is_signed(&self) -> bool {
        self.signature.is_some()
    }
}

/// A checked, decoded frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Header fields.
    pub header: FrameHeader,
    /// The decoded common-dialect message.
    pub message: MavMessage,
}
