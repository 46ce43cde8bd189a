//! The air's velocity over time and position: mean wind plus turbulent gusts.
//!
//! Why it exists: a parafoil flying at ~5 m/s cannot make headway against winds above ~5 m/s,
//! so wind decides where the stack lands and whether guidance can reach the target. The model
//! needs the air's velocity at the canopy at every derivative evaluation.
//!
//! Why deterministic functions of `(t, position)` rather than a random process stepped along:
//! adaptive integrators evaluate the model at trial times that go back and forth inside a step
//! and may be rejected; a gust drawn from a random number generator at each call would differ
//! between the trial and the retry, and runs would not reproduce. Everything here, turbulence
//! included, returns the same value for the same arguments.
//!
//! How the parts fit:
//! - [`WindField`] is what the model depends on;
//! - mean winds: [`Calm`], [`ConstantWind`], [`WindProfile`] (a table over altitude);
//! - [`Turbulence`]: Dryden-spectrum gusts built as a sum of sinusoids drawn once from a seed;
//! - [`WindComposite`] adds a mean wind and optional turbulence; [`WindConfig`] is its TOML
//!   form, validated by [`WindConfig::build`].
//!
//! Conventions:
//! - Velocities are in the flat-Earth North-East-Down frame, m/s: the vector is where the air
//!   goes, so a wind *from* the north has a negative north component.
//! - Directions are meteorological: the direction the wind blows *from*, degrees clockwise
//!   from true north.
//! - `position_ned_m` has its origin on the ground (the NED origin of the simulation), so the
//!   altitude above ground that [`WindProfile`] uses is `−z`. Callers that need altitude above
//!   sea level for the atmosphere add the ground's elevation themselves.

use std::f64::consts::PI;

use nalgebra::Vector3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// The air's velocity as a deterministic function of time and position.
pub trait WindField: Send + Sync {
    /// Air velocity in NED, m/s, at `time_s` (s) and `position_ned_m` (NED, m, origin on the
    /// ground so that altitude above ground is `−position_ned_m.z`).
    fn wind_ned_mps(&self, time_s: f64, position_ned_m: &Vector3<f64>) -> Vector3<f64>;
}

impl<W: WindField + ?Sized> WindField for &W {
    fn wind_ned_mps(&self, time_s: f64, position_ned_m: &Vector3<f64>) -> Vector3<f64> {
        (**self).wind_ned_mps(time_s, position_ned_m)
    }
}

