//! The Lab's comparison of a recorded flight with the model (issue 16 item 3; `stx compare` in
//! the dashboard): what the page asks ([`super::LabJobBody::Compare`] names a recording of the
//! station's recordings directory, and may name a window of it), the checks made before a job
//! starts (a recording holds a flight: [`missing_flight`]; a window is one:
//! [`check_window`]), and what the page draws ([`CompareSeries`]). The flying is stx-lab's
//! (stx-analysis sits above the station); it hands the series over thinned to at most
//! [`MAX_COMPARE_POINTS`] instants ([`plotted`]), while the error figures are over every
//! recorded sample.

use std::io::{Read, Seek};

use schemars::JsonSchema;
use serde::Serialize;
use stx_record::Recording;

use crate::recording::telemetry_topic;

/// Most instants a comparison's plots carry: a plot a few hundred pixels wide shows no more,
/// and an hour's flight at 4 Hz (14,400 samples × 9 channels × 2) would be megabytes of JSON
/// on every page's poll.
pub const MAX_COMPARE_POINTS: usize = 1500;

/// The telemetry a flight log is made of, and how many messages of each it needs: the GPS
/// position is the time base (at least three instants to fly between), the attitude and the
/// servo commands are held from their latest (stx-analysis' `flight_log::recording`).
pub const FLIGHT_TELEMETRY: [(&str, u64); 3] = [
    ("GLOBAL_POSITION_INT", 3),
    ("ATTITUDE", 1),
    ("SERVO_OUTPUT_RAW", 1),
];

/// Why `recording` holds no flight to compare (the telemetry it lacks), from its index
/// alone: `None` when it has what [`FLIGHT_TELEMETRY`] asks.
pub fn missing_flight<R: Read + Seek>(recording: &Recording<R>) -> Option<String> {
    let missing: Vec<String> = FLIGHT_TELEMETRY
        .iter()
        .filter_map(|(name, least)| {
            let have = recording
                .channel(&telemetry_topic(name))
                .map_or(0, |c| c.message_count);
            (have < *least).then(|| format!("{name} ({have} of at least {least} messages)"))
        })
        .collect();
    (!missing.is_empty()).then(|| {
        format!(
            "the recording holds no flight to compare: it lacks {} telemetry",
            missing.join(", ")
        )
    })
}

/// Refuses a window of a recording (`from_s`, `to_s`: s from its flight log's first sample)
/// that is no window of any flight: `(field, reason)`. Either end may be absent; each must be
/// finite and ≥ 0, and the end after the start. Whether the recording's flight reaches into
/// the window is known only once its log is read, so the work answers that
/// ([`super::LabWorker::check_window`]). The rule is
/// stx-analysis' `flight_log::window::Window::check` (above the station; a test of stx-lab
/// holds the two equal).
pub fn check_window(from_s: Option<f64>, to_s: Option<f64>) -> Result<(), (String, String)> {
    for (field, value) in [("from_s", from_s), ("to_s", to_s)] {
        if let Some(v) = value.filter(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err((
                field.into(),
                format!("must be a finite number of seconds from the log's start, ≥ 0, not {v}"),
            ));
        }
    }
    match (from_s, to_s) {
        (Some(from), Some(to)) if to <= from => Err((
            "to_s".into(),
            format!("the window must end after it starts (from {from} s, to {to} s)"),
        )),
        _ => Ok(()),
    }
}

/// The indices of the instants plotted of `n` samples: all of them up to `max`, else `max`
/// spread evenly, the first and the last included.
pub fn plotted(n: usize, max: usize) -> Vec<usize> {
    if n <= max {
        return (0..n).collect();
    }
    if max < 2 {
        return (0..max).collect();
    }
    let last = (n - 1) as f64;
    let steps = (max - 1) as f64;
    let mut out: Vec<usize> = (0..max)
        .map(|k| (k as f64 * last / steps).round() as usize)
        .collect();
    out.dedup();
    out
}

/// One channel of a comparison: recorded and modelled at the plotted instants, and the error
/// figures over every sample.
#[derive(Debug, Clone, Default, Serialize, JsonSchema)]
pub struct CompareChannel {
    /// `north_m`, `east_m`, `height_m`, `roll_deg`, `pitch_deg`, `yaw_deg`, `airspeed_mps`,
    /// `sink_mps` or `turn_rate_deg_s`.
    pub name: String,
    /// Unit of the values and of the error figures (`m`, `deg`, `m/s`, `deg/s`).
    pub unit: String,
    /// What the drone recorded (`null` where it measured nothing, as airspeed without pitot).
    pub recorded: Vec<Option<f64>>,
    /// What the model flew (`null` where its value is not a finite number).
    pub model: Vec<Option<f64>>,
    /// Root-mean-square of model − recorded (yaw wrapped to ±180°).
    pub rms: f64,
    /// Largest |model − recorded|.
    pub max_abs: f64,
    /// Mean of model − recorded.
    pub bias: f64,
    /// Samples the figures are over.
    pub count: u32,
}

