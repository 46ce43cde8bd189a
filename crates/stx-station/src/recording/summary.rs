//! A recording in one line, for the dashboard's list of past flights: when it starts, how long
//! it lasts, what it is of, and where the flight ended and how far from its target.
//!
//! Cheap on purpose, since a list reads every file in the directory: the index gives the times
//! and the metadata, and only the last few seconds of [`STATE`] are decoded — the station's
//! own view of the flight at the end of the recording (stage, GPS, estimate, target). A flight
//! that had landed shows its landing; one that had not, the stage it was in.

use std::io::{Read, Seek};

use schemars::JsonSchema;
use serde::Serialize;
use serde_json::Value;
use stx_gnc::geo::LocalFrame;
use stx_link::telemetry::{GpsFix, has_position_fix};
use stx_record::{IndexSource, ReadError, Recording};

use super::STATE;

/// How far back from a recording's end its last `state` is looked for, ns: the station
/// records `state` at 1 Hz, so this is several of them even when the last seconds are quiet.
const LAST_STATE_WINDOW_NS: u64 = 10_000_000_000;

/// One past (or current) recording of the station.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct RecordingSummary {
    /// File name in the recordings directory.
    pub name: String,
    /// Size on disk, B.
    pub size_bytes: u64,
    /// Unix time of the first message, ms; for a recording with no message yet, when its
    /// name says its run started (`null` if the name does not say).
    pub start_ms: Option<u64>,
    /// From the first message to the last, ms.
    pub duration_ms: u64,
    /// Messages in it.
    pub messages: u64,
    /// The mission, as its metadata names it.
    pub mission: Option<String>,
    /// The vehicle, as its metadata names it.
    pub vehicle: Option<String>,
    /// Closed with its index (`true`), or cut short (the station stopped without closing it,
    /// or is still writing it): readable up to its last whole chunk, `stx record recover`
    /// writes a clean copy.
    pub complete: bool,
    /// The station is writing this file now.
    pub recording_now: bool,
    /// The stage of the flight at the end of the recording (`landed`, `descent`, …).
    pub last_stage: Option<String>,
    /// Where the flight landed, when the recording ends landed.
    pub landing: Option<LandingSummary>,
}

/// Where a recorded flight came down.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct LandingSummary {
    /// Latitude, degrees: the landing the station measured (`state.mission.landing`); in
    /// recordings made before it did, the drone's last GPS, else the station's estimate.
    pub lat_deg: f64,
    /// Longitude, degrees.
    pub lon_deg: f64,
    /// Horizontal distance to the drone's target, m, as the station measured it (`null`
    /// without a target): the figure every page shows.
    pub miss_m: Option<f64>,
    /// Which body the position is of, as the station measured it (`drone`: its GPS
    /// receiver); `null` in recordings made before the station said.
    pub body: Option<String>,
}

/// Why a recording could not be summarised.
#[derive(Debug, thiserror::Error)]
#[error("{name}: {source}")]
pub struct SummaryError {
    /// The file.
    pub name: String,
    /// What went wrong reading it.
    #[source]
    pub source: ReadError,
}

/// The summary of `recording`, the file `name` of `size_bytes`.
pub fn summarize<R: Read + Seek>(
    name: &str,
    size_bytes: u64,
    recording: &mut Recording<R>,
) -> Result<RecordingSummary, SummaryError> {
    let failed = |source| SummaryError {
        name: name.to_owned(),
        source,
    };
    let info = recording.info().map(|(info, _)| info);
    let range = recording.time_range();
    let last_state = match range {
        Some((_, end)) => {
            last_state(recording, end.saturating_sub(LAST_STATE_WINDOW_NS)).map_err(failed)?
        }
        None => None,
    };
    let last_stage = last_state.as_ref().and_then(stage);
    let landing = last_state
        .as_ref()
        .filter(|_| last_stage.as_deref() == Some("landed"))
        .and_then(landing);
    Ok(RecordingSummary {
        name: name.to_owned(),
        size_bytes,
        // A file just begun has no message yet (its first chunk is still being written):
        // its name says when its run started, so it is listed as the newest, not the oldest.
        start_ms: range
            .map(|(start, _)| start / 1_000_000)
            .or_else(|| stx_record::file::run_started_ms_from_name(name)),
        duration_ms: range.map_or(0, |(start, end)| (end - start) / 1_000_000),
        messages: recording.message_count(),
        mission: info.as_ref().map(|i| i.mission().to_owned()),
        vehicle: info.as_ref().map(|i| i.vehicle().to_owned()),
        complete: recording.index() == IndexSource::Summary,
        recording_now: false,
        last_stage,
        landing,
    })
}

