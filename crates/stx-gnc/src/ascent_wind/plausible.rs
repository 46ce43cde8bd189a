//! Which measured bands are believed: a band is refused, with its reason, when its wind is
//! faster than any a balloon meets at its height or its 1-σ is too large to be of use. A
//! refused band is still reported (the pages list it with the reason) but never merged into
//! the profile the predictions fly ([`super::merge_with_forecast`],
//! [`crate::flight_path::merge_measured`]): the span it covered is interpolated between its
//! believed neighbours, or left to the forecast at the edges.
//!
//! **Why refuse at all.** A band is the drift of the stack over a clock; when the clock is not
//! the one the fixes were taken on (a recording of a 20× rehearsal timed by the station's
//! clock read 88–176 m/s where the air moved at 2–4 m/s), or the GPS jumps, the fit states a
//! wind the air never had, and a prediction flown in it lands hundreds of kilometres off
//! without a word. Such a band is absurd on its face; these rules say when.
//!
//! **The rules** (settings of [`AscentWindConfig`], defaults in brackets):
//! - *Speed*: at most `max_wind_ground_mps` (40) at the frame's ground, growing by
//!   `max_wind_gain_mps_per_km` (10) per kilometre of height up to `max_wind_mps` (120).
//!   Hurricane force begins at 32.7 m/s (Beaufort 12) and no balloon is launched in it; the
//!   strongest low-level jets of severe storms reach a few tens of m/s within the lowest
//!   kilometres; jet-stream cores, at 9–12 km, are the fastest winds a balloon meets, the
//!   strongest measured about 110 m/s. The bound reaches 120 m/s at 8 km, a margin above the
//!   record, so that it refuses only what no air does.
//! - *Uncertainty*: the larger component σ at most `max_sigma_mps` (3), twice the 1.5 m/s a
//!   plan assumes for a forecast row that states none. A band less certain than that tells
//!   less than the forecast it would replace, and the Newey–West scatter behind such a σ means
//!   the fixes disagreed with one another (a clock or GPS fault), not a gusty sky: the
//!   checked ascents (`tests/gnc/ascent_wind.rs`) give 0.1–0.5 m/s.

use serde::{Deserialize, Serialize};

use super::{AscentWindConfig, WindBand};

/// Why a band is not believed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(tag = "reason", rename_all = "snake_case")]
pub enum Implausible {
    /// Faster than any wind a balloon meets at its height.
    TooFast {
        /// The band's speed, m/s.
        speed_mps: f64,
        /// The most believed at its height, m/s.
        limit_mps: f64,
    },
    /// Its 1-σ (the larger component's) is too large to be of use.
    TooUncertain {
        /// The band's larger component σ, m/s.
        sigma_mps: f64,
        /// The most accepted, m/s.
        limit_mps: f64,
    },
}

impl std::fmt::Display for Implausible {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::TooFast {
                speed_mps,
                limit_mps,
            } => write!(
                f,
                "{speed_mps:.1} m/s is faster than any wind a balloon meets at this height (at most {limit_mps:.0} m/s)"
            ),
            Self::TooUncertain {
                sigma_mps,
                limit_mps,
            } => write!(
                f,
                "its 1-σ of {sigma_mps:.1} m/s is too large to be of use (at most {limit_mps:.1} m/s)"
            ),
        }
    }
}

/// The fastest wind believed at `height_m` above the frame's ground, m/s.
pub fn max_plausible_wind_mps(config: &AscentWindConfig, height_m: f64) -> f64 {
    let grown =
        config.max_wind_ground_mps + config.max_wind_gain_mps_per_km * height_m.max(0.0) / 1000.0;
    grown.min(config.max_wind_mps)
}

/// Why `band` is not believed under `config`'s rules; `None` if it is. Speed is judged at the
/// band's highest fix, where the bound is loosest.
pub fn judge(band: &WindBand, config: &AscentWindConfig) -> Option<Implausible> {
    let speed_mps = band.speed_mps();
    let limit_mps = max_plausible_wind_mps(config, band.altitude_max_m);
    // A NaN is refused too: it is not within the bound.
    if speed_mps.is_nan() || speed_mps > limit_mps {
        return Some(Implausible::TooFast {
            speed_mps,
            limit_mps,
        });
    }
    let sigma_mps = band.sigma_north_mps.max(band.sigma_east_mps);
    if sigma_mps.is_nan() || sigma_mps > config.max_sigma_mps {
        return Some(Implausible::TooUncertain {
            sigma_mps,
            limit_mps: config.max_sigma_mps,
        });
    }
    None
}
