//! The station's configuration (`config/station.toml`): where the drone link is, who may watch
//! and who may command, the mission frame, the map tiles, the forecast wind.
//!
//! Staged like every stx config: the TOML as written ([`StationConfig`]), checked by
//! [`StationConfig::validate`] with errors that name the field, before any task starts.

use std::collections::HashMap;
use std::ffi::OsString;
use std::net::{IpAddr, SocketAddr};
use std::path::PathBuf;
use subtle::ConstantTimeEq;

use serde::{Deserialize, Serialize};
use stx_gnc::ascent_wind::AscentWindConfig;
pub use stx_gnc::flight_path::ForecastRow;
use stx_gnc::flight_path::StackConfig;
use stx_gnc::geo::LocalFrame;
use stx_gnc::guidance::GuidanceConfig;
use stx_link::signing::{KeyText, SIGNING_KEY_ENV, SigningKey};
use thiserror::Error;

use crate::limits::LimitSettings;
use crate::recording::settings::RecordingSettings;

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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
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
    /// `serial:PATH:BAUD`. With more radios (`more_addresses`), the primary.
    pub address: String,
    /// Further radios to the same drone (a backup radio), in order of preference, in the
    /// form of `address`. Telemetry is taken from every radio, a frame heard twice once;
    /// commands go out on the first radio (the primary first) heard within the link timeout
    /// (3.5 s). Each radio's rate, loss and age are shown beside the link's.
    #[serde(default)]
    pub more_addresses: Vec<String>,
    /// MAVLink 2 signing key written here, 64 hexadecimal characters (32 bytes). It is then
    /// as secret as this file (mode 0600); prefer `signing_key_file` or the environment
    /// variable `STX_SIGNING_KEY`. At most one of the three; none: signing off. Never shown:
    /// its debug and serialised forms are `<redacted>`.
    #[serde(default)]
    pub signing_key_hex: Option<KeyText>,
    /// File holding the signing key, 64 hexadecimal characters (e.g. `openssl rand -hex 32`),
    /// readable only by the station's user.
    #[serde(default)]
    pub signing_key_file: Option<PathBuf>,
    /// File keeping the signing timestamp's high-water mark across restarts, so timestamps
    /// stay monotonic even when the clock is set back. Required with signing on; when absent,
    /// `stx serve` uses `signing.timestamp` in the state directory (`$STATE_DIRECTORY`, set by
    /// systemd's `StateDirectory=`, else `$XDG_STATE_HOME/stx`, else `~/.local/state/stx`).
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

/// Name of the signing timestamp file in the state directory.
pub const SIGNING_TIMESTAMP_FILE_NAME: &str = "signing.timestamp";

impl LinkSettings {
    /// Every radio's address, the primary first.
    pub fn addresses(&self) -> impl Iterator<Item = &String> {
        std::iter::once(&self.address).chain(&self.more_addresses)
    }

    /// Whether MAVLink 2 signing is on (a key is configured).
    pub fn signing_on(&self) -> bool {
        self.signing_key_hex.is_some() || self.signing_key_file.is_some()
    }