/// The last `state` logged at or after `from` (ns), parsed.
fn last_state<R: Read + Seek>(
    recording: &mut Recording<R>,
    from: u64,
) -> Result<Option<Value>, ReadError> {
    let mut last = None;
    for message in recording.messages_from(from)? {
        let message = message?;
        if &*message.topic == STATE {
            last = Some(message.data);
        }
    }
    Ok(last.and_then(|data| serde_json::from_slice(&data).ok()))
}

fn text(state: &Value, pointer: &str) -> Option<String> {
    state.pointer(pointer)?.as_str().map(str::to_owned)
}

/// The mission's stage as the station saw it (its own, else the drone's).
fn stage(state: &Value) -> Option<String> {
    text(state, "/mission/stage").or_else(|| text(state, "/vehicle/stage"))
}

fn lat_lon(v: Option<&Value>) -> Option<(f64, f64, f64)> {
    let v = v?;
    let lat = v.get("lat_deg")?.as_f64()?;
    let lon = v.get("lon_deg")?.as_f64()?;
    let alt = v.get("alt_msl_m").and_then(Value::as_f64).unwrap_or(0.0);
    Some((lat, lon, alt))
}

/// The drone's GPS in a recorded state, when it is a position (a fix, not 0°, 0°:
/// [`has_position_fix`]).
fn gps_position(state: &Value) -> Option<(f64, f64, f64)> {
    let gps = state.pointer("/vehicle/gps")?;
    let fix: GpsFix = serde_json::from_value(gps.get("fix")?.clone()).ok()?;
    lat_lon(Some(gps)).filter(|&(lat, lon, _)| has_position_fix(fix, lat, lon))
}

fn landing(state: &Value) -> Option<LandingSummary> {
    if let Some(l) = state.pointer("/mission/landing").filter(|l| !l.is_null()) {
        // The station's own figure: the same everywhere, not worked out again here.
        let (lat, lon, _) = lat_lon(l.get("position"))?;
        return Some(LandingSummary {
            lat_deg: lat,
            lon_deg: lon,
            miss_m: l.get("miss_m").and_then(Value::as_f64),
            body: l.get("body").and_then(Value::as_str).map(String::from),
        });
    }
    let (lat, lon, alt) = gps_position(state).or_else(|| lat_lon(state.get("estimate")))?;
    let miss_m = lat_lon(state.pointer("/guidance/target")).map(|(t_lat, t_lon, t_alt)| {
        let target = LocalFrame {
            lat_deg: t_lat,
            lon_deg: t_lon,
            alt_msl_m: t_alt,
        };
        target.to_ned(lat, lon, alt).xy().norm()
    });
    Some(LandingSummary {
        lat_deg: lat,
        lon_deg: lon,
        miss_m,
        body: None,
    })
}

#[cfg(test)]
mod tests {
    use std::io::Cursor;
    use std::time::Duration;

    use serde_json::json;
    use stx_record::{ChannelSpec, CoreOptions, Output, RecorderCore, RecordingInfo};

    use super::*;

    const T0: u64 = 1_767_225_600_000_000_000;

    /// A recording of `states` at 1 Hz on the station's state topic, closed or cut.
    fn recording(states: &[Value], closed: bool) -> Vec<u8> {
        let info = RecordingInfo::new("test", "straplex-2", "field day");
        let mut core = RecorderCore::new(CoreOptions::default(), info, Duration::ZERO).unwrap();
        let spec = ChannelSpec::json(STATE, "stx.StateMsg", &json!({"type": "object"})).unwrap();
        let ch = core.add_channel(Duration::ZERO, spec).unwrap();
        let mut bytes = Vec::new();
        let drain = |core: &mut RecorderCore, bytes: &mut Vec<u8>| {
            while let Some(out) = core.poll_output() {
                if let Output::Bytes { data, .. } = out {
                    bytes.extend(data);
                }
            }
        };
        for (i, s) in states.iter().enumerate() {
            let t = T0 + i as u64 * 1_000_000_000;
            let now = Duration::from_secs(i as u64);
            core.write(now, ch, t, t, s.to_string().as_bytes()).unwrap();
            drain(&mut core, &mut bytes);
        }
        if closed {
            core.finish().unwrap();
        } else {
            // What a killed station leaves: the chunks closed on time, nothing after.
            core.write(Duration::from_secs(3600), ch, T0, T0, b"{}")
                .unwrap();
        }
        drain(&mut core, &mut bytes);
        bytes
    }

    fn state(stage: &str, at: (f64, f64), target: Option<(f64, f64)>) -> Value {
        json!({
            "type": "state",
            "mission": {"stage": stage},
            "vehicle": {"gps": {"fix": "fix3d", "lat_deg": at.0, "lon_deg": at.1, "alt_msl_m": 300.0}},
            "guidance": target.map(|t| json!({"target": {"lat_deg": t.0, "lon_deg": t.1, "alt_msl_m": 300.0}})),
        })
    }

    fn summary(bytes: Vec<u8>) -> RecordingSummary {
        let size = bytes.len() as u64;
        let mut rec = Recording::from_reader(Cursor::new(bytes)).unwrap();
        summarize("flight.mcap", size, &mut rec).unwrap()
    }

