//! The measured bands joined to the forecast: the profile every descent prediction uses.

use stx_types::wind::{ProfileRow, WindError, WindProfile};

use super::WindBand;

/// A [`WindProfile`] of the believed measured `bands` (as
/// [`super::AscentWindEstimator::profile`] returns them, lowest first; refused ones are left
/// out) with the `forecast` rows (altitude above the local origin,
/// strictly increasing) strictly below the lowest band's lowest fix and strictly above the
/// highest band's highest fix; forecast rows inside the measured span are dropped. With no
/// band, the forecast alone; with neither, [`WindError::EmptyProfile`].
///
/// The whole forecast is validated even where the measurement replaces it, so that a bad
/// forecast is reported when it is loaded rather than when the balloon happens to climb
/// past its bad row.
pub fn merge_with_forecast(
    bands: &[WindBand],
    forecast: &[ProfileRow],
) -> Result<WindProfile, WindError> {
    if !forecast.is_empty() {
        WindProfile::new(forecast.to_vec())?;
    }
    let bands: Vec<&WindBand> = bands.iter().filter(|b| b.is_believed()).collect();
    let (Some(lowest), Some(highest)) = (bands.first(), bands.last()) else {
        return WindProfile::new(forecast.to_vec());
    };
    let below = forecast
        .iter()
        .filter(|r| r.altitude_m < lowest.altitude_min_m);
    let above = forecast
        .iter()
        .filter(|r| r.altitude_m > highest.altitude_max_m);
    let rows = below
        .copied()
        .chain(bands.iter().map(|b| b.profile_row()))
        .chain(above.copied())
        .collect();
    WindProfile::new(rows)
}
