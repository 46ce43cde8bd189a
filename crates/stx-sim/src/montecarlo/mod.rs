//! Monte Carlo of spiral landings: many guided flights with the full model from random release
//! points, headings and winds (sheared and turbulent), sensors on, scored on what the operators
//! care about — distance to the target, landing into the wind, touchdown speed — and on the
//! wind estimate.
//!
//! Every run draws its conditions from its own generator seeded from `(seed, run index)`, so a
//! report depends only on the seed and the run count, never on how the runs were spread over
//! threads.

mod config;
mod report;
mod run;

use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use stx_dynamics::integrate::IntegrateError;
use stx_dynamics::vehicle::Vehicle;

use crate::closed_loop::Navigator;
pub use config::MonteCarloConfig;
pub use report::{
    INTO_WIND_DEG, MonteCarloReport, Stats, WORST_RUNS, WorstRun, into_wind_fraction,
};
pub use run::{
    CALM_WIND_MPS, RunConditions, RunResult, TrackPoint, conditions, run_one, steady_glide_state,
    wind_field,
};

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
