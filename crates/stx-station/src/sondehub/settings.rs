//! `[sondehub]` in the station's configuration, checked.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

/// Where the station's receiver is, for the map's station icon and each point's
/// `uploader_position`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StationPosition {
    /// Latitude, °.
    pub lat_deg: f64,
    /// Longitude, °.
    pub lon_deg: f64,
    /// Altitude above mean sea level, m.
    pub alt_m: f64,
}

impl StationPosition {
    /// As SondeHub writes a position: `[lat, lon, alt]`.
    pub fn as_array(&self) -> [f64; 3] {
        [self.lat_deg, self.lon_deg, self.alt_m]
    }
}

/// `[sondehub]`: the upload to SondeHub-Amateur; off unless configured.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SondehubConfig {
    /// The API's base address (the real one by default); `/amateur/telemetry` and
    /// `/amateur/listeners` are under it.
    #[serde(default = "default_url")]
    pub url: String,
    /// Who uploads: the station's callsign on the SondeHub map.
    pub uploader_callsign: String,
    /// The payload's callsign on the SondeHub map.
    pub payload_callsign: String,
    /// Time between two points (and two uploads), s (2–30).
    #[serde(default = "default_period_s")]
    pub period_s: f64,
    /// The station's position: shown as a station on the map (re-sent every 6 h) and sent
    /// with each point. None: neither.
    #[serde(default)]
    pub station_position: Option<StationPosition>,
    /// The station's radio, free text for the map (`uploader_radio`).
    #[serde(default)]
    pub radio: String,
    /// The station's antenna, free text for the map (`uploader_antenna`).
    #[serde(default)]
    pub antenna: String,
    /// The callsign under which a recovery phone's position shows as a chase car (default:
    /// the uploader's with `_CHASE`).
    #[serde(default)]
    pub chase_callsign: Option<String>,
    /// Where points wait while the server cannot be reached (a journal file and its mark);
    /// default `sondehub/` in the state directory. None (no state directory): in memory only.
    #[serde(default)]
    pub queue_dir: Option<PathBuf>,
    /// Points kept waiting at most; beyond, the oldest are dropped (counted and shown).
    #[serde(default = "default_queue_max_points")]
    pub queue_max_points: usize,
    /// A point older than this when it is sent goes as `historical: true`, s (10–86,400).
    /// SondeHub hides points more than 24 h from its clock unless they are marked so; the
    /// default, 23 h, leaves an hour for clocks that disagree.
    #[serde(default = "default_historical_after_s")]
    pub historical_after_s: f64,
    /// Longest wait between two tries while the server fails, s (1–3,600); the waits double
    /// from 5 s (or this, if shorter) up to it.
    #[serde(default = "default_retry_max_s")]
    pub retry_max_s: f64,
    /// How long one upload may take before it counts as failed and is tried again, s (1–120).
    #[serde(default = "default_timeout_s")]
    pub timeout_s: f64,
}

fn default_url() -> String {
    "https://api.v2.sondehub.org".into()
}

fn default_period_s() -> f64 {
    10.0
}

fn default_queue_max_points() -> usize {
    20_000
}

fn default_historical_after_s() -> f64 {
    23.0 * 3600.0
}

fn default_retry_max_s() -> f64 {
    120.0
}

fn default_timeout_s() -> f64 {
    20.0
}

/// Callsigns SondeHub hides (its defaults and test callsigns): a flight uploaded under one
/// would not show.
const HIDDEN_CALLSIGNS: [&str; 4] = ["N0CALL", "MYCALL", "CHANGEME_RDZTTGO", "4FSKTEST"];

fn callsign_ok(c: &str) -> bool {
    !c.is_empty() && c.len() <= 32 && c.chars().all(|ch| ch.is_ascii_graphic())
}

fn hidden(c: &str) -> bool {
    HIDDEN_CALLSIGNS
        .iter()
        .any(|h| c.eq_ignore_ascii_case(h) || (*h == "4FSKTEST" && c.starts_with(h)))
}

