//! MAVLink 2 message signing, kept apart so that the secret and the replay rules live in one
//! small, boring place.
//!
//! - [`SigningKey`] holds the 32-byte secret. It never prints its bytes (`Debug` shows
//!   `SigningKey(<redacted>)`, there is no `Display` and no `Serialize`) and is wiped on drop
//!   (`zeroize`, a wipe the optimiser keeps).
//!   It is read from 64 hexadecimal characters ([`SigningKey::from_hex`]), a key file
//!   ([`SigningKey::from_file`]) or an environment variable ([`SIGNING_KEY_ENV`]) — never from
//!   a command-line argument, which other users see in `ps` and shells keep in their history.
//! - [`KeyText`] holds a key as written in a configuration file until it is parsed: it too
//!   never shows (`Debug` and `Serialize` give `<redacted>`) and is wiped on drop.
//! - [`SigningClock`] turns the monotonic `now` every sans-io call receives into MAVLink's
//!   signing time: 10 µs units since 2015-01-01 00:00:00 UTC, anchored on one wall-clock
//!   reading that the caller takes when it starts.
//! - [`Signer`] stamps outgoing frames. Its timestamp never goes backwards, including across
//!   restarts: it starts after a persisted high-water mark and tells the caller, through
//!   [`Signer::take_value_to_persist`], when a new mark must be written (the tokio adapter
//!   writes it to a small file).
//! - [`Verifier`] checks incoming signatures in constant time and refuses replays: timestamps
//!   must increase per `(system id, component id, link id)` stream, and a stream never seen
//!   before must not start further in the past than [`Verifier::new_stream_window`].
//!
//! The frame decoder ([`crate::frame`]) calls the verifier with the raw bytes of each frame;
//! the encoder calls the signer. The policy "when signing is on, refuse unsigned and MAVLink 1
//! frames" is applied by the decoder, which counts every refusal.

pub mod persist;

use std::collections::HashMap;
use std::fmt;
use std::time::Duration;

use sha2::{Digest, Sha256};
use zeroize::Zeroize;

/// Seconds from 1970-01-01 to 2015-01-01 00:00:00 UTC, the MAVLink signing epoch.
pub const MAVLINK_SIGNING_EPOCH_UNIX_S: u64 = 1_420_070_400;

/// Length of the signature block at the end of a signed frame: link id (1), timestamp (6),
/// signature (6).
pub const SIGNATURE_BLOCK_LEN: usize = 13;

/// Largest timestamp representable in the 48-bit wire field.
pub const MAX_TIMESTAMP: u64 = (1 << 48) - 1;

/// How far ahead of the last timestamp used the persisted high-water mark is kept, in 10 µs
/// units (10 s). A crash loses nothing as long as the mark is written within half of this.
pub const PERSIST_RESERVE_10US: u64 = 1_000_000;

/// Number of distinct incoming streams the verifier remembers. Only streams whose signature
/// verified are stored, so only a holder of the key can fill it; beyond the cap the oldest
/// stream is forgotten (it then has to pass the new-stream window again).
pub const MAX_STREAMS: usize = 1024;

/// Environment variable holding the signing key as 64 hexadecimal characters (what
/// `stx drone` and `stx serve` read when no key file is given).
pub const SIGNING_KEY_ENV: &str = "STX_SIGNING_KEY";

/// Why a signing key could not be read. Never contains the key's text.
#[derive(Debug, thiserror::Error)]
pub enum KeyError {
    /// Not 64 hexadecimal characters.
    #[error("a signing key is 64 hexadecimal characters (32 bytes); this is not one")]
    NotHex,
    /// The key file could not be read.
    #[error("cannot read the signing key file {path}: {source}")]
    File {
        /// The file.
        path: std::path::PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The key file does not hold a key.
    #[error("signing key file {path}: expected 64 hexadecimal characters (32 bytes)")]
    FileNotHex {
        /// The file.
        path: std::path::PathBuf,
    },
}

/// The 32-byte shared secret of MAVLink 2 signing.
#[derive(Clone, PartialEq, Eq)]
pub struct SigningKey([u8; 32]);

impl SigningKey {
    /// Wraps raw key bytes.
    pub fn from_bytes(bytes: [u8; 32]) -> Self {
        Self(bytes)
    }

