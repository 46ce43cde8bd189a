//! The forecast wind file the planner reads: rows of altitude above mean sea level, wind speed,
//! the direction it blows from, and optionally its uncertainty.
//!
//! Two spellings of the same table are accepted, told apart by their first meaningful line:
//!
//! TOML (the station's `[[forecast_wind]]` table, so a station config's rows can be copied):
//!
//! ```toml
//! [[forecast_wind]]
//! alt_msl_m = 300.0   # altitude above mean sea level, m
//! speed_mps = 2.0     # wind speed, m/s (≥ 0)
//! from_deg = 270.0    # direction the wind blows from, degrees clockwise from true north
//! sigma_mps = 1.0     # optional: 1-σ error of each horizontal component, m/s (≥ 0)
//! ```
//!
//! CSV: one row per line, `alt_msl_m,speed_mps,from_deg[,sigma_mps]`, an optional header line
//! of those names, blank lines and lines starting with `#` ignored; cells may be quoted, as
//! spreadsheets write them.
//!
//! Rows must have strictly increasing altitudes, finite values, speeds and sigmas ≥ 0. Between
//! rows the wind is interpolated by component, above the top and below the bottom row the end
//! row holds ([`WindProfile`]); a missing sigma takes the planner's default.

use serde::{Deserialize, Serialize};
use stx_types::wind::{ProfileRow, WindError, WindProfile};

use crate::ascent_wind::WindBand;

/// One forecast level.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct ForecastRow {
    /// Altitude above mean sea level, m.
    pub alt_msl_m: f64,
    /// Wind speed, m/s (≥ 0).
    pub speed_mps: f64,
    /// Direction the wind blows from, degrees clockwise from true north.
    pub from_deg: f64,
    /// 1-σ error of each horizontal wind component, m/s (≥ 0); `None`: the planner's default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma_mps: Option<f64>,
}

