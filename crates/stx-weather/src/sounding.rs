//! A radiosonde sounding as the University of Wyoming's sounding page prints it
//! (`TEXT:LIST`), read into wind levels for the planner.
//!
//! The page is HTML around a fixed-width table:
//!
//! ```text
//! -----------------------------------------------------------------------------
//!    PRES   HGHT   TEMP   DWPT   RELH   MIXR   DRCT   SKNT   THTA   THTE   THTV
//!     hPa     m      C      C      %    g/kg    deg   knot     K      K      K
//! -----------------------------------------------------------------------------
//!  1000.0    108
//!  1013.0      3   13.4    9.4     77   7.30    300      4  285.4  306.2  286.7
//! ```
//!
//! Columns are found by name from the header line (each right-aligned to its name's last
//! character, 7 characters wide), so a table with other columns between still reads. A line
//! without a height, direction or speed (mandatory levels below ground print pressure and
//! height only) is skipped and counted; so is a line whose height does not rise above the
//! previous one. `HGHT` is geopotential height, turned into geometric height as GFS' `HGT`
//! ([`crate::geometric_height_m`]); `SKNT` is in knots. The table ends at the first line that
//! is not a row of numbers (the page's `</PRE>`). Markup is ignored, so the text saved from
//! the browser and the page's source both read.

use crate::{WindLevel, geometric_height_m};

/// One knot, m/s (the international nautical mile per hour).
const KNOT_MPS: f64 = 1852.0 / 3600.0;

/// Width of a column of the table, characters.
const COLUMN_WIDTH: usize = 7;

/// Why a text is not a sounding. Lines count from 1.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SoundingError {
    /// No header line naming PRES and HGHT.
    #[error(
        "no sounding table: expected a header line `PRES HGHT … DRCT SKNT` (University of \
         Wyoming, TEXT:LIST)"
    )]
    NoTable,
    /// The header lacks a column the wind needs.
    #[error("line {line}: the table has no {column} column (it needs HGHT, DRCT and SKNT)")]
    MissingColumn {
        /// The header's line.
        line: usize,
        /// The column's name.
        column: &'static str,
    },
    /// A cell is not a number.
    #[error("line {line}: {column} is not a number: `{text}`")]
    BadNumber {
        /// The line.
        line: usize,
        /// The column's name.
        column: &'static str,
        /// The cell.
        text: String,
    },
    /// A value breaks its rule (a direction outside 0–360°, a negative speed).
    #[error("line {line}: {column} = {value} is out of range ({rule})")]
    OutOfRange {
        /// The line.
        line: usize,
        /// The column's name.
        column: &'static str,
        /// The value.
        value: f64,
        /// What it must be.
        rule: &'static str,
    },
    /// No line had a height, a direction and a speed.
    #[error("the sounding has no line with a height, a wind direction and a speed")]
    NoWinds,
}

/// A sounding's winds.
#[derive(Debug, Clone, PartialEq)]
pub struct Sounding {
    /// One level per table line with a wind, lowest first, heights strictly increasing.
    pub levels: Vec<WindLevel>,
    /// Table lines left out: no height, direction or speed, or no rise in height.
    pub skipped_lines: usize,
}

impl Sounding {
    /// Reads the text of a University of Wyoming `TEXT:LIST` sounding.
    pub fn parse(text: &str) -> Result<Self, SoundingError> {
        let lines: Vec<String> = text.lines().map(strip_markup).collect();
        let (header_at, header) = lines
            .iter()
            .enumerate()
            .find(|(_, l)| {
                let mut words = l.split_whitespace();
                words.next() == Some("PRES") && l.split_whitespace().any(|w| w == "HGHT")
            })
            .ok_or(SoundingError::NoTable)?;
        let column_end = |name: &'static str| {
            header
                .split_whitespace()
                .any(|w| w == name)
                .then(|| header.find(&format!(" {name}")).map(|p| p + 1 + name.len()))
                .flatten()
                .ok_or(SoundingError::MissingColumn {
                    line: header_at + 1,
                    column: name,
                })
        };
        let pres = column_end("PRES").ok();
        let hght = column_end("HGHT")?;
        let drct = column_end("DRCT")?;
        let sknt = column_end("SKNT")?;
        let mut levels: Vec<WindLevel> = Vec::new();
        let mut skipped_lines = 0;
        let mut started = false;
        for (n, line) in lines.iter().enumerate().skip(header_at + 1) {
            let trimmed = line.trim();
            // The units line and the rule under the header come before the rows.
            if !started && (trimmed.starts_with('-') || trimmed.starts_with("hPa")) {
                continue;
            }
            if trimmed.is_empty() || !trimmed.starts_with(|c: char| c.is_ascii_digit()) {
                if started || !trimmed.is_empty() {
                    break;
                }
                continue;
            }
            started = true;
            let number = |end: usize, column: &'static str| -> Result<Option<f64>, SoundingError> {
                let cell = cell(line, end);
                if cell.is_empty() {
                    return Ok(None);
                }
                match cell.parse::<f64>() {
                    Ok(v) if v.is_finite() => Ok(Some(v)),
                    _ => Err(SoundingError::BadNumber {
                        line: n + 1,
                        column,
                        text: cell.to_string(),
                    }),
                }
            };
            let pressure = pres.map(|end| number(end, "PRES")).transpose()?.flatten();
            let (Some(z), Some(from), Some(knots)) = (
                number(hght, "HGHT")?,
                number(drct, "DRCT")?,
                number(sknt, "SKNT")?,
            ) else {
                skipped_lines += 1;
                continue;
            };
            if !(0.0..=360.0).contains(&from) {
                return Err(SoundingError::OutOfRange {
                    line: n + 1,
                    column: "DRCT",
                    value: from,
                    rule: "0–360°",
                });
            }
            if knots < 0.0 {
                return Err(SoundingError::OutOfRange {
                    line: n + 1,
                    column: "SKNT",
                    value: knots,
                    rule: "≥ 0 knots",
                });
            }
            let alt_msl_m = geometric_height_m(z);
            if levels.last().is_some_and(|l| alt_msl_m <= l.alt_msl_m) {
                skipped_lines += 1;
                continue;
            }
            let speed = knots * KNOT_MPS;
            let (sin, cos) = from.to_radians().sin_cos();
            levels.push(WindLevel {
                alt_msl_m,
                north_mps: -speed * cos,
                east_mps: -speed * sin,
                pressure_pa: pressure.map(|hpa| hpa * 100.0),
            });
        }
        if levels.is_empty() {
            return Err(SoundingError::NoWinds);
        }
        Ok(Self {
            levels,
            skipped_lines,
        })
    }
}

/// The cell of a fixed-width column ending at character `end` (exclusive), trimmed.
fn cell(line: &str, end: usize) -> &str {
    let start = end.saturating_sub(COLUMN_WIDTH);
    line.get(start.min(line.len())..end.min(line.len()))
        .unwrap_or("")
        .trim()
}

/// The line without HTML tags (`<PRE>`, `</PRE><H3>…`).
fn strip_markup(line: &str) -> String {
    let mut out = String::with_capacity(line.len());
    let mut in_tag = false;
    for c in line.chars() {
        match c {
            '<' => in_tag = true,
            '>' if in_tag => in_tag = false,
            _ if !in_tag => out.push(c),
            _ => {}
        }
    }
    out
}