    /// The signing key (read from its file if it is in one); `None`: signing off.
    pub fn signing_key(&self) -> Result<Option<SigningKey>, ConfigError> {
        let invalid = |field: &str, e: stx_link::signing::KeyError| ConfigError::Invalid {
            field: field.into(),
            rule: e.to_string(),
        };
        if let Some(text) = &self.signing_key_hex {
            return text
                .key()
                .map(Some)
                .map_err(|e| invalid("link.signing_key_hex", e));
        }
        self.signing_key_file
            .as_deref()
            .map(SigningKey::from_file)
            .transpose()
            .map_err(|e| invalid("link.signing_key_file", e))
    }
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
    /// is served from `tile_pack` and `tiles_dir`. Absent: `/tiles/{z}/{x}/{y}.EXT` when a
    /// tile pack opened, else the map shows its metric grid.
    #[serde(default)]
    pub tile_url: Option<String>,
    /// Attribution shown under the map; empty: the tile pack's own, if it has one.
    #[serde(default)]
    pub tile_attribution: String,
    /// Directory of offline tiles `{z}/{x}/{y}.png`, served under `/tiles/`.
    #[serde(default)]
    pub tiles_dir: Option<PathBuf>,
    /// Offline map in one file, an MBTiles (`.mbtiles`, SQLite) or PMTiles v3 (`.pmtiles`)
    /// pack of raster tiles prepared at home, served under `/tiles/`. A tile it lacks is
    /// looked for in `tiles_dir`. Opened at start: a missing or unreadable pack is logged and
    /// shown on the map, which then draws its metric grid; the station runs on.
    #[serde(default)]
    pub tile_pack: Option<PathBuf>,
    /// Keep-out zones (water, borders, forest, roads, people), a GeoJSON (RFC 7946) file of
    /// Polygon and MultiPolygon features, each with a `name` property, relative to the working
    /// directory. Read at start: a missing or invalid file stops the station with the reason
    /// (it would otherwise guide and predict as if the zones were not there). Operators' edits
    /// on the dashboard are written back to it. Absent: no zones until an operator draws some
    /// (which are then not kept across a restart).
    #[serde(default)]
    pub keep_out: Option<PathBuf>,
    /// Origin of the mission's local frame (launch site).
    pub origin: LocalFrame,
    /// The drone link.
    pub link: LinkSettings,
    /// Access tokens.
    pub tokens: Vec<TokenConfig>,
    /// The forecast wind, for comparison with the estimate, for the landing predictions
    /// above and below the altitudes the ascent measured, and to start the Plan page's plans
    /// from (the rows of a forecast file, `stx_gnc::flight_path::forecast`; a row's
    /// `sigma_mps` is used by plans only).
    #[serde(default)]
    pub forecast_wind: Vec<ForecastRow>,
    /// A forecast file in place of `forecast_wind` (`[forecast_file]`: GFS GRIB2 files and the
    /// instant to take them at, or a sounding; see
    /// [`crate::forecast_file::ForecastFileConfig`]), read into `forecast_wind` at the launch
    /// site (`origin`) before the station starts ([`Self::load_forecast_file`]).
    #[serde(default)]
    pub forecast_file: Option<crate::forecast_file::ForecastFileConfig>,
    /// How the wind is measured from the balloon's drift during the ascent (`[ascent_wind]`:
    /// band height, fixes per band, what counts as rising; see
    /// [`AscentWindConfig`]); the defaults suit a sounding balloon with a 1–10 Hz GPS.
    #[serde(default)]
    pub ascent_wind: AscentWindConfig,
    /// The stack's balloon, round chute and deployment as the live flight path flies them
    /// (`[flight_path]`: mean ascent rate m/s, burst altitude m MSL, chute Cd·A m² and mass kg,
    /// deploy height m above the origin, …; see [`StackConfig`]). The drone's `MIS_DEPLOY_M`,
    /// `MIS_CUTDOWN_M`, `MIS_BURST_M` and `MIS_ASCENT_MPS` win once its parameters are read.
    #[serde(default)]
    pub flight_path: StackConfig,
    /// The launch profile's `[flight_path]` settings ([`LAUNCH_PROFILE_KEYS`]) the file left
    /// out: the live flight path does not fly their defaults silently (`core/flight_path.rs`).
    /// Empty for a configuration built in code, whose values were chosen there.
    #[serde(skip)]
    pub flight_path_unset: Vec<&'static str>,
    /// The guidance replica's settings (the same defaults as onboard).
    #[serde(default)]
    pub guidance: GuidanceConfig,
    /// Seconds an armed cutdown waits for its confirmation, s.
    #[serde(default = "default_cutdown_window_s")]
    pub cutdown_window_s: f64,
    /// Flight recordings (`[recording]`): on by default, in the state directory.
    #[serde(default)]
    pub recording: RecordingSettings,
    /// The go/no-go board (`[readiness]`: the checklist file, the saved parameter set, the
    /// battery's least voltage V and the plan's least reach share; see
    /// [`crate::checklist::ReadinessConfig`]).
    #[serde(default)]
    pub readiness: crate::checklist::ReadinessConfig,
    /// What one caller may ask (`[limits]`: requests per token, wrong tokens per address,
    /// pages at once); the defaults suit a field laptop.
    #[serde(default)]
    pub limits: LimitSettings,
    /// Read-only MAVLink outputs for watching ground stations (`[[forward]]`, see
    /// [`crate::forward`]); none by default.
    #[serde(default)]
    pub forward: Vec<crate::forward::ForwardConfig>,
    /// The broadcast for chase cars' maps (`[chase]`, see [`crate::chase`]); off without it.
    #[serde(default)]
    pub chase: Option<crate::chase::settings::ChaseConfig>,
    /// The upload to SondeHub-Amateur (`[sondehub]`, see [`crate::sondehub`]); off without it.
    #[serde(default)]
    pub sondehub: Option<crate::sondehub::SondehubConfig>,
    /// The wind at the target (`[surface_wind]`, see [`crate::surface_wind`]): the ground
    /// anemometer, if any, and how its wind or the operator's is sent to the drone.
    #[serde(default)]
    pub surface_wind: crate::surface_wind::SurfaceWindConfig,
    /// Test-only: loopback addresses treated as not loopback, from the environment's
    /// [`NOT_LOOPBACK_ENV`] (see [`crate::exposure`]); empty in the field.
    #[serde(skip)]
    pub not_loopback: Vec<IpAddr>,
    /// Whether `forecast_wind` holds the rows read from `forecast_file`.
    #[serde(skip)]
    pub forecast_file_loaded: bool,
}

