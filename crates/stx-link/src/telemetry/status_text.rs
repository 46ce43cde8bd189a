//! Text from the drone ([`StatusText`], STATUSTEXT) with its [`Severity`]: one chunk of at
//! most [`STATUSTEXT_LEN`] bytes on the wire; [`split_status_text`] cuts a longer text into
//! chunks and [`StatusTextAssembler`] joins them again.

use mavlink::dialects::common as mc;
use mavlink::dialects::common::MavMessage;
use serde::{Deserialize, Serialize};

/// MAVLink severity (MAV_SEVERITY, RFC 5424).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "snake_case")]
pub enum Severity {
    Emergency,
    Alert,
    Critical,
    Error,
    Warning,
    Notice,
    Info,
    Debug,
}

impl Severity {
    fn to_mav(self) -> mc::MavSeverity {
        use mc::MavSeverity as S;
        match self {
            Self::Emergency => S::MAV_SEVERITY_EMERGENCY,
            Self::Alert => S::MAV_SEVERITY_ALERT,
            Self::Critical => S::MAV_SEVERITY_CRITICAL,
            Self::Error => S::MAV_SEVERITY_ERROR,
            Self::Warning => S::MAV_SEVERITY_WARNING,
            Self::Notice => S::MAV_SEVERITY_NOTICE,
            Self::Info => S::MAV_SEVERITY_INFO,
            Self::Debug => S::MAV_SEVERITY_DEBUG,
        }
    }
    fn from_mav(s: mc::MavSeverity) -> Self {
        use mc::MavSeverity as S;
        match s {
            S::MAV_SEVERITY_EMERGENCY => Self::Emergency,
            S::MAV_SEVERITY_ALERT => Self::Alert,
            S::MAV_SEVERITY_CRITICAL => Self::Critical,
            S::MAV_SEVERITY_ERROR => Self::Error,
            S::MAV_SEVERITY_WARNING => Self::Warning,
            S::MAV_SEVERITY_NOTICE => Self::Notice,
            S::MAV_SEVERITY_INFO => Self::Info,
            S::MAV_SEVERITY_DEBUG => Self::Debug,
        }
    }
}

/// Longest text in one STATUSTEXT, bytes.
pub const STATUSTEXT_LEN: usize = 50;

/// One STATUSTEXT chunk. Text is kept as bytes because a long text is split at byte
/// boundaries (a shorter chunk would mean "last chunk" to the receiver), which may cut a UTF-8
/// character in two; [`StatusTextAssembler`] joins the bytes before decoding them.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct StatusText {
    /// Severity.
    pub severity: Severity,
    /// Up to 50 bytes of UTF-8 text (without the terminating NUL).
    pub text: Vec<u8>,
    /// Id shared by the chunks of one long text; 0 for a single-chunk text.
    pub id: u16,
    /// Index of this chunk, from 0.
    pub chunk_seq: u8,
}

impl StatusText {
    /// A single-chunk text (truncated to 50 bytes at a character boundary).
    pub fn single(severity: Severity, text: &str) -> Self {
        let mut end = text.len().min(STATUSTEXT_LEN);
        while !text.is_char_boundary(end) {
            end -= 1;
        }
        Self {
            severity,
            text: text.as_bytes().get(..end).unwrap_or(&[]).to_vec(),
            id: 0,
            chunk_seq: 0,
        }
    }

    /// The chunk's text, with invalid UTF-8 replaced.
    pub fn text_lossy(&self) -> String {
        String::from_utf8_lossy(&self.text).into_owned()
    }

    /// The STATUSTEXT carrying it.
    pub(super) fn to_mavlink(&self) -> MavMessage {
        let mut text = [0_u8; STATUSTEXT_LEN];
        let n = self.text.len().min(STATUSTEXT_LEN);
        text[..n].copy_from_slice(self.text.get(..n).unwrap_or(&[]));
        MavMessage::STATUSTEXT(mc::STATUSTEXT_DATA {
            severity: self.severity.to_mav(),
            text: text.into(),
            id: self.id,
            chunk_seq: self.chunk_seq,
        })
    }

