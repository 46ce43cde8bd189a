//! MAVLink framing: bytes in, decoded messages with their headers out, and back.
//!
//! Radios and serial lines deliver frames cut anywhere, glued together, corrupted, or mixed
//! with noise; this module is the one place that turns such a byte stream into messages, so
//! everything above it sees only whole, checked messages.
//!
//! [`FrameDecoder`] is sans-io: [`FrameDecoder::push`] any chunk, then call
//! [`FrameDecoder::poll`] until it returns `None`. Each call yields either a [`Frame`] (header
//! plus [`MavMessage`]) or a [`FrameError`] saying why a candidate frame was dropped. After a
//! bad checksum it resynchronises on the next magic byte after the failed candidate's start,
//! so a valid frame hidden inside a corrupted one is still found. Nothing is silently
//! swallowed: [`DecoderStats`] counts CRC errors, unknown message ids, parse errors, bytes
//! discarded between frames, MAVLink 1 frames (accepted or refused), signing refusals and
//! truncated frames at end of stream. Lengths read from the wire are bounded by the format
//! (one byte, at most 255) and by [`MAX_FRAME_LEN`]; no wire value is used to index without a
//! checked access.
//!
//! [`FrameEncoder`] serialises messages into MAVLink 2 frames with our system/component ids
//! and a wrapping sequence number, signed when a [`Signer`] is set.

use std::time::Duration;

use mavlink::dialects::common::MavMessage;
use mavlink::{MavlinkVersion, Message};

use crate::signing::{SIGNATURE_BLOCK_LEN, SignatureError, Signer, Verifier};

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

/// Why a candidate frame was dropped. Each variant is also counted in [`DecoderStats`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FrameError {
    /// Checksum mismatch: noise, or a false start inside other data.
    #[error(
        "bad CRC on message id {message_id}: computed {computed:#06x}, received {received:#06x}"
    )]
    BadCrc {
        message_id: u32,
        computed: u16,
        received: u16,
    },
    /// Message id not in the common dialect; its CRC cannot be checked.
    #[error("unknown message id {message_id}")]
    UnknownMessage { message_id: u32 },
    /// MAVLink 2 header with incompatibility flags we do not implement.
    #[error("unsupported incompatibility flags {flags:#04x}")]
    UnsupportedFlags { flags: u8 },
    /// Valid CRC but the payload does not decode (e.g. an enum value outside the dialect).
    #[error("message id {message_id} (len {payload_len}) does not parse: {reason}")]
    Parse {
        message_id: u32,
        payload_len: u8,
        reason: String,
    },
    /// A MAVLink 1 frame while the policy refuses them.
    #[error("MAVLink 1 frame (message id {message_id}) refused by policy")]
    V1Refused { message_id: u32 },
    /// An unsigned frame while signing is required.
    #[error(
        "unsigned frame (message id {message_id}) from system {system_id} refused: signing is on"
    )]
    Unsigned { message_id: u32, system_id: u8 },
    /// A signed frame whose signature or timestamp was refused.
    #[error("message id {message_id}: {source}")]
    Signature {
        message_id: u32,
        #[source]
        source: SignatureError,
    },
    /// End of stream inside a frame.
    #[error("stream ended inside a frame ({have} of {need} bytes)")]
    Truncated { have: usize, need: usize },
}

/// Counters kept by the decoder. Every byte that does not end up in a frame is counted.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct DecoderStats {
    /// Bytes fed in.
    pub bytes_in: u64,
    /// Frames decoded and delivered.
    pub frames_ok: u64,
    /// Bytes skipped while looking for a frame start, or dropped with failed candidates.
    pub bytes_discarded: u64,
    /// Candidates with a checksum mismatch.
    pub crc_errors: u64,
    /// Candidates with a message id outside the dialect.
    pub unknown_message_ids: u64,
    /// Frames with a good CRC whose payload did not parse.
    pub parse_errors: u64,
    /// MAVLink 2 headers with unsupported incompatibility flags.
    pub bad_headers: u64,
    /// MAVLink 1 frames delivered.
    pub v1_accepted: u64,
    /// MAVLink 1 frames refused by policy (or because signing is on).
    pub v1_refused: u64,
    /// Signed frames delivered.
    pub signed_frames: u64,
    /// Unsigned frames refused because signing is on.
    pub unsigned_refused: u64,
    /// Signed frames with a wrong signature.
    pub bad_signatures: u64,
    /// Signed frames refused as replays (old timestamp, or a new stream starting too old).
    pub replays_refused: u64,
    /// Candidates cut off by the end of the stream.
    pub truncated: u64,
}

