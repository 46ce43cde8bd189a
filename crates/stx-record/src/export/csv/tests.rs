use std::time::Duration;

use serde_json::json;

use super::*;
use crate::export::track::{gpx, kml, track};
use crate::foxglove::{self, PositionCovarianceType, Timestamp};
use crate::{ChannelSpec, CoreOptions, Output, RecorderCore, RecordingInfo};

const T0: u64 = 1_795_576_246_000_000_000;

/// A recording with a GPS channel and a `state`-like channel whose schema documents units.
fn recording(dir: &Path) -> PathBuf {
    recording_after_no_fix(dir, 0)
}

/// [`recording`], its GPS channel opened by `no_fix` points at 0°, 0° (a receiver without a
/// fix, as recordings made before stx checked the fix type hold them).
fn recording_after_no_fix(dir: &Path, no_fix: u64) -> PathBuf {
    let mut core = RecorderCore::new(
        CoreOptions::default(),
        RecordingInfo::default(),
        Duration::ZERO,
    )
    .unwrap();
    let gps = core
        .add_channel(
            Duration::ZERO,
            foxglove::location_fix_channel("/vehicle/gps").unwrap(),
        )
        .unwrap();
    let schema = json!({
        "type": "object",
        "properties": {
            "estimate": {"$ref": "#/$defs/Estimate"},
            "note": {"type": "string", "description": "Free text."},
            "wind_ned_mps": {"type": "array", "items": {"type": "number"}, "description": "Wind NED, m/s."}
        },
        "$defs": {"Estimate": {"type": "object", "properties": {
            "alt_msl_m": {"type": "number", "description": "Altitude above mean sea level, m (wire: mm)."},
            "heading_deg": {"type": "number", "description": "Heading, degrees."},
            "glide": {"type": ["number", "null"], "description": "Glide through the air."}
        }}}
    });
    let state = core
        .add_channel(
            Duration::ZERO,
            ChannelSpec::json("/station/state", "stx.StateMsg", &schema).unwrap(),
        )
        .unwrap();
    for i in 0..no_fix {
        let t = T0 - (no_fix - i) * 1_000_000_000;
        let nowhere = foxglove::LocationFix {
            timestamp: Timestamp::from_nanos(t),
            frame_id: "gps".into(),
            latitude: 0.0,
            longitude: 0.0,
            altitude: 0.0,
            position_covariance: [0.0; 9],
            position_covariance_type: PositionCovarianceType::Unknown,
        };
        core.write(
            Duration::ZERO,
            gps,
            t,
            t,
            &serde_json::to_vec(&nowhere).unwrap(),
        )
        .unwrap();
    }
    for i in 0..10u64 {
        let now = Duration::from_millis(i * 500);
        let t = T0 + i * 500_000_000;
        let fix = foxglove::LocationFix {
            timestamp: Timestamp::from_nanos(t),
            frame_id: "gps".into(),
            latitude: 38.5 + i as f64 * 1e-4,
            longitude: -7.9,
            altitude: 900.0 - i as f64,
            position_covariance: [0.0; 9],
            position_covariance_type: PositionCovarianceType::Unknown,
        };
        core.write(now, gps, t, t, &serde_json::to_vec(&fix).unwrap())
            .unwrap();
        let s = json!({"estimate": {"alt_msl_m": 900.0 - i as f64, "heading_deg": 90.5,
            "glide": if i == 3 { Value::Null } else { json!(2.0) }},
            "note": "a, \"quoted\" note", "wind_ned_mps": [1.5, -0.5, 0.0]});
        core.write(now, state, t, t, s.to_string().as_bytes())
            .unwrap();
    }
    core.finish().unwrap();
    let mut bytes = Vec::new();
    while let Some(o) = core.poll_output() {
        if let Output::Bytes { data, .. } = o {
            bytes.extend(data);
        }
    }
    let path = dir.join("flight.mcap");
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn one_csv_per_channel_with_units_in_the_header_and_a_row_per_message() {
    let dir = tempfile::tempdir().unwrap();
    let mut rec = Recording::open(&recording(dir.path())).unwrap();
    let out = dir.path().join("csv");
    let report = export_csv(&mut rec, &out).unwrap();
    assert_eq!(report.skipped, 0);
    assert_eq!(report.files.len(), 2);
    assert!(
        report.files.iter().all(|(_, rows)| *rows == 10),
        "{report:?}"
    );
    let text = std::fs::read_to_string(out.join("station_state.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "log_time_s [s],utc,estimate.alt_msl_m [m],estimate.glide,estimate.heading_deg [degrees],note,wind_ned_mps[0] [m/s],wind_ned_mps[1] [m/s],wind_ned_mps[2] [m/s]"
    );
    assert_eq!(
        lines.next().unwrap(),
        "1795576246.000000000,2026-11-25T03:10:46.000Z,900.0,2.0,90.5,\"a, \"\"quoted\"\" note\",1.5,-0.5,0.0"
    );
    // A null is an empty field.
    assert!(
        text.lines().nth(4).unwrap().contains(",897.0,,90.5,"),
        "{text}"
    );
    let gps = std::fs::read_to_string(out.join("vehicle_gps.csv")).unwrap();
    let header = gps.lines().next().unwrap();
    assert!(
        header.contains("latitude [degrees]") && header.contains("altitude [m]"),
        "{header}"
    );
}

#[test]
fn the_track_is_well_formed_kml_and_gpx_with_every_point() {
    let dir = tempfile::tempdir().unwrap();
    let mut rec = Recording::open(&recording(dir.path())).unwrap();
    let (topic, points) = track(&mut rec).unwrap();
    assert_eq!(topic, "/vehicle/gps");
    assert_eq!(points.len(), 10);
    for (doc, point_tag) in [
        (gpx("flight <1> & co", &points), "trkpt"),
        (kml("flight <1> & co", &points), "Placemark"),
    ] {
        let mut reader = quick_xml::Reader::from_str(&doc);
        let mut count = 0;
        loop {
            match reader.read_event().expect("well-formed XML") {
                quick_xml::events::Event::Start(e) if e.name().as_ref() == point_tag.as_bytes() => {
                    count += 1
                }
                quick_xml::events::Event::Eof => break,
                _ => {}
            }
        }
        assert!(
            doc.contains("<name>flight &lt;1&gt; &amp; co</name>"),
            "escaped name: {doc}"
        );
        // GPX: a point each; KML: the line and the start and end marks.
        assert_eq!(count, if point_tag == "trkpt" { 10 } else { 3 }, "{doc}");
    }
    assert!(gpx("f", &points).contains("<time>2026-11-25T03:10:50.500Z</time>"));
    assert!(kml("f", &points).contains("-7.9000000,38.5009000,891.0"));
}

/// Regression: a tlog imported from an ArduPilot vehicle held LocationFix points at 0°, 0°
/// from before the GPS had a fix, and every export drew the track from the Gulf of Guinea.
#[test]
fn points_at_zero_zero_are_no_positions_in_any_export() {
    let dir = tempfile::tempdir().unwrap();
    let mut rec = Recording::open(&recording_after_no_fix(dir.path(), 3)).unwrap();
    let (_, points) = track(&mut rec).unwrap();
    assert_eq!(points.len(), 10);
    assert!(points.iter().all(|p| p.lat_deg > 38.0), "{points:?}");
    let out = dir.path().join("csv");
    let report = export_csv(&mut rec, &out).unwrap();
    assert_eq!(report.not_positions, 3);
    let gps = std::fs::read_to_string(out.join("vehicle_gps.csv")).unwrap();
    assert_eq!(gps.lines().count(), 11, "a header and the 10 fixes: {gps}");
    assert!(
        !gps.contains(",gps,0.0,0.0,"),
        "no latitude and longitude 0: {gps}"
    );
    for doc in [gpx("f", &points), kml("f", &points)] {
        assert!(!doc.contains("0.0000000,0.0000000"), "{doc}");
    }
}

#[test]
fn file_names_follow_topics() {
    assert_eq!(file_name("/station/state"), "station_state.csv");
    assert_eq!(
        file_name("/telemetry/GPS_RAW_INT"),
        "telemetry_GPS_RAW_INT.csv"
    );
    assert_eq!(file_name("/"), "root.csv");
}
