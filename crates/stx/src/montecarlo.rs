//! `stx montecarlo`: many spiral landings with the full model, sensors and onboard software,
//! from random release points and winds; prints the landing statistics.
//!
//! `--vehicle FILE` flies every run around a vehicle file (the truth, e.g. one `stx identify` or
//! the Lab wrote); `--guidance-vehicle FILE` makes guidance plan with that file's steady glide,
//! trimmed at each brake setting ([`stx_analysis::performance::glide_performance_of`]). Given
//! both, a campaign measures what planning with an identified stack is worth against the
//! shipped table; the report's header names each file given.

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::{Args, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use stx_gnc::estimator::EstimatorConfig;
use stx_gnc::geo::LocalFrame;
use stx_gnc::keep_out::{self, KeepOutZones};
use stx_sim::closed_loop::SensedNavigation;
use stx_sim::dispersions::Dispersions;
use stx_sim::montecarlo::{
    CampaignPart, MonteCarloConfig, MonteCarloReport, Shard, ZoneLandings, run_all,
};

use crate::BadInput;
use crate::drone::load_vehicle_flag;

#[derive(Args)]
#[command(args_conflicts_with_subcommands = true)]
pub struct MonteCarloArgs {
    #[command(subcommand)]
    command: Option<MonteCarloCommand>,
    #[command(flatten)]
    campaign: CampaignArgs,
}

#[derive(Subcommand)]
enum MonteCarloCommand {
    /// Merge the parts written by `--shard K/N --out FILE` into the campaign's report.
    Merge {
        /// Every part of the campaign (one per shard).
        #[arg(required = true)]
        parts: Vec<PathBuf>,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
        /// Include every run in the JSON.
        #[arg(long)]
        details: bool,
    },
}

#[derive(Args)]
struct CampaignArgs {
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
    gains: Option<PathBuf>,
    /// How each run's world differs from the one guidance assumes: `nominal`, `realistic`
    /// (config/dispersions/) or a dispersion file.
    #[arg(long, default_value = "nominal", value_name = "nominal|realistic|FILE")]
    dispersions: String,
    /// Fly only shard K of N of the campaign (runs K−1, K−1+N, …) and write them with `--out`;
    /// `stx montecarlo merge` puts the parts together.
    #[arg(long, value_name = "K/N", requires = "out", conflicts_with = "replay")]
    shard: Option<String>,
    /// Where `--shard` writes its part (JSON).
    #[arg(long, requires = "shard")]
    out: Option<PathBuf>,
    /// Keep-out zones (GeoJSON, as the station's `keep_out`) around the target, which lies at
    /// the default site (38.5333° N, 7.8889° W): guidance keeps out of them and the report
    /// counts the capsules landed in one, by wind (e.g. config/keep-out/montecarlo.geojson).
    #[arg(long, value_name = "FILE.geojson")]
    keep_out: Option<PathBuf>,
    /// Do not give guidance the `--keep-out` zones; only count the landings in them (what
    /// keeping out is worth is the difference).
    #[arg(long, requires = "keep_out")]
    keep_out_unguided: bool,
    /// Give guidance a simulated ground anemometer by the target (a 10-m mast reporting the
    /// mean of 10 s every 5 s, with a drawn calibration and vane error): the surface wind it
    /// plans the final with below the pattern
    #[arg(long)]
    anemometer: bool,
    /// Fly every run around this vehicle file (the truth; e.g. one `stx identify` or the Lab
    /// wrote) instead of the shipped STRAPLEX stack: the dispersions are drawn around it.
    /// Guidance still plans with its shipped table unless `--guidance-vehicle` is given.
    #[arg(long, value_name = "FILE")]
    vehicle: Option<PathBuf>,
    /// Guidance plans with the steady glide of this vehicle file (trimmed at each brake setting
    /// 100 m above sea level; the turn terms stay the shipped table's, a trim does not identify
    /// them) instead of the shipped table.
    #[arg(long, value_name = "FILE")]
    guidance_vehicle: Option<PathBuf>,
}

pub fn run(args: MonteCarloArgs) -> anyhow::Result<()> {
    match args.command {
        Some(MonteCarloCommand::Merge {
            parts,
            json,
            details,
        }) => merge(&parts, json, details),
        None => campaign(args.campaign),
    }
}

fn merge(paths: &[PathBuf], json: bool, details: bool) -> anyhow::Result<()> {
    let mut parts = Vec::new();
    for path in paths {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("reading part {}", path.display()))?;
        let part: CampaignPart = serde_json::from_str(&text).map_err(|e| {
            BadInput(anyhow::anyhow!(
                "{} is not a campaign part: {e}",
                path.display()
            ))
        })?;
        parts.push(part);
    }
    let report = stx_sim::montecarlo::merge(parts).map_err(|e| BadInput(e.into()))?;
    print_report(&report, json, details)
}

