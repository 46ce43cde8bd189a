//! A pre-flight plan as the operator asks for it and reads it: launch site and target in
//! latitude and longitude, the balloon's settings with their spreads, a forecast, a seed — and
//! back the burst, deploy and landing points with their 1-σ ellipses, the region steering
//! likely reaches and the target's reachability, again in latitude and longitude. The one
//! entry point of `stx plan` and of the station's `POST /api/plan`, so that both give the same
//! answer for the same request.
//!
//! The local frame of the plan has its origin on the launch site's ground; steering's reach
//! is the still-air glide disc of [`super::reach`].

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use stx_types::atmosphere::StandardAtmosphere;
use stx_types::validate::check;

use super::spread::{PlanInputs, PlanSample, PlanSpread, PointSpread, WindCase, monte_carlo_each};
use super::{Air, Dispersion, Ellipse, Forecast, ForecastRow, StackConfig, Start};
use crate::geo::LocalFrame;
use crate::performance::GlidePerformance;

/// Most Monte Carlo samples one plan may fly (a plan of that size takes about a second).
pub const MAX_RUNS: u32 = 5000;

/// What the plan is asked for. Every field but the launch site and the forecast has a default.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields)]
pub struct PlanRequest {
    /// Launch site latitude, degrees north.
    pub launch_lat_deg: f64,
    /// Launch site longitude, degrees east.
    pub launch_lon_deg: f64,
    /// Launch site ground altitude above mean sea level, m.
    #[serde(default)]
    pub launch_alt_msl_m: f64,
    /// The forecast wind, lowest level first (see [`super::forecast`]).
    pub forecast: Vec<ForecastRow>,
    /// Mean ascent rate from launch to burst, m/s.
    #[serde(default = "defaults::ascent_rate")]
    pub ascent_rate_mps: f64,
    /// Its 1-σ, m/s.
    #[serde(default = "defaults::ascent_rate_sigma")]
    pub ascent_rate_sigma_mps: f64,
    /// Burst altitude above mean sea level, m.
    #[serde(default = "defaults::burst_altitude")]
    pub burst_altitude_msl_m: f64,
    /// Its 1-σ, m.
    #[serde(default = "defaults::burst_altitude_sigma")]
    pub burst_altitude_sigma_m: f64,
    /// Height above the launch site at which the parafoil deploys, m (the onboard
    /// `MIS_DEPLOY_M`).
    #[serde(default = "defaults::deploy_height")]
    pub deploy_height_m: f64,
    /// 1-σ of each wind component where the forecast gives none, m/s.
    #[serde(default = "defaults::wind_sigma")]
    pub default_wind_sigma_mps: f64,
    /// The landing target, `[latitude, longitude]` in degrees.
    #[serde(default)]
    pub target_lat_lon_deg: Option<[f64; 2]>,
    /// Monte Carlo samples, 1…[`MAX_RUNS`] (a u32: the API's contract and JavaScript know no
    /// usize).
    #[serde(default = "defaults::runs")]
    pub runs: u32,
    /// Seed of the samples: the same request gives the same plan.
    #[serde(default = "defaults::seed")]
    pub seed: u64,
}

/// The request's defaults (serde needs them as functions).
mod defaults {
    pub fn ascent_rate() -> f64 {
        5.0
    }
    pub fn ascent_rate_sigma() -> f64 {
        0.5
    }
    pub fn burst_altitude() -> f64 {
        35_000.0
    }
    pub fn burst_altitude_sigma() -> f64 {
        1500.0
    }
    pub fn deploy_height() -> f64 {
        crate::params::MissionSettings::default().deploy_height_m
    }
    pub fn wind_sigma() -> f64 {
        1.5
    }
    pub fn runs() -> u32 {
        500
    }
    pub fn seed() -> u64 {
        1
    }
}