    #[test]
    fn a_landed_flight_shows_where_and_how_far_from_its_target() {
        // 0.0001° of latitude is 11.1 m; of longitude at 50° N, 7.2 m.
        let target = (50.0, 14.0);
        let states = [
            state("descent", (50.01, 14.0), Some(target)),
            state("descent", (50.001, 14.0), Some(target)),
            state("landed", (50.0001, 14.0001), Some(target)),
        ];
        let s = summary(recording(&states, true));
        assert_eq!(s.name, "flight.mcap");
        assert_eq!(s.start_ms, Some(T0 / 1_000_000));
        assert_eq!(s.duration_ms, 2000);
        assert_eq!(s.messages, 3);
        assert_eq!(s.mission.as_deref(), Some("field day"));
        assert_eq!(s.vehicle.as_deref(), Some("straplex-2"));
        assert!(s.complete);
        assert_eq!(s.last_stage.as_deref(), Some("landed"));
        let landing = s.landing.expect("landed");
        assert_eq!((landing.lat_deg, landing.lon_deg), (50.0001, 14.0001));
        let miss = landing.miss_m.expect("a target");
        let expected = (11.12_f64.powi(2) + 7.17_f64.powi(2)).sqrt();
        assert!((miss - expected).abs() < 0.1, "{miss} vs {expected}");
    }

    #[test]
    fn the_list_shows_the_landing_the_station_measured_not_its_own() {
        // The station's figure (from the GPS fix on the ground) is 2.3 m; the last state's
        // drone position and target would give another: the list shows the station's.
        let mut last = state("landed", (50.0001, 14.0001), Some((50.0, 14.0)));
        last["mission"]["landing"] = json!({
            "time_s": 1180.25,
            "body": "drone",
            "position": {"lat_deg": 50.00002, "lon_deg": 14.00001, "alt_msl_m": 300.0},
            "target": {"lat_deg": 50.0, "lon_deg": 14.0, "alt_msl_m": 300.0},
            "miss_m": 2.3,
        });
        let s = summary(recording(&[last], true));
        let landing = s.landing.expect("landed");
        assert_eq!(landing.miss_m, Some(2.3));
        assert_eq!((landing.lat_deg, landing.lon_deg), (50.00002, 14.00001));
    }

    #[test]
    fn a_gps_without_a_fix_is_no_landing_place() {
        let mut last = state("landed", (0.0, 0.0), Some((50.0, 14.0)));
        last["vehicle"]["gps"]["fix"] = json!("no_fix");
        last["estimate"] = json!({"lat_deg": 50.0001, "lon_deg": 14.0, "alt_msl_m": 300.0});
        let landing = summary(recording(&[last.clone()], true))
            .landing
            .expect("landed");
        assert_eq!((landing.lat_deg, landing.lon_deg), (50.0001, 14.0));
        last["vehicle"]["gps"]["fix"] = json!("fix3d");
        let landing = summary(recording(&[last], true)).landing.expect("landed");
        assert_eq!(
            (landing.lat_deg, landing.lon_deg),
            (50.0001, 14.0),
            "0°, 0° is no fix"
        );
    }

    #[test]
    fn a_flight_still_in_the_air_has_no_landing_and_says_its_stage() {
        let s = summary(recording(&[state("ascent", (50.0, 14.0), None)], true));
        assert_eq!(s.last_stage.as_deref(), Some("ascent"));
        assert_eq!(s.landing, None);
    }

    #[test]
    fn a_landing_without_a_target_has_no_miss() {
        let s = summary(recording(&[state("landed", (50.0, 14.0), None)], true));
        assert_eq!(s.landing.map(|l| l.miss_m), Some(None));
    }

    #[test]
    fn a_cut_recording_is_summarised_up_to_its_last_whole_chunk() {
        let states: Vec<Value> = (0..5)
            .map(|_| state("landed", (50.0, 14.0), Some((50.0, 14.0))))
            .collect();
        let s = summary(recording(&states, false));
        assert!(!s.complete);
        assert!(s.messages >= 1, "{s:?}");
        assert_eq!(s.landing.and_then(|l| l.miss_m), Some(0.0));
    }

    #[test]
    fn an_empty_recording_has_no_times() {
        let s = summary(recording(&[], true));
        assert_eq!((s.start_ms, s.duration_ms, s.messages), (None, 0, 0));
        assert_eq!(s.last_stage, None);
    }

    #[test]
    fn a_recording_just_begun_starts_when_its_name_says() {
        let mut r = Recording::from_reader(Cursor::new(recording(&[], true))).expect("opens");
        let s = summarize("stx-20261128T005951Z-001.mcap", 0, &mut r).expect("summarises");
        assert_eq!((s.start_ms, s.messages), (Some(1_795_827_591_000), 0));
    }
}
