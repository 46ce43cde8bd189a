//! Ascent winds: the wind profile measured from the drift of the balloon's GPS track while
//! it rises, by altitude band with a 1-σ per component, and merged with the forecast for the
//! descent predictions.
//!
//! Pure: no clock, no files, no threads. The caller hands in each fix with the instant it
//! describes ([`AscentWindEstimator::push_fix`]) and asks for the bands when it wants them
//! ([`AscentWindEstimator::profile`]); the same fixes give the same profile.
//!
//! **Why the track gives the wind.** A balloon has almost no horizontal airspeed: drag on the
//! envelope pulls it to the air's velocity within seconds, so its horizontal ground velocity
//! *is* the wind, lagged by those seconds (tens of metres of altitude at 5 m/s of ascent,
//! negligible against a 500-m band). The payload swings under it; over a band's passage of
//! a minute or two the swing averages out to `≈ amplitude / passage time`.
//!
//! **What a band reports.** The mean horizontal wind over the passage through the band, the
//! passage's altitude and time range, and a 1-σ per component:
//! - with GPS velocities (at least `min_samples_per_band` of the band's fixes carry one): the
//!   value at mid-passage of a straight line fitted to the velocities against time, which is
//!   the passage's mean even when the fixes are unevenly spaced or a gap breaks them;
//! - from positions alone: the same line fitted to the velocities between successive fixes
//!   (position difference over time step). Their mean telescopes to the displacement over the
//!   passage divided by its duration, so a position's noise enters only at the two ends; and
//!   unlike a curve fitted to the positions themselves, whose residuals are the integral of
//!   the gusts (a random walk no standard error can judge), the differences' errors are
//!   stationary. A difference across a gap in the fixes counts as one sample.
//!
//! The 1-σ is `√(s² + floor² + (A/T)²)`: `s` the standard error of the fitted value from the
//! residuals (Newey–West, robust to the fixes' correlated errors, corrected for the band's
//! shortness and scaled so that its 2-σ interval covers about 95 %; see `fit.rs`), `floor`
//! the configured irreducible error (slow GPS drifts, the balloon's lag), and `A/T` the
//! payload's swing amplitude over the passage time.
//!
//! **Checked** (`tests/gnc/ascent_wind.rs`, 40 simulated ascents to 20 km through a sheared,
//! veering wind with a jet, 5-s gusts of 0.3 m/s, a 10-s swing of 1.5 m and GPS noise): with
//! the scatter term alone, 95.5 % of band components lie within 2 σ of the truth from 2-Hz
//! velocities, 99.4 % from 1-Hz positions (whose σ is about 1.5 times too large: differenced
//! white position noise cancels in the mean, which Newey–West only partly sees). With the
//! default floor, a 3-s balloon lag and slow GPS drifts added: 96.5 % and 99.6 %, RMS error
//! 0.10 m/s either way.
//!
//! **Which fixes count.** Only those of a rising stack: the vertical speed averaged over a
//! short window (the GPS's vertical velocity if every fix in it has one, else the slope of the
//! altitude) must be at least `min_ascent_rate_mps`, and a fix's own vertical velocity, when it
//! has one, too. On the ground the stack does not drift; at float it samples no new altitude.
//! When the averaged speed reaches `−end_descent_rate_mps`, the ascent is over for good (see
//! [`AscentWindConfig::end_descent_rate_mps`]). Fixes must arrive in time order; a late one is
//! refused rather than slotted in, because the vertical speed is judged causally.
//! A balloon that dips back into a band and rises through it again adds its second passage to
//! the first, as one series with a gap.
//!
//! **Altitudes** are above the local frame's origin (`−down`, see [`crate::geo`]), the
//! convention of [`stx_types::wind::WindProfile`]. A forecast given above mean sea level is
//! brought to it by subtracting the origin's `alt_msl_m`.
//!
//! **Believed or refused** (`plausible.rs`): a band faster than any wind a balloon meets at
//! its height, or with a σ too large to be of use, is reported with the reason
//! ([`WindBand::refused`]) and never merged.
//!
//! **Merging** ([`merge_with_forecast`]): believed bands wherever the ascent measured, the
//! forecast outside. Forecast rows strictly above the top of the highest measured band and
//! strictly below the bottom of the lowest one are kept (the latter matters when tracking
//! started above the ground, or for a surface row under the first band); forecast rows within
//! the measured span are dropped, and a band missing inside the span (a GPS dropout) is
//! interpolated between its measured neighbours, not taken from the forecast, whose bias
//! against the measurement would otherwise put a step into the profile twice.

