//! The plan's spread: the flight path flown many times over the uncertain inputs — the mean
//! ascent rate, the burst altitude and the forecast wind — giving where the balloon bursts,
//! where the parafoil deploys and where it lands, as means with 1-σ ellipses, the region
//! steering can likely reach, and the probability that the target is reachable.
//!
//! Each sample draws, from the injected random number generator (seeded by the caller, so a
//! plan reproduces):
//! - the mean ascent rate from a normal law, kept above a quarter of its mean (a balloon that
//!   barely rises is a failed launch, not a plan);
//! - the burst altitude from a normal law, kept at least 100 m above the ground;
//! - one wind error: a pair of standard normal numbers `(a, b)` that move the north and east
//!   wind components at every altitude by `(a, b)·σ(h)`, σ interpolated over the forecast's
//!   rows. The error is taken fully correlated over altitude: a forecast that is wrong is
//!   mostly wrong the same way over thousands of metres (a misplaced front or jet), and
//!   independent errors per level would average out over the long ascent and understate the
//!   spread.
//!
//! The region steering reaches is the ground enough of the samples' reach discs cover
//! ([`super::region`]).

use std::sync::atomic::AtomicUsize;

use nalgebra::{Matrix2, Vector2, Vector3};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};
use stx_types::validate::check;
use stx_types::wind::{WindField, count_below_near};

use super::region::{SteeredRegion, steered_region};
use super::{Air, FlightPath, FlightPathError, ReachDisc, StackConfig, Start, VerticalPath};
use crate::performance::GlidePerformance;

/// Most samples returned one by one (for a scatter on the map).
pub const MAX_SAMPLES_RETURNED: usize = 300;

/// The inputs' uncertainties.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields, default)]
pub struct Dispersion {
    /// 1-σ of the mean ascent rate, m/s (≥ 0).
    pub ascent_rate_sigma_mps: f64,
    /// 1-σ of the burst altitude, m (≥ 0).
    pub burst_altitude_sigma_m: f64,
    /// 1-σ error of each horizontal wind component by height above the origin, `(m, m/s)`
    /// rows with increasing heights, interpolated linearly, the end rows held beyond; empty:
    /// no wind error.
    pub wind_sigma: Vec<(f64, f64)>,
}

impl Default for Dispersion {
    fn default() -> Self {
        Self {
            ascent_rate_sigma_mps: 0.5,
            burst_altitude_sigma_m: 1500.0,
            wind_sigma: Vec::new(),
        }
    }
}

impl Dispersion {
    /// Checks the settings (see the fields).
    pub fn validate(&self) -> Result<(), FlightPathError> {
        let s = self.ascent_rate_sigma_mps;
        check("ascent_rate_sigma_mps", s, s >= 0.0, "≥ 0")?;
        let s = self.burst_altitude_sigma_m;
        check("burst_altitude_sigma_m", s, s >= 0.0, "≥ 0")?;
        check_wind_sigma(&self.wind_sigma)
    }
}

fn check_wind_sigma(rows: &[(f64, f64)]) -> Result<(), FlightPathError> {
    for (i, &(h, s)) in rows.iter().enumerate() {
        let increasing = i == 0 || h > rows[i - 1].0;
        check("wind_sigma height", h, increasing, "finite, increasing")?;
        check("wind_sigma", s, s >= 0.0, "≥ 0")?;
    }
    Ok(())
}

/// The 1-σ wind error at `height_m` of [`Dispersion::wind_sigma`]-like `rows`, `above` of
/// which lie strictly below it.
fn wind_sigma_at(rows: &[(f64, f64)], above: usize, height_m: f64) -> f64 {
    match (above, rows.len()) {
        (_, 0) => 0.0,
        (0, _) => rows[0].1,
        (a, n) if a == n => rows[n - 1].1,
        (a, _) => {
            let ((h0, s0), (h1, s1)) = (rows[a - 1], rows[a]);
            let f = (height_m - h0) / (h1 - h0);
            s0 * (1.0 - f) + s1 * f
        }
    }
}

/// The forecast wind moved by one sample's error.
struct PerturbedWind<'a> {
    base: &'a dyn WindField,
    wind_sigma: &'a [(f64, f64)],
    error: [f64; 2],
    /// A path asks its wind step by step, a few metres apart: where the base wind and the
    /// sigma rows found the last answer.
    base_hint: AtomicUsize,
    sigma_hint: AtomicUsize,
}

impl<'a> PerturbedWind<'a> {
    fn new(base: &'a dyn WindField, wind_sigma: &'a [(f64, f64)], error: [f64; 2]) -> Self {
        Self {
            base,
            wind_sigma,
            error,
            base_hint: AtomicUsize::new(0),
            sigma_hint: AtomicUsize::new(0),
        }
    }
}

impl WindField for PerturbedWind<'_> {
    fn wind_ned_mps(&self, time_s: f64, position_ned_m: &Vector3<f64>) -> Vector3<f64> {
        let rows = self.wind_sigma;
        let h = -position_ned_m.z;
        let above = count_below_near(rows.len(), |i| rows[i].0, h, &self.sigma_hint);
        let s = wind_sigma_at(rows, above, h);
        self.base
            .wind_ned_mps_near(time_s, position_ned_m, &self.base_hint)
            + Vector3::new(self.error[0] * s, self.error[1] * s, 0.0)
    }
}

