//! Monte Carlo of spiral landings: many guided flights with the full model from random release
//! points, headings and winds (sheared and turbulent), sensors on, scored on what the operators
//! care about — distance to the target, landing into the wind, touchdown speed — and on the
//! wind estimate.
//!
//! Every run draws its conditions from its own generator seeded from `(seed, run index)`, so a
//! report depends only on the seed and the run count, never on how the runs were spread over
//! threads.

use std::f64::consts::PI;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use nalgebra::Vector3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use stx_dynamics::atmosphere::StandardAtmosphere;
use stx_dynamics::integrate::{Hooks, IntegrateError, Rk4, integrate};
use stx_dynamics::model::{Environment, ParafoilModel};
use stx_dynamics::rotation::wrap_pi;
use stx_dynamics::state::{Pose, StateVector, idx};
use stx_dynamics::vehicle::Vehicle;
use stx_dynamics::wind::{
    ProfileRow, Turbulence, TurbulenceParams, WindComposite, WindField, WindProfile,
};
use stx_gnc::guidance::{Guidance, GuidanceConfig, PhaseEvent, Plan};
use stx_gnc::mission::{FlightMode, GuidancePhase};

use crate::closed_loop::{GuidedFlight, Navigator};

/// What to run.
#[derive(Debug, Clone, Serialize)]
pub struct MonteCarloConfig {
    /// Number of runs.
    pub runs: usize,
    /// Seed of the whole campaign.
    pub seed: u64,
    /// Largest mean wind speed drawn, m/s.
    pub wind_max_mps: f64,
    /// Release height above the target, m.
    pub altitude_m: f64,
    /// Release points are drawn uniformly within this distance of the target, m.
    pub release_radius_m: f64,
    /// Whether guidance flares (a campaign without it measures what the flare is worth).
    pub flare: bool,
    /// Worker threads.
    pub threads: usize,
    /// Fly only this run (by index), keeping its phase events and track: replays one run of a
    /// campaign exactly, since its conditions depend only on the seed and the index.
    pub only_run: Option<usize>,
    /// Guidance settings.
    #[serde(skip)]
    pub guidance: GuidanceConfig,
}

impl Default for MonteCarloConfig {
    fn default() -> Self {
        Self {
            runs: 100,
            seed: 1,
            wind_max_mps: 4.0,
            altitude_m: 600.0,
            release_radius_m: 400.0,
            flare: true,
            threads: 2,
            only_run: None,
            guidance: GuidanceConfig::default(),
        }
    }
}

/// The conditions of one run.
#[derive(Debug, Clone, Serialize)]
pub struct RunConditions {
    /// Release point relative to the target (north, east), m.
    pub release_ne_m: [f64; 2],
    /// Heading at release, degrees.
    pub heading_deg: f64,
    /// Mean wind speed, m/s.
    pub wind_speed_mps: f64,
    /// Direction it blows from at the ground, degrees.
    pub wind_from_deg: f64,
    /// Seed of this run's turbulence and sensors.
    pub seed: u64,
}

/// What one run gave.
#[derive(Debug, Clone, Serialize)]
pub struct RunResult {
    /// Index in the campaign.
    pub index: usize,
    /// Its conditions.
    pub conditions: RunConditions,
    /// Distance from the target to where the stack touched down, m.
    pub miss_m: f64,
    /// Canopy heading at touchdown minus the upwind direction, degrees.
    pub heading_vs_upwind_deg: f64,
    /// The mean wind where the stack touched down (gusts left out) was below
    /// [`CALM_WIND_MPS`]: there is no upwind to land into.
    pub calm: bool,
    /// Vertical speed of the first body to touch, m/s.
    pub touchdown_vertical_speed_mps: f64,
    /// RMS of the horizontal wind-estimate error from 30 s after release on, m/s.
    pub wind_estimate_rmse_mps: f64,
    /// Guidance found the target out of reach at some point.
    pub unreachable: bool,
    /// The best reachable point (north, east, m) guidance announced when it first called the
    /// target out of reach.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub best_reachable_ne_m: Option<[f64; 2]>,
    /// Distance from that point to where the stack touched down, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub from_best_reachable_m: Option<f64>,
    /// The best reachable point guidance announced last (it announces it again when it moves
    /// as the wind estimate firms up), north and east, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub last_best_reachable_ne_m: Option<[f64; 2]>,
    /// Distance from that point to the touchdown, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub from_last_best_reachable_m: Option<f64>,
    /// Flight time, s.
    pub flight_time_s: f64,
    /// Touchdown point relative to the target along the upwind direction (positive: beyond
    /// the target, i.e. long) and across it (positive right), m.
    pub long_short_m: f64,
    /// See `long_short_m`.
    pub left_right_m: f64,
    /// Guidance phase changes with their reasons (kept only when one run is replayed).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub events: Vec<PhaseEvent>,
    /// The flight every second (kept only when one run is replayed).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub track: Vec<TrackPoint>,
}