/// Why a forecast was refused. Rows and lines are counted from 1, as an editor shows them.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ForecastError {
    /// The text is not valid TOML of the expected shape.
    #[error("forecast (TOML): {0}")]
    Toml(String),
    /// A CSV line could not be read.
    #[error("forecast line {line}: {message}")]
    Csv {
        /// Line number, from 1.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// No rows.
    #[error("the forecast has no rows: it needs at least one level")]
    Empty,
    /// A row's sigma is negative or not finite.
    #[error("forecast row {row}: sigma_mps must be finite and ≥ 0, got {sigma_mps}")]
    Sigma {
        /// Row, from 1.
        row: usize,
        /// The sigma given, m/s.
        sigma_mps: f64,
    },
    /// The rows do not make a wind profile (row numbers in it count from 0).
    #[error("forecast: {0}")]
    Profile(#[from] WindError),
}

/// A validated forecast.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Forecast {
    rows: Vec<ForecastRow>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TomlForecast {
    forecast_wind: Vec<ForecastRow>,
}

impl Forecast {
    /// Validates `rows` (see the module doc).
    pub fn new(rows: Vec<ForecastRow>) -> Result<Self, ForecastError> {
        if rows.is_empty() {
            return Err(ForecastError::Empty);
        }
        for (i, r) in rows.iter().enumerate() {
            if let Some(s) = r.sigma_mps
                && !(s.is_finite() && s >= 0.0)
            {
                return Err(ForecastError::Sigma {
                    row: i + 1,
                    sigma_mps: s,
                });
            }
        }
        let forecast = Self { rows };
        // The profile's own checks: finite, speeds ≥ 0, altitudes increasing.
        forecast.profile(0.0)?;
        Ok(forecast)
    }

    /// Reads a forecast file's text, TOML or CSV (see the module doc).
    pub fn parse(text: &str) -> Result<Self, ForecastError> {
        let first = text
            .lines()
            .map(str::trim)
            .find(|l| !l.is_empty() && !l.starts_with('#'));
        match first {
            None => Err(ForecastError::Empty),
            Some(l) if l.starts_with('[') || l.contains('=') => {
                let t: TomlForecast =
                    toml::from_str(text).map_err(|e| ForecastError::Toml(e.to_string()))?;
                Self::new(t.forecast_wind)
            }
            Some(_) => Self::new(parse_csv(text)?),
        }
    }

    /// The rows, as given.
    pub fn rows(&self) -> &[ForecastRow] {
        &self.rows
    }

    /// The rows as profile rows above an origin `ground_msl_m` above sea level.
    pub fn profile_rows(&self, ground_msl_m: f64) -> Vec<ProfileRow> {
        self.rows
            .iter()
            .map(|r| ProfileRow {
                altitude_m: r.alt_msl_m - ground_msl_m,
                speed_mps: r.speed_mps,
                from_deg: r.from_deg,
            })
            .collect()
    }

    /// The wind profile above an origin `ground_msl_m` above sea level.
    pub fn profile(&self, ground_msl_m: f64) -> Result<WindProfile, WindError> {
        WindProfile::new(self.profile_rows(ground_msl_m))
    }

    /// The 1-σ wind error by height above the origin, m and m/s, with `default_sigma_mps` where
    /// a row gives none.
    pub fn sigma_rows(&self, ground_msl_m: f64, default_sigma_mps: f64) -> Vec<(f64, f64)> {
        self.rows
            .iter()
            .map(|r| {
                (
                    r.alt_msl_m - ground_msl_m,
                    r.sigma_mps.unwrap_or(default_sigma_mps),
                )
            })
            .collect()
    }
}

/// The `forecast` rows (possibly none) with the wind measured during an earlier ascent
/// (`bands` above an origin `origin_msl_m` above sea level, lowest first, as
/// [`crate::ascent_wind::AscentWindEstimator::profile`] gives them) in place of the forecast
/// rows over the span the measurement covers — the rule of
/// [`crate::ascent_wind::merge_with_forecast`], refused bands left out — each band's sigma the
/// larger of its two components'.
pub fn merge_measured(
    forecast: &[ForecastRow],
    bands: &[WindBand],
    origin_msl_m: f64,
) -> Result<Forecast, ForecastError> {
    let bands: Vec<&WindBand> = bands.iter().filter(|b| b.is_believed()).collect();
    let (Some(lowest), Some(highest)) = (bands.first(), bands.last()) else {
        return Forecast::new(forecast.to_vec());
    };
    let low = lowest.altitude_min_m + origin_msl_m;
    let high = highest.altitude_max_m + origin_msl_m;
    let measured = bands.iter().map(|b| ForecastRow {
        alt_msl_m: b.altitude_m + origin_msl_m,
        speed_mps: b.speed_mps(),
        from_deg: b.from_deg(),
        sigma_mps: Some(b.sigma_north_mps.max(b.sigma_east_mps)),
    });
    let rows = forecast
        .iter()
        .filter(|r| r.alt_msl_m < low)
        .copied()
        .chain(measured)
        .chain(forecast.iter().filter(|r| r.alt_msl_m > high).copied())
        .collect();
    Forecast::new(rows)
}

const CSV_COLUMNS: [&str; 4] = ["alt_msl_m", "speed_mps", "from_deg", "sigma_mps"];

fn parse_csv(text: &str) -> Result<Vec<ForecastRow>, ForecastError> {
    // The `csv` crate reads what spreadsheets write (quoted cells included); the header is
    // optional, so it is recognised here rather than by the reader.
    let (table, numbers) = stx_types::table_text::data_lines(text);
    let line_at = |p: Option<&csv::Position>| {
        p.map_or(0, |p| {
            stx_types::table_text::original_line(&numbers, p.line())
        })
    };
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(table.as_bytes());
    let mut rows = Vec::new();
    let mut seen_data = false;
    for record in reader.records() {
        let record = record.map_err(|e| ForecastError::Csv {
            line: line_at(e.position()),
            message: e.to_string(),
        })?;
        let cells: Vec<&str> = record.iter().collect();
        let err = |message: String| ForecastError::Csv {
            line: line_at(record.position()),
            message,
        };
        if !seen_data && cells.first() == Some(&CSV_COLUMNS[0]) {
            if cells.len() < 3
                || cells.len() > 4
                || cells.iter().zip(CSV_COLUMNS).any(|(c, n)| *c != n)
            {
                return Err(err(format!(
                    "header must be `{}` with an optional `,{}`",
                    CSV_COLUMNS[..3].join(","),
                    CSV_COLUMNS[3]
                )));
            }
            continue;
        }
        seen_data = true;
        if !(3..=4).contains(&cells.len()) {
            return Err(err(format!(
                "expected 3 or 4 values (alt_msl_m,speed_mps,from_deg[,sigma_mps]), got {}",
                cells.len()
            )));
        }
        let mut values = [0.0; 4];
        for (k, cell) in cells.iter().enumerate() {
            values[k] = cell
                .parse::<f64>()
                .map_err(|_| err(format!("{} is not a number: `{cell}`", CSV_COLUMNS[k])))?;
        }
        rows.push(ForecastRow {
            alt_msl_m: values[0],
            speed_mps: values[1],
            from_deg: values[2],
            sigma_mps: (cells.len() == 4).then_some(values[3]),
        });
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn toml_and_csv_spell_the_same_forecast() {
        let toml = "[[forecast_wind]]\nalt_msl_m = 300.0\nspeed_mps = 2.0\nfrom_deg = 270.0\n\n\
                    [[forecast_wind]]\nalt_msl_m = 3000.0\nspeed_mps = 6.0\nfrom_deg = 250.0\nsigma_mps = 1.5\n";
        let csv = "# levels\nalt_msl_m,speed_mps,from_deg,sigma_mps\n300,2,270\n3000,6,250,1.5\n";
        let a = Forecast::parse(toml).unwrap();
        let b = Forecast::parse(csv).unwrap();
        assert_eq!(a, b);
        assert_eq!(a.rows()[1].sigma_mps, Some(1.5));
        // As a spreadsheet saves it: quoted cells, CRLF line ends.
        let quoted = "\"alt_msl_m\",\"speed_mps\",\"from_deg\"\r\n\"300\",\"2\",\"270\"\r\n";
        let c = Forecast::parse(quoted).unwrap();
        assert_eq!(c.rows()[0], a.rows()[0]);
        assert_eq!(a.sigma_rows(245.0, 2.0), vec![(55.0, 2.0), (2755.0, 1.5)]);
        let p = a.profile(245.0).unwrap();
        assert!((p.rows()[0].altitude_m - 55.0).abs() < 1e-12);
    }

    #[test]
    fn bad_forecasts_say_where_and_why() {
        let cases = [
            ("", "no rows"),
            ("300,2\n", "line 1: expected 3 or 4"),
            ("alt_msl_m,speed,from_deg\n", "header must be"),
            ("300,2,270\n200,3,270\n", "strictly increase"),
            ("300,-2,270\n", "speed must be ≥ 0"),
            ("# c\n300,2,north\n", "line 2: from_deg is not a number"),
            ("300,2,270,-1\n", "row 1: sigma_mps"),
            ("[[forecast_wind]]\nalt_msl_m = 1\n", "TOML"),
            (
                "[[wind]]\nalt_msl_m = 1\nspeed_mps = 1\nfrom_deg = 1\n",
                "TOML",
            ),
        ];
        for (text, expected) in cases {
            let e = Forecast::parse(text).unwrap_err().to_string();
            assert!(e.contains(expected), "{text:?}: {e}");
        }
    }
}
