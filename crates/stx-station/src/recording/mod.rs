//! What the station records of a flight, and under which MCAP topics: the one place a
//! recording's layout is defined, so the station, `stx import` (tlogs), `stx export` and
//! replay agree on it. Pure: it turns the station's inputs and outputs into channel specs
//! and JSON payloads; the file thread that writes them is stx-record's `Recorder`, started by
//! the daemon.
//!
//! Topics (every channel JSON with a JSON Schema; times are MCAP log times, ns since the Unix
//! epoch, in whole milliseconds as the station records them):
//! - [`FRAMES`]: the link's bytes, both ways, per radio (`stx.MavlinkFrame`). Received
//!   entries are what the radio delivered — one UDP datagram (a MAVLink frame, or garbage a
//!   stranger sent) or one read of a stream — so a replay meets exactly what the station met;
//!   sent entries are one frame each.
//! - `/telemetry/<MAVLINK_MESSAGE>` ([`telemetry_topic`]): each decoded telemetry message, as
//!   stx-link's typed telemetry (`stx.telemetry.<MAVLINK_MESSAGE>`).
//! - [`VEHICLE_GPS`] (`foxglove.LocationFix`, the drone's GPS with its accuracy) and
//!   [`VEHICLE_ATTITUDE`] (`foxglove.FrameTransform`, body in the local NED frame): for
//!   Foxglove's map and 3-D panels.
//! - [`STATE`]: the station's `state` message at 1 Hz (link, vehicle, estimate, guidance phase
//!   and pattern, prediction, mission, the recording itself) — what the dashboard showed.
//! - [`ESTIMATE_POSITION`], [`PREDICTED_LANDING`] (`foxglove.LocationFix`): the station's
//!   estimate and predicted landing, with covariance, for the map.
//! - [`EVENTS`] (`stx.EventMsg`) and [`LOG`] (`foxglove.Log`): the event log.
//! - [`COMMANDS`] (who asked for what, when) and [`COMMAND_RESULTS`] (what became of it).
//! - [`PARAMS`]: the drone's parameter table each time it changes.
//! - [`CONFIG`]: the station's configuration at start, without secrets (token names and roles
//!   only, never a token or the signing key).

pub mod ascent;
pub mod settings;
pub mod station;
pub mod summary;
pub mod telemetry;
pub mod tlog;

/// The link's raw bytes, both directions.
pub const FRAMES: &str = "/mavlink/frames";
/// Prefix of the decoded telemetry topics.
pub const TELEMETRY_PREFIX: &str = "/telemetry/";
/// The drone's GPS position (`foxglove.LocationFix`).
pub const VEHICLE_GPS: &str = "/vehicle/gps";
/// The drone's attitude (`foxglove.FrameTransform`, parent `ned`, child `body`).
pub const VEHICLE_ATTITUDE: &str = "/vehicle/attitude";
/// The station's `state` messages.
pub const STATE: &str = "/station/state";
/// The station's estimate of the position (`foxglove.LocationFix`).
pub const ESTIMATE_POSITION: &str = "/station/estimate/position";
/// The station's predicted landing point (`foxglove.LocationFix`).
pub const PREDICTED_LANDING: &str = "/station/prediction/landing";
/// The station's events.
pub const EVENTS: &str = "/station/events";
/// The same events for Foxglove's log panel (`foxglove.Log`).
pub const LOG: &str = "/log";
/// Operators' requests: who asked for what.
pub const COMMANDS: &str = "/station/commands";
/// What became of each request.
pub const COMMAND_RESULTS: &str = "/station/command_results";
/// The drone's parameter table.
pub const PARAMS: &str = "/station/params";
/// The station's configuration, without secrets.
pub const CONFIG: &str = "/station/config";

/// The topic of a decoded telemetry message, by its MAVLink name (`GLOBAL_POSITION_INT` →
/// `/telemetry/GLOBAL_POSITION_INT`).
pub fn telemetry_topic(mavlink_name: &str) -> String {
    format!("{TELEMETRY_PREFIX}{mavlink_name}")
}

/// JSON of `value` as the recording stores it: every fractional number rounded to what it
/// carries — 7 significant digits below 1 (MAVLink's floats are f32, about 7.2 digits), 7
/// decimals from 1 up (latitude and longitude keep 1e-7°, about 1 cm, as MAVLink sends them).
/// Printed in full, an f32 widened to f64 takes 17 digits of which 10 are noise, and noise
/// does not compress: this takes about a fifth off a flight's file. Integers are untouched.
pub fn compact_json<T: serde::Serialize + ?Sized>(value: &T) -> Vec<u8> {
    // The station's messages are plain data (numbers, strings, maps with string keys):
    // serialising them cannot fail.
    serde_json::to_value(value).map_or_else(|_| Vec::new(), compact_value)
}

/// [`compact_json`] of a JSON value already built.
pub fn compact_value(mut v: serde_json::Value) -> Vec<u8> {
    round_numbers(&mut v);
    serde_json::to_vec(&v).unwrap_or_default()
}

fn round_numbers(v: &mut serde_json::Value) {
    use serde_json::Value;
    match v {
        Value::Number(n) if n.is_f64() => {
            if let Some(r) = n
                .as_f64()
                .map(round_figure)
                .and_then(serde_json::Number::from_f64)
            {
                *n = r;
            }
        }
        Value::Array(items) => items.iter_mut().for_each(round_numbers),
        Value::Object(map) => map.values_mut().for_each(round_numbers),
        _ => {}
    }
}

/// `x` to 7 significant digits below 1 in magnitude, to 7 decimals from 1 up.
pub fn round_figure(x: f64) -> f64 {
    if !x.is_finite() {
        return x;
    }
    let text = if x.abs() >= 1.0 {
        format!("{x:.7}")
    } else {
        format!("{x:.6e}")
    };
    text.parse().unwrap_or(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_keep_what_they_carry_and_lose_the_noise() {
        // An f32 widened to f64 (an attitude angle), a latitude, a pressure, a tiny rate.
        assert_eq!(round_figure(f64::from(0.136_435_67_f32)), 0.136_435_7);
        assert_eq!(round_figure(38.533_297_7), 38.533_297_7);
        assert_eq!(round_figure(-7.888_894_8), -7.888_894_8);
        assert_eq!(round_figure(98_426.196_289_062_5), 98_426.196_289_1);
        assert_eq!(round_figure(2.039_800_000_375_180_4e-5), 2.0398e-5);
        assert_eq!(round_figure(0.0), 0.0);
        assert_eq!(round_figure(-0.5), -0.5);
        let json = compact_json(&serde_json::json!({
            "roll_deg": 0.1364356700332228,
            "lat_deg": 38.5332977,
            "time_boot_ms": 325280,
            "v": [0.09, 1.0e-12, 12.553],
        }));
        assert_eq!(
            String::from_utf8(json).unwrap(),
            r#"{"lat_deg":38.5332977,"roll_deg":0.1364357,"time_boot_ms":325280,"v":[0.09,1e-12,12.553]}"#
        );
    }
}
