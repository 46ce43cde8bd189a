//! The air's velocity over time and position, as every crate that flies through it names it:
//! the [`WindField`] trait and the mean winds (calm, constant, a profile over altitude).
//!
//! Why deterministic functions of `(t, position)` rather than a random process stepped along:
//! adaptive integrators evaluate the model at trial times that go back and forth inside a step
//! and may be rejected; a gust drawn from a random number generator at each call would differ
//! between the trial and the retry, and runs would not reproduce. Every field returns the same
//! value for the same arguments.
//!
//! How the parts fit:
//! - [`WindField`] is what the flight model and the onboard predictions depend on;
//! - mean winds: [`Calm`], [`ConstantWind`], [`WindProfile`] (a table over altitude), refused
//!   with a [`WindError`] when their values break a rule;
//! - the simulator's turbulence and its wind configuration file live in `stx-dynamics`
//!   (`stx_dynamics::wind`), which adds them to these and re-exports them: the onboard code
//!   needs the profile, not the gusts.
//!
//! Conventions:
//! - Velocities are in the flat-Earth North-East-Down frame, m/s: the vector is where the air
//!   goes, so a wind *from* the north has a negative north component.
//! - Directions are meteorological: the direction the wind blows *from*, degrees clockwise
//!   from true north.
//! - `position_ned_m` has its origin on the ground (the NED origin of the simulation), so the
//!   altitude above ground that [`WindProfile`] uses is `−z`. Callers that need altitude above
//!   sea level for the atmosphere add the ground's elevation themselves.

use std::sync::atomic::{AtomicUsize, Ordering};

use nalgebra::Vector3;
use thiserror::Error;
/// The air's velocity as a deterministic function of time and position.
pub trait WindField: Send + Sync {
    /// Air velocity in NED, m/s, at `time_s` (s) and `position_ned_m` (NED, m, origin on the
    /// ground so that altitude above ground is `−position_ned_m.z`).
    fn wind_ned_mps(&self, time_s: f64, position_ned_m: &Vector3<f64>) -> Vector3<f64>;

    /// [`WindField::wind_ned_mps`], to the last bit, for a caller that asks again and again
    /// close to where it asked last (a path, step by step): `hint` keeps where the field found
    /// the last answer (a profile: its row), so that it may look there first. Any value of
    /// `hint` gives the same answer; an atomic, so that a field stays `Sync`.
    fn wind_ned_mps_near(
        &self,
        time_s: f64,
        position_ned_m: &Vector3<f64>,
        hint: &AtomicUsize,
    ) -> Vector3<f64> {
        let _ = hint;
        self.wind_ned_mps(time_s, position_ned_m)
    }
}

impl<W: WindField + ?Sized> WindField for &W {
    fn wind_ned_mps(&self, time_s: f64, position_ned_m: &Vector3<f64>) -> Vector3<f64> {
        (**self).wind_ned_mps(time_s, position_ned_m)
    }

    fn wind_ned_mps_near(
        &self,
        time_s: f64,
        position_ned_m: &Vector3<f64>,
        hint: &AtomicUsize,
    ) -> Vector3<f64> {
        (**self).wind_ned_mps_near(time_s, position_ned_m, hint)
    }
}

impl<W: WindField + ?Sized> WindField for Box<W> {
    fn wind_ned_mps(&self, time_s: f64, position_ned_m: &Vector3<f64>) -> Vector3<f64> {
        (**self).wind_ned_mps(time_s, position_ned_m)
    }

    fn wind_ned_mps_near(
        &self,
        time_s: f64,
        position_ned_m: &Vector3<f64>,
        hint: &AtomicUsize,
    ) -> Vector3<f64> {
        (**self).wind_ned_mps_near(time_s, position_ned_m, hint)
    }
}

/// Why a wind description was refused. Profile rows are counted from 0.
#[derive(Clone, Copy, Debug, Error, PartialEq)]
pub enum WindError {
    /// A profile needs at least one row.
    #[error("wind profile has no rows: it needs at least one")]
    EmptyProfile,
    /// A profile row has a non-finite value.
    #[error(
        "wind profile row {row}: values must be finite (altitude {altitude_m} m, speed \
         {speed_mps} m/s, from {from_deg}°)"
    )]
    ProfileRowNotFinite {
        /// Index of the row, from 0.
        row: usize,
        /// The row's altitude above ground, m.
        altitude_m: f64,
        /// The row's wind speed, m/s.
        speed_mps: f64,
        /// The row's direction the wind blows from, degrees clockwise from north.
        from_deg: f64,
    },
    /// A profile row has a negative speed.
    #[error("wind profile row {row}: speed must be ≥ 0, got {speed_mps} m/s")]
    ProfileNegativeSpeed {
        /// Index of the row, from 0.
        row: usize,
        /// The speed given, m/s.
        speed_mps: f64,
    },
    /// Profile altitudes must strictly increase from row to row.
    #[error(
        "wind profile row {row}: altitudes must strictly increase, got {altitude_m} m after \
         {previous_altitude_m} m"
    )]
    ProfileAltitudeNotIncreasing {
        /// Index of the row, from 0.
        row: usize,
        /// This row's altitude, m.
        altitude_m: f64,
        /// The previous row's altitude, m.
        previous_altitude_m: f64,
    },
    /// A constant wind needs a finite speed ≥ 0 and a finite direction.
    #[error(
        "constant wind: speed must be finite and ≥ 0 and direction finite, got {speed_mps} m/s \
         from {from_deg}°"
    )]
    InvalidConstantWind {
        /// The speed given, m/s.
        speed_mps: f64,
        /// The direction given, degrees.
        from_deg: f64,
    },
    /// A turbulence parameter breaks its rule.
    #[error("turbulence parameter `{parameter}` = {value} is invalid: must be {rule}")]
    InvalidTurbulence {
        /// Name of the parameter.
        parameter: &'static str,
        /// The value given, in the parameter's unit.
        value: f64,
        /// The rule it breaks.
        rule: &'static str,
    },
}