mod config;
mod fit;
mod merge;
mod plausible;

use std::collections::{BTreeMap, VecDeque};

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use stx_types::wind::{ProfileRow, WindError, WindProfile};
use thiserror::Error;

pub use config::{AscentWindConfig, AscentWindConfigError};
pub use merge::merge_with_forecast;
pub use plausible::{Implausible, judge, max_plausible_wind_mps};

use crate::geo::LocalFrame;
use crate::measurement::GpsFix;

/// Most fixes held across all bands: at 10 Hz, almost three hours of ascent. Beyond it fixes
/// are refused ([`Disposition::Full`]) so that a station left running cannot grow without
/// bound.
pub const MAX_SAMPLES: usize = 100_000;

/// One position (and perhaps velocity) of the stack.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AscentFix {
    /// Instant the fix describes, s on the mission clock.
    pub time_s: f64,
    /// Position in the local NED frame, m (altitude above the origin is `−z`).
    pub position_ned_m: Vector3<f64>,
    /// Velocity over the ground, NED, m/s, when the receiver reports one.
    pub velocity_ned_mps: Option<Vector3<f64>>,
}

impl AscentFix {
    /// A fix given as latitude (degrees north), longitude (degrees east) and altitude above
    /// mean sea level (m), placed in `frame`.
    pub fn from_geodetic(
        frame: &LocalFrame,
        time_s: f64,
        lat_deg: f64,
        lon_deg: f64,
        alt_msl_m: f64,
        velocity_ned_mps: Option<Vector3<f64>>,
    ) -> Self {
        Self {
            time_s,
            position_ned_m: frame.to_ned(lat_deg, lon_deg, alt_msl_m),
            velocity_ned_mps,
        }
    }
}

impl From<&GpsFix> for AscentFix {
    fn from(fix: &GpsFix) -> Self {
        Self {
            time_s: fix.time_s,
            position_ned_m: fix.position_ned_m,
            velocity_ned_mps: Some(fix.velocity_ned_mps),
        }
    }
}

/// Why a fix was refused as input.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum AscentFixError {
    /// A value is NaN or infinite.
    #[error("ascent fix: `{field}` must be finite, got {value}")]
    NotFinite {
        /// Which value: `time_s`, `position_ned_m` or `velocity_ned_mps`.
        field: &'static str,
        /// The value given.
        value: f64,
    },
}

/// What became of a valid fix.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(tag = "disposition", rename_all = "snake_case")]
pub enum Disposition {
    /// Added to altitude band `band` (altitudes `[band·h, (band+1)·h)`).
    Used {
        /// Index of the band.
        band: i64,
    },
    /// Not rising fast enough (on the ground, at float, or a fix sinking on its own).
    NotAscending,
    /// Too few fixes in the window yet to judge the vertical speed.
    VerticalRateUnknown,
    /// The ascent is over (burst or cut-away seen): no fix is used any more.
    AscentOver,
    /// Not later than the previous fix: refused.
    OutOfOrder,
    /// [`MAX_SAMPLES`] fixes are held already.
    Full,
}

/// How many fixes went where.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct AscentWindCounts {
    /// Added to a band (and not withdrawn).
    pub used: u64,
    /// Not rising, or the vertical speed not known yet.
    pub not_ascending: u64,
    /// After the end of the ascent.
    pub after_ascent: u64,
    /// Taken in, then withdrawn when the end of the ascent was seen.
    pub withdrawn: u64,
    /// Out of time order.
    pub out_of_order: u64,
    /// Refused: non-finite, or over [`MAX_SAMPLES`].
    pub refused: u64,
}

/// Where a band's wind comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "snake_case")]
pub enum BandMethod {
    /// The GPS's velocity over the ground, averaged.
    GpsVelocity,
    /// The differences of successive GPS positions over their time steps.
    PositionDifferences,
}

