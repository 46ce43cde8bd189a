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