impl<W: WindField + ?Sized> WindField for Box<W> {
    fn wind_ned_mps(&self, time_s: f64, position_ned_m: &Vector3<f64>) -> Vector3<f64> {
        (**self).wind_ned_mps(time_s, position_ned_m)
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
fn blowing_north_east_mps(speed_mps: f64, from_deg: f64) -> (f64, f64) {
    let (sin, cos) = from_deg.to_radians().sin_cos();
    (-speed_mps * cos, -speed_mps * sin)
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
        let above = table.partition_point(|&(a, _, _)| a < altitude_m);
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

impl WindField for WindProfile {
    fn wind_ned_mps(&self, _time_s: f64, position_ned_m: &Vector3<f64>) -> Vector3<f64> {
        let (north, east) = self.north_east_at(-position_ned_m.z);
        Vector3::new(north, east, 0.0)
    }
}

/// Default number of sinusoids per axis in [`Turbulence`].
pub const DEFAULT_TURBULENCE_COMPONENTS: usize = 64;
/// Most sinusoids per axis accepted, to bound memory and evaluation cost.
pub const MAX_TURBULENCE_COMPONENTS: usize = 1 << 16;

fn default_components() -> usize {
    DEFAULT_TURBULENCE_COMPONENTS
}

/// Parameters of Dryden turbulence (MIL-F-8785C / MIL-HDBK-1797 forms).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TurbulenceParams {
    /// RMS intensity of each horizontal gust component, m/s (≥ 0).
    pub sigma_horizontal_mps: f64,
    /// RMS intensity of the vertical gust component, m/s (≥ 0).
    pub sigma_vertical_mps: f64,
    /// Length scale of the horizontal components, m (> 0).
    pub length_scale_horizontal_m: f64,
    /// Length scale of the vertical component, m (> 0).
    pub length_scale_vertical_m: f64,
    /// Speed at which the vehicle is taken to cross the frozen gust field, m/s (> 0): converts
    /// the spatial spectrum into a temporal one (Taylor's hypothesis). Use the expected airspeed.
    pub reference_airspeed_mps: f64,
    /// Seed of the generator that draws frequencies and phases; same seed, same gusts.
    pub seed: u64,
    /// Sinusoids per axis (1 … 65 536; default 64). More reproduce the spectrum more closely
    /// at a proportional cost per evaluation. Changing it changes every draw.
    #[serde(default = "default_components")]
    pub components: usize,
}

/// One term `amplitude·cos(ω t + phase)` of a gust component.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Sinusoid {
    angular_frequency_rad_per_s: f64,
    phase_rad: f64,
    amplitude_mps: f64,
}

/// Dryden-spectrum gusts as a smooth, reproducible function of time.
///
/// Each NED axis is a sum of `N` cosines with random phases and with frequencies drawn from the
/// Dryden spectrum itself (normalised as a probability density), each with amplitude
/// `σ·√(2/N)`. Then the variance is exactly `σ²` and the autocorrelation, averaged over draws,
/// is exactly Dryden's; one draw approaches it as `N` grows. The frequencies are stratified —
/// one drawn from each of `N` equal-probability bands of the spectrum — which keeps a single
/// draw close to the spectrum with few terms. The top band is cut at the spectrum's
/// `1 − 1/(4N)` quantile, so one unlucky draw cannot put an arbitrarily high frequency (and
/// an arbitrarily stiff right-hand side) into the model; that discards 1/(4N) of the spectrum's
/// probability mass, while the variance stays exactly `σ²`.
///
/// Spectra over spatial frequency Ω (rad/m), one-sided, each integrating to σ²:
/// - longitudinal (north axis): `Φ(Ω) = σ_h² (2L_h/π) / (1 + (L_hΩ)²)`,
///   autocorrelation `σ² e^(−ξ/L)`;
/// - lateral (east axis, σ_h, L_h) and vertical (down axis, σ_v, L_v):
///   `Φ(Ω) = σ² (L/π) (1 + 3(LΩ)²) / (1 + (LΩ)²)²`, autocorrelation `σ² (1 − ξ/2L) e^(−ξ/L)`.
///
/// Time enters as distance `ξ = V·t` at the reference airspeed: the vehicle is taken to fly
/// straight through a frozen field, so position is not used. The north axis carries the
/// longitudinal form as if that straight path ran north: a parafoil turns, and no fixed axis
/// is really "along the path", so this is a modelling choice, not a derivation.
#[derive(Clone, Debug, PartialEq)]
pub struct Turbulence {
    params: TurbulenceParams,
    axes: [Vec<Sinusoid>; 3],
}

/// Which Dryden form an axis uses.
#[derive(Clone, Copy)]
enum DrydenForm {
    Longitudinal,
    Transverse,
}

impl DrydenForm {
    /// Normalised spatial frequency `LΩ` at which the spectrum's cumulative distribution
    /// reaches `probability` (in [0, 1)).
    fn quantile(self, probability: f64) -> f64 {
        match self {
            // CDF = (2/π)·atan(x).
            Self::Longitudinal => (0.5 * PI * probability).tan(),
            // CDF = (2/π)·atan(x) − x/(π(1 + x²)); with φ = 2·atan(x) this is
            // (φ − sin φ / 2)/π, increasing in φ on [0, π): solve by bisection.
            Self::Transverse => {
                let target = PI * probability;
                let (mut low, mut high) = (0.0_f64, PI);
                for _ in 0..64 {
                    let mid = 0.5 * (low + high);
                    if mid - 0.5 * mid.sin() < target {
                        low = mid;
                    } else {
                        high = mid;
                    }
                }
                (0.25 * (low + high)).tan()
            }
        }
    }
}

impl Turbulence {
    /// Validates the parameters and draws the sinusoids from `params.seed`.
    pub fn new(params: TurbulenceParams) -> Result<Self, WindError> {
        let invalid = |parameter, value, rule| {
            Err(WindError::InvalidTurbulence {
                parameter,
                value,
                rule,
            })
        };
        for (name, value) in [
            ("sigma_horizontal_mps", params.sigma_horizontal_mps),
            ("sigma_vertical_mps", params.sigma_vertical_mps),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return invalid(name, value, "finite and ≥ 0");
            }
        }
        for (name, value) in [
            (
                "length_scale_horizontal_m",
                params.length_scale_horizontal_m,
            ),
            ("length_scale_vertical_m", params.length_scale_vertical_m),
            ("reference_airspeed_mps", params.reference_airspeed_mps),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return invalid(name, value, "finite and > 0");
            }
        }
        if !(1..=MAX_TURBULENCE_COMPONENTS).contains(&params.components) {
            return invalid("components", params.components as f64, "1 … 65536");
        }

        let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
        let axes = [
            (
                DrydenForm::Longitudinal,
                params.sigma_horizontal_mps,
                params.length_scale_horizontal_m,
            ),
            (
                DrydenForm::Transverse,
                params.sigma_horizontal_mps,
                params.length_scale_horizontal_m,
            ),
            (
                DrydenForm::Transverse,
                params.sigma_vertical_mps,
                params.length_scale_vertical_m,
            ),
        ]
        .map(|(form, sigma_mps, length_scale_m)| {
            draw_axis(
                &mut rng,
                form,
                sigma_mps,
                length_scale_m,
                params.reference_airspeed_mps,
                params.components,
            )
        });
        Ok(Self { params, axes })
    }

    /// The parameters the gusts were drawn from.
    pub fn params(&self) -> &TurbulenceParams {
        &self.params
    }

    /// The gust velocity in NED at `time_s`, m/s.
    pub fn gust_ned_mps(&self, time_s: f64) -> Vector3<f64> {
        Vector3::from_fn(|axis, _| {
            self.axes[axis]
                .iter()
                .map(|s| {
                    s.amplitude_mps * (s.angular_frequency_rad_per_s * time_s + s.phase_rad).cos()
                })
                .sum()
        })
    }
}

