use stx_link::telemetry::GpsFix;
use stx_record::{CoreOptions, RecordingInfo};

use super::*;

fn channels() -> TelemetryChannels {
    let mut core = RecorderCore::new(
        CoreOptions::default(),
        RecordingInfo::new("t", "v", "m"),
        Duration::ZERO,
    )
    .expect("core");
    TelemetryChannels::register(&mut core, Duration::ZERO).expect("channels")
}

fn gps(h_acc_m: Option<f64>, v_acc_m: Option<f64>) -> GpsRaw {
    GpsRaw {
        time_usec: 1,
        fix: GpsFix::Fix3d,
        lat_deg: 38.5,
        lon_deg: -7.9,
        alt_msl_m: 900.0,
        ground_speed_mps: Some(7.0),
        course_deg: Some(45.0),
        satellites: Some(12),
        h_acc_m,
        v_acc_m,
    }
}

fn attitude(roll_deg: f64, pitch_deg: f64, yaw_deg: f64) -> Attitude {
    Attitude {
        time_boot_ms: 0,
        roll_rad: roll_deg.to_radians(),
        pitch_rad: pitch_deg.to_radians(),
        yaw_rad: yaw_deg.to_radians(),
        roll_rate_radps: 0.0,
        pitch_rate_radps: 0.0,
        yaw_rate_radps: 0.0,
    }
}

#[test]
fn each_kind_of_telemetry_has_one_channel_with_a_real_schema() {
    let kinds = kinds();
    let mut names: Vec<_> = kinds.iter().map(|(n, _)| *n).collect();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), kinds.len(), "one channel per message");
    for (name, schema) in &kinds {
        assert!(
            schema["properties"].is_object() || schema["oneOf"].is_array(),
            "{name}: {schema}"
        );
    }
    let gps_schema = &kinds
        .iter()
        .find(|(n, _)| *n == "GPS_RAW_INT")
        .expect("gps")
        .1;
    assert!(gps_schema["properties"]["lat_deg"].is_object());
}

#[test]
fn a_gps_fix_is_recorded_as_itself_and_on_the_map_with_its_accuracy() {
    let ch = channels();
    let out = ch.records(1_000, &Telemetry::GpsRaw(gps(Some(2.0), Some(3.0))));
    assert_eq!(out.len(), 2);
    let raw: Value = serde_json::from_slice(&out[0].1).expect("JSON");
    assert_eq!(raw["lat_deg"], 38.5);
    assert_eq!(raw["satellites"], 12);
    let fix: Value = serde_json::from_slice(&out[1].1).expect("JSON");
    let cov: Vec<f64> = serde_json::from_value(fix["position_covariance"].clone()).expect("cov");
    assert_eq!(cov, [4.0, 0.0, 0.0, 0.0, 4.0, 0.0, 0.0, 0.0, 9.0]);
    assert_eq!(
        fix["position_covariance_type"],
        PositionCovarianceType::DiagonalKnown as u8
    );
    let unknown = gps_fix(Timestamp::from_nanos(0), &gps(None, Some(3.0)));
    assert_eq!(
        unknown.position_covariance_type,
        PositionCovarianceType::Unknown
    );
}

/// Regression: a tlog from an ArduPilot vehicle put LocationFix points at 0°, 0° (the receiver's
/// zeros before its first fix), and Foxglove drew the track from the Gulf of Guinea.
#[test]
fn a_report_without_a_fix_is_kept_as_telemetry_but_is_no_location_fix() {
    let ch = channels();
    for (fix, lat_deg, lon_deg) in [
        (GpsFix::NoGps, 0.0, 0.0),
        (GpsFix::NoFix, 0.0, 0.0),
        (GpsFix::NoFix, 38.5, -7.9),
        (GpsFix::Fix3d, 0.0, 0.0),
    ] {
        let g = GpsRaw {
            fix,
            lat_deg,
            lon_deg,
            ..gps(None, None)
        };
        let out = ch.records(1_000, &Telemetry::GpsRaw(g));
        assert_eq!(
            out.len(),
            1,
            "{fix:?} at {lat_deg}, {lon_deg}: telemetry only"
        );
        let raw: Value = serde_json::from_slice(&out[0].1).expect("JSON");
        assert_eq!(raw["lat_deg"], lat_deg);
    }
    let fix2d = GpsRaw {
        fix: GpsFix::Fix2d,
        ..gps(None, None)
    };
    assert_eq!(ch.records(1_000, &Telemetry::GpsRaw(fix2d)).len(), 2);
}

#[test]
fn the_attitude_quaternion_turns_the_body_as_roll_pitch_and_yaw_say() {
    let ts = Timestamp::from_nanos(0);
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let close = |q: &Quaternion, x: f64, y: f64, z: f64, w: f64| {
        (q.x - x).abs() < 1e-12
            && (q.y - y).abs() < 1e-12
            && (q.z - z).abs() < 1e-12
            && (q.w - w).abs() < 1e-12
    };
    let east = attitude_transform(ts, &attitude(0.0, 0.0, 90.0));
    assert!(close(&east.rotation, 0.0, 0.0, h, h), "{:?}", east.rotation);
    let rolled = attitude_transform(ts, &attitude(90.0, 0.0, 0.0));
    assert!(
        close(&rolled.rotation, h, 0.0, 0.0, h),
        "{:?}",
        rolled.rotation
    );
    // Yaw applied after pitch: a 30°-nose-up body turned east points east and 30° up.
    let q = attitude_transform(ts, &attitude(0.0, 30.0, 90.0)).rotation;
    let r = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q.w, q.x, q.y, q.z));
    let nose = r * nalgebra::Vector3::x();
    // Nose east and 30° up (NED: up is −z).
    assert!(
        (nose - nalgebra::Vector3::new(0.0, 30f64.to_radians().cos(), -(30f64.to_radians().sin())))
            .norm()
            < 1e-12,
        "{nose}"
    );
    assert_eq!(
        (east.parent_frame_id.as_str(), east.child_frame_id.as_str()),
        ("ned", "body")
    );
}