fn default_web_dir() -> PathBuf {
    PathBuf::from("web/dist")
}

fn default_cutdown_window_s() -> f64 {
    5.0
}

/// The `[flight_path]` settings that describe this flight's balloon rather than a model: the
/// drone's `MIS_BURST_M` and `MIS_ASCENT_MPS` give them when loaded.
pub const LAUNCH_PROFILE_KEYS: [&str; 2] = ["burst_altitude_msl_m", "mean_ascent_rate_mps"];

/// Test-only: loopback addresses (comma-separated, e.g. `127.0.0.2`) the station treats as
/// not loopback, so a test on one machine sees what a station on the field network does
/// ([`crate::exposure`]).
pub const NOT_LOOPBACK_ENV: &str = "STX_TEST_NOT_LOOPBACK";

/// The loopback addresses [`NOT_LOOPBACK_ENV`] names in `env`; `Err` names what is not an
/// address.
pub fn not_loopback_from_env(
    env: impl Fn(&str) -> Option<OsString>,
) -> Result<Vec<IpAddr>, String> {
    let Some(text) = env(NOT_LOOPBACK_ENV) else {
        return Ok(Vec::new());
    };
    let text = text.to_string_lossy().into_owned();
    text.split(',')
        .map(str::trim)
        .filter(|a| !a.is_empty())
        .map(|a| a.parse().map_err(|_| format!("`{a}` is not an IP address")))
        .collect()
}

/// Where the SondeHub queue waits in the state directory unless `sondehub.queue_dir` says.
pub const SONDEHUB_QUEUE_DIR_NAME: &str = "sondehub";

/// The shipped configuration: the simulated drone on loopback, demo tokens.
pub const DEFAULT_STATION_TOML: &str = include_str!("../../../config/station.toml");

impl StationConfig {
    /// Parses and validates a configuration as written (nothing from the environment).
    pub fn from_toml_str(text: &str) -> Result<Self, ConfigError> {
        Self::from_toml_str_with_env(text, |_| None)
    }

