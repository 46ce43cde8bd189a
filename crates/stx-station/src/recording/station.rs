//! The station's own channels: what it showed (`state`), its estimate and predicted landing
//! on the map, its events, operators' requests and their results, the parameter table and
//! its configuration. Each function returns what to write — `(channel, payload)` — so it is
//! tested without a file, and the daemon hands the pairs to the recorder's queue.

use schemars::{JsonSchema, schema_for};
use serde::Serialize;
use serde_json::{Value, json};
use stx_record::foxglove::{self, LocationFix, Log, LogLevel, PositionCovarianceType, Timestamp};
use stx_record::{ChannelId, ChannelSpec, RecorderCore, WriteError};

use super::{compact_json, compact_value};
use crate::config::StationConfig;
use crate::messages::{
    CommandResultMsg, EstimateView, EventMsg, Level, ParamsMsg, StateMsg, TouchdownView,
};

/// Schema name of [`CommandRecord`].
pub const COMMAND_RECORD: &str = "stx.CommandRecord";

/// An operator's request as the station accepted it (its outcome follows on
/// [`super::COMMAND_RESULTS`] under the same `request_id`).
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct CommandRecord {
    /// Mission clock, s.
    pub time_s: f64,
    /// The request's id.
    pub request_id: String,
    /// The name of the token it came with.
    pub by: String,
    /// What was asked, as the event log says it.
    pub text: String,
}

/// The station's channels, registered in a recorder.
#[derive(Debug, Clone)]
pub struct StationChannels {
    state: ChannelId,
    estimate_position: ChannelId,
    predicted_landing: ChannelId,
    events: ChannelId,
    log: ChannelId,
    commands: ChannelId,
    command_results: ChannelId,
    params: ChannelId,
    config: ChannelId,
}

fn schema_of<T: JsonSchema>() -> Value {
    serde_json::to_value(schema_for!(T)).unwrap_or_else(|_| json!({"type": "object"}))
}

fn channel(
    core: &mut RecorderCore,
    now: std::time::Duration,
    spec: Result<ChannelSpec, stx_record::ChannelError>,
) -> Result<ChannelId, WriteError> {
    core.add_channel(now, spec?)
}

impl StationChannels {
    /// Registers the channels in `core` at `now` (the core's clock).
    pub fn register(core: &mut RecorderCore, now: std::time::Duration) -> Result<Self, WriteError> {
        let config_schema = json!({
            "title": "stx.StationConfig",
            "description": "The station's TOML as it ran (crates/stx-station/src/config.rs), \
                            tokens reduced to their holders' names and roles",
            "type": "object"
        });
        Ok(Self {
            state: channel(
                core,
                now,
                ChannelSpec::json(super::STATE, "stx.StateMsg", &schema_of::<StateMsg>()),
            )?,
            estimate_position: channel(
                core,
                now,
                foxglove::location_fix_channel(super::ESTIMATE_POSITION),
            )?,
            predicted_landing: channel(
                core,
                now,
                foxglove::location_fix_channel(super::PREDICTED_LANDING),
            )?,
            events: channel(
                core,
                now,
                ChannelSpec::json(super::EVENTS, "stx.EventMsg", &schema_of::<EventMsg>()),
            )?,
            log: channel(core, now, foxglove::log_channel(super::LOG))?,
            commands: channel(
                core,
                now,
                ChannelSpec::json(
                    super::COMMANDS,
                    COMMAND_RECORD,
                    &schema_of::<CommandRecord>(),
                ),
            )?,
            command_results: channel(
                core,
                now,
                ChannelSpec::json(
                    super::COMMAND_RESULTS,
                    "stx.CommandResultMsg",
                    &schema_of::<CommandResultMsg>(),
                ),
            )?,
            params: channel(
                core,
                now,
                ChannelSpec::json(super::PARAMS, "stx.ParamsMsg", &schema_of::<ParamsMsg>()),
            )?,
            config: channel(
                core,
                now,
                ChannelSpec::json(super::CONFIG, "stx.StationConfig", &config_schema),
            )?,
        })
    }

    /// A `state` message (as [`recorded_state`] keeps it), and the estimate and predicted
    /// landing it holds for the map.
    /// `ground_alt_msl_m` is the launch site's altitude (predictions are to its ground).
    pub fn state(&self, state: &StateMsg, ground_alt_msl_m: f64) -> Vec<(ChannelId, Vec<u8>)> {
        let ts = Timestamp::from_nanos(wall_ns(state.wall_ms));
        let mut out = vec![(self.state, compact_value(recorded_state(state)))];
        if let Some(e) = &state.estimate {
            out.push((self.estimate_position, compact_json(&estimate_fix(ts, e))));
        }
        if let Some(p) = &state.prediction {
            let touchdown = p.planned.as_ref().unwrap_or(&p.uncontrolled);
            out.push((
                self.predicted_landing,
                compact_json(&touchdown_fix(ts, touchdown, ground_alt_msl_m)),
            ));
        }
        out
    }

