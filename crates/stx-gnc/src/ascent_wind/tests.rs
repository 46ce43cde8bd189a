//! The estimator on small noise-free ascents whose every band is known exactly; the noisy,
//! many-seed coverage check is `tests/gnc/ascent_wind.rs`.

use nalgebra::Vector3;
use stx_types::wind::{ProfileRow, WindError, WindField};

use super::*;

/// Wind (north, east), m/s, at altitude `h` m: 4 m/s from the west at the ground, turning
/// and strengthening linearly.
fn linear_wind(h: f64) -> (f64, f64) {
    (0.001 * h, 4.0 + 0.002 * h)
}

/// A noise-free ascent at `climb` m/s from `start_alt` for `duration` s at 1 Hz, drifting
/// with [`linear_wind`], starting at `t0`; velocities reported if `with_velocity`.
fn ascent(
    t0: f64,
    start_alt: f64,
    climb: f64,
    duration: u32,
    with_velocity: bool,
) -> Vec<AscentFix> {
    // Position is the integral of the wind along the altitude path: with h = h0 + c·τ,
    // north = ∫0.001·h dτ and east = ∫(4 + 0.002·h) dτ.
    (0..=duration)
        .map(|i| {
            let tau = f64::from(i);
            let h = start_alt + climb * tau;
            let integral_h = start_alt * tau + 0.5 * climb * tau * tau;
            let (vn, ve) = linear_wind(h);
            AscentFix {
                time_s: t0 + tau,
                position_ned_m: Vector3::new(
                    0.001 * integral_h,
                    4.0 * tau + 0.002 * integral_h,
                    -h,
                ),
                velocity_ned_mps: with_velocity.then_some(Vector3::new(vn, ve, -climb)),
            }
        })
        .collect()
}

fn estimator() -> AscentWindEstimator {
    AscentWindEstimator::new(AscentWindConfig::default()).expect("valid config")
}

fn feed(est: &mut AscentWindEstimator, fixes: &[AscentFix]) -> Vec<Disposition> {
    fixes
        .iter()
        .map(|f| est.push_fix(f).expect("finite fix"))
        .collect()
}

fn band(wind_north_mps: f64, wind_east_mps: f64) -> WindBand {
    WindBand {
        band: 2,
        altitude_m: 1250.0,
        altitude_min_m: 1000.0,
        altitude_max_m: 1499.0,
        time_start_s: 0.0,
        time_end_s: 100.0,
        wind_north_mps,
        wind_east_mps,
        sigma_north_mps: 0.1,
        sigma_east_mps: 0.1,
        samples: 100,
        method: BandMethod::GpsVelocity,
        refused: None,
    }
}

#[test]
fn direction_is_where_the_wind_blows_from() {
    let close = |b: WindBand, deg: f64| assert!((b.from_deg() - deg).abs() < 1e-9, "{b:?}");
    close(band(-5.0, 0.0), 0.0); // air going south: from the north
    close(band(0.0, -5.0), 90.0);
    close(band(5.0, 0.0), 180.0);
    close(band(0.0, 5.0), 270.0);
    close(band(-3.0, 3.0), 315.0);
    assert!((band(3.0, 4.0).speed_mps() - 5.0).abs() < 1e-12);
    // And back through the predictors' profile: the same components at the band's altitude.
    let b = band(2.0, -7.0);
    let profile = WindProfile::new(vec![b.profile_row()]).expect("one row");
    let w = profile.wind_ned_mps(0.0, &Vector3::new(0.0, 0.0, -b.altitude_m));
    assert!(
        (w.x - 2.0).abs() < 1e-9 && (w.y + 7.0).abs() < 1e-9,
        "{w:?}"
    );
}

