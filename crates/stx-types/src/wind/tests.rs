use super::*;

fn at_altitude(altitude_m: f64) -> Vector3<f64> {
    Vector3::new(120.0, -40.0, -altitude_m)
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-12
}

#[test]
fn wind_from_the_north_blows_south() {
    let wind = ConstantWind::from_speed_direction(5.0, 0.0).unwrap();
    let v = wind.wind_ned_mps(0.0, &at_altitude(100.0));
    assert!(close(v.x, -5.0) && close(v.y, 0.0) && v.z == 0.0, "{v}");
    // From the west (270°) the air moves east; from the south-east (135°) it moves north-west.
    let v = ConstantWind::from_speed_direction(5.0, 270.0)
        .unwrap()
        .wind_ned_mps(0.0, &at_altitude(0.0));
    assert!(close(v.x, 0.0) && close(v.y, 5.0), "{v}");
    let v = ConstantWind::from_speed_direction(2.0_f64.sqrt(), 135.0)
        .unwrap()
        .wind_ned_mps(0.0, &at_altitude(0.0));
    assert!(close(v.x, 1.0) && close(v.y, -1.0), "{v}");
    assert_eq!(Calm.wind_ned_mps(3.0, &at_altitude(10.0)), Vector3::zeros());
}

#[test]
fn constant_wind_refuses_negative_or_non_finite_values() {
    for (speed, from) in [(-1.0, 0.0), (f64::NAN, 0.0), (1.0, f64::INFINITY)] {
        let error = ConstantWind::from_speed_direction(speed, from).unwrap_err();
        assert!(matches!(error, WindError::InvalidConstantWind { .. }));
    }
}

fn profile(rows: &[[f64; 3]]) -> Result<WindProfile, WindError> {
    WindProfile::from_rows(rows)
}

#[test]
fn profile_interpolates_components_linearly_and_clamps_outside() {
    // From 350° at 100 m to from 10° at 300 m: halfway, components average to a wind from
    // due north (interpolating the angle naively would give one from due south).
    let wind = profile(&[
        [100.0, 4.0, 350.0],
        [300.0, 4.0, 10.0],
        [1_000.0, 10.0, 90.0],
    ])
    .unwrap();
    let mid = wind.wind_ned_mps(0.0, &at_altitude(200.0));
    let expected_north = -4.0 * 10.0_f64.to_radians().cos();
    assert!(close(mid.x, expected_north) && close(mid.y, 0.0), "{mid}");

    // A quarter of the way from 300 m to 1000 m: components interpolated.
    let v = wind.wind_ned_mps(0.0, &at_altitude(475.0));
    let (n0, e0) = (
        -4.0 * 10.0_f64.to_radians().cos(),
        -4.0 * 10.0_f64.to_radians().sin(),
    );
    let (n1, e1) = (0.0, -10.0);
    assert!(
        close(v.x, n0 + 0.25 * (n1 - n0)) && close(v.y, e0 + 0.25 * (e1 - e0)),
        "{v}"
    );

    // Exactly on rows, and clamped outside the table (including below ground).
    let row = wind.wind_ned_mps(0.0, &at_altitude(1_000.0));
    assert!(close(row.x, 0.0) && close(row.y, -10.0));
    assert_eq!(wind.wind_ned_mps(0.0, &at_altitude(5_000.0)), row);
    let bottom = wind.wind_ned_mps(0.0, &at_altitude(100.0));
    assert_eq!(wind.wind_ned_mps(0.0, &at_altitude(-3.0)), bottom);
    assert_eq!(wind.wind_ned_mps(0.0, &at_altitude(0.0)), bottom);
    // Altitude is −z: the horizontal position and the time do not matter.
    assert_eq!(
        wind.wind_ned_mps(99.0, &Vector3::new(-5e3, 7e3, -475.0)),
        wind.wind_ned_mps(0.0, &at_altitude(475.0))
    );
    // A single row is a constant wind.
    let single = profile(&[[0.0, 3.0, 180.0]]).unwrap();
    assert!(close(single.wind_ned_mps(0.0, &at_altitude(1e4)).x, 3.0));
    assert!(
        wind.wind_ned_mps(0.0, &Vector3::new(0.0, 0.0, f64::NAN))
            .x
            .is_nan()
    );
}

#[test]
fn profile_validation_names_the_row_and_the_rule() {
    assert_eq!(profile(&[]).unwrap_err(), WindError::EmptyProfile);
    let error = profile(&[[0.0, 1.0, 0.0], [10.0, f64::NAN, 0.0]]).unwrap_err();
    assert!(matches!(
        error,
        WindError::ProfileRowNotFinite { row: 1, .. }
    ));
    assert!(error.to_string().contains("row 1") && error.to_string().contains("finite"));
    let error = profile(&[[0.0, -1.0, 0.0]]).unwrap_err();
    assert_eq!(
        error,
        WindError::ProfileNegativeSpeed {
            row: 0,
            speed_mps: -1.0
        }
    );
    assert!(error.to_string().contains("row 0") && error.to_string().contains("≥ 0"));
    let error = profile(&[[0.0, 1.0, 0.0], [10.0, 1.0, 0.0], [10.0, 1.0, 0.0]]).unwrap_err();
    assert_eq!(
        error,
        WindError::ProfileAltitudeNotIncreasing {
            row: 2,
            altitude_m: 10.0,
            previous_altitude_m: 10.0
        }
    );
    assert!(error.to_string().contains("strictly increase"));
}

#[test]
fn count_below_near_counts_as_count_below_whatever_its_hint() {
    use std::sync::atomic::AtomicUsize;
    let rows = [-50.0, 0.0, 120.0, 1500.0, 9000.0];
    let xs = [
        -1e9,
        -50.0,
        -49.9,
        0.0,
        60.0,
        120.0,
        1499.0,
        9000.0,
        9000.5,
        f64::NAN,
    ];
    for x in xs {
        let expected = count_below(rows.iter().copied(), x);
        for start in [0, 2, 4, 5, 6, usize::MAX] {
            let hint = AtomicUsize::new(start);
            for _ in 0..2 {
                let got = count_below_near(rows.len(), |i| rows[i], x, &hint);
                assert_eq!(got, expected, "x {x}, hint {start}");
            }
        }
    }
    let profile = WindProfile::from_rows(&[[0.0, 3.0, 200.0], [900.0, 9.0, 250.0]]).unwrap();
    let hint = AtomicUsize::new(7);
    for h in [-10.0, 0.0, 450.0, 900.0, 2000.0, 450.0] {
        let p = Vector3::new(0.0, 0.0, -h);
        assert_eq!(
            profile.wind_ned_mps_near(0.0, &p, &hint),
            profile.wind_ned_mps(0.0, &p)
        );
    }
}