impl PlanRequest {
    /// A request with every default, from `launch` over `forecast`.
    pub fn new(launch: LocalFrame, forecast: Vec<ForecastRow>) -> Self {
        Self {
            launch_lat_deg: launch.lat_deg,
            launch_lon_deg: launch.lon_deg,
            launch_alt_msl_m: launch.alt_msl_m,
            forecast,
            ascent_rate_mps: defaults::ascent_rate(),
            ascent_rate_sigma_mps: defaults::ascent_rate_sigma(),
            burst_altitude_msl_m: defaults::burst_altitude(),
            burst_altitude_sigma_m: defaults::burst_altitude_sigma(),
            deploy_height_m: defaults::deploy_height(),
            default_wind_sigma_mps: defaults::wind_sigma(),
            target_lat_lon_deg: None,
            runs: defaults::runs(),
            seed: defaults::seed(),
        }
    }
}

/// Why a plan was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlanError {
    /// A request field breaks its rule.
    #[error("`{field}` = {value} is invalid: must be {rule}")]
    Invalid {
        /// The field.
        field: &'static str,
        /// Its value.
        value: f64,
        /// The rule.
        rule: &'static str,
    },
    /// The forecast was refused.
    #[error(transparent)]
    Forecast(#[from] super::ForecastError),
    /// The flight path could not be flown.
    #[error(transparent)]
    Path(#[from] super::FlightPathError),
}

/// A point of the plan: the mean over the samples, where it is, and how it spreads.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct PlannedPoint {
    /// Latitude, degrees north.
    pub lat_deg: f64,
    /// Longitude, degrees east.
    pub lon_deg: f64,
    /// Altitude above mean sea level, m.
    pub alt_msl_m: f64,
    /// North of the launch site, m.
    pub north_m: f64,
    /// East of the launch site, m.
    pub east_m: f64,
    /// Mean time after launch, s.
    pub time_s: f64,
    /// 1-σ of the time, s.
    pub time_sigma_s: f64,
    /// 1-σ ellipse of the position.
    pub ellipse: Ellipse,
}

/// The target and whether steering reaches it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct TargetReach {
    /// Latitude, degrees north.
    pub lat_deg: f64,
    /// Longitude, degrees east.
    pub lon_deg: f64,
    /// Fraction of the samples from whose deploy point steering reaches it, 0…1.
    pub reachable_probability: f64,
    /// Distance from the mean unsteered landing, m.
    pub from_unsteered_landing_m: f64,
}

/// The plan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct PlanReport {
    /// The request it answers (with its defaults filled in).
    pub request: PlanRequest,
    /// Where the balloon bursts.
    pub burst: PlannedPoint,
    /// Where the round chute is released and the parafoil deploys.
    pub deploy: PlannedPoint,
    /// Where the parafoil lands unsteered (servos neutral).
    pub landing_unsteered: PlannedPoint,
    /// Where the stack would land had the round chute never been released.
    pub round_chute_landing: PlannedPoint,
    /// Fraction of the samples that reach each point of the steered region, at least: half the
    /// best-reached point's (`flight_path::region` says why), 0…1.
    pub steered_region_probability: f64,
    /// Fraction of the samples that reach the best-reached point, 0…1: the most a target can
    /// hope for.
    pub steered_region_best_probability: f64,
    /// Outline of the region steering reaches with that probability, `[lat, lon]` degrees, its
    /// first point repeated at the end; empty if steering reaches nowhere.
    pub steered_region_lat_lon_deg: Vec<[f64; 2]>,
    /// Mean radius of the glide disc steering reaches from the deploy point, m.
    pub steered_reach_radius_m: f64,
    /// How steering's reach is computed.
    pub reach_method: String,
    /// The target's reachability, if a target was given.
    pub target: Option<TargetReach>,
    /// Unsteered landings of up to 300 samples, `[lat, lon]` degrees, for a scatter.
    pub landing_samples_lat_lon_deg: Vec<[f64; 2]>,
}

stx_types::invalid_into!(PlanError);

/// Makes the plan `request` asks for (see the module doc).
pub fn plan(request: &PlanRequest) -> Result<PlanReport, PlanError> {
    let forecasts = std::slice::from_ref(&request.forecast);
    let mut reports = plan_each(request, forecasts).map_err(|(_, e)| e)?;
    Ok(reports.remove(0))
}