    /// Parses 64 hexadecimal characters (surrounding whitespace ignored). The error never
    /// repeats the text.
    pub fn from_hex(text: &str) -> Result<Self, KeyError> {
        let text = text.trim().as_bytes();
        if text.len() != 64 {
            return Err(KeyError::NotHex);
        }
        let mut bytes = [0_u8; 32];
        for (out, pair) in bytes.iter_mut().zip(text.chunks_exact(2)) {
            let digit = |c: u8| char::from(c).to_digit(16).ok_or(KeyError::NotHex);
            // Both digits are < 16, so the byte cannot overflow.
            *out = (digit(pair[0])? * 16 + digit(pair[1])?) as u8;
        }
        Ok(Self(bytes))
    }

    /// Reads a key file: 64 hexadecimal characters (a trailing newline is fine), e.g. made
    /// with `openssl rand -hex 32 > key && chmod 600 key`.
    pub fn from_file(path: &std::path::Path) -> Result<Self, KeyError> {
        let text = std::fs::read_to_string(path).map_err(|source| KeyError::File {
            path: path.to_path_buf(),
            source,
        })?;
        let key = Self::from_hex(&text).map_err(|_| KeyError::FileNotHex {
            path: path.to_path_buf(),
        });
        let mut text = text;
        text.zeroize();
        key
    }

    /// Derives a key from a passphrase the way MAVProxy and QGroundControl do: SHA-256 of the
    /// UTF-8 passphrase.
    pub fn from_passphrase(passphrase: &str) -> Self {
        let digest = Sha256::digest(passphrase.as_bytes());
        let mut bytes = [0_u8; 32];
        bytes.copy_from_slice(&digest);
        Self(bytes)
    }

    fn bytes(&self) -> &[u8; 32] {
        &self.0
    }
}

impl fmt::Debug for SigningKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("SigningKey(<redacted>)")
    }
}

impl Drop for SigningKey {
    fn drop(&mut self) {
        // `zeroize`: a wipe the optimiser keeps.
        self.0.zeroize();
    }
}

/// A signing key as written in a configuration file (64 hexadecimal characters), held until
/// it is parsed with [`KeyText::key`]. It never shows: `Debug` and `Serialize` give
/// `<redacted>`, there is no `Display`; it is wiped on drop.
#[derive(Clone, PartialEq, Eq, serde::Deserialize)]
#[serde(transparent)]
pub struct KeyText(String);

impl KeyText {
    /// Holds `text`.
    pub fn new(text: String) -> Self {
        Self(text)
    }

    /// The key it spells.
    pub fn key(&self) -> Result<SigningKey, KeyError> {
        SigningKey::from_hex(&self.0)
    }
}

impl fmt::Debug for KeyText {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("<redacted>")
    }
}

impl serde::Serialize for KeyText {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str("<redacted>")
    }
}

impl Drop for KeyText {
    fn drop(&mut self) {
        self.0.zeroize();
    }
}

/// Maps the monotonic `now` of the sans-io calls to MAVLink signing time.
///
/// Built from one wall-clock reading (`unix_time`, time since 1970-01-01 UTC) taken at the
/// monotonic instant `mono_at_reading`; afterwards only the monotonic clock advances it, so a
/// wall-clock step (NTP, GPS time arriving) cannot make our timestamps jump back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SigningClock {
    /// Signing time at the reading, 10 µs units since 2015-01-01 UTC.
    base_10us: u64,
    /// Monotonic time of the reading.
    mono_at_reading: Duration,
}