#[test]
fn a_clean_ascent_gives_each_band_its_mean_wind_from_velocities_or_positions() {
    for with_velocity in [true, false] {
        let mut est = estimator();
        // 30 s on the ground, then 5 m/s for 400 s: bands 0…3 full, band 4 with 0–20 m of
        // it... (2000 m is the start of band 4).
        let mut fixes = ascent(0.0, 0.0, 0.0, 30, with_velocity);
        fixes.extend(
            ascent(31.0, 0.0, 5.0, 400, with_velocity)
                .into_iter()
                .skip(1),
        );
        let dispositions = feed(&mut est, &fixes);
        assert!(
            dispositions[..30]
                .iter()
                .all(|d| !matches!(d, Disposition::Used { .. })),
            "the ground is not the wind"
        );
        let bands = est.profile();
        assert_eq!(bands.len(), 4, "{bands:#?}");
        for b in &bands {
            // The wind is linear in height, so the passage's mean is the wind at its middle.
            let (vn, ve) = linear_wind(b.altitude_m);
            assert!(
                (b.wind_north_mps - vn).abs() < 1e-6,
                "{with_velocity} {b:?}"
            );
            assert!((b.wind_east_mps - ve).abs() < 1e-6, "{with_velocity} {b:?}");
            let floor = 0.05_f64.hypot(2.0 / (b.time_end_s - b.time_start_s));
            assert!((b.sigma_north_mps - floor).abs() < 1e-6, "{b:?}");
            let expected = if with_velocity {
                BandMethod::GpsVelocity
            } else {
                BandMethod::PositionDifferences
            };
            assert_eq!(b.method, expected);
            assert!(b.altitude_min_m >= b.band as f64 * 500.0);
            assert!(b.altitude_max_m < (b.band + 1) as f64 * 500.0);
        }
    }
}

#[test]
fn a_band_with_too_few_fixes_is_not_reported() {
    let mut est = estimator();
    // Up to 540 m: band 1 holds 500–540 m, 8 fixes at 5 m/s, fewer than 20.
    feed(&mut est, &ascent(0.0, 0.0, 5.0, 108, true));
    let bands = est.profile();
    assert_eq!(bands.iter().map(|b| b.band).collect::<Vec<_>>(), vec![0]);
}

#[test]
fn descent_after_burst_is_ignored_and_the_last_window_withdrawn() {
    for with_velocity in [true, false] {
        let mut est = estimator();
        feed(&mut est, &ascent(0.0, 0.0, 5.0, 300, with_velocity));
        let before = est.profile();
        // Burst at 1500 m: falling at 30 m/s, thrown sideways at 20 m/s.
        let t_burst = 300.0;
        for i in 1..=60 {
            let tau = f64::from(i);
            let fix = AscentFix {
                time_s: t_burst + tau,
                position_ned_m: Vector3::new(0.0, 20.0 * tau, -(1500.0 - 30.0 * tau)),
                velocity_ned_mps: with_velocity.then_some(Vector3::new(0.0, 20.0, 30.0)),
            };
            est.push_fix(&fix).expect("finite");
        }
        // The 10-s average (11 fixes) reaches −3 m/s on the third falling fix.
        let over = est.ascent_over_at_s().expect("burst seen");
        assert!(over > t_burst && over <= t_burst + 5.0, "{over}");
        // Later rising (a thermal under the canopy) is not the balloon's drift.
        let thermal = ascent(400.0, 100.0, 3.0, 60, with_velocity);
        assert!(
            feed(&mut est, &thermal)
                .iter()
                .all(|d| *d == Disposition::AscentOver)
        );
        let after = est.profile();
        assert_eq!(before.len(), after.len());
        for (b, a) in before.iter().zip(&after) {
            // Still the clean ascent's wind, over a band cut short by the withdrawal.
            let (vn, ve) = linear_wind(a.altitude_m);
            assert!((a.wind_north_mps - vn).abs() < 1e-6, "{b:?} {a:?}");
            assert!((a.wind_east_mps - ve).abs() < 1e-6, "{b:?} {a:?}");
            assert!(a.time_end_s < over - est.config().vertical_rate_window_s);
        }
        let counts = est.counts();
        assert!(counts.withdrawn >= 8, "{counts:?}");
        assert!(counts.after_ascent >= 57 + 61, "{counts:?}");
        assert_eq!(
            counts.used,
            after.iter().map(|b| u64::from(b.samples)).sum::<u64>()
        );
    }
}

#[test]
fn a_level_or_slowly_moving_stack_is_not_used() {
    let mut est = estimator();
    // Float at 3 km with the GPS altitude wandering slowly.
    let fixes: Vec<AscentFix> = (0..200)
        .map(|i| {
            let t = f64::from(i);
            AscentFix {
                time_s: t,
                position_ned_m: Vector3::new(0.0, 10.0 * t, -(3000.0 + 0.3 * t)),
                velocity_ned_mps: None,
            }
        })
        .collect();
    assert!(feed(&mut est, &fixes).iter().all(|d| matches!(
        d,
        Disposition::NotAscending | Disposition::VerticalRateUnknown
    )));
    assert!(est.profile().is_empty());
    assert!(est.ascent_over_at_s().is_none());
}

