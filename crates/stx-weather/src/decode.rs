//! GRIB2 bytes to decoded messages, through the `grib` crate: each message's parameter, level,
//! reference and forecast time, grid shape and values with their latitudes and longitudes.
//!
//! The one place that talks to `grib`: [`crate::gfs`] builds its field from what this returns,
//! and the tests hold it against ecCodes' reading of the same files. Lengths are capped before
//! anything is allocated ([`MAX_POINTS`]), and a panic inside the decoder on a corrupt file is
//! turned into an error (the crate is not fuzzed as our own decoders are; a bad file from the
//! field must not take the station down).

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Arc;

use grib::LatLons;

/// Most grid points one message may hold: a 0.25° global grid has 1 038 240; four times that
/// leaves room for finer grids while a corrupt length cannot ask for gigabytes.
pub const MAX_POINTS: usize = 4 << 20;

/// Why bytes could not be decoded.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DecodeError {
    /// The bytes are not GRIB2, or a section is cut or inconsistent.
    #[error("not a readable GRIB2 file: {reason}")]
    Corrupt {
        /// What the decoder said.
        reason: String,
    },
    /// A message of the file could not be decoded.
    #[error("GRIB2 message {message}: {reason}")]
    Message {
        /// The message, from 1 as `grib_ls` counts.
        message: usize,
        /// What is wrong.
        reason: String,
    },
    /// The file holds no message.
    #[error("the file holds no GRIB2 message")]
    Empty,
}

/// One decoded GRIB2 (sub)message.
#[derive(Debug, Clone, PartialEq)]
pub struct Message {
    /// Discipline (GRIB2 code table 0.0; 0 = meteorological).
    pub discipline: u8,
    /// Parameter category (code table 4.1), if the product template has one.
    pub category: Option<u8>,
    /// Parameter number (code table 4.2).
    pub number: Option<u8>,
    /// Product definition template number (0: a forecast at a point in time).
    pub product_template: u16,
    /// Type of the first fixed surface (code table 4.5; 100 = isobaric, in Pa).
    pub surface_type: Option<u8>,
    /// The first fixed surface's value in its unit (Pa for isobaric levels).
    pub surface_value: f64,
    /// Reference time (the model run), UTC, if the date in section 1 is a valid one.
    pub reference_time: Option<time::OffsetDateTime>,
    /// Forecast time after the reference time, s, if its unit is one of fixed length.
    pub forecast_s: Option<i64>,
    /// Points along a row (i, longitude on a latitude/longitude grid).
    pub ni: usize,
    /// Rows (j, latitude).
    pub nj: usize,
    /// Where each value lies; shared by the messages of a file on the same grid (section 3
    /// byte for byte the same), so a caller works a grid out once ([`Arc::ptr_eq`]).
    pub points: Arc<GridPoints>,
    /// The values in the file's order; missing points (bitmap) are NaN.
    pub values: Vec<f32>,
}

/// Where a message's values lie, in the file's order.
#[derive(Debug, Clone, PartialEq)]
pub struct GridPoints {
    /// Per value: its (i, j) in the grid.
    pub ij: Vec<(usize, usize)>,
    /// Per value: latitude and longitude, degrees.
    pub lat_lon_deg: Vec<(f64, f64)>,
}

/// Every message of `bytes`, decoded; [`DecodeError`] on the first that cannot be.
pub fn decode(bytes: &[u8]) -> Result<Vec<Message>, DecodeError> {
    match catch_unwind(AssertUnwindSafe(|| decode_unguarded(bytes))) {
        Ok(result) => result,
        Err(panic) => Err(DecodeError::Corrupt {
            reason: format!(
                "the GRIB decoder gave up: {}",
                panic
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "panic".into())
            ),
        }),
    }
}