/// A recording compared with the model (`stx compare` in the Lab).
#[derive(Debug, Clone, Default, Serialize, JsonSchema)]
pub struct CompareSeries {
    /// The recording's file name.
    pub recording: String,
    /// The vehicle parameters changed from the seed's for the model (`name = value`; empty:
    /// the seed's STRAPLEX vehicle).
    pub vehicle_changes: Vec<String>,
    /// Duration of the recorded flight compared (the window's, when the job asked for one), s.
    pub duration_s: f64,
    /// The part of the recording compared, `[from, to]` in s of its drone clock from its first
    /// position: a mission recording's parafoil stage (`null`: the whole recording).
    pub parafoil_stage_s: Option<[f64; 2]>,
    /// How long the recording's positions last, s.
    pub recorded_s: f64,
    /// Samples in the recorded flight compared (one per GPS position).
    pub samples: u32,
    /// Times of the plotted instants, s from the first sample compared (at most
    /// [`MAX_COMPARE_POINTS`], spread evenly).
    pub time_s: Vec<f64>,
    /// Each channel.
    pub channels: Vec<CompareChannel>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;
    use stx_record::{CoreOptions, RecorderCore, RecordingInfo, foxglove};

    #[test]
    fn a_window_needs_times_from_the_start_and_an_end_after_its_start() {
        assert_eq!(check_window(None, None), Ok(()));
        assert_eq!(check_window(Some(0.0), Some(0.5)), Ok(()));
        assert_eq!(check_window(None, Some(3.0)), Ok(()));
        let field = |from, to| check_window(from, to).unwrap_err().0;
        assert_eq!(field(Some(-0.1), None), "from_s");
        assert_eq!(field(Some(f64::NAN), Some(3.0)), "from_s");
        assert_eq!(field(None, Some(f64::INFINITY)), "to_s");
        assert_eq!(field(Some(5.0), Some(5.0)), "to_s");
        let (_, why) = check_window(Some(9.0), Some(2.0)).unwrap_err();
        assert!(why.contains("end after it starts"), "{why}");
    }

    #[test]
    fn plotted_keeps_short_flights_whole_and_thins_long_ones_evenly() {
        assert_eq!(plotted(4, 10), vec![0, 1, 2, 3]);
        assert_eq!(plotted(0, 10), Vec::<usize>::new());
        let long = plotted(14_400, MAX_COMPARE_POINTS);
        assert_eq!(long.len(), MAX_COMPARE_POINTS);
        assert_eq!((long[0], long[long.len() - 1]), (0, 14_399));
        let gaps: Vec<usize> = long.windows(2).map(|w| w[1] - w[0]).collect();
        assert!(gaps.iter().all(|g| (9..=10).contains(g)), "{gaps:?}");
        assert_eq!(plotted(11, 2), vec![0, 10]);
    }

    /// A closed recording with `counts` messages on each telemetry topic.
    fn recording(counts: &[(&str, u64)]) -> Recording<std::io::Cursor<Vec<u8>>> {
        let info = RecordingInfo::new("test", "straplex-2", "lab compare");
        let mut core = RecorderCore::new(CoreOptions::default(), info, Duration::ZERO).unwrap();
        let t0 = 1_767_225_600_000_000_000u64;
        for (name, n) in counts {
            let spec = foxglove::log_channel(telemetry_topic(name)).unwrap();
            let ch = core.add_channel(Duration::ZERO, spec).unwrap();
            for i in 0..*n {
                let t = t0 + i * 250_000_000;
                core.write(Duration::from_millis(250 * i), ch, t, t, b"{}")
                    .unwrap();
            }
        }
        core.finish().unwrap();
        let mut bytes = Vec::new();
        while let Some(out) = core.poll_output() {
            if let stx_record::Output::Bytes { data, .. } = out {
                bytes.extend(data);
            }
        }
        Recording::from_reader(std::io::Cursor::new(bytes)).unwrap()
    }

    #[test]
    fn a_recording_without_position_attitude_or_commands_holds_no_flight() {
        let whole = [
            ("GLOBAL_POSITION_INT", 3),
            ("ATTITUDE", 2),
            ("SERVO_OUTPUT_RAW", 1),
            ("VFR_HUD", 1),
        ];
        assert_eq!(missing_flight(&recording(&whole)), None);
        let why = missing_flight(&recording(&[("ATTITUDE", 5), ("GLOBAL_POSITION_INT", 2)]))
            .expect("no flight");
        assert!(
            why.contains("GLOBAL_POSITION_INT (2 of at least 3")
                && why.contains("SERVO_OUTPUT_RAW (0 of")
                && !why.contains("ATTITUDE"),
            "{why}"
        );
        assert!(missing_flight(&recording(&[])).is_some());
    }
}