impl SigningClock {
    /// Anchors the clock on a wall-clock reading (time since the Unix epoch) taken at the
    /// monotonic instant `mono_at_reading`. A reading before 2015 counts as 2015-01-01.
    pub fn new(unix_time: Duration, mono_at_reading: Duration) -> Self {
        let since_epoch =
            unix_time.saturating_sub(Duration::from_secs(MAVLINK_SIGNING_EPOCH_UNIX_S));
        Self {
            base_10us: duration_to_10us(since_epoch),
            mono_at_reading,
        }
    }

    /// Signing time at monotonic `now`, 10 µs units since 2015-01-01 UTC.
    pub fn timestamp_at(&self, now: Duration) -> u64 {
        let elapsed = now.saturating_sub(self.mono_at_reading);
        self.base_10us
            .saturating_add(duration_to_10us(elapsed))
            .min(MAX_TIMESTAMP)
    }
}

fn duration_to_10us(d: Duration) -> u64 {
    u64::try_from(d.as_micros() / 10).unwrap_or(u64::MAX)
}

/// Stamps and signs our outgoing frames.
#[derive(Debug, Clone)]
pub struct Signer {
    key: SigningKey,
    /// Link id written into every signature block (identifies our channel to the peer).
    link_id: u8,
    clock: SigningClock,
    /// Last timestamp put on a frame (10 µs units); the next one is strictly greater.
    last_used: u64,
    /// High-water mark most recently handed out for persisting; `last_used` stays below it.
    reserved: u64,
    /// Set when `reserved` moved and the caller has not yet taken the new value.
    persist_pending: bool,
}

impl Signer {
    /// A signer whose first timestamp is after both the clock's current time and the
    /// persisted high-water mark from a previous run (`None` on first start).
    pub fn new(
        key: SigningKey,
        link_id: u8,
        clock: SigningClock,
        now: Duration,
        persisted: Option<u64>,
    ) -> Self {
        let floor = persisted
            .unwrap_or(0)
            .max(clock.timestamp_at(now).saturating_sub(1));
        let mut signer = Self {
            key,
            link_id,
            clock,
            last_used: floor,
            reserved: floor,
            persist_pending: false,
        };
        signer.bump_reservation();
        signer
    }

    /// Link id put in our signature blocks.
    pub fn link_id(&self) -> u8 {
        self.link_id
    }

    /// Last timestamp used on a frame (10 µs units since 2015-01-01 UTC).
    pub fn last_timestamp(&self) -> u64 {
        self.last_used
    }

    /// The high-water mark to persist, when it changed since the last call. Write it
    /// somewhere that survives a restart and pass it back to [`Signer::new`]; our timestamps
    /// stay below it until a newer mark is handed out here.
    pub fn take_value_to_persist(&mut self) -> Option<u64> {
        if self.persist_pending {
            self.persist_pending = false;
            Some(self.reserved)
        } else {
            None
        }
    }

    /// The current high-water mark (whether or not it was already taken).
    pub fn value_to_persist(&self) -> u64 {
        self.reserved
    }

    fn bump_reservation(&mut self) {
        if self.last_used.saturating_add(PERSIST_RESERVE_10US / 2) > self.reserved {
            self.reserved = self
                .last_used
                .saturating_add(PERSIST_RESERVE_10US)
                .min(MAX_TIMESTAMP);
            self.persist_pending = true;
        }
    }

    /// Next timestamp: the clock's time, or one more than the last one if the clock has not
    /// advanced past it.
    fn next_timestamp(&mut self, now: Duration) -> u64 {
        let ts = self
            .clock
            .timestamp_at(now)
            .max(self.last_used.saturating_add(1))
            .min(MAX_TIMESTAMP);
        self.last_used = ts;
        self.bump_reservation();
        ts
    }

    /// Appends the 13-byte signature block to `frame`, which must hold a complete MAVLink 2
    /// frame (magic to CRC) with the signed incompatibility flag already set.
    pub fn sign(&mut self, now: Duration, frame: &mut Vec<u8>) {
        let ts = self.next_timestamp(now);
        frame.push(self.link_id);
        frame.extend_from_slice(&ts.to_le_bytes()[..6]);
        let sig = compute_signature(&self.key, frame);
        frame.extend_from_slice(&sig);
    }
}