    /// An event, on the station's channel and Foxglove's log.
    pub fn event(&self, event: &EventMsg) -> Vec<(ChannelId, Vec<u8>)> {
        let log = Log {
            timestamp: Timestamp::from_nanos(wall_ns(event.wall_ms)),
            level: match event.level {
                Level::Info => LogLevel::Info,
                Level::Warning => LogLevel::Warning,
                Level::Error => LogLevel::Error,
            },
            message: event.text.clone(),
            name: event.source.to_owned(),
            file: String::new(),
            line: 0,
        };
        vec![
            (self.events, compact_json(event)),
            (self.log, compact_json(&log)),
        ]
    }

    /// An accepted request.
    pub fn command(&self, record: &CommandRecord) -> (ChannelId, Vec<u8>) {
        (self.commands, compact_json(record))
    }

    /// A request's result.
    pub fn command_result(&self, result: &CommandResultMsg) -> (ChannelId, Vec<u8>) {
        (self.command_results, compact_json(result))
    }

    /// The parameter table.
    pub fn params(&self, params: &ParamsMsg) -> (ChannelId, Vec<u8>) {
        (self.params, compact_json(params))
    }

    /// The configuration, without secrets.
    pub fn config(&self, config: &StationConfig) -> (ChannelId, Vec<u8>) {
        (self.config, compact_json(&redacted(config)))
    }
}

impl stx_record::Named for crate::config::TokenConfig {
    fn name(&self) -> &str {
        &self.name
    }
}

/// Unix ms → ns.
pub fn wall_ns(wall_ms: u64) -> u64 {
    wall_ms.saturating_mul(1_000_000)
}

/// The configuration as JSON with every token replaced by its holder's name and role. The
/// signing key never serialises (`KeyText`); the tokens are removed here.
pub fn redacted(config: &StationConfig) -> Value {
    let mut value = serde_json::to_value(config).unwrap_or(Value::Null);
    if let Some(tokens) = value.get_mut("tokens").and_then(Value::as_array_mut) {
        for t in tokens.iter_mut() {
            if let Some(map) = t.as_object_mut() {
                map.remove("token");
            }
        }
    }
    value
}

fn estimate_fix(timestamp: Timestamp, e: &EstimateView) -> LocationFix {
    let var = e.position_sigma_m * e.position_sigma_m;
    LocationFix {
        timestamp,
        frame_id: "estimate".into(),
        latitude: e.lat_deg,
        longitude: e.lon_deg,
        altitude: e.alt_msl_m,
        // The estimator's horizontal σ, taken for all three axes: approximate.
        position_covariance: [var, 0.0, 0.0, 0.0, var, 0.0, 0.0, 0.0, var],
        position_covariance_type: PositionCovarianceType::Approximated,
    }
}

/// A predicted touchdown with its 1-σ ellipse as an East-North covariance: semi-axes `a`
/// (along the major axis at `θ` clockwise from north) and `b`, Σ = a²·u·uᵀ + b²·v·vᵀ with
/// u = (sin θ, cos θ) and v = (cos θ, −sin θ) in (E, N).
fn touchdown_fix(timestamp: Timestamp, t: &TouchdownView, ground_alt_msl_m: f64) -> LocationFix {
    let (s, c) = t.major_axis_deg.to_radians().sin_cos();
    let (a2, b2) = (t.semi_major_m.powi(2), t.semi_minor_m.powi(2));
    let ee = a2 * s * s + b2 * c * c;
    let nn = a2 * c * c + b2 * s * s;
    let en = (a2 - b2) * s * c;
    LocationFix {
        timestamp,
        frame_id: "predicted_landing".into(),
        latitude: t.lat_deg,
        longitude: t.lon_deg,
        altitude: ground_alt_msl_m,
        position_covariance: [ee, en, 0.0, en, nn, 0.0, 0.0, 0.0, 0.0],
        // Horizontal only: the point is on the ground.
        position_covariance_type: PositionCovarianceType::Approximated,
    }
}

/// `state` as recorded: what the dashboard showed, less two parts another record holds
/// exactly — `link.ages_s` (each telemetry message's age, which its `/telemetry/…` log times
/// give to the nanosecond) and `recording` (this file's own figures; a replay shows none).
/// Noise-like and changing every second, they were nearly a tenth of a flight's file.
pub fn recorded_state(state: &StateMsg) -> Value {
    let mut v = serde_json::to_value(state).unwrap_or(Value::Null);
    if let Some(ages) = v.pointer_mut("/link/ages_s") {
        *ages = json!({});
    }
    if let Some(recording) = v.get_mut("recording") {
        *recording = Value::Null;
    }
    v
}

#[cfg(test)]
mod tests;