#[test]
fn non_finite_and_out_of_order_fixes_are_refused_without_effect() {
    let mut est = estimator();
    let fixes = ascent(0.0, 0.0, 5.0, 50, true);
    feed(&mut est, &fixes[..40]);
    let snapshot = est.profile();
    let good = fixes[40];
    let mut nan_time = good;
    nan_time.time_s = f64::NAN;
    let mut inf_position = good;
    inf_position.position_ned_m.z = f64::NEG_INFINITY;
    let mut nan_velocity = good;
    nan_velocity.velocity_ned_mps = Some(Vector3::new(0.0, f64::NAN, 0.0));
    for (fix, field) in [
        (nan_time, "time_s"),
        (inf_position, "position_ned_m"),
        (nan_velocity, "velocity_ned_mps"),
    ] {
        match est.push_fix(&fix) {
            Err(AscentFixError::NotFinite { field: f, .. }) => assert_eq!(f, field),
            other => panic!("expected {field} refused, got {other:?}"),
        }
    }
    assert_eq!(est.push_fix(&fixes[10]), Ok(Disposition::OutOfOrder));
    assert_eq!(est.push_fix(&fixes[39]), Ok(Disposition::OutOfOrder));
    assert_eq!(est.profile(), snapshot);
    let counts = est.counts();
    assert_eq!((counts.refused, counts.out_of_order), (3, 2));
    assert!(matches!(
        est.push_fix(&good),
        Ok(Disposition::Used { band: 0 })
    ));
}

#[test]
fn a_bad_config_is_refused() {
    let config = AscentWindConfig {
        band_height_m: -1.0,
        ..Default::default()
    };
    assert!(matches!(
        AscentWindEstimator::new(config),
        Err(AscentWindConfigError::Invalid {
            field: "band_height_m",
            ..
        })
    ));
}

#[test]
fn a_fix_can_be_given_as_latitude_longitude_and_altitude() {
    let frame = LocalFrame::default();
    let p = Vector3::new(120.0, -340.0, -800.0);
    let (lat, lon, alt) = frame.to_geodetic(&p);
    let fix = AscentFix::from_geodetic(&frame, 5.0, lat, lon, alt, None);
    assert!((fix.position_ned_m - p).norm() < 1e-6, "{fix:?}");
}

fn row(altitude_m: f64, speed_mps: f64, from_deg: f64) -> ProfileRow {
    ProfileRow {
        altitude_m,
        speed_mps,
        from_deg,
    }
}

#[test]
fn merge_keeps_the_forecast_only_outside_the_measured_span() {
    let forecast = vec![
        row(10.0, 3.0, 270.0),
        row(900.0, 6.0, 280.0),
        row(1200.0, 7.0, 285.0),
        row(2600.0, 9.0, 290.0),
        row(5000.0, 15.0, 300.0),
    ];
    let low = WindBand {
        band: 1,
        altitude_m: 750.0,
        altitude_min_m: 520.0,
        altitude_max_m: 990.0,
        ..band(-1.0, 5.0)
    };
    // Band 2 missing (a dropout): interpolated between 1 and 3, not forecast.
    let high = WindBand {
        band: 3,
        altitude_m: 1750.0,
        altitude_min_m: 1500.0,
        altitude_max_m: 1990.0,
        ..band(-2.0, 8.0)
    };
    let merged = merge_with_forecast(&[low, high], &forecast).expect("valid");
    let altitudes: Vec<f64> = merged.rows().iter().map(|r| r.altitude_m).collect();
    assert_eq!(altitudes, vec![10.0, 750.0, 1750.0, 2600.0, 5000.0]);
    assert_eq!(merged.rows()[1], low.profile_row());
    assert_eq!(merged.rows()[3], forecast[3]);
    // No band: the forecast as it is; neither: an error.
    let alone = merge_with_forecast(&[], &forecast).expect("valid");
    assert_eq!(alone.rows(), &forecast[..]);
    assert_eq!(merge_with_forecast(&[], &[]), Err(WindError::EmptyProfile));
    // No forecast: the bands alone.
    assert_eq!(
        merge_with_forecast(&[low], &[])
            .expect("valid")
            .rows()
            .len(),
        1
    );
}

