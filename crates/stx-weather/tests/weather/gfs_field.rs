//! The wind field's profile against its own grid values (which the ecCodes tests hold against
//! ecCodes): exact at grid points and forecast hours, linear between them; and the files it
//! refuses, each error naming what is missing.

use stx_weather::{GfsError, GfsField, geometric_height_m, parse_time};

use crate::common::{bytes, field, split_messages};

const RUN: &str = "2026-11-30T06:00:00Z";

fn at(hours: f64) -> stx_weather::OffsetDateTime {
    let run = parse_time(RUN).unwrap();
    let span = std::time::Duration::from_secs_f64(hours.abs() * 3600.0);
    if hours < 0.0 { run - span } else { run + span }
}

#[test]
fn the_profile_at_a_grid_point_and_hour_is_that_points_values_lowest_first() {
    let f = field("gfs_0p25_subset.grib2");
    assert_eq!(f.reference_time(), parse_time(RUN).unwrap());
    assert_eq!(f.shape(), (17, 21));
    assert_eq!(f.levels_pa().len(), 11);
    assert_eq!(f.levels_pa()[10], 40.0);
    // Row 4 is 39° N, column 8 is 352° E; hour 3 is the second forecast time.
    assert_eq!(f.grid_point_deg(4, 8), (39.0, -8.0));
    let profile = f.profile(39.0, -8.0, at(3.0)).unwrap();
    assert_eq!(profile.len(), 11);
    for (k, level) in profile.iter().enumerate() {
        let [u, v, gh] = f.at_grid_point(1, k, 4, 8);
        assert!((level.east_mps - f64::from(u)).abs() < 1e-9);
        assert!((level.north_mps - f64::from(v)).abs() < 1e-9);
        assert!((level.alt_msl_m - geometric_height_m(f64::from(gh))).abs() < 1e-6);
        assert_eq!(level.pressure_pa, Some(f.levels_pa()[k]));
    }
    assert!(profile.windows(2).all(|w| w[1].alt_msl_m > w[0].alt_msl_m));
    // The 0.4 hPa level of the made-up field lies near 51 km of geopotential.
    assert!(profile[10].alt_msl_m > 50_000.0);
    // East longitudes past 180° and west ones name the same place.
    assert_eq!(f.profile(39.0, 352.0, at(3.0)).unwrap(), profile);
}

#[test]
fn between_points_and_hours_the_profile_is_the_mean_of_the_eight_around() {
    let f = field("gfs_0p25_subset.grib2");
    // Midway between rows 4 and 5 (39.0, 38.75° N), columns 8 and 9 (352.0, 352.25° E),
    // hours 0 and 3.
    let profile = f.profile(38.875, 352.125, at(1.5)).unwrap();
    for (k, level) in profile.iter().enumerate() {
        let mut mean = [0.0; 3];
        for t in [0, 1] {
            for j in [4, 5] {
                for i in [8, 9] {
                    let values = f.at_grid_point(t, k, j, i);
                    for (m, v) in mean.iter_mut().zip(values) {
                        *m += f64::from(v) / 8.0;
                    }
                }
            }
        }
        assert!((level.east_mps - mean[0]).abs() < 1e-6, "level {k}");
        assert!((level.north_mps - mean[1]).abs() < 1e-6, "level {k}");
        assert!((level.alt_msl_m - geometric_height_m(mean[2])).abs() < 1e-4);
    }
}

#[test]
fn one_file_per_forecast_hour_makes_the_same_field_as_one_file() {
    let whole = bytes("gfs_0p25_subset.grib2");
    let messages = split_messages(&whole);
    assert_eq!(messages.len(), 99);
    // 33 messages per hour, as NOMADS serves a file per hour.
    let files: Vec<Vec<u8>> = messages.chunks(33).map(|c| c.concat()).collect();
    let named: Vec<(String, &[u8])> = files
        .iter()
        .enumerate()
        .map(|(h, b)| (format!("f{:03}", 3 * h), b.as_slice()))
        .collect();
    let split = GfsField::from_files(named.iter().map(|(n, b)| (n.as_str(), *b))).unwrap();
    assert_eq!(split, field("gfs_0p25_subset.grib2"));
}

#[test]
fn a_place_outside_the_box_or_a_time_outside_the_hours_is_refused_naming_the_span() {
    let f = field("gfs_0p50_simple.grib2");
    let e = f.profile(41.0, -8.0, at(0.0)).unwrap_err();
    assert!(matches!(e, GfsError::OutsideBox { .. }));
    let text = e.to_string();
    assert!(
        text.contains("outside the file's box") && text.contains("latitudes 36…40°"),
        "{text}"
    );
    let e = f.profile(38.0, 0.0, at(0.0)).unwrap_err().to_string();
    assert!(e.contains("longitudes -10…-5°"), "{e}");
    let e = f.profile(38.0, -8.0, at(6.5)).unwrap_err();
    assert_eq!(
        e.to_string(),
        "2026-11-30T12:30:00Z is outside the forecast: its hours cover 2026-11-30T06:00:00Z to \
         2026-11-30T12:00:00Z"
    );
    assert!(f.profile(38.0, -8.0, at(6.0)).is_ok());
    assert!(f.profile(38.0, -8.0, at(-0.1)).is_err());
}

#[test]
fn a_file_without_hgt_or_missing_one_message_is_refused_naming_what_is_missing() {
    let b = bytes("no_hgt.grib2");
    let e = GfsField::from_files([("no_hgt.grib2", b.as_slice())]).unwrap_err();
    assert_eq!(e, GfsError::MissingVariable { variable: "HGT" });
    assert!(e.to_string().starts_with("no HGT on isobaric levels"));

    // The 0.5° file less its 5th message: VGRD at 500 hPa, hour 0.
    let whole = bytes("gfs_0p50_simple.grib2");
    let mut messages = split_messages(&whole);
    messages.remove(4);
    let cut = messages.concat();
    let e = GfsField::from_files([("cut", cut.as_slice())]).unwrap_err();
    assert_eq!(
        e.to_string(),
        "no VGRD at 500 hPa for forecast hour 0: every level needs UGRD, VGRD and HGT at every hour"
    );

    // The same file twice: its messages would replace one another.
    let e = GfsField::from_files([("a", whole.as_slice()), ("b", whole.as_slice())]).unwrap_err();
    assert_eq!(
        e.to_string(),
        "b: a second UGRD at 1000 hPa for forecast hour 0 (a file given twice, or several \
         ensemble members?)"
    );

    // Cut inside a message (its 24 are of one size: half the file is a whole 12): the
    // reason, with the file's name.
    let e = GfsField::from_files([("half.grib2", &whole[..whole.len() / 2 + 100])]).unwrap_err();
    assert!(matches!(e, GfsError::Decode { .. }), "{e:?}");
    assert_eq!(
        e.to_string(),
        "half.grib2: not a readable GRIB2 file: message 13 is cut: it declares 377 bytes, the \
         file holds 100 more"
    );
    let e = GfsField::from_files([("text", b"not a grib file".as_slice())]).unwrap_err();
    assert!(e.to_string().starts_with("text: "), "{e}");
}