/// SHA-256 over key ‖ `signed_part`, truncated to 48 bits. `signed_part` is the frame from its
/// magic byte through the link id and timestamp.
pub fn compute_signature(key: &SigningKey, signed_part: &[u8]) -> [u8; 6] {
    let mut hasher = Sha256::new();
    hasher.update(key.bytes());
    hasher.update(signed_part);
    let digest = hasher.finalize();
    let mut out = [0_u8; 6];
    out.copy_from_slice(&digest[..6]);
    out
}

/// Equality of two signatures in time independent of where they differ.
pub fn constant_time_eq(a: &[u8; 6], b: &[u8; 6]) -> bool {
    let mut diff = 0_u8;
    for (x, y) in a.iter().zip(b.iter()) {
        diff |= std::hint::black_box(x ^ y);
    }
    std::hint::black_box(diff) == 0
}

/// Why a signed frame was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SignatureError {
    /// The signature does not match our key.
    #[error("bad signature from system {system_id} component {component_id} link {link_id}")]
    BadSignature {
        system_id: u8,
        component_id: u8,
        link_id: u8,
    },
    /// The timestamp is not newer than the last one accepted on the same stream.
    #[error(
        "replayed or reordered frame from system {system_id} component {component_id} link {link_id}: timestamp {timestamp} <= last {last}"
    )]
    Replay {
        system_id: u8,
        component_id: u8,
        link_id: u8,
        timestamp: u64,
        last: u64,
    },
    /// A stream never seen before starts too far in the past.
    #[error(
        "new stream from system {system_id} component {component_id} link {link_id} starts at {timestamp}, older than {oldest_accepted}"
    )]
    StaleNewStream {
        system_id: u8,
        component_id: u8,
        link_id: u8,
        timestamp: u64,
        oldest_accepted: u64,
    },
}

/// Checks signatures and timestamps of incoming frames.
#[derive(Debug, Clone)]
pub struct Verifier {
    key: SigningKey,
    clock: SigningClock,
    /// How far in the past (by our clock) a never-seen stream may start; `None` accepts any
    /// first timestamp. MAVLink recommends one minute.
    pub new_stream_window: Option<Duration>,
    /// Last accepted timestamp per (system id, component id, link id).
    streams: HashMap<(u8, u8, u8), u64>,
}

impl Verifier {
    /// A verifier for `key`, with a one-minute window for new streams.
    pub fn new(key: SigningKey, clock: SigningClock) -> Self {
        Self {
            key,
            clock,
            new_stream_window: Some(Duration::from_secs(60)),
            streams: HashMap::new(),
        }
    }

    /// Verifies a complete signed frame: `frame` runs from the magic byte through the
    /// 13-byte signature block. On success the stream's timestamp advances.
    ///
    /// Returns `None` if `frame` is too short to hold a signature block (the decoder never
    /// passes such a frame).
    pub fn verify(
        &mut self,
        now: Duration,
        system_id: u8,
        component_id: u8,
        frame: &[u8],
    ) -> Option<Result<(), SignatureError>> {
        let split = frame.len().checked_sub(6)?;
        let (signed_part, sig) = frame.split_at(split);
        let sig: &[u8; 6] = sig.try_into().ok()?;
        let block = frame.get(frame.len().checked_sub(SIGNATURE_BLOCK_LEN)?..)?;
        let link_id = *block.first()?;
        let mut ts_bytes = [0_u8; 8];
        ts_bytes[..6].copy_from_slice(block.get(1..7)?);
        let timestamp = u64::from_le_bytes(ts_bytes);

        let expected = compute_signature(&self.key, signed_part);
        if !constant_time_eq(&expected, sig) {
            return Some(Err(SignatureError::BadSignature {
                system_id,
                component_id,
                link_id,
            }));
        }
        let stream = (system_id, component_id, link_id);
        match self.streams.get(&stream) {
            Some(&last) if timestamp <= last => {
                return Some(Err(SignatureError::Replay {
                    system_id,
                    component_id,
                    link_id,
                    timestamp,
                    last,
                }));
            }
            Some(_) => {}
            None => {
                if let Some(window) = self.new_stream_window {
                    let oldest_accepted = self
                        .clock
                        .timestamp_at(now)
                        .saturating_sub(duration_to_10us(window));
                    if timestamp < oldest_accepted {
                        return Some(Err(SignatureError::StaleNewStream {
                            system_id,
                            component_id,
                            link_id,
                            timestamp,
                            oldest_accepted,
                        }));
                    }
                }
                if self.streams.len() >= MAX_STREAMS
                    && let Some(oldest) = self
                        .streams
                        .iter()
                        .min_by_key(|(_, ts)| **ts)
                        .map(|(k, _)| *k)
                {
                    self.streams.remove(&oldest);
                }
            }
        }
        self.streams.insert(stream, timestamp);
        Some(Ok(()))
    }
}