/// The measured wind of one altitude band.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct WindBand {
    /// Index of the band: it spans `[band·h, (band+1)·h)` above the origin, `h` the band
    /// height.
    pub band: i64,
    /// Altitude the wind is reported at, above the origin, m: the middle of the altitudes
    /// flown through, where a steady ascent is at mid-passage.
    pub altitude_m: f64,
    /// Lowest altitude of the fixes used, m.
    pub altitude_min_m: f64,
    /// Highest altitude of the fixes used, m.
    pub altitude_max_m: f64,
    /// First fix used, s on the mission clock.
    pub time_start_s: f64,
    /// Last fix used, s.
    pub time_end_s: f64,
    /// North component of the wind (where the air goes), m/s.
    pub wind_north_mps: f64,
    /// East component of the wind, m/s.
    pub wind_east_mps: f64,
    /// 1-σ of the north component, m/s.
    pub sigma_north_mps: f64,
    /// 1-σ of the east component, m/s.
    pub sigma_east_mps: f64,
    /// Fixes used.
    pub samples: u32,
    /// Velocities or positions.
    pub method: BandMethod,
    /// Why the band is not believed (see `plausible.rs`); `None`: it is, and it is merged
    /// into the profile the predictions fly.
    #[serde(default)]
    pub refused: Option<Implausible>,
}

impl WindBand {
    /// Believed: merged into the profiles (see [`Implausible`]).
    pub fn is_believed(&self) -> bool {
        self.refused.is_none()
    }

    /// Wind speed, m/s.
    pub fn speed_mps(&self) -> f64 {
        self.wind_north_mps.hypot(self.wind_east_mps)
    }

    /// Direction the wind blows *from*, degrees clockwise from true north, in [0, 360): the
    /// opposite of where the air goes.
    pub fn from_deg(&self) -> f64 {
        let deg = (-self.wind_east_mps)
            .atan2(-self.wind_north_mps)
            .to_degrees()
            .rem_euclid(360.0);
        // `rem_euclid` of a tiny negative angle rounds to 360.0 itself.
        if deg >= 360.0 { 0.0 } else { deg }
    }

    /// The band as a row of a [`WindProfile`].
    pub fn profile_row(&self) -> ProfileRow {
        ProfileRow {
            altitude_m: self.altitude_m,
            speed_mps: self.speed_mps(),
            from_deg: self.from_deg(),
        }
    }
}

/// A fix kept in a band.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Sample {
    time_s: f64,
    north_m: f64,
    east_m: f64,
    altitude_m: f64,
    velocity_ne_mps: Option<[f64; 2]>,
}

/// A fix in the vertical-speed window.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Recent {
    time_s: f64,
    altitude_m: f64,
    climb_mps: Option<f64>,
}

/// Bins the fixes of an ascent by altitude band and estimates each band's wind.
#[derive(Debug, Clone)]
pub struct AscentWindEstimator {
    config: AscentWindConfig,
    bands: BTreeMap<i64, Vec<Sample>>,
    recent: VecDeque<Recent>,
    last_time_s: Option<f64>,
    ascent_over_at_s: Option<f64>,
    held: usize,
    counts: AscentWindCounts,
}

impl AscentWindEstimator {
    /// An estimator with no fixes, once `config` is valid.
    pub fn new(config: AscentWindConfig) -> Result<Self, AscentWindConfigError> {
        config.validate()?;
        Ok(Self {
            config,
            bands: BTreeMap::new(),
            recent: VecDeque::new(),
            last_time_s: None,
            ascent_over_at_s: None,
            held: 0,
            counts: AscentWindCounts::default(),
        })
    }

    /// The settings.
    pub fn config(&self) -> &AscentWindConfig {
        &self.config
    }

    /// What became of the fixes so far.
    pub fn counts(&self) -> AscentWindCounts {
        self.counts
    }

    /// The instant the end of the ascent was seen, s; `None` while it goes on.
    pub fn ascent_over_at_s(&self) -> Option<f64> {
        self.ascent_over_at_s
    }