/// One second of a replayed run: truth and what guidance saw.
#[derive(Debug, Clone, Serialize)]
pub struct TrackPoint {
    /// Time, s.
    pub time_s: f64,
    /// True canopy position (north, east, height above the target), m.
    pub position_neh_m: [f64; 3],
    /// Estimated wind (north, east), m/s.
    pub wind_estimate_ne_mps: [f64; 2],
    /// True wind at the canopy (north, east), m/s.
    pub wind_ne_mps: [f64; 2],
    /// Guidance phase.
    pub phase: GuidancePhase,
    /// Final-approach height the spiral plans with, m.
    pub final_approach_height_m: f64,
    /// Symmetric brake commanded, 0…1.
    pub brake: f64,
}

/// A run among the worst of a campaign, enough to replay it (`only_run`).
#[derive(Debug, Clone, Serialize)]
pub struct WorstRun {
    /// Index in the campaign.
    pub index: usize,
    /// Miss distance, m.
    pub miss_m: f64,
    /// Long (+) or short (−) along the upwind direction, m.
    pub long_short_m: f64,
    /// Right (+) or left (−) of it, m.
    pub left_right_m: f64,
    /// Heading at touchdown minus upwind, degrees.
    pub heading_vs_upwind_deg: f64,
    /// Its conditions.
    pub conditions: RunConditions,
}

/// Median, 95th percentile, maximum and mean of a sample.
#[derive(Debug, Clone, Copy, Serialize, Default)]
pub struct Stats {
    /// Median.
    pub median: f64,
    /// 95th percentile (nearest rank).
    pub p95: f64,
    /// Largest.
    pub max: f64,
    /// Mean.
    pub mean: f64,
}

