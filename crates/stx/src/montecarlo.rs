//! `stx montecarlo`: many spiral landings with the full model, sensors and onboard software,
//! from random release points and winds; prints the landing statistics.

use anyhow::{Context, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use stx_gnc::estimator::EstimatorConfig;
use stx_sim::closed_loop::SensedNavigation;
use stx_sim::montecarlo::{MonteCarloConfig, MonteCarloReport, run_all};
use stx_sim::sensors::SensorConfig;

use crate::BadInput;

#[derive(Args)]
pub struct MonteCarloArgs {
    /// Number of runs.
    #[arg(long, default_value_t = 100)]
    runs: usize,
    /// Seed: the same seed gives the same result.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Largest mean wind speed drawn, m/s (uniform from 0).
    #[arg(long, default_value_t = 4.0)]
    wind_max: f64,
    /// Release height above the target, m.
    #[arg(long, default_value_t = 600.0)]
    altitude: f64,
    /// Fly without the flare, to measure what it is worth.
    #[arg(long)]
    no_flare: bool,
    /// Worker threads (default: every core).
    #[arg(long)]
    threads: Option<usize>,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    json: bool,
    /// Include every run in the JSON.
    #[arg(long)]
    details: bool,
    /// Fly only run INDEX of the campaign (as listed under `worst`), and print it with its
    /// phase events and track as JSON.
    #[arg(long, value_name = "INDEX")]
    replay: Option<usize>,
    /// Control gains file (as `stx tune` writes; default: the built-in gains).
    #[arg(long)]
    gains: Option<std::path::PathBuf>,
}

pub fn run(args: MonteCarloArgs) -> anyhow::Result<()> {
    if args.runs == 0 {
        return Err(BadInput(anyhow::anyhow!("--runs must be at least 1")).into());
    }
    if !(args.wind_max >= 0.0 && args.wind_max.is_finite()) {
        return Err(BadInput(anyhow::anyhow!("--wind-max must be a finite speed ≥ 0 m/s")).into());
    }
    if !(args.altitude > 20.0 && args.altitude <= 30_000.0) {
        return Err(BadInput(anyhow::anyhow!("--altitude must be in (20, 30000] m")).into());
    }
    if let Some(index) = args.replay
        && index >= args.runs
    {
        return Err(BadInput(anyhow::anyhow!(
            "--replay {index} is not a run of a {}-run campaign",
            args.runs
        ))
        .into());
    }
    let threads = args
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let mut config = MonteCarloConfig {
        runs: args.runs,
        seed: args.seed,
        wind_max_mps: args.wind_max,
        altitude_m: args.altitude,
        flare: !args.no_flare,
        threads,
        only_run: args.replay,
        ..MonteCarloConfig::default()
    };
    if let Some(path) = &args.gains {
        config.guidance.gains = crate::inputs::load_gains(path)?;
    }
    let sensors = SensorConfig::default();
    let estimator = EstimatorConfig::default();
    // Fail on bad settings before any thread starts.
    SensedNavigation::new(&sensors, estimator.clone(), 0).context("navigation settings")?;
    let bar = ProgressBar::new(args.runs as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} runs, {elapsed} elapsed, ~{eta} left")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let report = run_all(
        &config,
        |c| SensedNavigation::new(&sensors, estimator.clone(), c.seed).map_err(|e| e.to_string()),
        |done| bar.set_position(done as u64),
    )
    .context("Monte Carlo")?;
    bar.finish_and_clear();
    if !report.failed_runs.is_empty() && report.failed_runs.len() == report.runs {
        bail!("every run failed; first: {:?}", report.failed_runs.first());
    }
    if args.replay.is_some() {
        match report.results.first() {
            Some(run) => println!("{}", serde_json::to_string(run)?),
            None => bail!("the run failed: {:?}", report.failed_runs),
        }
    } else if args.json {
        let mut value = serde_json::to_value(&report)?;
        if !args.details
            && let Some(object) = value.as_object_mut()
        {
            object.remove("results");
        }
        println!("{}", serde_json::to_string(&value)?);
    } else {
        print_table(&report);
    }
    Ok(())
}

fn print_table(r: &MonteCarloReport) {
    println!(
        "{} runs, seed {}, wind up to {} m/s, released {} m above the target{}",
        r.runs,
        r.seed,
        r.wind_max_mps,
        r.altitude_m,
        if r.flare { "" } else { ", no flare" }
    );
    println!(
        "miss distance: median {:.1} m, 95th percentile {:.1} m, worst {:.1} m",
        r.miss_m.median, r.miss_m.p95, r.miss_m.max
    );
    println!(
        "into the wind (within 30°): {:.1} % of touchdowns ({} in calm air, below 0.5 m/s, count \
         as into the wind; judged like the others: {:.1} %)",
        100.0 * r.into_wind_fraction,
        r.calm_runs,
        100.0 * r.into_wind_fraction_strict
    );
    println!(
        "touchdown vertical speed: median {:.2} m/s, 95th percentile {:.2} m/s",
        r.touchdown_vertical_speed_mps.median, r.touchdown_vertical_speed_mps.p95
    );
    println!(
        "wind estimate error after 30 s: {:.2} m/s RMS (per run: median {:.2}, worst {:.2})",
        r.wind_estimate_rmse_mps,
        r.wind_estimate_rmse_per_run_mps.median,
        r.wind_estimate_rmse_per_run_mps.max
    );
    println!("target out of reach in {} runs", r.unreachable_runs);
    if r.unreachable_runs > 0 {
        println!(
            "  touchdown from the best reachable point announced first: median {:.0} m, worst \
             {:.0} m; announced last: median {:.0} m, worst {:.0} m",
            r.unreachable_from_best_m.median,
            r.unreachable_from_best_m.max,
            r.unreachable_from_last_best_m.median,
            r.unreachable_from_last_best_m.max
        );
    }
    if !r.failed_runs.is_empty() {
        println!("{} runs failed: {:?}", r.failed_runs.len(), r.failed_runs);
    }
    for w in &r.worst {
        println!(
            "worst: run {} missed by {:.1} m ({:+.1} m long, {:+.1} m right), heading {:+.0}° \
             from upwind, wind {:.1} m/s (--replay {})",
            w.index,
            w.miss_m,
            w.long_short_m,
            w.left_right_m,
            w.heading_vs_upwind_deg,
            w.conditions.wind_speed_mps,
            w.index
        );
    }
    println!("wall time {:.1} s", r.wall_time_s);
}