    /// The vertical speed averaged over the window ending at the latest fix, m/s, up
    /// positive; `None` with too few fixes to tell.
    pub fn vertical_rate_mps(&self) -> Option<f64> {
        let n = self.recent.len();
        if n > 0 && self.recent.iter().all(|r| r.climb_mps.is_some()) {
            let sum: f64 = self.recent.iter().filter_map(|r| r.climb_mps).sum();
            return Some(sum / n as f64);
        }
        let (first, last) = (self.recent.front()?, self.recent.back()?);
        if n < 3 || last.time_s - first.time_s < 0.5 * self.config.vertical_rate_window_s {
            return None;
        }
        let mean_t = self.recent.iter().map(|r| r.time_s).sum::<f64>() / n as f64;
        let mean_h = self.recent.iter().map(|r| r.altitude_m).sum::<f64>() / n as f64;
        let (mut sxy, mut sxx) = (0.0, 0.0);
        for r in &self.recent {
            sxy += (r.time_s - mean_t) * (r.altitude_m - mean_h);
            sxx += (r.time_s - mean_t).powi(2);
        }
        Some(sxy / sxx)
    }

    /// Takes in one fix. A non-finite value is refused with an error; every valid fix gets a
    /// [`Disposition`] saying whether it was used.
    pub fn push_fix(&mut self, fix: &AscentFix) -> Result<Disposition, AscentFixError> {
        if let Err(e) = check_finite(fix) {
            self.counts.refused += 1;
            return Err(e);
        }
        if self.ascent_over_at_s.is_some() {
            self.counts.after_ascent += 1;
            return Ok(Disposition::AscentOver);
        }
        if self.last_time_s.is_some_and(|last| fix.time_s <= last) {
            self.counts.out_of_order += 1;
            return Ok(Disposition::OutOfOrder);
        }
        self.last_time_s = Some(fix.time_s);
        let altitude_m = -fix.position_ned_m.z;
        let climb_mps = fix.velocity_ned_mps.map(|v| -v.z);
        self.recent.push_back(Recent {
            time_s: fix.time_s,
            altitude_m,
            climb_mps,
        });
        let window_start = fix.time_s - self.config.vertical_rate_window_s;
        while self.recent.front().is_some_and(|r| r.time_s < window_start) {
            self.recent.pop_front();
        }
        let Some(rate) = self.vertical_rate_mps() else {
            self.counts.not_ascending += 1;
            return Ok(Disposition::VerticalRateUnknown);
        };
        if rate <= -self.config.end_descent_rate_mps {
            self.end_ascent(fix.time_s);
            self.counts.after_ascent += 1;
            return Ok(Disposition::AscentOver);
        }
        let own_climb_ok = climb_mps.is_none_or(|c| c >= self.config.min_ascent_rate_mps);
        if rate < self.config.min_ascent_rate_mps || !own_climb_ok {
            self.counts.not_ascending += 1;
            return Ok(Disposition::NotAscending);
        }
        if self.held >= MAX_SAMPLES {
            self.counts.refused += 1;
            return Ok(Disposition::Full);
        }
        // Finite by the check above; `as` saturates for absurd altitudes.
        let band = (altitude_m / self.config.band_height_m).floor() as i64;
        self.bands.entry(band).or_default().push(Sample {
            time_s: fix.time_s,
            north_m: fix.position_ned_m.x,
            east_m: fix.position_ned_m.y,
            altitude_m,
            velocity_ne_mps: fix.velocity_ned_mps.map(|v| [v.x, v.y]),
        });
        self.held += 1;
        self.counts.used += 1;
        Ok(Disposition::Used { band })
    }

    /// Latches the end of the ascent and withdraws the fixes of the last window: the
    /// window's average still read "rising" for a moment after the burst, and the stack's
    /// velocity then is the fall's, not the wind's.
    fn end_ascent(&mut self, time_s: f64) {
        self.ascent_over_at_s = Some(time_s);
        let suspect_from = time_s - self.config.vertical_rate_window_s;
        let mut withdrawn = 0usize;
        for samples in self.bands.values_mut() {
            let keep = samples.partition_point(|s| s.time_s < suspect_from);
            withdrawn += samples.len() - keep;
            samples.truncate(keep);
        }
        self.bands.retain(|_, samples| !samples.is_empty());
        self.held -= withdrawn;
        self.counts.used -= withdrawn as u64;
        self.counts.withdrawn += withdrawn as u64;
        self.recent.clear();
    }

