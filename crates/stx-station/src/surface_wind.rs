//! The wind at the ground by the landing target: `[surface_wind]` in the station's
//! configuration, what the pages are shown of it, and the intake of a ground anemometer's
//! NMEA 0183 output.
//!
//! Guidance plans its final below about 100 m with this wind mixed in (the estimator's wind
//! is the wind where the stack flies, not where it lands). Two sources give it: a mast
//! anemometer sending `MWV` sentences (marine and weather instruments do, over a serial line
//! or a UDP broadcast), read by the daemon and averaged here; or a value the operator types
//! (a hand-held reading, a windsock). A fresh anemometer mean wins over the operator's value.
//! The core (`core::surface_wind`) uplinks the one in force every
//! [`SurfaceWindConfig::uplink_every_s`] and lets the replica use what the drone accepted.
//!
//! The intake ([`SentenceLines`]) is sans-io: the daemon's reader hands it bytes as they
//! came, and it hands back whole lines; the sentences are parsed by [`stx_types::mwv`].

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use stx_link::address::Address;

/// `[surface_wind]`: where the ground anemometer is heard and how its wind is used.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceWindConfig {
    /// The anemometer's NMEA 0183 output, as a link address: `udpin:0.0.0.0:10110` (a UDP
    /// port its sentences are sent or broadcast to) or `serial:/dev/ttyUSB0:4800` (NMEA's
    /// usual 4800 baud). None: no anemometer, the operator may type a value.
    #[serde(default)]
    pub anemometer: Option<String>,
    /// True bearing of the anemometer's zero mark, degrees: added to a relative (`R`) angle
    /// to give where the wind comes from (0 for a vane aligned on true north; a `T` angle is
    /// taken as true as it is).
    #[serde(default)]
    pub zero_mark_deg: f64,
    /// The wind sent is the vector mean of the sentences of this long, s (1–600).
    #[serde(default = "default_average_s")]
    pub average_s: f64,
    /// The wind in force goes to the drone this often, s (1–120): guidance ignores a surface
    /// wind older than 120 s.
    #[serde(default = "default_uplink_every_s")]
    pub uplink_every_s: f64,
    /// An anemometer silent this long is stale: its mean is no longer sent, s (2–600).
    #[serde(default = "default_stale_after_s")]
    pub stale_after_s: f64,
    /// An operator's value is sent as the wind now for this long after it was typed, s
    /// (10–7200); then it lapses, said in the log.
    #[serde(default = "default_operator_valid_s")]
    pub operator_valid_s: f64,
}

fn default_average_s() -> f64 {
    10.0
}
fn default_uplink_every_s() -> f64 {
    5.0
}
fn default_stale_after_s() -> f64 {
    30.0
}
fn default_operator_valid_s() -> f64 {
    900.0
}

impl Default for SurfaceWindConfig {
    fn default() -> Self {
        Self {
            anemometer: None,
            zero_mark_deg: 0.0,
            average_s: default_average_s(),
            uplink_every_s: default_uplink_every_s(),
            stale_after_s: default_stale_after_s(),
            operator_valid_s: default_operator_valid_s(),
        }
    }
}

impl SurfaceWindConfig {
    /// The anemometer's address, checked: UDP in or serial only (an anemometer talks, it is
    /// not called).
    pub fn anemometer_address(&self) -> Result<Option<Address>, String> {
        let Some(text) = &self.anemometer else {
            return Ok(None);
        };
        match text.parse::<Address>() {
            Ok(a @ (Address::UdpIn(_) | Address::Serial { .. })) => Ok(Some(a)),
            Ok(_) => Err("udpin:IP:PORT or serial:PATH:BAUD".into()),
            Err(e) => Err(e.to_string()),
        }
    }