/// The plans of `request` over each of `forecasts` in place of its own (a launch window's
/// winds): report `i` is, to the last bit, [`plan`]'s for `request` with `forecasts[i]`, and
/// each sample's wind-free part is worked out once for all of them
/// ([`super::monte_carlo_each`]). A refusal names the forecast it is about (0 when it is the
/// request's own).
pub fn plan_each(
    request: &PlanRequest,
    forecasts: &[Vec<ForecastRow>],
) -> Result<Vec<PlanReport>, (usize, PlanError)> {
    let r = request;
    let (frame, target_ne_m) = checked(r).map_err(|e| (0, e))?;
    let alt = r.launch_alt_msl_m;
    let sigma = r.default_wind_sigma_mps;
    let mut winds = Vec::with_capacity(forecasts.len());
    for (i, rows) in forecasts.iter().enumerate() {
        let forecast = Forecast::new(rows.clone()).map_err(|e| (i, e.into()))?;
        let wind = forecast
            .profile(alt)
            .map_err(|e| (i, super::ForecastError::from(e).into()))?;
        winds.push((wind, forecast.sigma_rows(alt, sigma)));
    }
    let Some((first_wind, _)) = winds.first() else {
        return Ok(Vec::new());
    };
    let stack = StackConfig {
        mean_ascent_rate_mps: r.ascent_rate_mps,
        burst_altitude_msl_m: r.burst_altitude_msl_m,
        deploy_height_m: r.deploy_height_m,
        ..StackConfig::default()
    };
    let inputs = PlanInputs {
        start: Start::pad(),
        stack,
        dispersion: Dispersion {
            ascent_rate_sigma_mps: r.ascent_rate_sigma_mps,
            burst_altitude_sigma_m: r.burst_altitude_sigma_m,
            wind_sigma: Vec::new(),
        },
        runs: r.runs as usize,
        target_ne_m,
        region_share_of_best: 0.5,
    };
    let air = Air {
        wind: first_wind,
        atmosphere: &StandardAtmosphere,
        ground_msl_m: alt,
    };
    let cases: Vec<WindCase<'_>> = winds
        .iter()
        .map(|(wind, wind_sigma)| WindCase { wind, wind_sigma })
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(r.seed);
    let spreads = monte_carlo_each(&inputs, &cases, air, &GlidePerformance::default(), &mut rng)
        .map_err(|e| (0, e.into()))?;
    Ok(spreads
        .iter()
        .zip(forecasts)
        .map(|(spread, rows)| report(r, rows, frame, target_ne_m, spread))
        .collect())
}

/// The request's own checks: its launch frame and its target (north, east), m.
fn checked(r: &PlanRequest) -> Result<(LocalFrame, Option<[f64; 2]>), PlanError> {
    let alt = r.launch_alt_msl_m;
    let (rate, burst, deploy) = (r.ascent_rate_mps, r.burst_altitude_msl_m, r.deploy_height_m);
    let (rate_sigma, burst_sigma) = (r.ascent_rate_sigma_mps, r.burst_altitude_sigma_m);
    let sigma = r.default_wind_sigma_mps;
    // The request's own names and a balloon's plausible ranges, before the flight path's
    // checks (which know the settings by other names, and accept any finite rate), in the
    // order a form shows them. Each is also checked to be finite.
    let rules: [(&'static str, f64, bool, &'static str); 11] = [
        (
            "launch_lat_deg",
            r.launch_lat_deg,
            r.launch_lat_deg.abs() <= 89.0,
            "within ±89°",
        ),
        (
            "launch_lon_deg",
            r.launch_lon_deg,
            r.launch_lon_deg.abs() <= 180.0,
            "within ±180°",
        ),
        (
            "launch_alt_msl_m",
            alt,
            (-500.0..=9000.0).contains(&alt),
            "in −500…9000",
        ),
        (
            "runs",
            f64::from(r.runs),
            (1..=MAX_RUNS).contains(&r.runs),
            "in 1…5000",
        ),
        (
            "ascent_rate_mps",
            rate,
            rate > 0.1 && rate <= 50.0,
            "in (0.1, 50]",
        ),
        (
            "ascent_rate_sigma_mps",
            rate_sigma,
            (0.0..=rate).contains(&rate_sigma),
            "in 0…ascent_rate_mps",
        ),
        (
            "burst_altitude_msl_m",
            burst,
            burst > alt + 100.0,
            "over 100 m above the launch site",
        ),
        (
            "burst_altitude_msl_m",
            burst,
            burst < 60_000.0,
            "below 60 000 (a balloon's ceiling)",
        ),
        (
            "burst_altitude_sigma_m",
            burst_sigma,
            (0.0..=10_000.0).contains(&burst_sigma),
            "in 0…10 000",
        ),
        (
            "deploy_height_m",
            deploy,
            deploy >= 0.0 && alt + deploy < burst,
            "≥ 0 and below the burst altitude",
        ),
        (
            "default_wind_sigma_mps",
            sigma,
            (0.0..=50.0).contains(&sigma),
            "in 0…50",
        ),
    ];
    for (field, value, ok, rule) in rules {
        check(field, value, ok, rule)?;
    }
    let frame = LocalFrame {
        lat_deg: r.launch_lat_deg,
        lon_deg: r.launch_lon_deg,
        alt_msl_m: alt,
    };
    let target_ne_m = match r.target_lat_lon_deg {
        Some([lat, lon]) => {
            check("target latitude", lat, lat.abs() <= 90.0, "within ±90°")?;
            check("target longitude", lon, lon.abs() <= 180.0, "within ±180°")?;
            let p = frame.to_ned(lat, lon, alt);
            check(
                "target distance",
                p.x.hypot(p.y),
                p.x.hypot(p.y) < 1.0e6,
                "< 1000 km",
            )?;
            Some([p.x, p.y])
        }
        None => None,
    };
    Ok((frame, target_ne_m))
}