impl Stats {
    /// Statistics of `values` (NaN-free).
    pub fn of(values: &[f64]) -> Self {
        if values.is_empty() {
            return Self::default();
        }
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        let rank =
            |q: f64| sorted[((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len()) - 1];
        Self {
            median: if sorted.len() % 2 == 1 {
                sorted[sorted.len() / 2]
            } else {
                0.5 * (sorted[sorted.len() / 2 - 1] + sorted[sorted.len() / 2])
            },
            p95: rank(0.95),
            max: sorted[sorted.len() - 1],
            mean: sorted.iter().sum::<f64>() / sorted.len() as f64,
        }
    }
}

/// The campaign's result (printed by `stx montecarlo --json`).
#[derive(Debug, Clone, Serialize)]
pub struct MonteCarloReport {
    /// Runs flown.
    pub runs: usize,
    /// Campaign seed.
    pub seed: u64,
    /// Largest mean wind, m/s.
    pub wind_max_mps: f64,
    /// Release height above the target, m.
    pub altitude_m: f64,
    /// Whether guidance flared.
    pub flare: bool,
    /// Distance from the target at touchdown, m.
    pub miss_m: Stats,
    /// Share of touchdowns with the heading within 30° of upwind (runs in calm air, where no
    /// upwind exists, count as into the wind).
    pub into_wind_fraction: f64,
    /// The same share with calm runs judged like the others, against the instantaneous wind
    /// (gusts included) where they touched down.
    pub into_wind_fraction_strict: f64,
    /// Runs that touched down in calm air (mean wind below [`CALM_WIND_MPS`]).
    pub calm_runs: usize,
    /// Vertical speed at touchdown, m/s.
    pub touchdown_vertical_speed_mps: Stats,
    /// RMS of the wind-estimate error from 30 s after release, over all runs, m/s.
    pub wind_estimate_rmse_mps: f64,
    /// Per-run wind-estimate RMS errors, m/s.
    pub wind_estimate_rmse_per_run_mps: Stats,
    /// Runs in which guidance found the target out of reach.
    pub unreachable_runs: usize,
    /// Over those runs, the distance from the best reachable point guidance first announced
    /// to the touchdown, m.
    pub unreachable_from_best_m: Stats,
    /// The same from the best reachable point announced last, m.
    pub unreachable_from_last_best_m: Stats,
    /// Runs that failed to fly (integration error), with their index and reason.
    pub failed_runs: Vec<(usize, String)>,
    /// Wall-clock time, s.
    pub wall_time_s: f64,
    /// The runs with the largest misses, worst first (at most [`WORST_RUNS`]).
    pub worst: Vec<WorstRun>,
    /// Every run.
    pub results: Vec<RunResult>,
}

/// Below this mean surface wind, m/s (about 1 kn), the air counts as calm: weather reports
/// (METAR) give a wind under 1 kn as calm, with no direction. Below it the gusts of a run outweigh its mean
/// wind and turn the instantaneous wind through any direction in seconds, so "upwind" at
/// touchdown is not something guidance could have known a final approach earlier.
pub const CALM_WIND_MPS: f64 = 0.5;

/// Largest angle between heading and upwind at touchdown that counts as into the wind, degrees.
pub const INTO_WIND_DEG: f64 = 30.0;

/// Share of `results` that touched down into the wind (within [`INTO_WIND_DEG`] of upwind);
/// with `calm_counts`, runs in calm air count as into the wind whatever their heading.
pub fn into_wind_fraction(results: &[RunResult], calm_counts: bool) -> f64 {
    if results.is_empty() {
        return 0.0;
    }
    let into_wind = results
        .iter()
        .filter(|r| (calm_counts && r.calm) || r.heading_vs_upwind_deg.abs() <= INTO_WIND_DEG)
        .count();
    into_wind as f64 / results.len() as f64
}

/// How many of the worst runs a report names.
pub const WORST_RUNS: usize = 5;

/// A steady glide (after the seed's initial conditions settle in still air), heading north at
/// the origin: the template every run's release state is rotated and moved from.
pub fn steady_glide_state(vehicle: &Vehicle) -> Result<StateVector, IntegrateError> {
    let mut model = ParafoilModel::new(
        vehicle.clone(),
        Environment {
            atmosphere: Arc::new(StandardAtmosphere),
            wind: Arc::new(stx_dynamics::wind::Calm),
            ground_altitude_msl_m: 0.0,
        },
    );
    let pose = Pose {
        position_ned_m: [0.0, 0.0, -1000.0],
        canopy_euler_deg: [0.0, 6.5, 0.0],
        canopy_velocity_mps: [3.3, 0.0, 1.0],
        line_pitch_deg: -9.0,
        drone_euler_deg: [0.0, 20.0, 0.0],
        capsule_angles_deg: [0.0, -7.0],
        transponder_angles_deg: [0.0, 5.0],
        ..Default::default()
    };
    let outcome = integrate(
        &mut Rk4::new(0.02),
        &mut model,
        0.0,
        &pose.to_state(),
        40.0,
        Hooks::default(),
    )?;
    let mut x = outcome.state;
    x[idx::POSITION] = 0.0;
    x[idx::POSITION + 1] = 0.0;
    x[idx::POSITION + 2] = 0.0;
    x[idx::CANOPY_EULER + 2] = 0.0;
    Ok(x)
}

/// Draws the conditions of run `index`.
pub fn conditions(config: &MonteCarloConfig, index: usize) -> RunConditions {
    let seed = config
        .seed
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add(index as u64);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let radius = config.release_radius_m * rng.random::<f64>().sqrt();
    let bearing = 2.0 * PI * rng.random::<f64>();
    RunConditions {
        release_ne_m: [radius * bearing.cos(), radius * bearing.sin()],
        heading_deg: 360.0 * rng.random::<f64>() - 180.0,
        wind_speed_mps: config.wind_max_mps * rng.random::<f64>(),
        wind_from_deg: 360.0 * rng.random::<f64>(),
        seed: rng.random::<u64>(),
    }
}

/// The wind of a run: the mean speed sheared over height (±20 % about the mean from the
/// ground to the release height, veering up to ±20°) plus Dryden turbulence of 10 % of the
/// mean speed (at least 0.1 m/s).
pub fn wind_field(
    c: &RunConditions,
    altitude_m: f64,
) -> Result<WindComposite, stx_dynamics::wind::WindError> {
    let mut rng = ChaCha8Rng::seed_from_u64(c.seed ^ 0x005E_ED0F_517D);
    let shear = 0.4 * rng.random::<f64>() - 0.2;
    let veer_deg = 40.0 * rng.random::<f64>() - 20.0;
    let rows = (0..=4)
        .map(|k| {
            let f = k as f64 / 4.0;
            ProfileRow {
                altitude_m: f * (altitude_m + 100.0),
                speed_mps: c.wind_speed_mps * (1.0 - shear + 2.0 * shear * f),
                from_deg: (c.wind_from_deg + veer_deg * f).rem_euclid(360.0),
            }
        })
        .collect();
    let sigma = (0.1 * c.wind_speed_mps).max(0.1);
    let turbulence = Turbulence::new(TurbulenceParams {
        sigma_horizontal_mps: sigma,
        sigma_vertical_mps: 0.5 * sigma,
        length_scale_horizontal_m: 200.0,
        length_scale_vertical_m: 50.0,
        reference_airspeed_mps: 6.7,
        seed: c.seed,
        components: 24,
    })?;
    Ok(WindComposite {
        mean: Box::new(WindProfile::new(rows)?),
        turbulence: Some(turbulence),
    })
}

/// Flies run `index` with navigation from `navigator(&conditions)`.
pub fn run_one<N: Navigator>(
    config: &MonteCarloConfig,
    vehicle: &Vehicle,
    template: &StateVector,
    index: usize,
    navigator: impl Fn(&RunConditions) -> Result<N, String>,
) -> Result<RunResult, String> {
    let c = conditions(config, index);
    let composite = Arc::new(wind_field(&c, config.altitude_m).map_err(|e| e.to_string())?);
    let wind: Arc<dyn WindField> = composite.clone();
    let model = ParafoilModel::new(
        vehicle.clone(),
        Environment {
            atmosphere: Arc::new(StandardAtmosphere),
            wind: wind.clone(),
            ground_altitude_msl_m: stx_gnc::geo::LocalFrame::default().alt_msl_m,
        },
    );
    let mut x = *template;
    x[idx::POSITION] = c.release_ne_m[0];
    x[idx::POSITION + 1] = c.release_ne_m[1];
    x[idx::POSITION + 2] = -config.altitude_m;
    x[idx::CANOPY_EULER + 2] = c.heading_deg.to_radians();
    let mut guidance_config = config.guidance;
    guidance_config.spiral.flare = config.flare;
    let mut guidance = Guidance::new(guidance_config);
    guidance.set_plan(
        Plan {
            target_ned_m: Vector3::zeros(),
            ..Plan::default()
        },
        0.0,
    );
    guidance.set_mode(FlightMode::SpiralLanding, 0.0);
    let mut flight = GuidedFlight::new(
        model,
        x,
        0.0,
        guidance,
        navigator(&c)?,
        crate::guided::STEP_S,
        crate::guided::CONTROL_PERIOD_S,
    );
    let mut wind_error_sq = 0.0;
    let mut wind_samples = 0usize;
    let replay = config.only_run == Some(index);
    let mut track = Vec::new();
    let mut next_track_s = 0.0;
    let touchdown = loop {
        if let Some(t) = flight.advance().map_err(|e| e.to_string())? {
            break t;
        }
        if replay
            && let Some(est) = flight.estimate
            && est.time_s >= next_track_s
        {
            next_track_s += 1.0;
            let p = Vector3::new(
                flight.state[idx::POSITION],
                flight.state[idx::POSITION + 1],
                flight.state[idx::POSITION + 2],
            );
            let truth = wind.wind_ned_mps(est.time_s, &p);
            track.push(TrackPoint {
                time_s: est.time_s,
                position_neh_m: [p.x, p.y, -p.z],
                wind_estimate_ne_mps: [est.wind_ned_mps.x, est.wind_ned_mps.y],
                wind_ne_mps: [truth.x, truth.y],
                phase: flight.guidance.phase(),
                final_approach_height_m: flight.guidance.spiral_status().final_approach_height_m,
                brake: flight.model.controls().brake_left,
            });
        }
        if let Some(est) = flight.estimate
            && est.time_s >= 30.0
        {
            let truth = wind.wind_ned_mps(est.time_s, &est.position_ned_m);
            let (dn, de) = (est.wind_ned_mps.x - truth.x, est.wind_ned_mps.y - truth.y);
            wind_error_sq += dn * dn + de * de;
            wind_samples += 1;
        }
        if flight.time_s > 4.0 * config.altitude_m {
            return Err(format!(
                "run {index} still flying after {} s",
                flight.time_s
            ));
        }
    };
    let heading_vs_upwind = if touchdown.upwind_rad.is_finite() {
        wrap_pi(touchdown.heading_rad - touchdown.upwind_rad).to_degrees()
    } else {
        0.0
    };
    let mean_wind_at_touchdown = composite.mean.wind_ned_mps(
        touchdown.time_s,
        &Vector3::new(touchdown.position_ne_m[0], touchdown.position_ne_m[1], 0.0),
    );
    let first_announced = flight.best_reachable_announced.first().map(|(_, ne)| *ne);
    let last_announced = flight.best_reachable_announced.last().map(|(_, ne)| *ne);
    let from_touchdown =
        |b: [f64; 2]| (touchdown.position_ne_m[0] - b[0]).hypot(touchdown.position_ne_m[1] - b[1]);
    Ok(RunResult {
        index,
        miss_m: touchdown.position_ne_m[0].hypot(touchdown.position_ne_m[1]),
        heading_vs_upwind_deg: heading_vs_upwind,
        calm: mean_wind_at_touchdown.x.hypot(mean_wind_at_touchdown.y) < CALM_WIND_MPS,
        touchdown_vertical_speed_mps: touchdown.vertical_speed_mps,
        wind_estimate_rmse_mps: if wind_samples > 0 {
            (wind_error_sq / wind_samples as f64).sqrt()
        } else {
            0.0
        },
        unreachable: !flight.best_reachable_announced.is_empty(),
        best_reachable_ne_m: first_announced,
        from_best_reachable_m: first_announced.map(from_touchdown),
        last_best_reachable_ne_m: last_announced,
        from_last_best_reachable_m: last_announced.map(from_touchdown),
        flight_time_s: touchdown.time_s,
        long_short_m: if touchdown.upwind_rad.is_finite() {
            touchdown.position_ne_m[0] * touchdown.upwind_rad.cos()
                + touchdown.position_ne_m[1] * touchdown.upwind_rad.sin()
        } else {
            0.0
        },
        left_right_m: if touchdown.upwind_rad.is_finite() {
            -touchdown.position_ne_m[0] * touchdown.upwind_rad.sin()
                + touchdown.position_ne_m[1] * touchdown.upwind_rad.cos()
        } else {
            0.0
        },
        conditions: c,
        events: if replay {
            std::mem::take(&mut flight.events)
        } else {
            Vec::new()
        },
        track,
    })
}

/// Flies every run on `config.threads` threads, calling `progress(done)` as runs finish.
pub fn run_all<N: Navigator>(
    config: &MonteCarloConfig,
    navigator: impl Fn(&RunConditions) -> Result<N, String> + Sync,
    progress: impl Fn(usize) + Sync,
) -> Result<MonteCarloReport, IntegrateError> {
    let started = Instant::now();
    let vehicle = Vehicle::straplex();
    let template = steady_glide_state(&vehicle)?;
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let mut outcomes: Vec<(usize, Result<RunResult, String>)> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..config.threads.max(1))
            .map(|_| {
                scope.spawn(|| {
                    let mut mine = Vec::new();
                    loop {
                        let index = match config.only_run {
                            Some(only) if next.fetch_add(1, Ordering::Relaxed) == 0 => only,
                            Some(_) => break mine,
                            None => next.fetch_add(1, Ordering::Relaxed),
                        };
                        if index >= config.runs && config.only_run.is_none() {
                            break mine;
                        }
                        mine.push((
                            index,
                            run_one(config, &vehicle, &template, index, &navigator),
                        ));
                        progress(done.fetch_add(1, Ordering::Relaxed) + 1);
                    }
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().unwrap_or_default())
            .collect()
    });
    outcomes.sort_by_key(|(i, _)| *i);
    let mut results = Vec::new();
    let mut failed_runs = Vec::new();
    for (index, outcome) in outcomes {
        match outcome {
            Ok(r) => results.push(r),
            Err(e) => failed_runs.push((index, e)),
        }
    }
    let misses: Vec<f64> = results.iter().map(|r| r.miss_m).collect();
    let speeds: Vec<f64> = results
        .iter()
        .map(|r| r.touchdown_vertical_speed_mps)
        .collect();
    let wind_errors: Vec<f64> = results.iter().map(|r| r.wind_estimate_rmse_mps).collect();
    let pooled = if results.is_empty() {
        0.0
    } else {
        (wind_errors.iter().map(|e| e * e).sum::<f64>() / wind_errors.len() as f64).sqrt()
    };
    let mut by_miss: Vec<&RunResult> = results.iter().collect();
    by_miss.sort_by(|a, b| b.miss_m.total_cmp(&a.miss_m));
    let worst = by_miss
        .iter()
        .take(WORST_RUNS)
        .map(|r| WorstRun {
            index: r.index,
            miss_m: r.miss_m,
            long_short_m: r.long_short_m,
            left_right_m: r.left_right_m,
            heading_vs_upwind_deg: r.heading_vs_upwind_deg,
            conditions: r.conditions.clone(),
        })
        .collect();
    Ok(MonteCarloReport {
        runs: results.len() + failed_runs.len(),
        seed: config.seed,
        wind_max_mps: config.wind_max_mps,
        altitude_m: config.altitude_m,
        flare: config.flare,
        miss_m: Stats::of(&misses),
        into_wind_fraction: into_wind_fraction(&results, true),
        into_wind_fraction_strict: into_wind_fraction(&results, false),
        calm_runs: results.iter().filter(|r| r.calm).count(),
        touchdown_vertical_speed_mps: Stats::of(&speeds),
        wind_estimate_rmse_mps: pooled,
        wind_estimate_rmse_per_run_mps: Stats::of(&wind_errors),
        unreachable_runs: results.iter().filter(|r| r.unreachable).count(),
        unreachable_from_best_m: Stats::of(
            &results
                .iter()
                .filter_map(|r| r.from_best_reachable_m)
                .collect::<Vec<_>>(),
        ),
        unreachable_from_last_best_m: Stats::of(
            &results
                .iter()
                .filter_map(|r| r.from_last_best_reachable_m)
                .collect::<Vec<_>>(),
        ),
        failed_runs,
        wall_time_s: started.elapsed().as_secs_f64(),
        worst,
        results,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn landed(heading_vs_upwind_deg: f64, calm: bool) -> RunResult {
        RunResult {
            index: 0,
            conditions: conditions(&MonteCarloConfig::default(), 0),
            miss_m: 1.0,
            heading_vs_upwind_deg,
            calm,
            touchdown_vertical_speed_mps: 2.5,
            wind_estimate_rmse_mps: 0.2,
            unreachable: false,
            best_reachable_ne_m: None,
            from_best_reachable_m: None,
            last_best_reachable_ne_m: None,
            from_last_best_reachable_m: None,
            flight_time_s: 200.0,
            long_short_m: 0.0,
            left_right_m: 0.0,
            events: Vec::new(),
            track: Vec::new(),
        }
    }

    #[test]
    fn into_the_wind_means_within_30_degrees_of_upwind_on_either_side() {
        let runs = [
            landed(29.0, false),
            landed(-30.0, false),
            landed(31.0, false),
            landed(-179.0, false),
        ];
        assert_eq!(into_wind_fraction(&runs, true), 0.5);
        assert_eq!(into_wind_fraction(&runs, false), 0.5);
    }

    #[test]
    fn a_calm_touchdown_counts_as_into_the_wind_whatever_its_heading_except_when_strict() {
        let runs = [landed(150.0, true), landed(150.0, false)];
        assert_eq!(into_wind_fraction(&runs, true), 0.5);
        assert_eq!(into_wind_fraction(&runs, false), 0.0);
        assert_eq!(into_wind_fraction(&[], true), 0.0);
    }
}