#[test]
fn merge_refuses_a_bad_forecast_even_where_measured() {
    let measured = band(0.0, 5.0);
    let not_increasing = [row(1300.0, 5.0, 0.0), row(1200.0, 5.0, 0.0)];
    assert!(matches!(
        merge_with_forecast(&[measured], &not_increasing),
        Err(WindError::ProfileAltitudeNotIncreasing { row: 1, .. })
    ));
    let nan = [row(1300.0, f64::NAN, 0.0)];
    assert!(matches!(
        merge_with_forecast(&[measured], &nan),
        Err(WindError::ProfileRowNotFinite { row: 0, .. })
    ));
}

#[test]
fn the_believed_wind_grows_from_the_ground_to_the_jet_streams_bound() {
    let c = AscentWindConfig::default();
    for (height_m, limit) in [
        (-50.0, 40.0),
        (0.0, 40.0),
        (1000.0, 50.0),
        (8000.0, 120.0),
        (30_000.0, 120.0),
    ] {
        assert!(
            (max_plausible_wind_mps(&c, height_m) - limit).abs() < 1e-9,
            "{height_m}"
        );
    }
}

#[test]
fn a_band_too_fast_or_too_uncertain_is_refused_with_its_reason_and_not_merged() {
    let c = AscentWindConfig::default();
    let believed = band(-2.0, 5.0);
    assert_eq!(judge(&believed, &c), None);
    // 88 m/s at 1000–1499 m: the bound there is 55 m/s.
    let fast = band(0.0, 88.0);
    match judge(&fast, &c) {
        Some(Implausible::TooFast {
            speed_mps,
            limit_mps,
        }) => {
            assert!((speed_mps - 88.0).abs() < 1e-9 && (limit_mps - 54.99).abs() < 1e-9);
        }
        other => panic!("{other:?}"),
    }
    let uncertain = WindBand {
        sigma_east_mps: 3.5,
        ..believed
    };
    assert!(matches!(
        judge(&uncertain, &c),
        Some(Implausible::TooUncertain { sigma_mps, .. }) if sigma_mps == 3.5
    ));
    let nan = band(f64::NAN, 0.0);
    assert!(matches!(judge(&nan, &c), Some(Implausible::TooFast { .. })));
    assert!(
        Implausible::TooFast {
            speed_mps: 88.0,
            limit_mps: 55.0
        }
        .to_string()
        .contains("88.0 m/s is faster than any wind")
    );
    // Merged: the refused band is left out, the forecast takes its place.
    let refused = WindBand {
        refused: judge(&fast, &c),
        ..fast
    };
    let forecast = [row(0.0, 3.0, 270.0), row(5000.0, 3.0, 270.0)];
    let merged = merge_with_forecast(&[refused], &forecast).expect("valid");
    assert_eq!(merged.rows(), &forecast[..]);
    let measured = crate::flight_path::merge_measured(&[], &[refused], 0.0);
    assert_eq!(measured, Err(crate::flight_path::ForecastError::Empty));
}

/// Issue 28: a recording of a 20× rehearsal read with the station's clock gave 88–176 m/s
/// between 840 and 2,223 m. The same ascent's fixes timed 20 times too fast are all refused.
#[test]
fn regression_absurd_measured_winds_from_a_20x_rehearsal_on_the_stations_clock_are_refused() {
    let on_the_drones_clock: Vec<AscentFix> = ascent(0.0, 0.0, 5.0, 500, false);
    let mut est = estimator();
    feed(&mut est, &on_the_drones_clock);
    let believed = est.profile();
    assert_eq!(believed.len(), 5);
    assert!(believed.iter().all(WindBand::is_believed), "{believed:#?}");
    let on_the_stations_clock: Vec<AscentFix> = on_the_drones_clock
        .iter()
        .map(|f| AscentFix {
            time_s: f.time_s / 20.0,
            velocity_ned_mps: None,
            ..*f
        })
        .collect();
    let mut est = estimator();
    feed(&mut est, &on_the_stations_clock);
    let bands = est.profile();
    assert!(bands.len() >= 4, "{bands:#?}");
    for b in &bands {
        assert!(b.speed_mps() > 80.0, "{b:?}");
        assert!(
            matches!(b.refused, Some(Implausible::TooFast { .. })),
            "{b:?}"
        );
    }
    assert_eq!(est.merged_with_forecast(&[]), Err(WindError::EmptyProfile));
}