    /// What a STATUSTEXT carries.
    pub(super) fn from_mavlink(t: &mc::STATUSTEXT_DATA) -> Self {
        let raw: &[u8] = &t.text[..];
        let end = raw.iter().position(|&b| b == 0).unwrap_or(raw.len());
        StatusText {
            severity: Severity::from_mav(t.severity),
            text: raw.get(..end).unwrap_or(&[]).to_vec(),
            id: t.id,
            chunk_seq: t.chunk_seq,
        }
    }
}

/// Splits `text` into STATUSTEXT chunks. Text of at most 50 bytes gives one chunk with id 0;
/// longer text gives chunks of 50 bytes with the given non-zero `id` and `chunk_seq` 0, 1, …,
/// the last shorter than 50 bytes (an empty one is added when the length is a multiple of 50,
/// since a NUL in the text marks the last chunk). At most 256 chunks (12 800 bytes); longer
/// text is cut.
pub fn split_status_text(severity: Severity, text: &str, id: u16) -> Vec<StatusText> {
    let bytes = text.as_bytes();
    if bytes.len() <= STATUSTEXT_LEN {
        return vec![StatusText {
            severity,
            text: bytes.to_vec(),
            id: 0,
            chunk_seq: 0,
        }];
    }
    let id = id.max(1);
    let mut chunks: Vec<StatusText> = bytes
        .chunks(STATUSTEXT_LEN)
        .take(256)
        .enumerate()
        .map(|(i, c)| StatusText {
            severity,
            text: c.to_vec(),
            id,
            chunk_seq: i as u8,
        })
        .collect();
    if chunks
        .last()
        .is_some_and(|c| c.text.len() == STATUSTEXT_LEN)
        && chunks.len() < 256
    {
        let seq = chunks.len() as u8;
        chunks.push(StatusText {
            severity,
            text: Vec::new(),
            id,
            chunk_seq: seq,
        });
    }
    chunks
}

/// A text being re-assembled: ((system id, component id, text id), severity, bytes so far,
/// next expected `chunk_seq`).
type PendingText = ((u8, u8, u16), Severity, Vec<u8>, u8);

/// Re-assembles chunked STATUSTEXTs per (sender, id). Incomplete texts are dropped when a new
/// text with the same id starts or when more than [`StatusTextAssembler::MAX_PENDING`] are
/// pending; both cases are counted in `dropped`.
#[derive(Debug, Default)]
pub struct StatusTextAssembler {
    pending: Vec<PendingText>,
    /// Incomplete texts dropped.
    pub dropped: u64,
}

impl StatusTextAssembler {
    /// Most incomplete texts kept at once.
    pub const MAX_PENDING: usize = 16;

    /// Feeds one chunk from `(system_id, component_id)`; returns the whole text when complete.
    pub fn push(
        &mut self,
        system_id: u8,
        component_id: u8,
        chunk: &StatusText,
    ) -> Option<(Severity, String)> {
        if chunk.id == 0 {
            return Some((chunk.severity, chunk.text_lossy()));
        }
        let key = (system_id, component_id, chunk.id);
        let last = chunk.text.len() < STATUSTEXT_LEN;
        let idx = self.pending.iter().position(|p| p.0 == key);
        match (idx, chunk.chunk_seq) {
            (Some(i), seq) if seq != 0 => {
                let entry = self.pending.get_mut(i)?;
                if entry.3 != seq {
                    self.pending.remove(i);
                    self.dropped += 1;
                    return None;
                }
                entry.2.extend_from_slice(&chunk.text);
                entry.3 = seq.wrapping_add(1);
                if last || seq == 255 {
                    let (_, sev, text, _) = self.pending.remove(i);
                    return Some((sev, String::from_utf8_lossy(&text).into_owned()));
                }
                None
            }
            (None, seq) if seq != 0 => {
                self.dropped += 1;
                None
            }
            (existing, _) => {
                if let Some(i) = existing {
                    self.pending.remove(i);
                    self.dropped += 1;
                }
                if last {
                    return Some((chunk.severity, chunk.text_lossy()));
                }
                if self.pending.len() >= Self::MAX_PENDING {
                    self.pending.remove(0);
                    self.dropped += 1;
                }
                self.pending
                    .push((key, chunk.severity, chunk.text.clone(), 1));
                None
            }
        }
    }
}