    /// The first problem as `(field, rule)`, if any.
    pub fn invalid(&self) -> Option<(&'static str, String)> {
        if let Err(rule) = self.anemometer_address() {
            return Some(("surface_wind.anemometer", rule));
        }
        let within = |v: f64, lo: f64, hi: f64| v.is_finite() && (lo..=hi).contains(&v);
        if !within(self.zero_mark_deg, -360.0, 360.0) {
            return Some(("surface_wind.zero_mark_deg", "between −360 and 360°".into()));
        }
        if !within(self.average_s, 1.0, 600.0) {
            return Some(("surface_wind.average_s", "between 1 and 600 s".into()));
        }
        if !within(self.uplink_every_s, 1.0, 120.0) {
            return Some(("surface_wind.uplink_every_s", "between 1 and 120 s".into()));
        }
        if !within(self.stale_after_s, 2.0, 600.0) {
            return Some(("surface_wind.stale_after_s", "between 2 and 600 s".into()));
        }
        if !within(self.operator_valid_s, 10.0, 7200.0) {
            return Some((
                "surface_wind.operator_valid_s",
                "between 10 and 7200 s".into(),
            ));
        }
        None
    }
}

/// Where the wind in force comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SurfaceWindSource {
    /// The ground anemometer's mean.
    Anemometer,
    /// A value the operator typed.
    Operator,
}

/// The drone's copy of the surface wind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum DroneCopy {
    /// Nothing sent yet (no wind, or no drone heard).
    None,
    /// Sent, not yet acknowledged.
    Sending,
    /// The drone accepted the last one sent.
    Held,
    /// The last send failed (see `last_error`); tried again at the next period.
    Failed,
}

/// A surface wind as the pages show it.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct SurfaceWindReadingView {
    /// Speed, m/s.
    pub speed_mps: f64,
    /// Where it blows from, degrees true, 0…360.
    pub from_deg: f64,
    /// Its source.
    pub source: SurfaceWindSource,
    /// Seconds since it was measured: an anemometer's newest sentence in the mean; for the
    /// operator's value as the wind in force (`wind`, `held`) 0 when sent, as the operator
    /// vouches for it as the wind now, and in `operator` the seconds since it was typed.
    pub age_s: f64,
}

/// The ground anemometer's intake.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct AnemometerView {
    /// The address read, as configured.
    pub address: String,
    /// Wind sentences taken.
    pub sentences: u64,
    /// Lines refused (bad checksum, bad field, status "invalid"); other NMEA sentences are
    /// passed over without counting.
    pub rejected: u64,
    /// Why the last line was refused, or the reader failed.
    pub last_error: Option<String>,
    /// Seconds since the last wind sentence; `null` before the first.
    pub heard_age_s: Option<f64>,
    /// Sentences in the mean now.
    pub in_mean: usize,
}

/// The `surface_wind` part of the `state` message.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct SurfaceWindView {
    /// The wind in force, sent to the drone; `null` when there is none (no anemometer heard
    /// within `stale_after_s` and no operator value within `operator_valid_s`).
    pub wind: Option<SurfaceWindReadingView>,
    /// The operator's value, while it is valid (shown also when the anemometer's wins).
    pub operator: Option<SurfaceWindReadingView>,
    /// The drone's copy.
    pub drone: DroneCopy,
    /// What the drone accepted last (its age since measured, as for `wind`); `null` before.
    pub held: Option<SurfaceWindReadingView>,
    /// Seconds since the drone last accepted one; `null` before.
    pub drone_accepted_age_s: Option<f64>,
    /// Why the last send failed.
    pub last_error: Option<String>,
    /// The anemometer; `null` when none is configured.
    pub anemometer: Option<AnemometerView>,
}

/// Most bytes kept of an unfinished line: NMEA sentences are at most 82 characters, so
/// anything longer is noise (a wrong baud rate) and is dropped rather than grown.
const MAX_LINE: usize = 256;

