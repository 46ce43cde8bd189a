//! [`FrameEncoder`]: messages out as MAVLink 2 frames with our system/component ids and a
//! wrapping sequence number, signed when a [`Signer`] is set; [`encode_frame_into`] for one
//! frame with ids of the caller's choosing.

use std::time::Duration;

use mavlink::dialects::common::MavMessage;
use mavlink::{MavlinkVersion, Message};

use super::crc::crc_mavlink;
use super::format::{IFLAG_SIGNED, MAGIC_V2};
use crate::signing::Signer;

/// Serialises messages into MAVLink 2 frames from one system/component.
#[derive(Debug)]
pub struct FrameEncoder {
    /// Our system id.
    pub system_id: u8,
    /// Our component id.
    pub component_id: u8,
    sequence: u8,
    signer: Option<Signer>,
}

impl FrameEncoder {
    /// An encoder for frames from `system_id`/`component_id`, unsigned, sequence starting at 0.
    pub fn new(system_id: u8, component_id: u8) -> Self {
        Self {
            system_id,
            component_id,
            sequence: 0,
            signer: None,
        }
    }

    /// Switches signing of outgoing frames on (`Some`) or off.
    pub fn set_signer(&mut self, signer: Option<Signer>) {
        self.signer = signer;
    }

    /// The signer, when signing is on.
    pub fn signer(&self) -> Option<&Signer> {
        self.signer.as_ref()
    }

    /// The signer, when signing is on (to take the value to persist).
    pub fn signer_mut(&mut self) -> Option<&mut Signer> {
        self.signer.as_mut()
    }

    /// Sequence number the next frame will carry.
    pub fn next_sequence(&self) -> u8 {
        self.sequence
    }

    /// Appends one frame carrying `message` to `out`. `now` is used for the signature
    /// timestamp.
    pub fn encode_into(&mut self, now: Duration, message: &MavMessage, out: &mut Vec<u8>) {
        let seq = self.sequence;
        self.sequence = self.sequence.wrapping_add(1);
        encode_frame_into(
            now,
            message,
            FrameIds {
                system_id: self.system_id,
                component_id: self.component_id,
                sequence: seq,
            },
            self.signer.as_mut(),
            out,
        );
    }

    /// One frame carrying `message`.
    pub fn encode(&mut self, now: Duration, message: &MavMessage) -> Vec<u8> {
        let mut out = Vec::with_capacity(64);
        self.encode_into(now, message, &mut out);
        out
    }
}

/// Sender ids and sequence of one frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameIds {
    /// Sender system id.
    pub system_id: u8,
    /// Sender component id.
    pub component_id: u8,
    /// Sequence number.
    pub sequence: u8,
}

/// Appends one MAVLink 2 frame to `out`, signed if `signer` is given.
pub fn encode_frame_into(
    now: Duration,
    message: &MavMessage,
    ids: FrameIds,
    signer: Option<&mut Signer>,
    out: &mut Vec<u8>,
) {
    let mut payload = [0_u8; 255];
    let len = message.ser(MavlinkVersion::V2, &mut payload).min(255);
    let message_id = message.message_id();
    let id = message_id.to_le_bytes();
    let start = out.len();
    out.extend_from_slice(&[
        MAGIC_V2,
        len as u8,
        if signer.is_some() { IFLAG_SIGNED } else { 0 },
        0,
        ids.sequence,
        ids.system_id,
        ids.component_id,
        id[0],
        id[1],
        id[2],
    ]);
    out.extend_from_slice(payload.get(..len).unwrap_or(&[]));
    let crc = crc_mavlink(
        out.get(start + 1..).unwrap_or(&[]),
        MavMessage::extra_crc(message_id),
    );
    out.extend_from_slice(&crc.to_le_bytes());
    if let Some(signer) = signer {
        let mut frame = out.split_off(start);
        signer.sign(now, &mut frame);
        out.extend_from_slice(&frame);
    }
}