fn print_report(report: &MonteCarloReport, json: bool, details: bool) -> anyhow::Result<()> {
    let (nominal, nominal_payload) =
        stx_sim::montecarlo::nominal_single_landing().context("nominal landing")?;
    if json {
        let mut value = serde_json::to_value(report)?;
        if let Some(object) = value.as_object_mut() {
            if !details {
                object.remove("results");
            }
            object.insert(
                "nominal_single_landing".into(),
                serde_json::to_value(nominal)?,
            );
            object.insert(
                "nominal_single_payload_landing".into(),
                serde_json::to_value(nominal_payload)?,
            );
        }
        println!("{}", serde_json::to_string(&value)?);
    } else {
        print_table(report);
        if let Some(landing) = nominal {
            println!(
                "nominal single landing (stx sim --scenario spiral-landing): {} touched {:.1} m \
                 from the target",
                landing.body,
                landing.miss_m.unwrap_or(f64::NAN)
            );
        }
        if let Some(payload) = nominal_payload.filter(|p| Some(p) != nominal.as_ref()) {
            println!(
                "  then the payload: the {} touched {:.1} m from the target",
                payload.body,
                payload.miss_m.unwrap_or(f64::NAN)
            );
        }
    }
    Ok(())
}

fn campaign(args: CampaignArgs) -> anyhow::Result<()> {
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
    let shard = args
        .shard
        .as_deref()
        .map(Shard::parse)
        .transpose()
        .map_err(|e| BadInput(anyhow::anyhow!("--shard: {e}")))?;
    let dispersions = Dispersions::load(&args.dispersions)
        .map_err(|e| BadInput(anyhow::Error::new(e).context("--dispersions")))?;
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
        shard,
        dispersions,
        anemometer: args.anemometer,
        ..MonteCarloConfig::default()
    };
    if let Some(path) = &args.gains {
        config.guidance.gains = crate::inputs::load_gains(path)?;
    }
    if let Some(path) = &args.vehicle {
        config.vehicle = load_vehicle_flag("--vehicle", path)?;
        config.vehicle_name = Some(path.display().to_string());
    }
    if let Some(path) = &args.guidance_vehicle {
        config.guidance.performance = crate::inputs::load_polar("--guidance-vehicle", path)?;
        config.guidance_vehicle_name = Some(path.display().to_string());
    }
    if let Some(path) = &args.keep_out {
        config.keep_out = load_zones(path)?;
        config.keep_out_guided = !args.keep_out_unguided;
    }
    let estimator = EstimatorConfig::default();
    // Fail on bad settings before any thread starts.
    SensedNavigation::new(&config.sensors, estimator.clone(), 0).context("navigation settings")?;
    let bar = ProgressBar::new(config.indices().len() as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} runs, {elapsed} elapsed, ~{eta} left")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let report = run_all(
        &config,
        |c, sensors| {
            SensedNavigation::new(sensors, estimator.clone(), c.seed).map_err(|e| e.to_string())
        },
        |done| bar.set_position(done as u64),
    )
    .context("Monte Carlo")?;
    bar.finish_and_clear();
    if !report.failed_runs.is_empty() && report.failed_runs.len() == report.runs {
        bail!("every run failed; first: {:?}", report.failed_runs.first());
    }
    if let (Some(shard), Some(out)) = (shard, &args.out) {
        let part = CampaignPart::of(report, shard);
        let text = serde_json::to_string(&part)?;
        std::fs::write(out, text).with_context(|| format!("writing {}", out.display()))?;
        eprintln!(
            "shard {}/{}: {} runs ({} failed) in {:.1} s written to {}",
            shard.index,
            shard.count,
            part.results.len() + part.failed_runs.len(),
            part.failed_runs.len(),
            part.wall_time_s,
            out.display()
        );
        return Ok(());
    }
    if args.replay.is_some() {
        match report.results.first() {
            Some(run) => println!("{}", serde_json::to_string(run)?),
            None => bail!("the run failed: {:?}", report.failed_runs),
        }
        return Ok(());
    }
    print_report(&report, args.json, args.details)
}