/// The report of `spread`, the plan of `r` over `forecast`.
fn report(
    r: &PlanRequest,
    forecast: &[ForecastRow],
    frame: LocalFrame,
    target_ne_m: Option<[f64; 2]>,
    spread: &PlanSpread,
) -> PlanReport {
    let alt = r.launch_alt_msl_m;
    let geo = |ne: [f64; 2]| {
        let (lat, lon, _) = frame.to_geodetic(&nalgebra::Vector3::new(ne[0], ne[1], 0.0));
        [lat, lon]
    };
    let point = |s: &PointSpread| {
        let [lat_deg, lon_deg] = geo(s.mean_ne_m);
        PlannedPoint {
            lat_deg,
            lon_deg,
            alt_msl_m: alt + s.mean_height_m,
            north_m: s.mean_ne_m[0],
            east_m: s.mean_ne_m[1],
            time_s: s.mean_time_s,
            time_sigma_s: s.time_sigma_s,
            ellipse: s.ellipse,
        }
    };
    let landing = point(&spread.landing);
    let target = r
        .target_lat_lon_deg
        .zip(target_ne_m)
        .map(|([lat, lon], ne)| TargetReach {
            lat_deg: lat,
            lon_deg: lon,
            reachable_probability: spread.target_reachable_probability.unwrap_or(0.0),
            from_unsteered_landing_m: (ne[0] - landing.north_m).hypot(ne[1] - landing.east_m),
        });
    let samples: &[PlanSample] = &spread.samples;
    PlanReport {
        request: PlanRequest {
            forecast: forecast.to_vec(),
            ..r.clone()
        },
        burst: point(spread.burst.as_ref().expect("a plan from the pad bursts")),
        deploy: point(&spread.deploy),
        landing_unsteered: landing,
        round_chute_landing: point(&spread.round_chute_landing),
        steered_region_probability: spread.steered_region.probability,
        steered_region_best_probability: spread.steered_region.best_probability,
        steered_region_lat_lon_deg: spread
            .steered_region
            .outline_ne_m
            .iter()
            .map(|&p| geo(p))
            .collect(),
        steered_reach_radius_m: samples.iter().map(|s| s.reach_radius_m).sum::<f64>()
            / samples.len().max(1) as f64,
        reach_method: "still-air glide disc around the drifted air mass (flight_path::reach)"
            .to_string(),
        target,
        landing_samples_lat_lon_deg: samples.iter().map(|s| geo(s.landing_ne_m)).collect(),
    }
}
