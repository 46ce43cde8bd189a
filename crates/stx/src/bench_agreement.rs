//! `stx bench agreement`: flies a campaign of whole missions with the station's core beside the
//! simulated drone (`stx_agreement`) and prints how far what the station shows was from the
//! truth, mission by mission, then the campaign against its goals. Exits 1 when a goal is not
//! met, so a script can gate on it.

use anyhow::{Context, bail};
use indicatif::{ProgressBar, ProgressStyle};
use stx_agreement::campaign::{CampaignOptions, MAX_SPEED, Summary, run, specs, summarise};
use stx_agreement::report::MissionReport;

use crate::BadInput;

/// What `stx bench agreement` flies.
#[derive(Debug, Clone)]
pub struct AgreementBenchOptions {
    /// The campaign.
    pub campaign: CampaignOptions,
    /// The keep-out zones file the station loads.
    pub keep_out: Option<std::path::PathBuf>,
    /// Threads.
    pub threads: usize,
    /// Print JSON instead of tables.
    pub json: bool,
}

/// A speed argument: a factor of real time, or `max`.
pub fn parse_speed(s: &str) -> Result<f64, String> {
    if s == "max" {
        return Ok(MAX_SPEED);
    }
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!(
            "`{s}` is not a positive factor of real time or `max`"
        )),
    }
}

pub fn run_bench(options: AgreementBenchOptions) -> anyhow::Result<()> {
    let keep_out = match &options.keep_out {
        Some(path) => Some((
            path.display().to_string(),
            std::fs::read_to_string(path)
                .with_context(|| format!("--keep-out: cannot read {}", path.display()))
                .map_err(BadInput)?,
        )),
        None => None,
    };
    let specs = specs(&options.campaign, keep_out)
        .context("the campaign")
        .map_err(BadInput)?;
    let bar = ProgressBar::new(specs.len() as u64);
    bar.set_style(
        ProgressStyle::with_template(
            "{bar:40} {pos}/{len} missions, {elapsed} elapsed, ~{eta} left",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let started = std::time::Instant::now();
    let results = run(&specs, options.threads, &|_| bar.inc(1));
    bar.finish_and_clear();
    let summary = summarise(&results);
    if options.json {
        let reports: Vec<&MissionReport> = results.iter().filter_map(|r| r.as_ref().ok()).collect();
        println!(
            "{}",
            serde_json::to_string_pretty(&serde_json::json!({
                "missions": reports,
                "summary": summary,
                "wall_time_s": started.elapsed().as_secs_f64(),
            }))?
        );
    } else {
        for r in results.iter().filter_map(|r| r.as_ref().ok()) {
            print_mission(r);
        }
        print_summary(&summary, started.elapsed().as_secs_f64());
    }
    let unmet: Vec<&str> = summary
        .goals
        .iter()
        .filter(|g| !g.met)
        .map(|g| g.name)
        .collect();
    if !unmet.is_empty() {
        bail!("goals not met: {}", unmet.join("; "));
    }
    Ok(())
}

fn print_mission(r: &MissionReport) {
    let landing = r.landing.as_ref();
    let fmt = |v: Option<f64>| v.map_or_else(|| "—".into(), |v| format!("{v:.1}"));
    let predictions = r
        .predictions_at
        .iter()
        .map(|p| {
            format!(
                "{:.0} m: {} / {}",
                p.height_m,
                fmt(p.station_error_m),
                fmt(p.onboard_error_m)
            )
        })
        .collect::<Vec<_>>()
        .join(", ");
    println!(
        "{} seed {} ({}) at {}x, heard {}: phase agreed {:.2} % of {:.0} s under the parafoil (longest apart {:.2} s), final course within {:.1}°, target {:.3} m, trim within {:.3} mm; predicted landing off (station / drone, m) {predictions}; landed {} s: drone {} m, payload {} m from the target, the station says {} m",
        r.mission,
        r.seed,
        r.dispersions,
        r.speed,
        r.delivery,
        100.0 * r.phase.agreed(),
        r.parafoil_s,
        r.longest_phase_span_s(),
        r.final_course_error_deg.max,
        r.target_error_m.max,
        r.trim_error_mm.max,
        fmt(landing.map(|l| l.time_s)),
        fmt(landing.and_then(|l| l.drone_miss_m)),
        fmt(landing.and_then(|l| l.payload_miss_m)),
        fmt(landing.and_then(|l| l.station_miss_m)),
    );
}

fn print_summary(s: &Summary, wall_s: f64) {
    println!(
        "{} missions flown, {} failed, in {wall_s:.0} s: phase agreed over {:.3} % of all parafoil flight (lowest mission {:.3} %), longest disagreement {:.2} s, {} away from a transition",
        s.missions,
        s.failed.len(),
        100.0 * s.phase_agreed_all,
        100.0 * s.phase_agreed_min,
        s.longest_phase_span_s,
        s.phase_spans_away_from_transitions
    );
    for f in &s.failed {
        println!(
            "  FAILED {} seed {} at {}x, heard {}: {}",
            f.mission, f.seed, f.speed, f.delivery, f.error
        );
    }
    for p in &s.predictions {
        println!(
            "  predicted landing at {:.0} m above the ground vs the drone's touchdown: station p50 {:.1} m, p95 {:.1} m, max {:.1} m; the drone's own p50 {:.1} m, p95 {:.1} m, max {:.1} m; the station worse by at most {:.1} m",
            p.height_m,
            p.station_error_m.p50,
            p.station_error_m.p95,
            p.station_error_m.max,
            p.onboard_error_m.p50,
            p.onboard_error_m.p95,
            p.onboard_error_m.max,
            p.worst_excess_over_onboard_m
        );
    }
    println!(
        "  the station's miss against the drone body's true one: p50 {:.1} m, p95 {:.1} m, max {:.1} m (the GPS's error)",
        s.station_miss_error_m.p50, s.station_miss_error_m.p95, s.station_miss_error_m.max
    );
    for g in &s.goals {
        println!(
            "  {} {}: {:.3} (bound {})",
            if g.met { "MET    " } else { "NOT MET" },
            g.name,
            g.measured,
            g.bound
        );
    }
}