    /// Parses a configuration, completes it from the environment `env` (e.g.
    /// `|k| std::env::var_os(k)`, see [`StationConfig::apply_environment`]) and validates it.
    pub fn from_toml_str_with_env(
        text: &str,
        env: impl Fn(&str) -> Option<OsString>,
    ) -> Result<Self, ConfigError> {
        let mut config: StationConfig = toml::from_str(text)?;
        let table: toml::Table = toml::from_str(text)?;
        let given = |key: &str| table.get("flight_path").and_then(|f| f.get(key)).is_some();
        config.flight_path_unset = LAUNCH_PROFILE_KEYS
            .into_iter()
            .filter(|k| !given(k))
            .collect();
        config.apply_environment(env)?;
        config.validate()?;
        Ok(config)
    }

    /// Takes the signing key from `STX_SIGNING_KEY` in `env` when it is set (a key in the file
    /// as well is refused: one source only), and, with signing on and no
    /// `link.signing_timestamp_file`, the default one in the state directory; and a test's
    /// addresses that are not loopback ([`NOT_LOOPBACK_ENV`]).
    pub fn apply_environment(
        &mut self,
        env: impl Fn(&str) -> Option<OsString>,
    ) -> Result<(), ConfigError> {
        if let Some(text) = env(SIGNING_KEY_ENV) {
            if self.link.signing_on() {
                return Err(ConfigError::Invalid {
                    field: "link.signing_key_hex".into(),
                    rule: format!("the key is also in {SIGNING_KEY_ENV}: give it one way only"),
                });
            }
            let text = text.into_string().map_err(|_| ConfigError::Invalid {
                field: SIGNING_KEY_ENV.into(),
                rule: "64 hexadecimal characters (32 bytes)".into(),
            })?;
            self.link.signing_key_hex = Some(KeyText::new(text));
        }
        if self.link.signing_on() && self.link.signing_timestamp_file.is_none() {
            self.link.signing_timestamp_file = stx_link::signing::persist::default_state_dir(&env)
                .map(|dir| dir.join(SIGNING_TIMESTAMP_FILE_NAME));
        }
        self.not_loopback = not_loopback_from_env(&env).map_err(|rule| ConfigError::Invalid {
            field: NOT_LOOPBACK_ENV.into(),
            rule,
        })?;
        if let Some(sondehub) = self.sondehub.as_mut()
            && sondehub.queue_dir.is_none()
        {
            sondehub.queue_dir = stx_link::signing::persist::default_state_dir(&env)
                .map(|dir| dir.join(SONDEHUB_QUEUE_DIR_NAME));
        }
        if self.recording.enabled && self.recording.dir.is_none() {
            self.recording.dir = stx_link::signing::persist::default_state_dir(&env)
                .map(|dir| stx_record::file::recordings_dir(&dir));
        }
        Ok(())
    }