/// Counters of several decoders (one per radio) added up.
impl<'a> std::iter::Sum<&'a DecoderStats> for DecoderStats {
    fn sum<I: Iterator<Item = &'a DecoderStats>>(decoders: I) -> Self {
        decoders.fold(DecoderStats::default(), |a, d| DecoderStats {
            bytes_in: a.bytes_in + d.bytes_in,
            frames_ok: a.frames_ok + d.frames_ok,
            bytes_discarded: a.bytes_discarded + d.bytes_discarded,
            crc_errors: a.crc_errors + d.crc_errors,
            unknown_message_ids: a.unknown_message_ids + d.unknown_message_ids,
            parse_errors: a.parse_errors + d.parse_errors,
            bad_headers: a.bad_headers + d.bad_headers,
            v1_accepted: a.v1_accepted + d.v1_accepted,
            v1_refused: a.v1_refused + d.v1_refused,
            signed_frames: a.signed_frames + d.signed_frames,
            unsigned_refused: a.unsigned_refused + d.unsigned_refused,
            bad_signatures: a.bad_signatures + d.bad_signatures,
            replays_refused: a.replays_refused + d.replays_refused,
            truncated: a.truncated + d.truncated,
        })
    }
}

/// What the decoder accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DecoderPolicy {
    /// Deliver MAVLink 1 frames (never when signing is on).
    pub accept_v1: bool,
}

impl Default for DecoderPolicy {
    fn default() -> Self {
        Self { accept_v1: true }
    }
}

/// Sans-io MAVLink frame decoder. See the module documentation.
#[derive(Debug)]
pub struct FrameDecoder {
    buf: Vec<u8>,
    /// Read position in `buf`; bytes before it are consumed.
    pos: usize,
    /// Set by [`FrameDecoder::finish`]: incomplete candidates are dropped rather than awaited.
    eof: bool,
    policy: DecoderPolicy,
    verifier: Option<Verifier>,
    stats: DecoderStats,
}

impl Default for FrameDecoder {
    fn default() -> Self {
        Self::new(DecoderPolicy::default())
    }
}

// Internal and short-lived: each value is moved once out of `step`; boxing the frame would
// cost an allocation per frame on the hot path.
#[allow(clippy::large_enum_variant)]
enum Step {
    NeedMore,
    Skip(usize),
    Frame(Frame, usize),
    Error(FrameError, usize),
}

impl FrameDecoder {
    /// A decoder with the given policy and signing off.
    pub fn new(policy: DecoderPolicy) -> Self {
        Self {
            buf: Vec::new(),
            pos: 0,
            eof: false,
            policy,
            verifier: None,
            stats: Default::default(),
        }
    }

    /// Switches signing verification on (`Some`) or off (`None`). When on, unsigned and
    /// MAVLink 1 frames are refused.
    pub fn set_verifier(&mut self, verifier: Option<Verifier>) {
        self.verifier = verifier;
    }

    /// Whether signing verification is on.
    pub fn signing_required(&self) -> bool {
        self.verifier.is_some()
    }

    /// The counters so far.
    pub fn stats(&self) -> &DecoderStats {
        &self.stats
    }

    /// Bytes buffered and not yet consumed.
    pub fn buffered(&self) -> usize {
        self.buf.len() - self.pos
    }

    /// Appends received bytes.
    pub fn push(&mut self, bytes: &[u8]) {
        if self.pos > 0 && self.pos >= self.buf.len() / 2 {
            self.buf.drain(..self.pos);
            self.pos = 0;
        }
        self.buf.extend_from_slice(bytes);
        self.stats.bytes_in += bytes.len() as u64;
        self.eof = false;
    }

