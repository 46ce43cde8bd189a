//! The flight-log CSV: one file, one row per instant, for logs from other autopilots or
//! spreadsheets and for handing a flight to `stx compare` / `stx identify`.
//!
//! Format: comma-separated (fields may be quoted, as spreadsheets write them), a header row
//! naming the columns (in any order; a unit in brackets after a name, `north_m [m]`, is
//! allowed and ignored; other columns are ignored), then one row per instant in increasing
//! time. Lines starting with `#` are comments.
//!
//! | column | unit | meaning |
//! |---|---|---|
//! | `time_s` | s | time, any origin |
//! | `north_m`, `east_m` | m | drone (GPS) position north and east of any fixed origin |
//! | `alt_msl_m` | m | drone altitude above mean sea level |
//! | `v_north_mps`, `v_east_mps`, `v_down_mps` | m/s | velocity over the ground, NED |
//! | `roll_deg`, `pitch_deg`, `yaw_deg` | ° | drone attitude relative to NED (3-2-1) |
//! | `airspeed_mps` | m/s | true airspeed; empty when not measured |
//! | `main_line` | −1 … 1 | main-line command, fraction of the travel (+ turns right) |
//! | `brake_right`, `brake_left` | 0 … 1 | brake commands |
//! | `wind_north_mps`, `wind_east_mps` | m/s | the drone's wind estimate (air velocity, NED) |
//! | `wind_down_mps` | m/s | optional, 0 when absent |
//!
//! `stx compare FILE.mcap --write-log FILE.csv` writes a station recording in this form.

use std::fmt::Write as _;

use super::{FlightLog, FlightLogError, LogSample};

/// The required columns, in the order [`to_csv`] writes them.
pub const COLUMNS: [&str; 16] = [
    "time_s",
    "north_m",
    "east_m",
    "alt_msl_m",
    "v_north_mps",
    "v_east_mps",
    "v_down_mps",
    "roll_deg",
    "pitch_deg",
    "yaw_deg",
    "airspeed_mps",
    "main_line",
    "brake_right",
    "brake_left",
    "wind_north_mps",
    "wind_east_mps",
];
const WIND_DOWN: &str = "wind_down_mps";

/// Reads a flight log from CSV text.
pub fn from_csv(text: &str) -> Result<FlightLog, FlightLogError> {
    // The `csv` crate reads what spreadsheets write: quoted fields, commas inside them.
    // Blank and comment lines are left out first, so that errors name the editor's line.
    let (table, numbers) = stx_types::table_text::data_lines(text);
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(table.as_bytes());
    let line_of = |p: Option<&csv::Position>| {
        p.map_or(0, |p| {
            stx_types::table_text::original_line(&numbers, p.line())
        })
    };
    let mut records = reader.records().map(|r| match r {
        Err(e) => Err(FlightLogError::Csv {
            line: line_of(e.position()),
            message: e.to_string(),
        }),
        Ok(r) => Ok((line_of(r.position()), r)),
    });
    let Some(header) = records.next().transpose()?.map(|(_, r)| r) else {
        return Err(FlightLogError::TooShort { samples: 0 });
    };
    let names: Vec<&str> = header
        .iter()
        .map(|h| h.split('[').next().unwrap_or(h).trim())
        .collect();
    let find = |c: &'static str| names.iter().position(|n| *n == c);
    let mut at = [0usize; COLUMNS.len()];
    for (k, c) in COLUMNS.iter().enumerate() {
        at[k] = find(c).ok_or(FlightLogError::MissingColumn(c))?;
    }
    let wind_down = find(WIND_DOWN);
    let mut samples = Vec::new();
    for record in records {
        let (line, row) = record?;
        let fields: Vec<&str> = row.iter().collect();
        let cell = |k: usize| -> Result<Option<f64>, FlightLogError> {
            let text = fields.get(k).copied().ok_or_else(|| FlightLogError::Csv {
                line,
                message: format!("{} fields, the header has {}", fields.len(), names.len()),
            })?;
            if text.is_empty() {
                return Ok(None);
            }
            text.parse::<f64>()
                .map(Some)
                .map_err(|_| FlightLogError::Csv {
                    line,
                    message: format!("`{}` is not a number: {text:?}", names[k]),
                })
        };
        let mut v = [0.0; COLUMNS.len()];
        for (k, c) in COLUMNS.iter().enumerate() {
            match (cell(at[k])?, *c) {
                (Some(x), _) => v[k] = x,
                (None, "airspeed_mps") => v[k] = f64::NAN,
                (None, c) => {
                    return Err(FlightLogError::Csv {
                        line,
                        message: format!("`{c}` is empty"),
                    });
                }
            }
        }
        let down = match wind_down {
            Some(k) => cell(k)?.unwrap_or(0.0),
            None => 0.0,
        };
        let rad = f64::to_radians;
        samples.push(LogSample {
            time_s: v[0],
            position_ned_m: [v[1], v[2], -v[3]],
            velocity_ned_mps: [v[4], v[5], v[6]],
            euler_rad: [rad(v[7]), rad(v[8]), rad(v[9])],
            airspeed_mps: (!v[10].is_nan()).then_some(v[10]),
            main_line: v[11],
            brake_right: v[12],
            brake_left: v[13],
            wind_ned_mps: [v[14], v[15], down],
        });
    }
    FlightLog::new(samples)
}