fn draw_axis(
    rng: &mut ChaCha8Rng,
    form: DrydenForm,
    sigma_mps: f64,
    length_scale_m: f64,
    airspeed_mps: f64,
    components: usize,
) -> Vec<Sinusoid> {
    let count = components as f64;
    let amplitude_mps = sigma_mps * (2.0 / count).sqrt();
    (0..components)
        .map(|band| {
            // Width of the band actually sampled: the top one stops short of probability 1.
            let width = if band + 1 == components { 0.75 } else { 1.0 };
            let probability = (band as f64 + width * rng.random::<f64>()) / count;
            let phase_rad = 2.0 * PI * rng.random::<f64>();
            let spatial_frequency_rad_per_m = form.quantile(probability) / length_scale_m;
            Sinusoid {
                angular_frequency_rad_per_s: spatial_frequency_rad_per_m * airspeed_mps,
                phase_rad,
                amplitude_mps,
            }
        })
        .collect()
}

impl WindField for Turbulence {
    fn wind_ned_mps(&self, time_s: f64, _position_ned_m: &Vector3<f64>) -> Vector3<f64> {
        self.gust_ned_mps(time_s)
    }
}

/// A mean wind plus optional turbulence.
pub struct WindComposite {
    /// The mean wind.
    pub mean: Box<dyn WindField>,
    /// Gusts added to it, if any.
    pub turbulence: Option<Turbulence>,
}

impl WindField for WindComposite {
    fn wind_ned_mps(&self, time_s: f64, position_ned_m: &Vector3<f64>) -> Vector3<f64> {
        let mean = self.mean.wind_ned_mps(time_s, position_ned_m);
        match &self.turbulence {
            Some(turbulence) => mean + turbulence.gust_ned_mps(time_s),
            None => mean,
        }
    }
}

/// The mean wind as written in a configuration file, selected by `kind`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum MeanWindConfig {
    /// No wind. Written with braces, as a variant with no fields, so that stray keys beside
    /// `kind = "calm"` are refused like everywhere else.
    Calm {},
    /// A [`ConstantWind`].
    Constant {
        /// Wind speed, m/s.
        speed_mps: f64,
        /// Direction the wind blows from, degrees clockwise from north.
        from_deg: f64,
    },
    /// A [`WindProfile`].
    Profile {
        /// Rows `[altitude above ground (m), speed (m/s), from (degrees)]`.
        rows: Vec<[f64; 3]>,
    },
}

/// A wind as written in a configuration file: the mean wind's fields (with `kind`) and an
/// optional `turbulence` table of [`TurbulenceParams`], e.g.
///
/// ```toml
/// kind = "profile"
/// rows = [[0, 2.0, 270], [1000, 6.0, 250], [10000, 20.0, 240]]
///
/// [turbulence]
/// sigma_horizontal_mps = 1.0
/// sigma_vertical_mps = 0.7
/// length_scale_horizontal_m = 200
/// length_scale_vertical_m = 50
/// reference_airspeed_mps = 6
/// seed = 7
/// ```
///
/// Unknown keys are refused, so a misspelt field cannot silently fall back to a default.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(try_from = "toml::Table")]
pub struct WindConfig {
    /// The mean wind.
    pub mean: MeanWindConfig,
    /// Gusts, if any.
    pub turbulence: Option<TurbulenceParams>,
}

impl TryFrom<toml::Table> for WindConfig {
    type Error = toml::de::Error;

    fn try_from(mut table: toml::Table) -> Result<Self, Self::Error> {
        let turbulence = table
            .remove("turbulence")
            .map(|value| value.try_into::<TurbulenceParams>())
            .transpose()?;
        let mean = table.try_into::<MeanWindConfig>()?;
        Ok(Self { mean, turbulence })
    }
}

impl WindConfig {
    /// Validates the configuration and builds the wind field it describes.
    pub fn build(&self) -> Result<Box<dyn WindField>, WindError> {
        let mean: Box<dyn WindField> = match &self.mean {
            MeanWindConfig::Calm {} => Box::new(Calm),
            MeanWindConfig::Constant {
                speed_mps,
                from_deg,
            } => Box::new(ConstantWind::from_speed_direction(*speed_mps, *from_deg)?),
            MeanWindConfig::Profile { rows } => Box::new(WindProfile::new(
                rows.iter()
                    .map(|&[altitude_m, speed_mps, from_deg]| ProfileRow {
                        altitude_m,
                        speed_mps,
                        from_deg,
                    })
                    .collect(),
            )?),
        };
        let turbulence = self.turbulence.clone().map(Turbulence::new).transpose()?;
        Ok(Box::new(WindComposite { mean, turbulence }))
    }
}

#[cfg(test)]
mod tests;