    /// Marks the end of the stream: candidates that can no longer complete are dropped and
    /// counted as truncated, so frames behind them are still found by further [`poll`]s.
    ///
    /// [`poll`]: FrameDecoder::poll
    pub fn finish(&mut self) {
        self.eof = true;
    }

    /// The next frame or error, `None` when more bytes are needed.
    ///
    /// `now` (monotonic) is only used for the signing window of new streams.
    pub fn poll(&mut self, now: Duration) -> Option<Result<Frame, FrameError>> {
        loop {
            let rest = self.buf.get(self.pos..).unwrap_or(&[]);
            if rest.is_empty() {
                return None;
            }
            match self.step(now) {
                Step::NeedMore => {
                    if self.eof {
                        let have = self.buffered();
                        let need = self.candidate_len().unwrap_or(have + 1);
                        self.stats.truncated += 1;
                        self.discard(1);
                        return Some(Err(FrameError::Truncated { have, need }));
                    }
                    return None;
                }
                Step::Skip(n) => self.discard(n),
                Step::Frame(frame, len) => {
                    self.pos += len;
                    self.stats.frames_ok += 1;
                    return Some(Ok(frame));
                }
                Step::Error(err, len) => {
                    self.discard(len);
                    return Some(Err(err));
                }
            }
        }
    }

    fn discard(&mut self, n: usize) {
        let n = n.min(self.buffered());
        self.pos += n;
        self.stats.bytes_discarded += n as u64;
    }

    /// Declared length of the candidate at the read position, if its header is complete.
    fn candidate_len(&self) -> Option<usize> {
        let rest = self.buf.get(self.pos..)?;
        match *rest.first()? {
            MAGIC_V2 => {
                let len = usize::from(*rest.get(1)?);
                let flags = *rest.get(2)?;
                let sig = if flags & IFLAG_SIGNED != 0 {
                    SIGNATURE_BLOCK_LEN
                } else {
                    0
                };
                Some(V2_HEADER_LEN + len + 2 + sig)
            }
            MAGIC_V1 => Some(V1_HEADER_LEN + usize::from(*rest.get(1)?) + 2),
            _ => None,
        }
    }

    fn step(&mut self, now: Duration) -> Step {
        let rest = self.buf.get(self.pos..).unwrap_or(&[]);
        // Find the next magic byte.
        let Some(start) = rest.iter().position(|&b| b == MAGIC_V2 || b == MAGIC_V1) else {
            return Step::Skip(rest.len());
        };
        if start > 0 {
            return Step::Skip(start);
        }
        match rest.first() {
            Some(&MAGIC_V2) => self.step_v2(now),
            _ => self.step_v1(),
        }
    }

