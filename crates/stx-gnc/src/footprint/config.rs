//! Settings of the reachable footprint, checked before use: a raw [`FootprintConfig`] from
//! TOML becomes a [`ValidFootprintConfig`] or a typed [`FootprintConfigError`].

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Settings of the reachable footprint, as read (units in each field's name and doc).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FootprintConfig {
    /// Number of dispersed draws (wind, airspeed, sink, position) per refresh, 10…100 000.
    /// The probability of each cell is a fraction of these: 400 draws put a 95 % contour
    /// within about ±1.1 % (binomial 1-σ) of its level.
    pub draws: usize,
    /// Side of a square grid cell, m (1…1000).
    pub cell_size_m: f64,
    /// Thickness of the height layers the descent is integrated over, m (1…500): the wind
    /// field and the air density are read once per layer.
    pub layer_m: f64,
    /// Height kept for the final approach and the flare, m (≥ 0): below it the vehicle flies
    /// into the wind to the point. Guidance's final needs about 156 m, plus a base leg when
    /// the point lies downwind; 250 m is what the full-model test needed
    /// (`crates/stx-sim/tests/sim/footprint_against_full_model.rs`).
    pub reserve_height_m: f64,
    /// Distance taken off every reach for the turns a flight to the point needs (towards it,
    /// onto the base leg and the final), m (≥ 0); 100 m set by the same test.
    pub edge_margin_m: f64,
    /// 1-σ of the wind below the vehicle that the estimate's own σ does not carry (the wind
    /// changes with height and time), m/s per horizontal component (≥ 0); added in quadrature
    /// to the estimate's wind σ.
    pub extra_wind_sigma_mps: f64,
    /// 1-σ of the airspeed relative to the performance assumed (fraction, 0…0.5).
    pub airspeed_sigma_fraction: f64,
    /// 1-σ of the sink rate relative to the performance assumed (fraction, 0…0.5).
    pub sink_sigma_fraction: f64,
    /// Height of the drone above the lowest body (the capsule) at touchdown, m (≥ 0).
    pub hang_height_m: f64,
    /// Most grid cells one refresh may use (bounds memory and time), 1…20 000 000.
    pub max_cells: usize,
}

impl Default for FootprintConfig {
    fn default() -> Self {
        Self {
            draws: 400,
            cell_size_m: 25.0,
            layer_m: 25.0,
            reserve_height_m: 250.0,
            edge_margin_m: 100.0,
            extra_wind_sigma_mps: 0.5,
            airspeed_sigma_fraction: 0.05,
            sink_sigma_fraction: 0.05,
            hang_height_m: 8.4,
            max_cells: 4_000_000,
        }
    }
}

/// Why a footprint configuration was refused.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum FootprintConfigError {
    /// The number of draws is outside 10…100 000.
    #[error("footprint draws = {draws}: it must be 10…100000")]
    Draws {
        /// Number given.
        draws: usize,
    },
    /// A setting is not finite or outside its range.
    #[error("footprint {field} = {value}: it must be within {min}…{max}")]
    OutOfRange {
        /// Name of the setting.
        field: &'static str,
        /// Value given.
        value: f64,
        /// Smallest value allowed.
        min: f64,
        /// Largest value allowed.
        max: f64,
    },
    /// The cell budget is outside 1…20 000 000.
    #[error("footprint max_cells = {max_cells}: it must be 1…20000000")]
    MaxCells {
        /// Number given.
        max_cells: usize,
    },
}

/// A checked [`FootprintConfig`]; only [`FootprintConfig::validate`] makes one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ValidFootprintConfig(FootprintConfig);

impl ValidFootprintConfig {
    /// The settings.
    pub fn get(&self) -> &FootprintConfig {
        &self.0
    }
}

impl FootprintConfig {
    /// Checks every setting against its documented range.
    pub fn validate(self) -> Result<ValidFootprintConfig, FootprintConfigError> {
        if !(10..=100_000).contains(&self.draws) {
            return Err(FootprintConfigError::Draws { draws: self.draws });
        }
        if !(1..=20_000_000).contains(&self.max_cells) {
            return Err(FootprintConfigError::MaxCells {
                max_cells: self.max_cells,
            });
        }
        let checks: [(&'static str, f64, f64, f64); 8] = [
            ("cell_size_m", self.cell_size_m, 1.0, 1000.0),
            ("layer_m", self.layer_m, 1.0, 500.0),
            ("reserve_height_m", self.reserve_height_m, 0.0, 10_000.0),
            ("edge_margin_m", self.edge_margin_m, 0.0, 10_000.0),
            ("extra_wind_sigma_mps", self.extra_wind_sigma_mps, 0.0, 50.0),
            (
                "airspeed_sigma_fraction",
                self.airspeed_sigma_fraction,
                0.0,
                0.5,
            ),
            ("sink_sigma_fraction", self.sink_sigma_fraction, 0.0, 0.5),
            ("hang_height_m", self.hang_height_m, 0.0, 100.0),
        ];
        for (field, value, min, max) in checks {
            // NaN fails both comparisons, so it is refused too.
            if !(value >= min && value <= max) {
                return Err(FootprintConfigError::OutOfRange {
                    field,
                    value,
                    min,
                    max,
                });
            }
        }
        Ok(ValidFootprintConfig(self))
    }
}
