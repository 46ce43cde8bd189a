//! What a replay "as recorded" has shown up to its position: the newest recorded `state`, the
//! track and the plots' history drawn from the recorded states, and the event log. A live
//! station's core keeps these for its pages; a replay of the recorded messages has no core
//! that heard them, so this keeps them instead — a page that connects, and every page after
//! a seek, gets the flight as it was at that moment from here.
//!
//! Recorded messages stay JSON as recorded (a recording of an older station keeps its own
//! fields); one that is not JSON is skipped.

use std::collections::VecDeque;

use serde_json::{Value, json};

use crate::core::{MAX_TRACK_POINTS, thin_track};
use crate::messages::TrackPoint;

/// States kept for the plots (the station records one a second: 5 minutes, as a live
/// station's history).
const MAX_STATES: usize = 300;
/// Events sent in a `history` (as a live station's).
const MAX_EVENTS: usize = 500;
/// Seconds between track points at least. The station records a state a second (as its
/// 4 Hz states fall: 1.0 s apart give or take a few ms), each a point of the track.
const TRACK_PERIOD_S: f64 = 0.5;

/// The recorded flight up to the replay's position.
#[derive(Debug, Clone, Default)]
pub struct RecordedTimeline {
    latest: Option<Value>,
    track: Vec<TrackPoint>,
    states: VecDeque<Value>,
    events: VecDeque<Value>,
}

impl RecordedTimeline {
    /// A recorded `state`; returns it parsed (`None`: not JSON, skipped).
    pub fn state(&mut self, json: &[u8]) -> Option<&Value> {
        let state: Value = serde_json::from_slice(json).ok()?;
        if let Some(point) = track_point(&state)
            && self
                .track
                .last()
                .is_none_or(|l| point.time_s - l.time_s >= TRACK_PERIOD_S)
        {
            self.track.push(point);
            if self.track.len() > MAX_TRACK_POINTS {
                thin_track(&mut self.track);
            }
        }
        if self.states.len() >= MAX_STATES {
            self.states.pop_front();
        }
        self.states.push_back(state.clone());
        self.latest = Some(state);
        self.latest.as_ref()
    }

    /// A recorded event; returns it parsed (`None`: not JSON, skipped).
    pub fn event(&mut self, json: &[u8]) -> Option<&Value> {
        let event: Value = serde_json::from_slice(json).ok()?;
        if self.events.len() >= MAX_EVENTS {
            self.events.pop_front();
        }
        self.events.push_back(event);
        self.events.back()
    }

    /// The newest recorded `state`.
    pub fn latest(&self) -> Option<&Value> {
        self.latest.as_ref()
    }

    /// The track so far.
    pub fn track(&self) -> &[TrackPoint] {
        &self.track
    }

    /// The `history` message (`HistoryMsg`) of seek `epoch`.
    pub fn history(&self, epoch: u64) -> Value {
        json!({
            "type": "history",
            "track": self.track,
            "events": self.events,
            "states": self.states,
            "replay_epoch": epoch,
        })
    }
}

/// Where the station's estimate put the stack, unless the link was stale (as the pages
/// draw the track) or it is no position (0°, 0°, `stx_link::telemetry::is_position`).
fn track_point(state: &Value) -> Option<TrackPoint> {
    if state.pointer("/link/stale").and_then(Value::as_bool) != Some(false) {
        return None;
    }
    let estimate = state.get("estimate")?;
    let number = |v: &Value, key: &str| v.get(key).and_then(Value::as_f64);
    let time_s = number(state, "time_s")?;
    let (lat_deg, lon_deg) = (number(estimate, "lat_deg")?, number(estimate, "lon_deg")?);
    if !stx_link::telemetry::is_position(lat_deg, lon_deg) {
        return None;
    }
    Some(TrackPoint {
        time_s,
        // Recordings older than the mission clock have only the station's.
        mission_time_s: number(state, "mission_time_s").unwrap_or(time_s),
        lat_deg,
        lon_deg,
        alt_msl_m: number(estimate, "alt_msl_m")?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(time_s: f64, stale: bool) -> Vec<u8> {
        json!({
            "type": "state",
            "time_s": time_s,
            "link": {"stale": stale},
            "estimate": {"lat_deg": 38.5 + time_s * 1e-5, "lon_deg": -7.9, "alt_msl_m": 900.0},
        })
        .to_string()
        .into_bytes()
    }

    #[test]
    fn the_track_history_and_log_are_the_recorded_ones_up_to_now() {
        let mut t = RecordedTimeline::default();
        assert!(t.state(b"not json").is_none(), "skipped");
        for i in 0..400 {
            t.state(&state(f64::from(i) * 0.25, i == 8));
        }
        t.event(br#"{"type":"event","text":"stage: Balloon -> Parafoil"}"#);
        assert_eq!(t.latest().unwrap()["time_s"], 99.75);
        let track = t.track();
        assert_eq!(track.len(), 200, "one point every half second of the 100 s");
        assert!(track.iter().all(|p| p.time_s != 2.0), "not while stale");
        assert!(track.iter().any(|p| p.time_s == 2.25));
        let history = t.history(3);
        assert_eq!(history["replay_epoch"], 3);
        let states = history["states"].as_array().unwrap();
        assert_eq!(states.len(), MAX_STATES);
        assert_eq!(states.last().unwrap()["time_s"], 99.75);
        assert_eq!(history["events"][0]["text"], "stage: Balloon -> Parafoil");
        assert_eq!(history["track"][0]["lat_deg"], 38.5);
    }

    #[test]
    fn a_recorded_point_at_zero_zero_is_no_track_point() {
        let nowhere = json!({
            "type": "state", "time_s": 1.0, "link": {"stale": false},
            "estimate": {"lat_deg": 0.0, "lon_deg": 0.0, "alt_msl_m": 0.0},
        });
        assert!(track_point(&nowhere).is_none());
        let somewhere: Value = serde_json::from_slice(&state(1.0, false)).unwrap();
        assert!(track_point(&somewhere).is_some());
    }
}