impl SondehubConfig {
    /// The first problem as `(field, rule)`, if any.
    pub fn invalid(&self) -> Option<(&'static str, &'static str)> {
        const CALLSIGN: &str = "1–32 printable ASCII characters, no spaces, not a default \
                                callsign SondeHub hides (N0CALL, MYCALL, 4FSKTEST…)";
        let url = self.url.trim_end_matches('/');
        let rest = url
            .strip_prefix("https://")
            .or_else(|| url.strip_prefix("http://"));
        if rest.is_none_or(|r| r.is_empty() || r.contains(char::is_whitespace)) {
            return Some(("sondehub.url", "an http:// or https:// address"));
        }
        if !callsign_ok(&self.uploader_callsign) || hidden(&self.uploader_callsign) {
            return Some(("sondehub.uploader_callsign", CALLSIGN));
        }
        if !callsign_ok(&self.payload_callsign) || hidden(&self.payload_callsign) {
            return Some(("sondehub.payload_callsign", CALLSIGN));
        }
        if self
            .chase_callsign
            .as_deref()
            .is_some_and(|c| !callsign_ok(c) || hidden(c))
        {
            return Some(("sondehub.chase_callsign", CALLSIGN));
        }
        if !(2.0..=30.0).contains(&self.period_s) {
            return Some(("sondehub.period_s", "between 2 and 30 s"));
        }
        if let Some(p) = &self.station_position
            && !(p.lat_deg.abs() <= 90.0
                && p.lon_deg.abs() <= 180.0
                && (-500.0..=10_000.0).contains(&p.alt_m))
        {
            return Some((
                "sondehub.station_position",
                "lat_deg −90…90 °, lon_deg −180…180 °, alt_m −500…10,000 m",
            ));
        }
        if !(10..=1_000_000).contains(&self.queue_max_points) {
            return Some(("sondehub.queue_max_points", "between 10 and 1,000,000"));
        }
        if !(10.0..=86_400.0).contains(&self.historical_after_s) {
            return Some(("sondehub.historical_after_s", "between 10 and 86,400 s"));
        }
        if !(1.0..=3600.0).contains(&self.retry_max_s) {
            return Some(("sondehub.retry_max_s", "between 1 and 3,600 s"));
        }
        if !(1.0..=120.0).contains(&self.timeout_s) {
            return Some(("sondehub.timeout_s", "between 1 and 120 s"));
        }
        None
    }

    /// The API's base address without a trailing `/`.
    pub fn base_url(&self) -> &str {
        self.url.trim_end_matches('/')
    }

    /// The chase car's callsign.
    pub fn chase_callsign(&self) -> String {
        self.chase_callsign
            .clone()
            .unwrap_or_else(|| format!("{}_CHASE", self.uploader_callsign))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const OK: &str = "uploader_callsign = \"CT1ABC\"\npayload_callsign = \"STRAPLEX1\"\n";

    fn parse(extra: &str) -> SondehubConfig {
        toml::from_str(&format!("{OK}{extra}")).expect("parses")
    }

    #[test]
    fn defaults_are_the_real_server_every_10_s_and_a_day_less_an_hour() {
        let c = parse("");
        assert_eq!(c.invalid(), None);
        assert_eq!(c.base_url(), "https://api.v2.sondehub.org");
        assert_eq!(
            (c.period_s, c.historical_after_s, c.queue_max_points),
            (10.0, 82_800.0, 20_000)
        );
        assert_eq!(c.chase_callsign(), "CT1ABC_CHASE");
        assert_eq!(
            parse("url = \"http://127.0.0.1:9/\"").base_url(),
            "http://127.0.0.1:9"
        );
    }

    #[test]
    fn a_bad_sondehub_table_names_its_field() {
        let field = |extra: &str| parse(extra).invalid().map(|e| e.0);
        assert_eq!(field("period_s = 1.0"), Some("sondehub.period_s"));
        assert_eq!(field("period_s = 31.0"), Some("sondehub.period_s"));
        assert_eq!(field("url = \"ftp://x\""), Some("sondehub.url"));
        assert_eq!(field("url = \"https://\""), Some("sondehub.url"));
        assert_eq!(
            field("station_position = { lat_deg = 91.0, lon_deg = 0.0, alt_m = 0.0 }"),
            Some("sondehub.station_position")
        );
        assert_eq!(
            field("queue_max_points = 1"),
            Some("sondehub.queue_max_points")
        );
        assert_eq!(
            field("historical_after_s = 90000.0"),
            Some("sondehub.historical_after_s")
        );
        assert_eq!(field("timeout_s = 0.0"), Some("sondehub.timeout_s"));
        assert_eq!(field("retry_max_s = 0.5"), Some("sondehub.retry_max_s"));
        assert_eq!(
            field("chase_callsign = \"N0CALL\""),
            Some("sondehub.chase_callsign")
        );
        let hidden: SondehubConfig =
            toml::from_str("uploader_callsign = \"CT1ABC\"\npayload_callsign = \"4FSKTEST-V2\"\n")
                .expect("parses");
        assert_eq!(
            hidden.invalid().map(|e| e.0),
            Some("sondehub.payload_callsign")
        );
        assert!(toml::from_str::<SondehubConfig>(&format!("{OK}period = 2")).is_err());
    }
}
