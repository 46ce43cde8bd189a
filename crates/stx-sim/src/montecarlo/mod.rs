//! Monte Carlo of spiral landings: many guided flights with the full model from random release
//! points, headings and winds (sheared and turbulent), sensors on, scored on what the operators
//! care about — distance to the target, landing into the wind, touchdown speed — and on the
//! wind estimate.
//!
//! Every run draws its conditions from its own generator seeded from `(seed, run index)`, so a
//! report depends only on the seed and the run count, never on how the runs were spread over
//! threads or machines: a campaign split into shards ([`Shard`], one [`CampaignPart`] each)
//! and [`merge`]d gives the one-machine report.
//!
//! Beside a campaign, [`nominal_single_landing`] flies the one nominal landing its report names.
//!
//! Every run flies [`MonteCarloConfig::vehicle`] (by default the shipped stack) with its
//! dispersions drawn around it, and guidance plans with the steady-glide table of its
//! [`GuidanceConfig`](stx_gnc::guidance::GuidanceConfig); the report's header names both when
//! they came from vehicle files, so a campaign flown around an identified stack, or planned
//! with one, says so.
//!
//! With keep-out zones ([`MonteCarloConfig::keep_out`]) guidance flies every run with them and
//! the report counts the capsules that came down in one ([`ZoneLandings`]).

mod config;
mod growth;
mod report;
mod run;
mod shard;
mod zones;

use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use stx_dynamics::integrate::IntegrateError;
use stx_dynamics::vehicle::Vehicle;

use crate::closed_loop::Navigator;
use crate::sensors::SensorConfig;
pub use config::{MonteCarloConfig, Shard};
pub use growth::{GROWTH_MISS_M, MissGrowth};
pub use report::{
    CampaignHeader, INTO_WIND_DEG, MonteCarloReport, Stats, WORST_RUNS, WorstRun,
    into_wind_fraction,
};
pub use run::{
    CALM_WIND_MPS, RunConditions, RunResult, SensorsLearned, TrackPoint, conditions, run_one,
    steady_glide_state, wind_field, wind_shape,
};
pub use shard::{CampaignPart, MergeError, merge};
pub use zones::{WIND_BIN_MPS, ZoneCount, ZoneLanding, ZoneLandings};

/// Why the nominal single landing could not be flown.
#[derive(Debug, thiserror::Error)]
pub enum NominalLandingError {
    /// The built-in scenario did not load.
    #[error("the built-in spiral-landing scenario: {0}")]
    Scenario(#[from] crate::scenario::ScenarioError),
    /// Its flight failed.
    #[error("the nominal spiral landing: {0}")]
    Run(#[from] crate::run::RunError),
}

/// The nominal single landing, which a campaign's report names beside its own figures: the
/// built-in `spiral-landing` scenario (the shipped vehicle and no dispersions, the onboard
/// software in closed loop; what `stx sim --scenario spiral-landing` flies): its first contact
/// and the payload's (the capsule's) touchdown, `None` each if the run did not land.
pub fn nominal_single_landing() -> Result<
    (
        Option<crate::summary::Landing>,
        Option<crate::summary::Landing>,
    ),
    NominalLandingError,
> {
    let scenario = crate::scenario::Scenario::builtin("spiral-landing")?;
    let run = crate::open_loop::run(&scenario, &Vehicle::straplex())?;
    Ok((run.summary.landing, run.summary.payload_landing))
}

/// Flies every run on `config.threads` threads, calling `progress(done)` as runs finish.
pub fn run_all<N: Navigator>(
    config: &MonteCarloConfig,
    navigator: impl Fn(&RunConditions, &SensorConfig) -> Result<N, String> + Sync,
    progress: impl Fn(usize) + Sync,
) -> Result<MonteCarloReport, IntegrateError> {
    run_until(config, navigator, progress, || false)
}

/// [`run_all`] with every run navigated as on the drone: its sensors, and the estimator set
/// by `estimator`, seeded by the run (what `stx montecarlo` and the regression tests fly).
pub fn run_sensed(
    config: &MonteCarloConfig,
    estimator: &stx_gnc::estimator::EstimatorConfig,
) -> Result<MonteCarloReport, IntegrateError> {
    run_all(
        config,
        |c, sensors| {
            crate::closed_loop::SensedNavigation::new(sensors, estimator.clone(), c.seed)
                .map_err(|e| e.to_string())
        },
        |_| {},
    )
}

/// [`run_all`] that stops starting runs once `stop()` is true (an operator's cancel, a time
/// cap): the runs in flight finish and the report holds only the runs flown, so a cancelled
/// campaign's report is smaller than asked, never padded.
pub fn run_until<N: Navigator>(
    config: &MonteCarloConfig,
    navigator: impl Fn(&RunConditions, &SensorConfig) -> Result<N, String> + Sync,
    progress: impl Fn(usize) + Sync,
    stop: impl Fn() -> bool + Sync,
) -> Result<MonteCarloReport, IntegrateError> {
    let started = Instant::now();
    let vehicle = &config.vehicle;
    let template = steady_glide_state(vehicle)?;
    let indices = config.indices();
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let mut outcomes: Vec<(usize, Result<RunResult, String>)> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..config.threads.max(1))
            .map(|_| {
                scope.spawn(|| {
                    let mut mine = Vec::new();
                    loop {
                        if stop() {
                            break mine;
                        }
                        let Some(&index) = indices.get(next.fetch_add(1, Ordering::Relaxed)) else {
                            break mine;
                        };
                        mine.push((
                            index,
                            run_one(config, vehicle, &template, index, &navigator),
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
    Ok(MonteCarloReport::assemble(
        CampaignHeader::of(config),
        results,
        failed_runs,
        started.elapsed().as_secs_f64(),
    ))
}