    /// The bands with enough fixes, lowest first. Every call fits every band afresh, at a
    /// cost of about fixes × Newey–West lag (2 ms for a 2-Hz ascent to 20 km, 50 ms at 10 Hz,
    /// optimised build): call it at a display rate, not once per fix.
    pub fn profile(&self) -> Vec<WindBand> {
        self.bands
            .iter()
            .filter_map(|(&band, samples)| self.estimate_band(band, samples))
            .collect()
    }

    /// The measured profile with the forecast outside it (see the module doc for the rule),
    /// ready for the predictors. `forecast` rows are above the origin, altitudes increasing.
    pub fn merged_with_forecast(&self, forecast: &[ProfileRow]) -> Result<WindProfile, WindError> {
        merge_with_forecast(&self.profile(), forecast)
    }

    fn estimate_band(&self, band: i64, samples: &[Sample]) -> Option<WindBand> {
        let min_samples = self.config.min_samples_per_band as usize;
        if samples.len() < min_samples {
            return None;
        }
        let with_velocity: Vec<&Sample> = samples
            .iter()
            .filter(|s| s.velocity_ne_mps.is_some())
            .collect();
        // (time, north, east) velocity samples, and the fixes they come from.
        let (used, method): (Vec<&Sample>, _) = if with_velocity.len() >= min_samples {
            (with_velocity, BandMethod::GpsVelocity)
        } else {
            (samples.iter().collect(), BandMethod::PositionDifferences)
        };
        let series: Vec<(f64, [f64; 2])> = match method {
            BandMethod::GpsVelocity => used
                .iter()
                .filter_map(|s| s.velocity_ne_mps.map(|v| (s.time_s, v)))
                .collect(),
            BandMethod::PositionDifferences => used
                .windows(2)
                .map(|pair| {
                    let (a, b) = (pair[0], pair[1]);
                    // Times strictly increase (push_fix refuses any other order).
                    let dt = b.time_s - a.time_s;
                    (
                        0.5 * (a.time_s + b.time_s),
                        [(b.north_m - a.north_m) / dt, (b.east_m - a.east_m) / dt],
                    )
                })
                .collect(),
        };
        let times: Vec<f64> = series.iter().map(|(t, _)| *t).collect();
        let design = fit::Design::new(&times, self.config.correlation_window_s)?;
        let component = |c: usize| -> Vec<f64> { series.iter().map(|(_, v)| v[c]).collect() };
        let north = design.fit(&component(0));
        let east = design.fit(&component(1));
        let (time_start_s, time_end_s) = (used[0].time_s, used[used.len() - 1].time_s);
        let swing = self.config.pendulum_amplitude_m / (time_end_s - time_start_s);
        let extra = self.config.velocity_floor_mps.powi(2) + swing * swing;
        let (mut low, mut high) = (f64::INFINITY, f64::NEG_INFINITY);
        for s in &used {
            low = low.min(s.altitude_m);
            high = high.max(s.altitude_m);
        }
        let mut measured = WindBand {
            band,
            altitude_m: 0.5 * (low + high),
            altitude_min_m: low,
            altitude_max_m: high,
            time_start_s,
            time_end_s,
            wind_north_mps: north.value,
            wind_east_mps: east.value,
            sigma_north_mps: (north.variance + extra).sqrt(),
            sigma_east_mps: (east.variance + extra).sqrt(),
            samples: u32::try_from(used.len()).unwrap_or(u32::MAX),
            method,
            refused: None,
        };
        measured.refused = plausible::judge(&measured, &self.config);
        Some(measured)
    }
}

fn check_finite(fix: &AscentFix) -> Result<(), AscentFixError> {
    let bad = |field, value: f64| Err(AscentFixError::NotFinite { field, value });
    if !fix.time_s.is_finite() {
        return bad("time_s", fix.time_s);
    }
    if let Some(&v) = fix.position_ned_m.iter().find(|v| !v.is_finite()) {
        return bad("position_ned_m", v);
    }
    if let Some(&v) = fix
        .velocity_ned_mps
        .iter()
        .flat_map(|v| v.iter())
        .find(|v| !v.is_finite())
    {
        return bad("velocity_ned_mps", v);
    }
    Ok(())
}

#[cfg(test)]
mod tests;