/// Splits an NMEA byte stream into lines, whatever the chunks it arrives in.
#[derive(Debug, Default)]
pub struct SentenceLines {
    partial: Vec<u8>,
    /// The line under way grew too long: skipped up to its end.
    skipping: bool,
    /// Lines dropped for being too long or not text.
    pub dropped: u64,
}

impl SentenceLines {
    /// Takes `bytes` and returns the lines they complete (without their end), in order.
    pub fn push(&mut self, bytes: &[u8]) -> Vec<String> {
        let mut out = Vec::new();
        for &b in bytes {
            if b == b'\n' || b == b'\r' {
                if std::mem::take(&mut self.skipping) {
                    self.partial.clear();
                } else if !self.partial.is_empty() {
                    match std::str::from_utf8(&self.partial) {
                        Ok(s) if s.is_ascii() => out.push(s.to_string()),
                        _ => self.dropped += 1,
                    }
                    self.partial.clear();
                }
            } else if self.skipping {
            } else if self.partial.len() < MAX_LINE {
                self.partial.push(b);
            } else {
                self.partial.clear();
                self.skipping = true;
                self.dropped += 1;
            }
        }
        out
    }

    /// Takes one datagram: a sentence without its line end is whole too.
    pub fn push_datagram(&mut self, bytes: &[u8]) -> Vec<String> {
        let mut lines = self.push(bytes);
        lines.extend(self.push(b"\n"));
        lines
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_come_whole_whatever_the_chunks() {
        let mut l = SentenceLines::default();
        assert!(l.push(b"$WIMWV,27").is_empty());
        assert_eq!(
            l.push(b"0.0,T,3.0,M,A*XX\r\n$IIMWV,1"),
            vec!["$WIMWV,270.0,T,3.0,M,A*XX".to_string()]
        );
        assert_eq!(
            l.push(b"0,R,2,N,A\n"),
            vec!["$IIMWV,10,R,2,N,A".to_string()]
        );
        assert_eq!(
            l.push_datagram(b"$WIMWV,1,T,1,M,A"),
            vec!["$WIMWV,1,T,1,M,A".to_string()]
        );
        assert_eq!(l.dropped, 0);
    }

    #[test]
    fn noise_is_dropped_and_counted_never_grown() {
        let mut l = SentenceLines::default();
        let noise = vec![b'x'; 10_000];
        assert!(l.push(&noise).is_empty());
        assert!(l.partial.len() <= MAX_LINE);
        // The noisy line ends: it is not handed out, the next one is.
        assert!(l.push(b"\n").is_empty());
        assert_eq!(l.dropped, 1);
        assert_eq!(l.push(b"$WIMWV\n"), vec!["$WIMWV".to_string()]);
        assert!(l.push(&[0xff, 0xfe, b'\n']).is_empty());
        assert_eq!(l.dropped, 2);
    }

    #[test]
    fn a_caller_and_not_a_talker_is_refused_as_the_anemometer() {
        let mut c = SurfaceWindConfig::default();
        assert_eq!(c.invalid(), None);
        c.anemometer = Some("udpin:0.0.0.0:10110".into());
        assert_eq!(c.invalid(), None);
        c.anemometer = Some("serial:/dev/ttyUSB0:4800".into());
        assert_eq!(c.invalid(), None);
        c.anemometer = Some("udpout:10.0.0.1:10110".into());
        assert_eq!(c.invalid().map(|(f, _)| f), Some("surface_wind.anemometer"));
        c.anemometer = Some("nonsense".into());
        assert_eq!(c.invalid().map(|(f, _)| f), Some("surface_wind.anemometer"));
        let mut c = SurfaceWindConfig {
            average_s: 0.0,
            ..Default::default()
        };
        assert_eq!(c.invalid().map(|(f, _)| f), Some("surface_wind.average_s"));
        c.average_s = f64::NAN;
        assert_eq!(c.invalid().map(|(f, _)| f), Some("surface_wind.average_s"));
    }
}
