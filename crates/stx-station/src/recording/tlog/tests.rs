use std::io::Cursor;

use stx_link::telemetry::GpsFix;
use stx_record::Recording;

use super::*;

/// A tlog of `n` GPS_RAW_INT frames and one frame the station does not decode, 250 ms apart,
/// as the station's own encoder writes them.
fn tlog(n: u64) -> Vec<u8> {
    let mut encoder = stx_link::frame::FrameEncoder::new(1, 1);
    let mut out = Vec::new();
    for i in 0..n {
        let gps = stx_link::telemetry::GpsRaw {
            time_usec: i,
            fix: GpsFix::Fix3d,
            lat_deg: 38.5 + i as f64 * 1e-5,
            lon_deg: -7.9,
            alt_msl_m: 900.0,
            ground_speed_mps: None,
            course_deg: None,
            satellites: Some(10),
            h_acc_m: Some(1.5),
            v_acc_m: Some(2.5),
        };
        let frame = encoder.encode(Duration::ZERO, &Telemetry::GpsRaw(gps).to_mavlink());
        out.extend((1_795_576_246_000_000 + i * 250_000).to_be_bytes());
        out.extend(frame);
    }
    let other = encoder.encode(
        Duration::ZERO,
        &stx_link::MavMessage::SYSTEM_TIME(Default::default()),
    );
    out.extend(1_795_576_300_000_000u64.to_be_bytes());
    out.extend(other);
    out
}

#[test]
fn every_frame_is_kept_and_what_the_station_decodes_is_on_its_channels() {
    let (mcap, report) = import_tlog(&tlog(20), RecordingInfo::new("t", "imported", "f")).unwrap();
    assert_eq!(report.frames, 21);
    assert_eq!(report.decoded, 20, "SYSTEM_TIME is kept raw only");
    assert_eq!(report.stopped_at, None);
    let rec = Recording::from_reader(Cursor::new(mcap)).unwrap();
    assert_eq!(rec.channel(FRAMES).unwrap().message_count, 21);
    assert_eq!(
        rec.channel("/telemetry/GPS_RAW_INT").unwrap().message_count,
        20
    );
    assert_eq!(
        rec.channel(super::super::VEHICLE_GPS)
            .unwrap()
            .message_count,
        20
    );
    let (start, end) = rec.time_range().unwrap();
    assert_eq!(start, 1_795_576_246_000_000_000);
    assert_eq!(end, 1_795_576_300_000_000_000);
}

/// A tlog as an ArduPilot vehicle writes one on the pad: `no_fix` seconds of GPS_RAW_INT without
/// a fix and GLOBAL_POSITION_INT before the estimator's origin, all at 0°, 0°, then `fixed`
/// seconds with a 3-D fix, one of each message a second.
fn tlog_from_the_pad(no_fix: u64, fixed: u64) -> Vec<u8> {
    let mut encoder = stx_link::frame::FrameEncoder::new(1, 1);
    let mut out = Vec::new();
    for i in 0..no_fix + fixed {
        let (fix, lat_deg, lon_deg) = if i < no_fix {
            (
                if i % 2 == 0 {
                    GpsFix::NoGps
                } else {
                    GpsFix::NoFix
                },
                0.0,
                0.0,
            )
        } else {
            (GpsFix::Fix3d, 38.5 + i as f64 * 1e-5, -7.9)
        };
        let gps = stx_link::telemetry::GpsRaw {
            time_usec: i * 1_000_000,
            fix,
            lat_deg,
            lon_deg,
            alt_msl_m: if i < no_fix { 0.0 } else { 245.0 },
            ground_speed_mps: None,
            course_deg: None,
            satellites: Some(if i < no_fix { 0 } else { 9 }),
            h_acc_m: None,
            v_acc_m: None,
        };
        // The drone's estimate, at the receiver's zeros until it has a fix.
        let Telemetry::Position(flying) = stx_link::fixtures::telemetry_sample(1) else {
            panic!("the fixture's second message is a GLOBAL_POSITION_INT");
        };
        let position = stx_link::telemetry::GlobalPosition {
            time_boot_ms: (i * 1000) as u32,
            lat_deg,
            lon_deg,
            ..flying
        };
        for (k, t) in [Telemetry::GpsRaw(gps), Telemetry::Position(position)]
            .into_iter()
            .enumerate()
        {
            out.extend((1_795_576_246_000_000 + i * 1_000_000 + k as u64 * 1000).to_be_bytes());
            out.extend(encoder.encode(Duration::ZERO, &t.to_mavlink()));
        }
    }
    out
}

/// Regression: a tlog imported from an ArduPilot vehicle wrote `foxglove.LocationFix` points at
/// 0°, 0° before the GPS had a fix, and Foxglove drew the track from the Gulf of Guinea.
#[test]
fn reports_without_a_fix_are_kept_as_telemetry_and_never_become_location_fixes() {
    let (mcap, report) =
        import_tlog(&tlog_from_the_pad(6, 4), RecordingInfo::default()).expect("imports");
    assert_eq!(report.frames, 20);
    assert_eq!(report.decoded, 20);
    let mut rec = Recording::from_reader(Cursor::new(mcap)).expect("reads");
    for (topic, n) in [
        ("/telemetry/GPS_RAW_INT", 10),
        ("/telemetry/GLOBAL_POSITION_INT", 10),
        (super::super::VEHICLE_GPS, 4),
    ] {
        assert_eq!(
            rec.channel(topic).map(|c| c.message_count),
            Some(n),
            "{topic}"
        );
    }
    let location_fix_topics: Vec<String> = rec
        .channels()
        .iter()
        .filter(|c| c.schema_name == stx_record::foxglove::LOCATION_FIX)
        .map(|c| c.topic.to_string())
        .collect();
    let mut fixes = Vec::new();
    for m in rec.messages().expect("messages") {
        let m = m.expect("message");
        if location_fix_topics.iter().any(|t| **t == *m.topic) {
            let f: stx_record::foxglove::LocationFix =
                serde_json::from_slice(&m.data).expect("a LocationFix");
            fixes.push((f.latitude, f.longitude));
        }
    }
    assert_eq!(fixes.len(), 4, "{fixes:?}");
    assert!(
        fixes.iter().all(|&(lat, lon)| lat > 38.0 && lon < -7.0),
        "no point at 0°, 0°: {fixes:?}"
    );
    // The export's track is the fixes alone.
    let (_, track) = stx_record::export::track::track(&mut rec).expect("a track");
    assert_eq!(track.len(), 4);
}

#[test]
fn a_cut_log_keeps_its_whole_records_and_a_stranger_is_refused() {
    let whole = tlog(5);
    let cut = &whole[..whole.len() - 7];
    let (_, report) = import_tlog(cut, RecordingInfo::default()).unwrap();
    assert_eq!(report.frames, 5);
    assert!(report.stopped_at.is_some());
    assert!(matches!(
        import_tlog(
            b"hello, this is not a tlog at all",
            RecordingInfo::default()
        ),
        Err(TlogError::NotATlog(_))
    ));
    assert!(matches!(import_tlog(&[], RecordingInfo::default()), Ok((_, r)) if r.frames == 0));
}

proptest::proptest! {
    /// Nothing on any input panics.
    #[test]
    fn any_bytes_import_or_are_refused(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..400)) {
        let _ = import_tlog(&bytes, RecordingInfo::default());
    }
}