/// Everything needed to switch signing on for an endpoint.
#[derive(Debug, Clone)]
pub struct SigningConfig {
    /// The shared secret.
    pub key: SigningKey,
    /// Link id we put in our signature blocks.
    pub link_id: u8,
    /// Wall-clock time (since the Unix epoch) read when the endpoint was created.
    pub unix_time_at_start: Duration,
    /// High-water mark persisted by a previous run (see [`Signer::take_value_to_persist`]).
    pub persisted_timestamp: Option<u64>,
    /// Window for never-seen incoming streams; see [`Verifier::new_stream_window`].
    pub new_stream_window: Option<Duration>,
}

impl SigningConfig {
    /// Signing with `key` on link `link_id`, first run (nothing persisted), one-minute window.
    pub fn new(key: SigningKey, link_id: u8, unix_time_at_start: Duration) -> Self {
        Self {
            key,
            link_id,
            unix_time_at_start,
            persisted_timestamp: None,
            new_stream_window: Some(Duration::from_secs(60)),
        }
    }

    /// Sets the high-water mark persisted by a previous run.
    pub fn with_persisted_timestamp(mut self, persisted: Option<u64>) -> Self {
        self.persisted_timestamp = persisted;
        self
    }

    /// Sets the window for never-seen incoming streams.
    pub fn with_new_stream_window(mut self, window: Option<Duration>) -> Self {
        self.new_stream_window = window;
        self
    }