fn decode_unguarded(bytes: &[u8]) -> Result<Vec<Message>, DecodeError> {
    whole_messages(bytes)?;
    let grib2 = grib::from_bytes(bytes).map_err(|e| DecodeError::Corrupt {
        reason: e.to_string(),
    })?;
    let mut out = Vec::new();
    let mut previous: Option<(grib::GridDefinition, Arc<GridPoints>)> = None;
    for (n, (_, sub)) in grib2.iter().enumerate() {
        let bad = |reason: String| DecodeError::Message {
            message: n + 1,
            reason,
        };
        let declared = sub.grid_def().num_points() as usize;
        if declared > MAX_POINTS {
            return Err(bad(format!(
                "{declared} grid points, more than the {MAX_POINTS} read"
            )));
        }
        let (ni, nj) = sub.grid_shape().map_err(|e| bad(e.to_string()))?;
        let points = match &previous {
            Some((grid, points)) if grid == sub.grid_def() => Arc::clone(points),
            _ => {
                let ij = sub.ij().map_err(|e| bad(e.to_string()))?.collect();
                let lat_lon_deg = sub.latlons().map_err(|e| bad(e.to_string()))?.collect();
                let points = Arc::new(GridPoints { ij, lat_lon_deg });
                previous = Some((sub.grid_def().clone(), Arc::clone(&points)));
                points
            }
        };
        let prod = sub.prod_def();
        let surface = prod.fixed_surfaces().map(|(first, _)| first);
        let reference_time = reference_time(&sub.identification().ref_time_unchecked());
        let forecast_s = prod.forecast_time().and_then(|ft| seconds(&ft));
        let message = Message {
            discipline: sub.indicator().discipline,
            category: prod.parameter_category(),
            number: prod.parameter_number(),
            product_template: prod.prod_tmpl_num(),
            surface_type: surface.as_ref().map(|s| s.surface_type),
            surface_value: surface.as_ref().map_or(f64::NAN, |s| s.value()),
            reference_time,
            forecast_s,
            ni,
            nj,
            points,
            values: Vec::new(),
        };
        let decoder = grib::Grib2SubmessageDecoder::from(sub).map_err(|e| bad(e.to_string()))?;
        let values: Vec<f32> = decoder
            .dispatch()
            .map_err(|e| bad(e.to_string()))?
            .collect();
        if values.len() != declared || declared != ni * nj {
            return Err(bad(format!(
                "{} values for a grid of {ni} × {nj} points ({declared} declared)",
                values.len()
            )));
        }
        out.push(Message { values, ..message });
    }
    if out.is_empty() {
        return Err(DecodeError::Empty);
    }
    Ok(out)
}

/// Checks that `bytes` are whole GRIB2 messages end to end (section 0 of each gives its
/// length): the `grib` crate reads the messages before a cut one and stops without a word, and
/// a file cut in transfer would then lose its last hours unnoticed.
fn whole_messages(bytes: &[u8]) -> Result<(), DecodeError> {
    let mut at = 0;
    let mut message = 0;
    while at < bytes.len() {
        message += 1;
        let rest = &bytes[at..];
        if rest.len() < 16 || &rest[..4] != b"GRIB" || rest[7] != 2 {
            return Err(DecodeError::Corrupt {
                reason: format!(
                    "byte {at} (after {} whole messages) does not start a GRIB2 message",
                    message - 1
                ),
            });
        }
        let length = u64::from_be_bytes(rest[8..16].try_into().expect("16 bytes checked"));
        if length > rest.len() as u64 || length < 16 {
            return Err(DecodeError::Corrupt {
                reason: format!(
                    "message {message} is cut: it declares {length} bytes, the file holds {} \
                     more",
                    rest.len()
                ),
            });
        }
        at += length as usize;
    }
    Ok(())
}

fn reference_time(
    t: &grib::def::grib2::template::param_set::DateTime,
) -> Option<time::OffsetDateTime> {
    let month = time::Month::try_from(t.month).ok()?;
    let date = time::Date::from_calendar_date(i32::from(t.year), month, t.day).ok()?;
    let clock = time::Time::from_hms(t.hour, t.minute, t.second).ok()?;
    Some(time::PrimitiveDateTime::new(date, clock).assume_utc())
}

/// A forecast time in seconds, for the units of code table 4.4 that have a fixed length.
fn seconds(ft: &grib::ForecastTime) -> Option<i64> {
    use grib::codetables::grib2::Table4_4;
    let unit_s = match ft.unit {
        grib::Code::Name(Table4_4::Second) => 1,
        grib::Code::Name(Table4_4::Minute) => 60,
        grib::Code::Name(Table4_4::Hour) => 3600,
        grib::Code::Name(Table4_4::ThreeHours) => 3 * 3600,
        grib::Code::Name(Table4_4::SixHours) => 6 * 3600,
        grib::Code::Name(Table4_4::TwelveHours) => 12 * 3600,
        grib::Code::Name(Table4_4::Day) => 86_400,
        _ => return None,
    };
    i64::from(ft.value).checked_mul(unit_s)
}