    fn step_v2(&mut self, now: Duration) -> Step {
        let rest = self.buf.get(self.pos..).unwrap_or(&[]);
        let Some(header) = rest.get(..V2_HEADER_LEN) else {
            return Step::NeedMore;
        };
        let [_, len, flags, _compat, seq, sysid, compid, id0, id1, id2] = header else {
            return Step::NeedMore;
        };
        let (payload_len, flags) = (*len, *flags);
        let message_id = u32::from_le_bytes([*id0, *id1, *id2, 0]);
        if flags & !IFLAG_SIGNED != 0 {
            self.stats.bad_headers += 1;
            return Step::Error(FrameError::UnsupportedFlags { flags }, 1);
        }
        // Decided on the header alone: a false start in noise must not hold back the frames
        // behind it until up to 280 bytes have arrived.
        let Some(extra) = known_extra_crc(message_id) else {
            self.stats.unknown_message_ids += 1;
            return Step::Error(FrameError::UnknownMessage { message_id }, 1);
        };
        let signed = flags & IFLAG_SIGNED != 0;
        let crc_end = V2_HEADER_LEN + usize::from(payload_len) + 2;
        let total = crc_end + if signed { SIGNATURE_BLOCK_LEN } else { 0 };
        debug_assert!(total <= MAX_FRAME_LEN);
        let Some(raw) = rest.get(..total) else {
            return Step::NeedMore;
        };
        let (Some(crc_input), Some(crc_bytes)) =
            (raw.get(1..crc_end - 2), raw.get(crc_end - 2..crc_end))
        else {
            return Step::Skip(1);
        };
        let computed = crc_mavlink(crc_input, extra);
        let received = u16::from_le_bytes([
            crc_bytes.first().copied().unwrap_or(0),
            crc_bytes.get(1).copied().unwrap_or(0),
        ]);
        if computed != received {
            self.stats.crc_errors += 1;
            return Step::Error(
                FrameError::BadCrc {
                    message_id,
                    computed,
                    received,
                },
                1,
            );
        }
        let (system_id, component_id, sequence) = (*sysid, *compid, *seq);
        let signature = if signed {
            raw.get(crc_end..crc_end + 7).map(|b| {
                let mut ts = [0_u8; 8];
                ts[..6].copy_from_slice(b.get(1..7).unwrap_or(&[0; 6]));
                SignatureBlock {
                    link_id: b.first().copied().unwrap_or(0),
                    timestamp_10us: u64::from_le_bytes(ts),
                }
            })
        } else {
            None
        };
        if let Some(verifier) = self.verifier.as_mut() {
            if !signed {
                self.stats.unsigned_refused += 1;
                return Step::Error(
                    FrameError::Unsigned {
                        message_id,
                        system_id,
                    },
                    total,
                );
            }
            match verifier.verify(now, system_id, component_id, raw) {
                Some(Ok(())) => {}
                Some(Err(source)) => {
                    match source {
                        SignatureError::BadSignature { .. } => self.stats.bad_signatures += 1,
                        _ => self.stats.replays_refused += 1,
                    }
                    return Step::Error(FrameError::Signature { message_id, source }, total);
                }
                None => return Step::Skip(1),
            }
        }
        let payload = raw.get(V2_HEADER_LEN..crc_end - 2).unwrap_or(&[]);
        match MavMessage::parse(MavlinkVersion::V2, message_id, payload) {
            Ok(message) => {
                if signed {
                    self.stats.signed_frames += 1;
                }
                let header = FrameHeader {
                    version: WireVersion::V2,
                    system_id,
                    component_id,
                    sequence,
                    message_id,
                    payload_len,
                    signature,
                    checksum: received,
                };
                Step::Frame(Frame { header, message }, total)
            }
            Err(e) => {
                self.stats.parse_errors += 1;
                Step::Error(
                    FrameError::Parse {
                        message_id,
                        payload_len,
                        reason: e.to_string(),
                    },
                    total,
                )
            }
        }
    }

    fn step_v1(&mut self) -> Step {
        let rest = self.buf.get(self.pos..).unwrap_or(&[]);
        let Some(&[_, len, seq, sysid, compid, id]) = rest.get(..V1_HEADER_LEN) else {
            return Step::NeedMore;
        };
        let message_id = u32::from(id);
        let Some(extra) = known_extra_crc(message_id) else {
            self.stats.unknown_message_ids += 1;
            return Step::Error(FrameError::UnknownMessage { message_id }, 1);
        };
        let crc_end = V1_HEADER_LEN + usize::from(len) + 2;
        let Some(raw) = rest.get(..crc_end) else {
            return Step::NeedMore;
        };
        let computed = crc_mavlink(raw.get(1..crc_end - 2).unwrap_or(&[]), extra);
        let received = u16::from_le_bytes([
            raw.get(crc_end - 2).copied().unwrap_or(0),
            raw.get(crc_end - 1).copied().unwrap_or(0),
        ]);
        if computed != received {
            self.stats.crc_errors += 1;
            return Step::Error(
                FrameError::BadCrc {
                    message_id,
                    computed,
                    received,
                },
                1,
            );
        }
        if !self.policy.accept_v1 || self.verifier.is_some() {
            self.stats.v1_refused += 1;
            return Step::Error(FrameError::V1Refused { message_id }, crc_end);
        }
        let payload = raw.get(V1_HEADER_LEN..crc_end - 2).unwrap_or(&[]);
        match MavMessage::parse(MavlinkVersion::V1, message_id, payload) {
            Ok(message) => {
                self.stats.v1_accepted += 1;
                let header = FrameHeader {
                    version: WireVersion::V1,
                    system_id: sysid,
                    component_id: compid,
                    sequence: seq,
                    message_id,
                    payload_len: len,
                    signature: None,
                    checksum: received,
                };
                Step::Frame(Frame { header, message }, crc_end)
            }
            Err(e) => {
                self.stats.parse_errors += 1;
                Step::Error(
                    FrameError::Parse {
                        message_id,
                        payload_len: len,
                        reason: e.to_string(),
                    },
                    crc_end,
                )
            }
        }
    }
}

