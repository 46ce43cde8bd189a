//! The simulated air's velocity over time and position: mean wind plus turbulent gusts.
//!
//! Why it exists: a parafoil flying at ~5 m/s cannot make headway against winds above ~5 m/s,
//! so wind decides where the stack lands and whether guidance can reach the target. The model
//! needs the air's velocity at the canopy at every derivative evaluation.
//!
//! How the parts fit:
//! - [`WindField`] and the mean winds ([`Calm`], [`ConstantWind`], [`WindProfile`]) are the
//!   vocabulary the onboard code shares, so they live in `stx_types::wind` (which says why
//!   every field is a deterministic function of `(t, position)`) and are re-exported here;
//! - [`Turbulence`]: Dryden-spectrum gusts built as a sum of sinusoids drawn once from a seed,
//!   the same for the same arguments like every other field;
//! - [`WindComposite`] adds a mean wind and optional turbulence; [`WindConfig`] is its TOML
//!   form, validated by [`WindConfig::build`].
//!
//! The gusts are the dearest part of a model evaluation (192 cosines), and a fixed-step RK4
//! asks for them twice at every time it visits (its two half-step stages, then its end point and
//! the derivative there), so [`Turbulence`] keeps its last answer, and carries the sinusoids
//! from one time to the next half step by rotating their phasors (`Phasors`).
//!
//! Conventions are those of `stx_types::wind`: NED velocities where the air goes, directions
//! the wind blows from, altitude above ground `−z`.

use std::f64::consts::PI;
use std::sync::Mutex;

use nalgebra::Vector3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

pub use stx_types::wind::{Calm, ConstantWind, ProfileRow, WindError, WindField, WindProfile};

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
    memory: GustMemory,
}

/// What [`Turbulence`] remembers between calls. A lock, not a cell, because a field is shared
/// between threads (`WindField: Sync`); a caller that finds it taken computes the gust itself.
#[derive(Debug, Default)]
struct GustMemory(Mutex<Remembered>);

/// The phasors of the time asked last, and of the time before that which was not a step on
/// from it.
///
/// Why two: a flight, having flown a control period, asks for the gust at the period's start,
/// and then the integrator goes on from its end. With one memory each such question cost the
/// integrator's phasors; with two it costs one `sin_cos`.
#[derive(Debug, Default)]
struct Remembered {
    last: Option<Phasors>,
    other: Option<Phasors>,
}

/// Every sinusoid's `(cos, sin)` of `ω t + phase` at one time, with the gust they sum to, and
/// the rotation that carries them one step on.
///
/// Why: RK4 visits times half a step apart, one after another, and `cos(ω(t + Δ) + φ)` is
/// `(cos, sin)` at `t` rotated by `ωΔ`: four products instead of a cosine, which was a tenth of
/// a campaign's time. Each rotation rounds, and times a step apart are only a step apart to
/// their rounding, so the phasors are taken afresh from `cos` and `sin` every [`FRESH_EVERY`]
/// steps: the gust then stays within 2e-11 m/s of the cosines' sum in the first minutes and
/// 1e-9 m/s late in a long descent (unit test `gusts_a_step_apart_stay_on_the_cosines_sum`),
/// though no longer the same bits as the sum's. A rotation is made for a step
/// seen twice in a row, so callers that ask at scattered times pay no more than `sin_cos`.
#[derive(Debug)]
struct Phasors {
    time_s: f64,
    gust: Vector3<f64>,
    /// `(cos, sin)` of each sinusoid, axis after axis.
    at: Vec<(f64, f64)>,
    /// The time since the phasors before, s: a step that, seen again, is worth a rotation.
    last_step_s: f64,
    /// The step a rotation was made for, s, and `(cos ωΔ, sin ωΔ)` of each sinusoid.
    rotation: Option<(f64, Vec<(f64, f64)>)>,
    /// Steps taken by rotation since the phasors were last computed afresh.
    rotated: u32,
}

/// Rotations in a row before the phasors are computed afresh.
const FRESH_EVERY: u32 = 16;

/// How far a step may be from another and still count as the same, s: the rounding of times
/// near 10⁴ s (a few ulps), far below anything the gusts resolve.
const SAME_STEP_S: f64 = 1e-11;

fn same_step(a_s: f64, b_s: f64) -> bool {
    (a_s - b_s).abs() <= SAME_STEP_S
}