/// Writes `log` as CSV (every column of [`COLUMNS`] and `wind_down_mps`).
pub fn to_csv(log: &FlightLog) -> String {
    let mut out = String::from("# stx flight log (stx_analysis::flight_log::csv)\n");
    out.push_str(&COLUMNS.join(","));
    out.push(',');
    out.push_str(WIND_DOWN);
    out.push('\n');
    for s in log.samples() {
        let deg = f64::to_degrees;
        let values = [
            s.time_s,
            s.position_ned_m[0],
            s.position_ned_m[1],
            -s.position_ned_m[2],
            s.velocity_ned_mps[0],
            s.velocity_ned_mps[1],
            s.velocity_ned_mps[2],
            deg(s.euler_rad[0]),
            deg(s.euler_rad[1]),
            deg(s.euler_rad[2]),
        ];
        let mut row: Vec<String> = values.iter().map(|v| format!("{v:.6}")).collect();
        row.push(s.airspeed_mps.map_or(String::new(), |a| format!("{a:.6}")));
        for v in [
            s.main_line,
            s.brake_right,
            s.brake_left,
            s.wind_ned_mps[0],
            s.wind_ned_mps[1],
            s.wind_ned_mps[2],
        ] {
            row.push(format!("{v:.6}"));
        }
        let _ = writeln!(out, "{}", row.join(","));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flight_log::tests::straight;

    #[test]
    fn a_log_survives_writing_and_reading() {
        let mut samples = straight(6);
        samples[3].airspeed_mps = None;
        let log = FlightLog::new(samples).unwrap();
        let back = from_csv(&to_csv(&log)).unwrap();
        assert_eq!(back.samples().len(), 6);
        for (a, b) in log.samples().iter().zip(back.samples()) {
            assert!((a.position_ned_m[2] - b.position_ned_m[2]).abs() < 1e-6);
            assert!((a.euler_rad[1] - b.euler_rad[1]).abs() < 1e-6);
            assert_eq!(a.airspeed_mps.is_some(), b.airspeed_mps.is_some());
        }
    }

    #[test]
    fn units_in_headers_are_ignored_and_bad_files_named() {
        let header = COLUMNS.map(|c| format!("{c} [u]")).join(",");
        let row = "0,0,0,100,5,0,2,0,5,0,,0,0,0,1,0";
        let rows = [0.0, 1.0, 2.0].map(|t| row.replacen('0', &t.to_string(), 1));
        let text = format!("{header}\n{}\n", rows.join("\n"));
        let log = from_csv(&text).unwrap();
        assert_eq!(log.samples()[1].position_ned_m[2], -100.0);
        assert_eq!(
            from_csv("time_s,north_m\n0,0\n"),
            Err(FlightLogError::MissingColumn("east_m"))
        );
        let bad = text.replace(",5,0,2,", ",five,0,2,");
        assert!(matches!(
            from_csv(&bad),
            Err(FlightLogError::Csv { line: 2, .. })
        ));
        // As `stx compare --write-log` writes it, headed by a comment: the editor's line 3.
        assert!(matches!(
            from_csv(&format!("# a flight log\n{bad}")),
            Err(FlightLogError::Csv { line: 3, .. })
        ));
    }

    /// A spreadsheet quotes a header with a comma in it (and may quote numbers): the columns
    /// after it stay where they are (a plain split on commas moved them one to the right).
    #[test]
    fn quoted_fields_with_commas_are_read() {
        let mut names = COLUMNS.map(String::from);
        names[0] = "\"time_s [s, any origin]\"".into();
        let header = names.join(",");
        let text = format!(
            "# exported\n{header}\n\"0\",1,2,100,5,0,2,0,5,0,,0,0,0,1,0\n1,2,3,99,5,0,2,0,5,0,,0,0,0,1,0\n\
             2,3,4,98,5,0,2,0,5,0,,0,0,0,1,0\n"
        );
        let log = from_csv(&text).unwrap();
        let s = &log.samples()[1];
        assert_eq!((s.time_s, s.position_ned_m), (1.0, [2.0, 3.0, -99.0]));
        assert_eq!(log.samples()[0].time_s, 0.0);
    }
}
