//! [`FrameDecoder`]: any chunk of bytes in, checked frames out, resynchronising after
//! garbage, with every dropped candidate a [`FrameError`] and counted in [`DecoderStats`]
//! (see the [module documentation](super)).

use std::time::Duration;

use mavlink::dialects::common::MavMessage;
use mavlink::{MavlinkVersion, Message};

use super::crc::{crc_mavlink, known_extra_crc};
use super::format::{
    Frame, FrameHeader, IFLAG_SIGNED, MAGIC_V1, MAGIC_V2, MAX_FRAME_LEN, SignatureBlock,
    V1_HEADER_LEN, V2_HEADER_LEN, WireVersion,
};
use crate::signing::{SIGNATURE_BLOCK_LEN, SignatureError, Verifier};

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

/// Sans-io MAVLink frame decoder. See the [module documentation](crate::frame).
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
    /// Length of the frame the last [`FrameDecoder::poll`] returned, ending at `pos`.
    last_len: usize,
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
            last_len: 0,
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

    /// The wire bytes of the frame the last [`poll`](FrameDecoder::poll) returned, as
    /// received (signature block included), until the next [`push`](FrameDecoder::push) or
    /// `poll`; empty if that poll returned no frame. For passing a checked frame on unchanged
    /// (a forward to a watching ground station) without encoding it again.
    pub fn last_frame_bytes(&self) -> &[u8] {
        self.pos
            .checked_sub(self.last_len)
            .and_then(|start| self.buf.get(start..self.pos))
            .unwrap_or(&[])
    }

    /// Appends received bytes.
    pub fn push(&mut self, bytes: &[u8]) {
        self.last_len = 0;
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
        self.last_len = 0;
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
                    self.last_len = len;
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