impl GustMemory {
    fn gust(&self, axes: &[Vec<Sinusoid>; 3], time_s: f64) -> Vector3<f64> {
        let Ok(mut memory) = self.0.try_lock() else {
            return sum(axes, |s, _| s.angle_rad(time_s).cos());
        };
        let Remembered { last, other } = &mut *memory;
        if other.as_ref().is_some_and(|p| p.is_at(time_s)) {
            std::mem::swap(last, other);
        }
        if let Some(p) = last.as_mut() {
            if p.is_at(time_s) {
                return p.gust;
            }
            let step_s = time_s - p.time_s;
            if p.rotated < FRESH_EVERY {
                if !p.has_rotation_for(step_s) && same_step(p.last_step_s, step_s) {
                    p.rotation = Some((step_s, rotation(axes, step_s)));
                }
                if p.has_rotation_for(step_s) {
                    return p.rotate(axes, time_s);
                }
            }
        }
        let step_s = last.as_ref().map_or(f64::NAN, |p| time_s - p.time_s);
        // Handed on to the phasors of a step on; a stray question leaves it where it was.
        let rotation = last
            .as_mut()
            .filter(|p| p.has_rotation_for(step_s))
            .and_then(|p| p.rotation.take());
        let fresh = Phasors::fresh(axes, time_s, step_s, rotation);
        let gust = fresh.gust;
        *other = last.replace(fresh);
        gust
    }
}

/// Each axis's sum of `amplitude · term(sinusoid, its index among all)`.
fn sum(axes: &[Vec<Sinusoid>; 3], mut term: impl FnMut(&Sinusoid, usize) -> f64) -> Vector3<f64> {
    let mut index = 0;
    Vector3::from_fn(|axis, _| {
        axes[axis]
            .iter()
            .map(|s| {
                index += 1;
                s.amplitude_mps * term(s, index - 1)
            })
            .sum()
    })
}

/// `(cos ωΔ, sin ωΔ)` of every sinusoid, axis after axis.
fn rotation(axes: &[Vec<Sinusoid>; 3], step_s: f64) -> Vec<(f64, f64)> {
    axes.iter()
        .flatten()
        .map(|s| {
            let (sin, cos) = (s.angular_frequency_rad_per_s * step_s).sin_cos();
            (cos, sin)
        })
        .collect()
}

impl Phasors {
    /// Computed from `cos` and `sin` at `time_s`, `step_s` after the phasors before.
    fn fresh(
        axes: &[Vec<Sinusoid>; 3],
        time_s: f64,
        step_s: f64,
        rotation: Option<(f64, Vec<(f64, f64)>)>,
    ) -> Self {
        let at: Vec<(f64, f64)> = axes
            .iter()
            .flatten()
            .map(|s| {
                let (sin, cos) = s.angle_rad(time_s).sin_cos();
                (cos, sin)
            })
            .collect();
        Self {
            time_s,
            gust: sum(axes, |_, i| at[i].0),
            at,
            last_step_s: step_s,
            rotation,
            rotated: 0,
        }
    }

    fn is_at(&self, time_s: f64) -> bool {
        self.time_s.to_bits() == time_s.to_bits()
    }

    fn has_rotation_for(&self, step_s: f64) -> bool {
        self.rotation
            .as_ref()
            .is_some_and(|(made_for_s, _)| same_step(*made_for_s, step_s))
    }

    /// Carries every phasor one step on, to `time_s`.
    fn rotate(&mut self, axes: &[Vec<Sinusoid>; 3], time_s: f64) -> Vector3<f64> {
        if let Some((_, rotation)) = &self.rotation {
            for ((cos, sin), (rc, rs)) in self.at.iter_mut().zip(rotation) {
                (*cos, *sin) = (*cos * rc - *sin * rs, *sin * rc + *cos * rs);
            }
        }
        let at = &self.at;
        self.gust = sum(axes, |_, i| at[i].0);
        self.time_s = time_s;
        self.rotated += 1;
        self.gust
    }
}

/// A copy starts with nothing remembered.
impl Clone for GustMemory {
    fn clone(&self) -> Self {
        Self::default()
    }
}

/// What is remembered is not part of the field's value.
impl PartialEq for GustMemory {
    fn eq(&self, _: &Self) -> bool {
        true
    }
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
        Ok(Self {
            params,
            axes,
            memory: GustMemory::default(),
        })
    }

    /// The parameters the gusts were drawn from.
    pub fn params(&self) -> &TurbulenceParams {
        &self.params
    }

    /// The gust velocity in NED at `time_s`, m/s.
    pub fn gust_ned_mps(&self, time_s: f64) -> Vector3<f64> {
        self.memory.gust(&self.axes, time_s)
    }
}

impl Sinusoid {
    fn angle_rad(&self, time_s: f64) -> f64 {
        self.angular_frequency_rad_per_s * time_s + self.phase_rad
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
            MeanWindConfig::Profile { rows } => Box::new(WindProfile::from_rows(rows)?),
        };
        let turbulence = self.turbulence.clone().map(Turbulence::new).transpose()?;
        Ok(Box::new(WindComposite { mean, turbulence }))
    }
}

#[cfg(test)]
mod tests;
