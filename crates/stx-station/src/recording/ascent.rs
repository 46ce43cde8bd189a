//! The wind an earlier flight measured on its ascent, read back from its recording, as a
//! forecast to plan the next flight with: the recording's GPS track (stx-record's `track`)
//! through the ascent wind estimator (`stx_gnc::flight_path::plan::measured_ascent`), merged
//! into a forecast over the span it measured (`merge_measured`). `stx plan --from-recording`
//! and the station's `POST /api/plan` both call [`measured_forecast`], so a recording gives
//! both the same winds.

use std::io::{Read, Seek};

use stx_gnc::flight_path::plan::measured_ascent;
use stx_gnc::flight_path::{Forecast, ForecastError, ForecastRow, merge_measured};
use stx_record::Recording;
use stx_record::export::ExportError;
use stx_record::export::track::track;

/// A forecast with a recording's measured ascent wind in it.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasuredForecast {
    /// The merged forecast.
    pub forecast: Forecast,
    /// Wind bands the recording measured.
    pub bands: usize,
    /// Bottom of the lowest band, m above mean sea level.
    pub lowest_msl_m: f64,
    /// Top of the highest band, m above mean sea level.
    pub highest_msl_m: f64,
}

/// Why a recording gave no measured wind.
#[derive(Debug, thiserror::Error)]
pub enum MeasuredAscentError {
    /// Its GPS track could not be read.
    #[error("its GPS track: {0}")]
    Track(#[from] ExportError),
    /// The track has too few fixes while rising for any band.
    #[error("no ascent wind could be measured (too few GPS fixes while rising)")]
    NoAscent,
    /// The measured bands and the forecast make no forecast together.
    #[error("the wind it measured: {0}")]
    Merge(#[from] ForecastError),
}

/// `forecast` (possibly empty) with the ascent wind `recording` measured in place of its rows
/// where it measured (see the module doc).
pub fn measured_forecast<R: Read + Seek>(
    recording: &mut Recording<R>,
    forecast: &[ForecastRow],
) -> Result<MeasuredForecast, MeasuredAscentError> {
    let (_, points) = track(recording)?;
    let fixes: Vec<_> = points
        .iter()
        .map(|p| (p.time_ns as f64 * 1e-9, p.lat_deg, p.lon_deg, p.alt_m))
        .collect();
    let (bands, frame) = measured_ascent(&fixes);
    let (Some(lowest), Some(highest)) = (bands.first(), bands.last()) else {
        return Err(MeasuredAscentError::NoAscent);
    };
    Ok(MeasuredForecast {
        forecast: merge_measured(forecast, &bands, frame.alt_msl_m)?,
        bands: bands.len(),
        lowest_msl_m: lowest.altitude_min_m + frame.alt_msl_m,
        highest_msl_m: highest.altitude_max_m + frame.alt_msl_m,
    })
}
