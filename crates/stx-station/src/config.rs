//! The station's configuration (`config/station.toml`): where the drone link is, who may watch
//! and who may command, the mission frame, the map tiles, the forecast wind.
//!
//! Staged like every stx config: the TOML as written ([`StationConfig`]), checked by
//! [`StationConfig::validate`] with errors that name the field, before any task starts.

use std::collections::HashMap;
use std::net::SocketAddr;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};
use stx_gnc::geo::LocalFrame;
use stx_gnc::guidance::GuidanceConfig;
use thiserror::Error;

/// Why a station configuration was refused.
#[derive(Debug, Error)]
pub enum ConfigError {
    /// Not valid TOML for this schema.
    #[error("station config is not valid: {0}")]
    Parse(#[from] toml::de::Error),
    /// A field breaks a rule.
    #[error("station config field `{field}` breaks the rule: {rule}")]
    Invalid {
        /// Path of the field.
        field: String,
        /// The rule.
        rule: String,
    },
}

/// Who may do what.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    /// May read everything.
    Viewer,
    /// May also command the drone.
    Operator,
}

/// One person's (or screen's) access.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TokenConfig {
    /// Name shown in the event log (who armed the cutdown).
    pub name: String,
    /// The secret sent with every request; at least 8 characters.
    pub token: String,
    /// Role.
    pub role: Role,
}

/// The drone link.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkSettings {
    /// stx-link address: `udpin:IP:PORT`, `udpout:…`, `tcp:HOST:PORT`, `tcpin:…`,
    /// `serial:PATH:BAUD`.
    pub address: String,
    /// MAVLink 2 signing key, 64 hex characters (32 bytes); absent: signing off.
    #[serde(default)]
    pub signing_key_hex: Option<String>,
    /// File keeping the signing timestamp's high-water mark across restarts.
    #[serde(default)]
    pub signing_timestamp_file: Option<PathBuf>,
    /// Seconds without a message after which the vehicle's data are shown stale, s.
    #[serde(default = "default_stale_after_s")]
    pub stale_after_s: f64,
}

fn default_stale_after_s() -> f64 {
    3.0
}

/// HTTPS for the dashboard and API (phones' browsers allow geolocation only on a secure
/// page). Both files PEM; see `deploy/README.md` for making them.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TlsSettings {
    /// The certificate chain, PEM, leaf first (e.g. `/etc/stx/station.crt`).
    pub cert_path: PathBuf,
    /// The certificate's private key, PEM (PKCS#8, PKCS#1 or SEC1), readable only by the
    /// station (e.g. `/etc/stx/station.key`).
    pub key_path: PathBuf,
}

/// A row of the forecast wind profile.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForecastRow {
    /// Altitude above mean sea level, m.
    pub alt_msl_m: f64,
    /// Wind speed, m/s.
    pub speed_mps: f64,
    /// Direction the wind blows from, degrees from north.
    pub from_deg: f64,
}

/// The station.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StationConfig {
    /// Name shown on the dashboard.
    pub name: String,
    /// Address the dashboard and API listen on, e.g. `127.0.0.1:8080`.
    pub listen: SocketAddr,
    /// Serve HTTPS instead of HTTP on `listen`; absent: plain HTTP.
    #[serde(default)]
    pub tls: Option<TlsSettings>,
    /// Built dashboard to serve (`npm run build` in `web/`), relative to the working directory.
    #[serde(default = "default_web_dir")]
    pub web_dir: PathBuf,
    /// Map tile URL template for the dashboard (`{z}/{x}/{y}`); a path starting with `/tiles/`
    /// is served from `tiles_dir`. Absent: the map shows its offline grid.
    #[serde(default)]
    pub tile_url: Option<String>,
    /// Attribution shown under the map.
    #[serde(default)]
    pub tile_attribution: String,
    /// Directory of offline tiles `{z}/{x}/{y}.png`, served under `/tiles/`.
    #[serde(default)]
    pub tiles_dir: Option<PathBuf>,
    /// Origin of the mission's local frame (launch site).
    pub origin: LocalFrame,
    /// The drone link.
    pub link: LinkSettings,
    /// Access tokens.
    pub tokens: Vec<TokenConfig>,
    /// The forecast wind, for comparison with the estimate.
    #[serde(default)]
    pub forecast_wind: Vec<ForecastRow>,
    /// The guidance replica's settings (the same defaults as onboard).
    #[serde(default)]
    pub guidance: GuidanceConfig,
    /// Seconds an armed cutdown waits for its confirmation, s.
    #[serde(default = "default_cutdown_window_s")]
    pub cutdown_window_s: f64,
}

fn default_web_dir() -> PathBuf {
    PathBuf::from("web/dist")
}

fn default_cutdown_window_s() -> f64 {
    5.0
}