/// A 1-σ ellipse.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct Ellipse {
    /// Semi-major axis, m.
    pub semi_major_m: f64,
    /// Semi-minor axis, m.
    pub semi_minor_m: f64,
    /// Direction of the major axis from north, rad.
    pub major_axis_rad: f64,
}

impl Ellipse {
    /// The 1-σ ellipse of a north-east covariance, m².
    pub fn from_covariance(cov: &Matrix2<f64>) -> Self {
        let (a, b, d) = (cov[(0, 0)], cov[(0, 1)], cov[(1, 1)]);
        let mean = 0.5 * (a + d);
        let radius = (0.25 * (a - d) * (a - d) + b * b).sqrt();
        Self {
            semi_major_m: (mean + radius).max(0.0).sqrt(),
            semi_minor_m: (mean - radius).max(0.0).sqrt(),
            major_axis_rad: 0.5 * (2.0 * b).atan2(a - d),
        }
    }
}

/// A position (NED, m) and its time (s).
type TimedPoint = ([f64; 3], f64);

/// How one point of the path spreads over the samples.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct PointSpread {
    /// Mean position (north, east), m.
    pub mean_ne_m: [f64; 2],
    /// Mean height above the origin, m.
    pub mean_height_m: f64,
    /// Mean time from the start, s.
    pub mean_time_s: f64,
    /// 1-σ of the time, s.
    pub time_sigma_s: f64,
    /// 1-σ ellipse of the position about the mean.
    pub ellipse: Ellipse,
}

impl PointSpread {
    /// The spread of `points`, each a position (NED, m) and a time (s).
    fn of(points: &[TimedPoint]) -> Self {
        let n = points.len().max(1) as f64;
        let mean = |f: &dyn Fn(&TimedPoint) -> f64| points.iter().map(f).sum::<f64>() / n;
        let (north, east) = (mean(&|p| p.0[0]), mean(&|p| p.0[1]));
        let time = mean(&|p| p.1);
        let mut cov = Matrix2::zeros();
        for (p, _) in points {
            let d = Vector2::new(p[0] - north, p[1] - east);
            cov += d * d.transpose() / n;
        }
        Self {
            mean_ne_m: [north, east],
            mean_height_m: mean(&|p| -p.0[2]),
            mean_time_s: time,
            time_sigma_s: mean(&|p| (p.1 - time).powi(2)).sqrt(),
            ellipse: Ellipse::from_covariance(&cov),
        }
    }
}

/// One sample's points, for a scatter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct PlanSample {
    /// Burst point (north, east), m, if the path had an ascent.
    pub burst_ne_m: Option<[f64; 2]>,
    /// Deploy point (north, east), m.
    pub deploy_ne_m: [f64; 2],
    /// Unsteered landing (north, east), m.
    pub landing_ne_m: [f64; 2],
    /// Centre of the disc steering reaches (north, east), m.
    pub reach_centre_ne_m: [f64; 2],
    /// Its radius, m.
    pub reach_radius_m: f64,
}

/// What the Monte Carlo found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct PlanSpread {
    /// The path with every input at its mean.
    pub nominal: FlightPath,
    /// Samples flown.
    pub runs: usize,
    /// Burst points; `None` if the path started under the round chute.
    pub burst: Option<PointSpread>,
    /// Deploy points.
    pub deploy: PointSpread,
    /// Unsteered parafoil landings.
    pub landing: PointSpread,
    /// Landings under the round chute had it never been released.
    pub round_chute_landing: PointSpread,
    /// The region steering reaches in enough of the samples.
    pub steered_region: SteeredRegion,
    /// Fraction of samples from whose deploy point steering can reach the target.
    pub target_reachable_probability: Option<f64>,
    /// Up to [`MAX_SAMPLES_RETURNED`] samples, in the order flown.
    pub samples: Vec<PlanSample>,
}

fn normal<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    StandardNormal.sample(rng)
}

/// What a plan is asked for, besides the air.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanInputs {
    /// Where the path starts.
    pub start: Start,
    /// The stack, with every uncertain input at its mean.
    pub stack: StackConfig,
    /// The uncertainties.
    pub dispersion: Dispersion,
    /// Samples to fly (≥ 1).
    pub runs: usize,
    /// The landing target (north, east), m, whose reachability is counted.
    pub target_ne_m: Option<[f64; 2]>,
    /// The steered region's level as a share of the best-reached point's, (0, 1].
    pub region_share_of_best: f64,
}

/// One of the winds [`monte_carlo_each`] flies the samples through.
#[derive(Clone, Copy)]
pub struct WindCase<'a> {
    /// The wind with no error.
    pub wind: &'a dyn WindField,
    /// Its 1-σ error by height, as [`Dispersion::wind_sigma`].
    pub wind_sigma: &'a [(f64, f64)],
}