/// North and east components of the air's velocity for a meteorological wind, m/s.
pub fn blowing_north_east_mps(speed_mps: f64, from_deg: f64) -> (f64, f64) {
    let (sin, cos) = from_deg.to_radians().sin_cos();
    (-speed_mps * cos, -speed_mps * sin)
}

/// The meteorological wind of the air's velocity (`north`, `east`, m/s): where it blows from,
/// degrees clockwise from true north in 0..360, and its speed, m/s (the inverse of
/// [`blowing_north_east_mps`]). A calm has no direction and is said to come from the north.
pub fn from_deg_and_speed(north: f64, east: f64) -> (f64, f64) {
    let speed_mps = north.hypot(east);
    if speed_mps == 0.0 {
        return (0.0, 0.0);
    }
    // rem_euclid of a tiny negative angle rounds up to 360.0 itself, outside 0..360.
    let from_deg = (-east).atan2(-north).to_degrees().rem_euclid(360.0);
    (if from_deg >= 360.0 { 0.0 } else { from_deg }, speed_mps)
}

/// No wind anywhere.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Calm;

impl WindField for Calm {
    fn wind_ned_mps(&self, _time_s: f64, _position_ned_m: &Vector3<f64>) -> Vector3<f64> {
        Vector3::zeros()
    }
}

/// The same horizontal wind everywhere and always.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConstantWind {
    /// Wind speed, m/s (≥ 0).
    pub speed_mps: f64,
    /// Direction the wind blows from, degrees clockwise from north.
    pub from_deg: f64,
}

impl ConstantWind {
    /// A wind of `speed_mps` (m/s, finite, ≥ 0) blowing from `from_deg` (degrees clockwise
    /// from north, finite).
    pub fn from_speed_direction(speed_mps: f64, from_deg: f64) -> Result<Self, WindError> {
        if speed_mps.is_finite() && speed_mps >= 0.0 && from_deg.is_finite() {
            Ok(Self {
                speed_mps,
                from_deg,
            })
        } else {
            Err(WindError::InvalidConstantWind {
                speed_mps,
                from_deg,
            })
        }
    }
}

impl WindField for ConstantWind {
    fn wind_ned_mps(&self, _time_s: f64, _position_ned_m: &Vector3<f64>) -> Vector3<f64> {
        let (north, east) = blowing_north_east_mps(self.speed_mps, self.from_deg);
        Vector3::new(north, east, 0.0)
    }
}

/// One row of a [`WindProfile`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProfileRow {
    /// Altitude above ground, m.
    pub altitude_m: f64,
    /// Wind speed, m/s (≥ 0).
    pub speed_mps: f64,
    /// Direction the wind blows from, degrees clockwise from north.
    pub from_deg: f64,
}

/// Horizontal wind tabulated over altitude above ground, as from a radiosonde or a forecast.
///
/// Between rows the north and east components are interpolated linearly in altitude. Not the
/// speed and angle: interpolating angles breaks across north (350° to 10° would pass through
/// 180°), and components also give the physically sensible result when the wind turns through
/// a calm layer. Above the top row and below the bottom one the end row's wind holds.
#[derive(Clone, Debug, PartialEq)]
pub struct WindProfile {
    rows: Vec<ProfileRow>,
    /// Per row: altitude (m), north and east components (m/s).
    components: Vec<(f64, f64, f64)>,
}

impl WindProfile {
    /// A profile from `[altitude m, speed m/s, from °]` rows, as config files and tests write
    /// them; the rules of [`WindProfile::new`].
    pub fn from_rows(rows: &[[f64; 3]]) -> Result<Self, WindError> {
        Self::new(
            rows.iter()
                .map(|&[altitude_m, speed_mps, from_deg]| ProfileRow {
                    altitude_m,
                    speed_mps,
                    from_deg,
                })
                .collect(),
        )
    }