/// The shipped configuration: the simulated drone on loopback, demo tokens.
pub const DEFAULT_STATION_TOML: &str = include_str!("../../../config/station.toml");

impl StationConfig {
    /// Parses and validates a configuration.
    pub fn from_toml_str(text: &str) -> Result<Self, ConfigError> {
        let config: StationConfig = toml::from_str(text)?;
        config.validate()?;
        Ok(config)
    }

    /// Checks every rule.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let invalid = |field: &str, rule: &str| {
            Err(ConfigError::Invalid {
                field: field.into(),
                rule: rule.into(),
            })
        };
        if self.tokens.is_empty() {
            return invalid("tokens", "at least one token is needed");
        }
        let mut seen: HashMap<&str, usize> = HashMap::new();
        for (i, t) in self.tokens.iter().enumerate() {
            if t.token.len() < 8 {
                return invalid(&format!("tokens[{i}].token"), "at least 8 characters");
            }
            if let Some(j) = seen.insert(t.token.as_str(), i) {
                return invalid(
                    &format!("tokens[{i}].token"),
                    &format!("must differ from tokens[{j}].token"),
                );
            }
            if t.name.trim().is_empty() {
                return invalid(&format!("tokens[{i}].name"), "must not be empty");
            }
        }
        if let Err(e) = self.link.address.parse::<stx_link::transport::Address>() {
            return invalid("link.address", &e.to_string());
        }
        if let Some(key) = &self.link.signing_key_hex
            && (key.len() != 64 || !key.chars().all(|c| c.is_ascii_hexdigit()))
        {
            return invalid(
                "link.signing_key_hex",
                "64 hexadecimal characters (32 bytes)",
            );
        }
        if !(self.link.stale_after_s > 0.0 && self.link.stale_after_s.is_finite()) {
            return invalid("link.stale_after_s", "a finite number of seconds > 0");
        }
        if let Some(tls) = &self.tls {
            if tls.cert_path.as_os_str().is_empty() {
                return invalid("tls.cert_path", "a PEM certificate file");
            }
            if tls.key_path.as_os_str().is_empty() {
                return invalid("tls.key_path", "a PEM private-key file");
            }
        }
        if !(self.cutdown_window_s > 0.0 && self.cutdown_window_s <= 60.0) {
            return invalid("cutdown_window_s", "in (0, 60] s");
        }
        let o = &self.origin;
        if !(o.lat_deg.abs() <= 90.0 && o.lon_deg.abs() <= 180.0 && o.alt_msl_m.is_finite()) {
            return invalid("origin", "latitude within ±90°, longitude within ±180°");
        }
        for (i, r) in self.forecast_wind.iter().enumerate() {
            if !(r.speed_mps >= 0.0 && r.alt_msl_m.is_finite() && r.from_deg.is_finite()) {
                return invalid(&format!("forecast_wind[{i}]"), "finite, speed ≥ 0");
            }
        }
        Ok(())
    }

    /// The role and name of a token, if it is known. Compares in constant time per token so
    /// the response time does not reveal how much of a guess was right.
    pub fn authenticate(&self, token: &str) -> Option<(&str, Role)> {
        self.tokens
            .iter()
            .find(|t| constant_time_eq(t.token.as_bytes(), token.as_bytes()))
            .map(|t| (t.name.as_str(), t.role))
    }
}

fn constant_time_eq(a: &[u8], b: &[u8]) -> bool {
    if a.len() != b.len() {
        return false;
    }
    a.iter().zip(b).fold(0_u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_config_is_valid() {
        let c = StationConfig::from_toml_str(DEFAULT_STATION_TOML).expect("valid");
        assert!(c.tokens.iter().any(|t| t.role == Role::Operator));
        assert!(c.tokens.iter().any(|t| t.role == Role::Viewer));
    }

    #[test]
    fn tokens_authenticate_and_bad_fields_are_named() {
        let c = StationConfig::from_toml_str(DEFAULT_STATION_TOML).expect("valid");
        let op = c
            .tokens
            .iter()
            .find(|t| t.role == Role::Operator)
            .expect("operator");
        assert_eq!(
            c.authenticate(&op.token).map(|(_, r)| r),
            Some(Role::Operator)
        );
        assert!(c.authenticate("nope-nope").is_none());
        let bad = DEFAULT_STATION_TOML.replace("udpin:", "udpfoo:");
        let err = StationConfig::from_toml_str(&bad).unwrap_err().to_string();
        assert!(err.contains("link.address"), "{err}");
        let short = DEFAULT_STATION_TOML.replacen(&op.token, "short", 1);
        let err = StationConfig::from_toml_str(&short)
            .unwrap_err()
            .to_string();
        assert!(err.contains("token"), "{err}");
    }
}