/// The zones of `path` around the campaign's target, which must lie outside every one.
fn load_zones(path: &std::path::Path) -> anyhow::Result<KeepOutZones> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("--keep-out: cannot read {}", path.display()))
        .map_err(BadInput)?;
    let zones = keep_out::from_geojson(&text, &LocalFrame::default())
        .map_err(|e| BadInput(anyhow::anyhow!("--keep-out {}: {e}", path.display())))?;
    if let Some(zone) = zones.zone_at([0.0, 0.0]) {
        return Err(BadInput(anyhow::anyhow!(
            "--keep-out {}: the target (38.5333° N, 7.8889° W) lies in zone '{}'",
            path.display(),
            zone.name
        ))
        .into());
    }
    Ok(zones)
}

fn print_zone_landings(z: &ZoneLandings) {
    println!(
        "capsules landed in a keep-out zone ({}; guidance {}): {} of {} landings ({} failed runs \
         not counted)",
        z.zones.join(", "),
        if z.guided {
            "kept out"
        } else {
            "did not know them"
        },
        z.in_zone,
        z.landings,
        z.failed
    );
    for b in &z.by_wind {
        println!(
            "  wind {:.0}–{:.0} m/s: {} of {}",
            b.wind_from_mps, b.wind_to_mps, b.in_zone, b.landings
        );
    }
    for l in &z.runs {
        println!(
            "  run {} in '{}' at {:.0} m N, {:.0} m E of the target, wind {:.1} m/s (--replay {})",
            l.index, l.zone, l.payload_ne_m[0], l.payload_ne_m[1], l.wind_mps, l.index
        );
    }
}