/// CRC_EXTRA of a message id in the common dialect, `None` for an unknown id.
pub fn known_extra_crc(message_id: u32) -> Option<u8> {
    let extra = MavMessage::extra_crc(message_id);
    if extra != 0 || is_known_id(message_id) {
        Some(extra)
    } else {
        None
    }
}

fn is_known_id(message_id: u32) -> bool {
    // Only reached for ids whose CRC_EXTRA is 0: the few such messages, and ids in noise
    // (which the dialect's match rejects without building anything).
    MavMessage::default_message_from_id(message_id).is_some()
}

/// The MAVLink checksum (CRC-16/MCRF4XX) of `data` followed by `extra`.
pub fn crc_mavlink(data: &[u8], extra: u8) -> u16 {
    let mut crc = 0xFFFF_u16;
    for &b in data.iter().chain(std::iter::once(&extra)) {
        crc = crc_accumulate(b, crc);
    }
    crc
}

#[inline]
fn crc_accumulate(byte: u8, crc: u16) -> u16 {
    let mut tmp = byte ^ (crc as u8);
    tmp ^= tmp << 4;
    let tmp = u16::from(tmp);
    (crc >> 8) ^ (tmp << 8) ^ (tmp << 3) ^ (tmp >> 4)
}

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signing::{SigningConfig, SigningKey};
    use mavlink::dialects::common::{ATTITUDE_DATA, HEARTBEAT_DATA};

    fn attitude(roll: f32) -> MavMessage {
        MavMessage::ATTITUDE(ATTITUDE_DATA {
            time_boot_ms: 7,
            roll,
            pitch: 0.5,
            yaw: -1.0,
            ..Default::default()
        })
    }

    fn decode_all(dec: &mut FrameDecoder) -> (Vec<Frame>, Vec<FrameError>) {
        let (mut ok, mut err) = (Vec::new(), Vec::new());
        while let Some(r) = dec.poll(Duration::ZERO) {
            match r {
                Ok(f) => ok.push(f),
                Err(e) => err.push(e),
            }
        }
        (ok, err)
    }

    #[test]
    fn crc_matches_known_vector() {
        // CRC-16/MCRF4XX check value for "123456789" is 0x6F91; with an extra byte appended
        // it is the CRC of "123456789" + extra.
        let mut crc = 0xFFFF;
        for &b in b"123456789" {
            crc = crc_accumulate(b, crc);
        }
        assert_eq!(crc, 0x6F91);
    }

    #[test]
    fn round_trip_every_chunk_size() {
        let mut enc = FrameEncoder::new(1, 1);
        let mut stream = Vec::new();
        for i in 0..5 {
            enc.encode_into(Duration::ZERO, &attitude(i as f32 * 0.1), &mut stream);
        }
        for chunk in 1..stream.len() {
            let mut dec = FrameDecoder::default();
            let mut got = Vec::new();
            for c in stream.chunks(chunk) {
                dec.push(c);
                while let Some(r) = dec.poll(Duration::ZERO) {
                    got.push(r.expect("valid frame"));
                }
            }
            assert_eq!(got.len(), 5, "chunk {chunk}");
            for (i, f) in got.iter().enumerate() {
                assert_eq!(f.header.sequence, i as u8);
                assert_eq!(f.message, attitude(i as f32 * 0.1));
            }
            assert_eq!(dec.stats().bytes_discarded, 0);
        }
    }

    #[test]
    fn resyncs_after_corrupted_crc_and_garbage() {
        let mut enc = FrameEncoder::new(1, 1);
        let a = enc.encode(Duration::ZERO, &attitude(0.1));
        let mut b = enc.encode(Duration::ZERO, &attitude(0.2));
        let c = enc.encode(Duration::ZERO, &attitude(0.3));
        let last = b.len() - 1;
        b[last] ^= 0xFF;
        let mut stream = vec![1, 2, 3];
        stream.extend(&a);
        stream.extend(&b);
        stream.extend([9, 9]);
        stream.extend(&c);
        let mut dec = FrameDecoder::default();
        dec.push(&stream);
        let (ok, err) = decode_all(&mut dec);
        assert_eq!(ok.len(), 2);
        assert_eq!(ok[1].message, attitude(0.3));
        assert!(
            err.iter()
                .any(|e| matches!(e, FrameError::BadCrc { message_id: 30, .. }))
        );
        assert_eq!(dec.stats().crc_errors, 1);
        assert_eq!(dec.stats().bytes_discarded as usize, 3 + b.len() + 2);
    }

    #[test]
    fn truncated_frame_then_valid_frame_is_recovered() {
        let mut enc = FrameEncoder::new(1, 1);
        let a = enc.encode(Duration::ZERO, &attitude(0.1));
        let b = enc.encode(Duration::ZERO, &attitude(0.2));
        let mut stream = a[..a.len() - 5].to_vec();
        stream.extend(&b);
        let mut dec = FrameDecoder::default();
        dec.push(&stream);
        let (ok, _) = decode_all(&mut dec);
        // The truncated candidate swallows the start of `b` until enough bytes arrive.
        dec.finish();
        let (ok2, err2) = decode_all(&mut dec);
        let all: Vec<_> = ok.into_iter().chain(ok2).collect();
        assert_eq!(all.len(), 1);
        assert_eq!(all[0].message, attitude(0.2));
        assert!(
            dec.stats().crc_errors + dec.stats().truncated >= 1,
            "{err2:?}"
        );
    }

    #[test]
    fn v1_policy_and_unknown_ids_are_counted() {
        // A MAVLink 1 heartbeat built by hand.
        let hb = MavMessage::HEARTBEAT(HEARTBEAT_DATA::default());
        let mut payload = [0_u8; 255];
        let len = hb.ser(MavlinkVersion::V1, &mut payload);
        let mut v1 = vec![MAGIC_V1, len as u8, 3, 9, 1, 0];
        v1.extend_from_slice(&payload[..len]);
        let crc = crc_mavlink(&v1[1..], MavMessage::extra_crc(0));
        v1.extend_from_slice(&crc.to_le_bytes());

        let mut dec = FrameDecoder::default();
        dec.push(&v1);
        let (ok, _) = decode_all(&mut dec);
        assert_eq!(ok.len(), 1);
        assert_eq!(ok[0].header.version, WireVersion::V1);
        assert_eq!(dec.stats().v1_accepted, 1);

        let mut dec = FrameDecoder::new(DecoderPolicy { accept_v1: false });
        dec.push(&v1);
        let (ok, err) = decode_all(&mut dec);
        assert!(ok.is_empty());
        assert_eq!(err, vec![FrameError::V1Refused { message_id: 0 }]);
        assert_eq!(dec.stats().v1_refused, 1);

        // Unknown id 0xABCDEF.
        let mut unk = vec![MAGIC_V2, 1, 0, 0, 0, 1, 1, 0xEF, 0xCD, 0xAB, 0x42, 0, 0];
        unk.extend(&v1);
        let mut dec = FrameDecoder::default();
        dec.push(&unk);
        let (ok, err) = decode_all(&mut dec);
        assert_eq!(ok.len(), 1);
        assert_eq!(
            err[0],
            FrameError::UnknownMessage {
                message_id: 0xABCDEF
            }
        );
        assert_eq!(dec.stats().unknown_message_ids, 1);
    }

    /// Regression: the unknown-id check used to wait for the whole candidate (up to 280
    /// bytes), so a false start in noise held back the valid frames behind it.
    #[test]
    fn a_false_start_with_an_unknown_id_does_not_hold_back_the_next_frame() {
        let mut enc = FrameEncoder::new(1, 1);
        let a = enc.encode(Duration::ZERO, &attitude(0.1));
        let unknown_v1 = (0..=255_u8)
            .find(|&id| known_extra_crc(u32::from(id)).is_none())
            .expect("an id MAVLink 1 does not know");
        for false_start in [
            vec![MAGIC_V2, 255, 0, 0, 0, 1, 1, 0xEF, 0xCD, 0xAB],
            vec![MAGIC_V1, 255, 0, 1, 1, unknown_v1],
        ] {
            let mut stream = false_start.clone();
            stream.extend(&a);
            let mut dec = FrameDecoder::default();
            dec.push(&stream);
            // No finish(): the frame must come out of what has arrived.
            let (ok, err) = decode_all(&mut dec);
            assert_eq!(ok.len(), 1, "{false_start:?}: {err:?}");
            assert_eq!(ok[0].message, attitude(0.1));
            assert!(matches!(err[..], [FrameError::UnknownMessage { .. }]));
            assert_eq!(dec.stats().unknown_message_ids, 1);
            assert_eq!(dec.stats().bytes_discarded as usize, false_start.len());
            assert_eq!(dec.buffered(), 0);
        }
    }

    #[test]
    fn invalid_enum_is_a_counted_parse_error() {
        let mut enc = FrameEncoder::new(1, 1);
        let mut f = enc.encode(
            Duration::ZERO,
            &MavMessage::HEARTBEAT(HEARTBEAT_DATA {
                custom_mode: 1,
                ..Default::default()
            }),
        );
        // mavtype byte (offset 4 in the payload) set to an undefined MAV_TYPE, CRC recomputed.
        f[V2_HEADER_LEN + 4] = 250;
        let n = f.len();
        let crc = crc_mavlink(&f[1..n - 2], MavMessage::extra_crc(0));
        f[n - 2..].copy_from_slice(&crc.to_le_bytes());
        let mut dec = FrameDecoder::default();
        dec.push(&f);
        let (ok, err) = decode_all(&mut dec);
        assert!(ok.is_empty());
        assert!(matches!(err[0], FrameError::Parse { message_id: 0, .. }));
        assert_eq!(dec.stats().parse_errors, 1);
    }

    #[test]
    fn signing_refuses_unsigned_bad_and_replayed_frames() {
        let t0 = Duration::from_secs(1_767_225_600);
        let key = SigningKey::from_bytes([7; 32]);
        let (signer, verifier) = SigningConfig::new(key, 3, t0).build(Duration::ZERO);
        let mut enc = FrameEncoder::new(1, 1);
        enc.set_signer(Some(signer));
        let signed = enc.encode(Duration::ZERO, &attitude(0.1));
        let mut plain = FrameEncoder::new(1, 1);
        let unsigned = plain.encode(Duration::ZERO, &attitude(0.1));
        let (_, wrong) =
            SigningConfig::new(SigningKey::from_bytes([8; 32]), 3, t0).build(Duration::ZERO);

        let mut dec = FrameDecoder::default();
        dec.set_verifier(Some(verifier));
        dec.push(&signed);
        dec.push(&unsigned);
        dec.push(&signed);
        let (ok, err) = decode_all(&mut dec);
        assert_eq!(ok.len(), 1);
        assert!(ok[0].header.is_signed());
        assert!(matches!(err[0], FrameError::Unsigned { .. }));
        assert!(matches!(
            err[1],
            FrameError::Signature {
                source: SignatureError::Replay { .. },
                ..
            }
        ));
        assert_eq!(dec.stats().unsigned_refused, 1);
        assert_eq!(dec.stats().replays_refused, 1);

        let mut dec = FrameDecoder::default();
        dec.set_verifier(Some(wrong));
        dec.push(&signed);
        let (ok, _) = decode_all(&mut dec);
        assert!(ok.is_empty());
        assert_eq!(dec.stats().bad_signatures, 1);

        // Without a verifier, signed frames are accepted (signature not checked).
        let mut dec = FrameDecoder::default();
        dec.push(&signed);
        let (ok, _) = decode_all(&mut dec);
        assert_eq!(ok.len(), 1);
        assert_eq!(ok[0].header.signature.map(|s| s.link_id), Some(3));
    }
}