    /// A profile from rows whose altitudes strictly increase; every value finite, speeds ≥ 0.
    pub fn new(rows: Vec<ProfileRow>) -> Result<Self, WindError> {
        if rows.is_empty() {
            return Err(WindError::EmptyProfile);
        }
        for (row, r) in rows.iter().enumerate() {
            if !(r.altitude_m.is_finite() && r.speed_mps.is_finite() && r.from_deg.is_finite()) {
                return Err(WindError::ProfileRowNotFinite {
                    row,
                    altitude_m: r.altitude_m,
                    speed_mps: r.speed_mps,
                    from_deg: r.from_deg,
                });
            }
            if r.speed_mps < 0.0 {
                return Err(WindError::ProfileNegativeSpeed {
                    row,
                    speed_mps: r.speed_mps,
                });
            }
            if row > 0 && r.altitude_m <= rows[row - 1].altitude_m {
                return Err(WindError::ProfileAltitudeNotIncreasing {
                    row,
                    altitude_m: r.altitude_m,
                    previous_altitude_m: rows[row - 1].altitude_m,
                });
            }
        }
        let components = rows
            .iter()
            .map(|r| {
                let (north, east) = blowing_north_east_mps(r.speed_mps, r.from_deg);
                (r.altitude_m, north, east)
            })
            .collect();
        Ok(Self { rows, components })
    }

    /// The validated rows.
    pub fn rows(&self) -> &[ProfileRow] {
        &self.rows
    }

    /// North and east components at `altitude_m` above ground, m/s.
    fn north_east_at(&self, altitude_m: f64) -> (f64, f64) {
        let table = &self.components;
        // Rows strictly below the altitude; for NaN this is 0 and the result is NaN below.
        let above = count_below(table.iter().map(|&(a, _, _)| a), altitude_m);
        self.north_east_above(above, altitude_m)
    }

    /// [`Self::north_east_at`] with `hint` the rows below the altitude last asked.
    fn north_east_near(&self, altitude_m: f64, hint: &AtomicUsize) -> (f64, f64) {
        let table = &self.components;
        let above = count_below_near(table.len(), |i| table[i].0, altitude_m, hint);
        self.north_east_above(above, altitude_m)
    }

    /// The components at `altitude_m`, which `above` rows lie strictly below.
    fn north_east_above(&self, above: usize, altitude_m: f64) -> (f64, f64) {
        let table = &self.components;
        if altitude_m.is_nan() {
            return (f64::NAN, f64::NAN);
        }
        if above == 0 {
            return (table[0].1, table[0].2);
        }
        if above == table.len() {
            let last = table[table.len() - 1];
            return (last.1, last.2);
        }
        let (a0, n0, e0) = table[above - 1];
        let (a1, n1, e1) = table[above];
        let fraction = (altitude_m - a0) / (a1 - a0);
        // Weighted form: exact at both rows (fraction 0 or 1), unlike `n0 + f·(n1 − n0)`.
        (
            n0 * (1.0 - fraction) + n1 * fraction,
            e0 * (1.0 - fraction) + e1 * fraction,
        )
    }
}

/// How many of the increasing `values` are below `x` (what `partition_point(|v| v < x)`
/// gives on them), counted without branching: a profile's few dozen rows are compared faster
/// than a binary search's unpredictable branches are taken, and the planner asks the wind at
/// every step of every sample.
pub fn count_below(values: impl Iterator<Item = f64>, x: f64) -> usize {
    values.map(|v| usize::from(v < x)).sum()
}

/// [`count_below`] of the `len` strictly increasing values `value(i)`, with `hint` the count
/// last time: the same count, in two comparisons when `x` lies in the same interval as then
/// (a path asks a few metres apart, a profile's rows lie hundreds apart).
pub fn count_below_near(
    len: usize,
    value: impl Fn(usize) -> f64,
    x: f64,
    hint: &AtomicUsize,
) -> usize {
    let c = hint.load(Ordering::Relaxed);
    // For increasing values the count is `c` exactly when the value before `c` is below `x`
    // and the one at `c` is not (NaN compares false both ways, so it is counted in full).
    if c <= len && (c == 0 || value(c - 1) < x) && (c == len || value(c) >= x) {
        return c;
    }
    let c = count_below((0..len).map(&value), x);
    hint.store(c, Ordering::Relaxed);
    c
}

impl WindField for WindProfile {
    fn wind_ned_mps(&self, _time_s: f64, position_ned_m: &Vector3<f64>) -> Vector3<f64> {
        let (north, east) = self.north_east_at(-position_ned_m.z);
        Vector3::new(north, east, 0.0)
    }

    fn wind_ned_mps_near(
        &self,
        _time_s: f64,
        position_ned_m: &Vector3<f64>,
        hint: &AtomicUsize,
    ) -> Vector3<f64> {
        let (north, east) = self.north_east_near(-position_ned_m.z, hint);
        Vector3::new(north, east, 0.0)
    }
}

#[cfg(test)]
mod tests;