    /// Reads `forecast_file`, if any, into `forecast_wind` at the launch site (reads files:
    /// the caller runs it once, after parsing and before the station starts).
    pub fn load_forecast_file(&mut self) -> Result<(), ConfigError> {
        let Some(file) = &self.forecast_file else {
            return Ok(());
        };
        self.forecast_wind = file
            .rows(self.origin.lat_deg, self.origin.lon_deg)
            .map_err(|rule| ConfigError::Invalid {
                field: "forecast_file".into(),
                rule,
            })?;
        self.forecast_file_loaded = true;
        Ok(())
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
        if let Some((field, rule)) = self.readiness.invalid() {
            return invalid(field, rule);
        }
        if let Some((field, rule)) = crate::forward::ForwardConfig::invalid(&self.forward) {
            return invalid(&field, &rule);
        }
        if let Some((field, rule)) = self.chase.as_ref().and_then(|c| c.invalid()) {
            return invalid(field, rule);
        }
        if let Some((field, rule)) = self.sondehub.as_ref().and_then(|c| c.invalid()) {
            return invalid(field, rule);
        }
        if let Some((field, rule)) = self.surface_wind.invalid() {
            return invalid(field, &rule);
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
        if let Err(e) = self.link.address.parse::<stx_link::address::Address>() {
            return invalid("link.address", &e.to_string());
        }
        for (i, more) in self.link.more_addresses.iter().enumerate() {
            use stx_link::address::Address;
            let field = format!("link.more_addresses[{i}]");
            let parsed = match more.parse::<Address>() {
                Ok(a) => a,
                Err(e) => return invalid(&field, &e.to_string()),
            };
            // Port 0 asks for a fresh port each time: the same text is another socket.
            let fresh_port =
                matches!(parsed, Address::UdpIn(a) | Address::TcpServer(a) if a.port() == 0);
            if !fresh_port && self.link.addresses().position(|a| a == more) != Some(i + 1) {
                return invalid(&field, "is already one of the link's addresses");
            }
        }
        if self.link.signing_key_hex.is_some() && self.link.signing_key_file.is_some() {
            return invalid(
                "link.signing_key_file",
                "give the key one way only (signing_key_hex or signing_key_file)",
            );
        }
        if let Some(text) = &self.link.signing_key_hex
            && let Err(e) = text.key()
        {
            return invalid("link.signing_key_hex", &e.to_string());
        }
        if self.link.signing_on() && self.link.signing_timestamp_file.is_none() {
            return invalid(
                "link.signing_timestamp_file",
                "required with signing on, so the timestamps stay monotonic across restarts \
                 (stx serve defaults it to signing.timestamp in $STATE_DIRECTORY, \
                 $XDG_STATE_HOME/stx or ~/.local/state/stx; none of them is set)",
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
        if let Some(pack) = &self.tile_pack {
            let extension = pack.extension().and_then(|e| e.to_str());
            if !extension.is_some_and(|e| {
                e.eq_ignore_ascii_case("mbtiles") || e.eq_ignore_ascii_case("pmtiles")
            }) {
                return invalid("tile_pack", "an .mbtiles or .pmtiles file");
            }
        }
        if self
            .keep_out
            .as_ref()
            .is_some_and(|p| p.as_os_str().is_empty())
        {
            return invalid("keep_out", "a GeoJSON file");
        }
        if let Err((field, rule)) = self.recording.check() {
            return invalid(field, rule);
        }
        if let Err((field, rule)) = self.limits.check() {
            return invalid(field, rule);
        }
        if !(self.cutdown_window_s > 0.0 && self.cutdown_window_s <= 60.0) {
            return invalid("cutdown_window_s", "in (0, 60] s");
        }
        let o = &self.origin;
        if !(o.lat_deg.abs() <= 90.0 && o.lon_deg.abs() <= 180.0 && o.alt_msl_m.is_finite()) {
            return invalid("origin", "latitude within ±90°, longitude within ±180°");
        }
        if let Err(stx_gnc::flight_path::FlightPathError::Invalid { field, rule, .. }) =
            self.flight_path.validate()
        {
            return invalid(&format!("flight_path.{field}"), rule);
        }
        if let Err(stx_gnc::ascent_wind::AscentWindConfigError::Invalid { field, rule, .. }) =
            self.ascent_wind.validate()
        {
            return invalid(&format!("ascent_wind.{field}"), rule);
        }
        if let Some(file) = &self.forecast_file {
            if let Some((field, rule)) = file.invalid() {
                return invalid(&format!("forecast_file.{field}"), &rule);
            }
            if !self.forecast_wind.is_empty() && !self.forecast_file_loaded {
                return invalid(
                    "forecast_file",
                    "give forecast_wind rows or a forecast_file, not both",
                );
            }
        }
        for (i, r) in self.forecast_wind.iter().enumerate() {
            let sigma_ok = r.sigma_mps.is_none_or(|s| s.is_finite() && s >= 0.0);
            let finite = r.alt_msl_m.is_finite() && r.from_deg.is_finite();
            if !(r.speed_mps >= 0.0 && finite && sigma_ok) {
                return invalid(
                    &format!("forecast_wind[{i}]"),
                    "finite, speed and sigma ≥ 0",
                );
            }
        }
        Ok(())
    }

    /// The role and name of a token, if it is known. Compares in constant time per token so
    /// the response time does not reveal how much of a guess was right.
    pub fn authenticate(&self, token: &str) -> Option<(&str, Role)> {
        self.tokens
            .iter()
            .find(|t| bool::from(t.token.as_bytes().ct_eq(token.as_bytes())))
            .map(|t| (t.name.as_str(), t.role))
    }

    /// The first operator's token: what `stx serve`, `stx replay` and the benches put in the
    /// dashboard's address they print.
    pub fn operator_token(&self) -> Option<&str> {
        self.tokens
            .iter()
            .find(|t| t.role == Role::Operator)
            .map(|t| t.token.as_str())
    }
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
    fn a_second_radio_is_taken_and_a_bad_or_repeated_one_is_named() {
        let with = |more: &str| {
            DEFAULT_STATION_TOML.replacen(
                "[link]\n",
                &format!("[link]\nmore_addresses = [{more}]\n"),
                1,
            )
        };
        let c = StationConfig::from_toml_str(&with("\"udpin:127.0.0.1:14551\""))
            .expect("a backup radio");
        assert_eq!(
            c.link.addresses().collect::<Vec<_>>(),
            ["udpin:127.0.0.1:14550", "udpin:127.0.0.1:14551"]
        );
        let err = StationConfig::from_toml_str(&with("\"udpin:127.0.0.1:14551\", \"radio\""))
            .unwrap_err()
            .to_string();
        assert!(err.contains("link.more_addresses[1]"), "{err}");
        let err = StationConfig::from_toml_str(&with("\"udpin:127.0.0.1:14550\""))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("link.more_addresses[0]") && err.contains("already"),
            "{err}"
        );
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

    #[test]
    fn a_tile_pack_must_be_an_mbtiles_or_pmtiles_file_and_need_not_exist_yet() {
        let with = |line: &str| {
            DEFAULT_STATION_TOML.replacen(
                "tile_attribution",
                &format!("{line}\ntile_attribution"),
                1,
            )
        };
        for good in [
            "/srv/maps/field.mbtiles",
            "field.PMTiles",
            "/nonexistent/alentejo.pmtiles",
        ] {
            let c = StationConfig::from_toml_str(&with(&format!("tile_pack = \"{good}\"")))
                .expect(good);
            assert_eq!(c.tile_pack, Some(PathBuf::from(good)));
        }
        for bad in ["", "/srv/maps/field.zip", "/srv/maps/tiles", "mbtiles"] {
            let err = StationConfig::from_toml_str(&with(&format!("tile_pack = \"{bad}\"")))
                .unwrap_err()
                .to_string();
            assert!(
                err.contains("`tile_pack`") && err.contains(".mbtiles or .pmtiles"),
                "{bad}: {err}"
            );
        }
        let c = StationConfig::from_toml_str(DEFAULT_STATION_TOML).expect("valid");
        assert_eq!(c.tile_pack, None);
    }

    const KEY: &str = "5ec2e75ec2e75ec2e75ec2e75ec2e75ec2e75ec2e75ec2e75ec2e75ec2e75ec2";

    fn with_link(extra: &str) -> String {
        DEFAULT_STATION_TOML.replace(
            "stale_after_s = 3.0",
            &format!("stale_after_s = 3.0\n{extra}"),
        )
    }

    fn env<'a>(vars: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<OsString> + 'a {
        move |k| {
            vars.iter()
                .find(|(name, _)| *name == k)
                .map(|(_, v)| OsString::from(v))
        }
    }

    /// Regression: a key without a timestamp file passed, and the timestamps then went back
    /// with the clock after a restart.
    #[test]
    fn signing_needs_a_timestamp_file_which_defaults_to_the_state_directory() {
        let text = with_link(&format!("signing_key_hex = \"{KEY}\""));
        let err = StationConfig::from_toml_str(&text).unwrap_err().to_string();
        assert!(err.contains("link.signing_timestamp_file"), "{err}");
        let c = StationConfig::from_toml_str_with_env(
            &text,
            env(&[("STATE_DIRECTORY", "/var/lib/stx"), ("HOME", "/home/op")]),
        )
        .expect("valid with a state directory");
        assert_eq!(
            c.link.signing_timestamp_file,
            Some(PathBuf::from("/var/lib/stx/signing.timestamp"))
        );
        let c = StationConfig::from_toml_str_with_env(&text, env(&[("HOME", "/home/op")]))
            .expect("valid with a home");
        assert_eq!(
            c.link.signing_timestamp_file,
            Some(PathBuf::from("/home/op/.local/state/stx/signing.timestamp"))
        );
        // Given explicitly, it is kept.
        let text = with_link(&format!(
            "signing_key_hex = \"{KEY}\"\nsigning_timestamp_file = \"/srv/ts\""
        ));
        let c = StationConfig::from_toml_str_with_env(&text, env(&[("HOME", "/home/op")]))
            .expect("valid");
        assert_eq!(
            c.link.signing_timestamp_file,
            Some(PathBuf::from("/srv/ts"))
        );
        // Without signing nothing is filled in.
        let c = StationConfig::from_toml_str_with_env(DEFAULT_STATION_TOML, env(&[("HOME", "/h")]))
            .expect("valid");
        assert_eq!(c.link.signing_timestamp_file, None);
        assert!(c.link.signing_key().expect("no key").is_none());
    }

    #[test]
    fn the_key_comes_from_one_place_the_file_or_the_environment() {
        let dir = std::env::temp_dir().join(format!("stx-station-key-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let key_file = dir.join("key");
        std::fs::write(&key_file, format!("{KEY}\n")).expect("write");
        let ts = "signing_timestamp_file = \"/srv/ts\"";
        let text = with_link(&format!("signing_key_file = {key_file:?}\n{ts}"));
        let c = StationConfig::from_toml_str(&text).expect("valid");
        let from_file = c.link.signing_key().expect("readable").expect("a key");
        assert!(from_file == SigningKey::from_hex(KEY).expect("hex"));

        let c =
            StationConfig::from_toml_str_with_env(&with_link(ts), env(&[(SIGNING_KEY_ENV, KEY)]))
                .expect("valid");
        assert!(c.link.signing_key().expect("valid").expect("a key") == from_file);

        for (text, vars, field) in [
            (
                with_link(&format!("signing_key_file = {key_file:?}\n{ts}")),
                vec![(SIGNING_KEY_ENV, KEY)],
                "link.signing_key_hex",
            ),
            (
                with_link(&format!(
                    "signing_key_file = {key_file:?}\nsigning_key_hex = \"{KEY}\"\n{ts}"
                )),
                vec![],
                "link.signing_key_file",
            ),
            (
                with_link(&format!("signing_key_hex = \"{}\"\n{ts}", &KEY[..60])),
                vec![],
                "link.signing_key_hex",
            ),
        ] {
            let err = StationConfig::from_toml_str_with_env(&text, env(&vars))
                .unwrap_err()
                .to_string();
            assert!(err.contains(field), "{field}: {err}");
            assert!(
                !err.contains(&KEY[..60]),
                "the key is never repeated: {err}"
            );
        }
        let missing = with_link(&format!("signing_key_file = \"/nonexistent/key\"\n{ts}"));
        let c = StationConfig::from_toml_str(&missing).expect("valid until read");
        let err = c.link.signing_key().map(drop).unwrap_err().to_string();
        assert!(err.contains("/nonexistent/key"), "{err}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Regression: `signing_key_hex` was a plain `String` that `Debug` and `Serialize` printed.
    #[test]
    fn debug_and_serialised_config_never_contain_the_key() {
        let text = with_link(&format!(
            "signing_key_hex = \"{KEY}\"\nsigning_timestamp_file = \"/srv/ts\""
        ));
        let c = StationConfig::from_toml_str(&text).expect("valid");
        assert!(c.link.signing_key().expect("valid").is_some());
        for shown in [
            format!("{c:?}"),
            format!("{:#?}", c.link),
            serde_json::to_string(&c).expect("json"),
            toml::to_string(&c).expect("toml"),
        ] {
            assert!(!shown.contains("5ec2e7"), "{shown}");
            assert!(shown.contains("<redacted>"), "{shown}");
        }
    }
}