    /// Builds the signer and verifier, taking `now` as the monotonic instant of the wall-clock
    /// reading.
    pub fn build(&self, now: Duration) -> (Signer, Verifier) {
        let clock = SigningClock::new(self.unix_time_at_start, now);
        let signer = Signer::new(
            self.key.clone(),
            self.link_id,
            clock,
            now,
            self.persisted_timestamp,
        );
        let mut verifier = Verifier::new(self.key.clone(), clock);
        verifier.new_stream_window = self.new_stream_window;
        (signer, verifier)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clock() -> SigningClock {
        // 2026-01-01 00:00:00 UTC
        SigningClock::new(Duration::from_secs(1_767_225_600), Duration::ZERO)
    }

    #[test]
    fn key_debug_is_redacted() {
        let key = SigningKey::from_bytes([0xAB; 32]);
        let shown = format!(
            "{key:?} {:?}",
            SigningConfig::new(key.clone(), 1, Duration::ZERO)
        );
        assert!(shown.contains("SigningKey(<redacted>)"));
        assert!(!shown.to_lowercase().contains("ab, ab"));
        assert!(!shown.contains("171"));
    }

    #[test]
    fn keys_parse_from_hex_and_files_and_errors_never_repeat_the_text() {
        let hex = "00112233445566778899aabbccddeeff00112233445566778899AABBCCDDEEFF";
        let key = SigningKey::from_hex(&format!(" {hex}\n")).expect("valid");
        let mut expected = [0_u8; 32];
        for (i, b) in expected.iter_mut().enumerate() {
            *b = [
                0x00, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88, 0x99, 0xAA, 0xBB, 0xCC, 0xDD,
                0xEE, 0xFF,
            ][i % 16];
        }
        assert!(key == SigningKey::from_bytes(expected));
        for bad in [
            &hex[..62],
            "zz".repeat(32).as_str(),
            "é".repeat(32).as_str(),
        ] {
            let e = SigningKey::from_hex(bad).map(drop).expect_err("refused");
            assert!(!e.to_string().contains(bad), "{e}");
        }
        let dir = std::env::temp_dir().join(format!("stx-key-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join("key");
        std::fs::write(&path, format!("{hex}\n")).expect("write");
        assert!(SigningKey::from_file(&path).expect("read") == key);
        std::fs::write(&path, "secret-but-not-hex\n").expect("write");
        let e = SigningKey::from_file(&path).map(drop).expect_err("refused");
        assert!(!e.to_string().contains("secret"), "{e}");
        let e = SigningKey::from_file(&dir.join("absent"))
            .map(drop)
            .expect_err("refused");
        assert!(e.to_string().contains("absent"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn key_text_never_shows_in_debug_or_serialised_form() {
        let hex = "ab".repeat(32);
        let text: KeyText = serde_json::from_str(&format!("\"{hex}\"")).expect("deserialises");
        assert!(text.key().is_ok());
        let shown = format!(
            "{text:?} {}",
            serde_json::to_string(&text).expect("serialises")
        );
        assert!(!shown.contains("abab"), "{shown}");
        assert!(shown.contains("<redacted>"));
    }

    #[test]
    fn clock_counts_10us_since_2015() {
        let c = SigningClock::new(
            Duration::from_secs(MAVLINK_SIGNING_EPOCH_UNIX_S + 1),
            Duration::from_secs(5),
        );
        assert_eq!(c.timestamp_at(Duration::from_secs(5)), 100_000);
        assert_eq!(c.timestamp_at(Duration::from_millis(5_001)), 100_100);
        // Before the reading: never before the reading's time.
        assert_eq!(c.timestamp_at(Duration::ZERO), 100_000);
    }

    #[test]
    fn signer_timestamps_strictly_increase_even_without_clock_progress() {
        let mut s = Signer::new(
            SigningKey::from_bytes([1; 32]),
            0,
            clock(),
            Duration::ZERO,
            None,
        );
        let mut last = 0;
        for _ in 0..100 {
            let ts = s.next_timestamp(Duration::ZERO);
            assert!(ts > last);
            last = ts;
        }
    }

    #[test]
    fn restart_with_clock_behind_continues_after_persisted_mark() {
        let mut s = Signer::new(
            SigningKey::from_bytes([1; 32]),
            0,
            clock(),
            Duration::ZERO,
            None,
        );
        let mut persisted = s.take_value_to_persist();
        let mut last = 0;
        for i in 0..5_000_u64 {
            last = s.next_timestamp(Duration::from_millis(i * 10));
            if let Some(p) = s.take_value_to_persist() {
                persisted = Some(p);
            }
        }
        assert!(persisted.is_some_and(|p| p > last));
        // Restart with a wall clock one hour behind.
        let behind = SigningClock::new(Duration::from_secs(1_767_225_600 - 3600), Duration::ZERO);
        let mut s2 = Signer::new(
            SigningKey::from_bytes([1; 32]),
            0,
            behind,
            Duration::ZERO,
            persisted,
        );
        assert!(s2.next_timestamp(Duration::ZERO) > last);
    }

    #[test]
    fn constant_time_eq_detects_any_difference() {
        let a = [1, 2, 3, 4, 5, 6];
        assert!(constant_time_eq(&a, &a));
        for i in 0..6 {
            let mut b = a;
            b[i] ^= 0x80;
            assert!(!constant_time_eq(&a, &b));
        }
    }
}
