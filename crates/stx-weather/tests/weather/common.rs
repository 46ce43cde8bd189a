//! The test files and what ecCodes read from them.

use std::path::{Path, PathBuf};

use serde_json::Value;
use stx_weather::GfsField;
use stx_weather::decode::Message;

/// Tolerance on a decoded value against ecCodes', in the value's unit (m/s for winds,
/// geopotential metres for heights): the goal of issue 31.
pub const ECCODES_TOLERANCE: f64 = 0.01;

pub fn testdata(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("testdata")
        .join(name)
}

pub fn bytes(name: &str) -> Vec<u8> {
    std::fs::read(testdata(name)).unwrap()
}

pub fn field(name: &str) -> GfsField {
    let b = bytes(name);
    GfsField::from_files([(name, b.as_slice())]).unwrap()
}

/// GRIB2 code table 4.2 (discipline 0) of ecCodes' short names.
pub fn parameter(short_name: &str) -> Option<(u8, u8)> {
    match short_name {
        "u" => Some((2, 2)),
        "v" => Some((2, 3)),
        "gh" => Some((3, 5)),
        _ => None,
    }
}

/// The level of an ecCodes reading, Pa.
pub fn level_pa(m: &Value) -> f64 {
    let level = m["level"].as_f64().unwrap();
    match m["type_of_level"].as_str().unwrap() {
        "isobaricInhPa" => level * 100.0,
        "isobaricInPa" => level,
        other => panic!("not an isobaric level: {other}"),
    }
}

/// Holds stx's decoding of `name` against ecCodes' `readings` of it (the messages of
/// read_grib.py's JSON, in file order): shape, level, step, and every point's value at its
/// latitude and longitude. Returns how many values were compared.
pub fn compare_decoding(name: &str, readings: &[Value]) -> usize {
    let messages: Vec<Message> = stx_weather::decode::decode(&bytes(name)).unwrap();
    assert_eq!(messages.len(), readings.len(), "{name}: messages");
    let mut compared = 0;
    for (n, (m, r)) in messages.iter().zip(readings).enumerate() {
        let at = format!("{name} message {}", n + 1);
        assert_eq!(m.ni as u64, r["ni"].as_u64().unwrap(), "{at}: Ni");
        assert_eq!(m.nj as u64, r["nj"].as_u64().unwrap(), "{at}: Nj");
        assert_eq!(
            m.forecast_s,
            Some(r["step_hours"].as_i64().unwrap() * 3600),
            "{at}: step"
        );
        if let Some((category, number)) = parameter(r["short_name"].as_str().unwrap()) {
            assert_eq!(
                (m.category, m.number),
                (Some(category), Some(number)),
                "{at}"
            );
            assert_eq!(m.surface_type, Some(100), "{at}: isobaric");
            assert!((m.surface_value - level_pa(r)).abs() < 1e-9, "{at}: level");
        }
        let t = m.reference_time.unwrap();
        let date = r["data_date"].as_i64().unwrap();
        let hhmm = r["data_time"].as_i64().unwrap();
        assert_eq!(
            (i64::from(t.year()), t.month() as i64, i64::from(t.day())),
            (date / 10000, date / 100 % 100, date % 100),
            "{at}: date"
        );
        assert_eq!(
            (i64::from(t.hour()), i64::from(t.minute())),
            (hhmm / 100, hhmm % 100)
        );
        let index: std::collections::HashMap<(i64, i64), usize> = m
            .points
            .lat_lon_deg
            .iter()
            .enumerate()
            .map(|(k, &(lat, lon))| (key(lat, lon), k))
            .collect();
        for p in r["points"].as_array().unwrap() {
            let (lat, lon, expected) = (
                p[0].as_f64().unwrap(),
                p[1].as_f64().unwrap(),
                p[2].as_f64().unwrap(),
            );
            let k = index[&key(lat, lon)];
            let got = f64::from(m.values[k]);
            assert!(
                (got - expected).abs() <= ECCODES_TOLERANCE,
                "{at} at {lat}, {lon}: stx {got}, ecCodes {expected}"
            );
            compared += 1;
        }
    }
    compared
}

/// A latitude and longitude as an exact key (micro-degrees, longitude modulo 360).
pub fn key(lat: f64, lon: f64) -> (i64, i64) {
    (
        (lat * 1e6).round() as i64,
        (lon.rem_euclid(360.0) * 1e6).round() as i64 % 360_000_000,
    )
}

/// The messages of a GRIB2 file, each its own bytes (section 0 holds its length).
pub fn split_messages(bytes: &[u8]) -> Vec<&[u8]> {
    let mut out = Vec::new();
    let mut at = 0;
    while at + 16 <= bytes.len() {
        assert_eq!(&bytes[at..at + 4], b"GRIB");
        let len = u64::from_be_bytes(bytes[at + 8..at + 16].try_into().unwrap()) as usize;
        out.push(&bytes[at..at + len]);
        at += len;
    }
    out
}