fn print_table(r: &MonteCarloReport) {
    let c = &r.campaign;
    println!(
        "{} runs, seed {}, wind up to {} m/s, released {} m above the target{}{}, dispersions: \
         {}, vehicle: {}, guidance planned with: {}",
        r.runs,
        c.seed,
        c.wind_max_mps,
        c.altitude_m,
        if c.flare { "" } else { ", no flare" },
        if c.anemometer {
            ", surface anemometer"
        } else {
            ""
        },
        c.dispersions.name,
        c.vehicle.as_deref().unwrap_or("shipped STRAPLEX"),
        c.guidance_vehicle
            .as_deref()
            .map_or("the shipped table".to_string(), |f| format!(
                "the glide of {f}"
            ))
    );
    println!(
        "miss distance (first ground contact; {} failed runs count as misses): median {:.1} m, \
         95th percentile {:.1} m, worst {:.1} m",
        r.failed_runs.len(),
        r.miss_m.median,
        r.miss_m.p95,
        r.miss_m.max
    );
    println!(
        "payload (capsule) miss: median {:.1} m, 95th percentile {:.1} m, worst {:.1} m; its \
         vertical speed at touchdown: median {:.2} m/s, 95th percentile {:.2} m/s",
        r.payload_miss_m.median,
        r.payload_miss_m.p95,
        r.payload_miss_m.max,
        r.payload_touchdown_vertical_speed_mps.median,
        r.payload_touchdown_vertical_speed_mps.p95
    );
    println!(
        "into the wind (within 30°): {:.1} % of touchdowns ({} in calm air, below 0.5 m/s, count \
         as into the wind; judged like the others: {:.1} %; of the others alone: {:.1} %, or \
         {:.1} % against their mean surface wind, gusts left out)",
        100.0 * r.into_wind_fraction,
        r.calm_runs,
        100.0 * r.into_wind_fraction_strict,
        100.0 * r.into_wind_fraction_non_calm,
        100.0 * r.into_surface_wind_fraction_non_calm
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
    println!(
        "learnt at touchdown, error: AHRS heading bias median {:.1}°, 95th percentile {:.1}°; \
         pitot scale median {:.3}, 95th percentile {:.3}",
        r.heading_bias_error_deg.median,
        r.heading_bias_error_deg.p95,
        r.pitot_scale_error.median,
        r.pitot_scale_error.p95
    );
    println!(
        "payload miss where guidance found the target within reach ({} runs): median {:.1} m, \
         95th percentile {:.1} m, worst {:.1} m",
        r.runs - r.unreachable_runs,
        r.reachable_payload_miss_m.median,
        r.reachable_payload_miss_m.p95,
        r.reachable_payload_miss_m.max
    );
    println!("target out of reach in {} runs", r.unreachable_runs);
    if r.unreachable_runs > 0 {
        println!(
            "  their payload miss: median {:.0} m, worst {:.0} m; touchdown from the best \
             reachable point announced first: median {:.0} m, worst {:.0} m; announced last: \
             median {:.0} m, 95th percentile {:.0} m, worst {:.0} m",
            r.unreachable_payload_miss_m.median,
            r.unreachable_payload_miss_m.max,
            r.unreachable_from_best_m.median,
            r.unreachable_from_best_m.max,
            r.unreachable_from_last_best_m.median,
            r.unreachable_from_last_best_m.p95,
            r.unreachable_from_last_best_m.max
        );
        println!(
            "  {} of them found the target within reach again and flew for it; the payload from \
             the point chosen last (that target, else the best reachable point announced last): \
             median {:.0} m, 95th percentile {:.0} m, worst {:.0} m",
            r.unreachable_back_in_reach_runs,
            r.unreachable_payload_from_last_aim_m.median,
            r.unreachable_payload_from_last_aim_m.p95,
            r.unreachable_payload_from_last_aim_m.max
        );
    }
    if let Some(z) = &r.keep_out {
        print_zone_landings(z);
    }
    if !r.failed_runs.is_empty() {
        println!("{} runs failed: {:?}", r.failed_runs.len(), r.failed_runs);
    }
    for w in &r.worst {
        println!(
            "worst: run {}, payload missed by {:.1} m, {}{}{} ({:+.1} m long, {:+.1} m right; \
             first contact {:.1} m), heading {:+.0}° from upwind, wind {:.1} m/s (--replay {})",
            w.index,
            w.payload_miss_m,
            w.cause,
            if w.unreachable { ", out of reach" } else { "" },
            w.miss_grew.map_or(String::new(), |g| if g.grew_m < 1.0 {
                // Never grew: the landing was expected that far off from the first kept
                // moment on (a release out of reach).
                ", expected from 30 s after release".to_string()
            } else {
                format!(
                    ", grew {:.0} m in {:?} from {:.0} m up",
                    g.grew_m, g.phase, g.from_height_m
                )
            }),
            w.long_short_m,
            w.left_right_m,
            w.miss_m,
            w.heading_vs_upwind_deg,
            w.conditions.wind_speed_mps,
            w.index
        );
    }
    println!("wall time {:.1} s", r.wall_time_s);
}