/// Flies `inputs.runs` samples of the path (see the module doc) through `air`, drawing from
/// `rng`.
pub fn monte_carlo<R: Rng + ?Sized>(
    inputs: &PlanInputs,
    air: Air<'_>,
    perf: &GlidePerformance,
    rng: &mut R,
) -> Result<PlanSpread, FlightPathError> {
    let case = WindCase {
        wind: air.wind,
        wind_sigma: &inputs.dispersion.wind_sigma,
    };
    let mut spreads = monte_carlo_each(inputs, &[case], air, perf, rng)?;
    Ok(spreads.remove(0))
}

/// [`monte_carlo`] through each of `winds` in turn (`air.wind` and
/// `inputs.dispersion.wind_sigma` unused), with the same draws for every wind: each sample's
/// [`VerticalPath`] is worked out once and flown through every wind. Spread `i` is the same to
/// the last bit as [`monte_carlo`]'s through `winds[i]` from the same `rng`.
pub fn monte_carlo_each<R: Rng + ?Sized>(
    inputs: &PlanInputs,
    winds: &[WindCase<'_>],
    air: Air<'_>,
    perf: &GlidePerformance,
    rng: &mut R,
) -> Result<Vec<PlanSpread>, FlightPathError> {
    let PlanInputs {
        start,
        ref stack,
        ref dispersion,
        runs,
        target_ne_m,
        region_share_of_best,
    } = *inputs;
    dispersion.validate()?;
    for case in winds {
        check_wind_sigma(case.wind_sigma)?;
    }
    check("runs", runs as f64, runs >= 1, "≥ 1")?;
    let p = region_share_of_best;
    check("region_share_of_best", p, p > 0.0 && p <= 1.0, "in (0, 1]")?;
    if let Some(t) = target_ne_m {
        check("target north", t[0], true, "finite")?;
        check("target east", t[1], true, "finite")?;
    }
    let vertical = |s: &StackConfig| VerticalPath::new(start, s, air.atmosphere, air.ground_msl_m);
    let nominal = vertical(stack)?;
    let mut paths: Vec<Vec<FlightPath>> = winds.iter().map(|_| Vec::with_capacity(runs)).collect();
    for _ in 0..runs {
        let mut s = *stack;
        let rate = stack.mean_ascent_rate_mps + normal(rng) * dispersion.ascent_rate_sigma_mps;
        s.mean_ascent_rate_mps = rate.max(0.25 * stack.mean_ascent_rate_mps);
        let burst = stack.burst_altitude_msl_m + normal(rng) * dispersion.burst_altitude_sigma_m;
        s.burst_altitude_msl_m = burst.max(air.ground_msl_m + 100.0);
        let error = [normal(rng), normal(rng)];
        let sample = vertical(&s)?;
        for (case, paths) in winds.iter().zip(&mut paths) {
            let wind = PerturbedWind::new(case.wind, case.wind_sigma, error);
            paths.push(sample.fly(Air { wind: &wind, ..air }, perf));
        }
    }
    Ok(winds
        .iter()
        .zip(paths)
        .map(|(case, paths)| {
            let nominal = nominal.fly(
                Air {
                    wind: case.wind,
                    ..air
                },
                perf,
            );
            spread(nominal, &paths, target_ne_m, p)
        })
        .collect())
}

/// The spread of the samples' `paths` about the `nominal` one.
fn spread(
    nominal: FlightPath,
    paths: &[FlightPath],
    target_ne_m: Option<[f64; 2]>,
    region_share_of_best: f64,
) -> PlanSpread {
    let runs = paths.len();
    let spread_of = |f: &dyn Fn(&FlightPath) -> super::PathPoint| {
        let points: Vec<TimedPoint> = paths
            .iter()
            .map(|p| {
                let q = f(p);
                (q.position_ned_m, q.time_s)
            })
            .collect();
        PointSpread::of(&points)
    };
    let burst = nominal
        .burst
        .map(|_| spread_of(&|p: &FlightPath| p.burst.expect("every sample of an ascent bursts")));
    let discs: Vec<ReachDisc> = paths.iter().map(|p| p.reach).collect();
    let target_reachable_probability =
        target_ne_m.map(|t| discs.iter().filter(|d| d.contains(t)).count() as f64 / runs as f64);
    PlanSpread {
        nominal,
        runs,
        burst,
        deploy: spread_of(&|p: &FlightPath| p.deploy),
        landing: spread_of(&|p: &FlightPath| p.landing),
        round_chute_landing: spread_of(&|p: &FlightPath| p.round_chute_landing),
        steered_region: steered_region(&discs, region_share_of_best),
        target_reachable_probability,
        samples: paths
            .iter()
            .take(MAX_SAMPLES_RETURNED)
            .map(|p| PlanSample {
                burst_ne_m: p.burst.map(|b| b.ne_m()),
                deploy_ne_m: p.deploy.ne_m(),
                landing_ne_m: p.landing.ne_m(),
                reach_centre_ne_m: p.reach.centre_ne_m,
                reach_radius_m: p.reach.radius_m,
            })
            .collect(),
    }
}
