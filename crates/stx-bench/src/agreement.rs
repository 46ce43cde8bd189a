//! `stx bench agreement`: flies a campaign of whole missions with the station's core beside the
//! simulated drone (`stx_agreement`) and says how far what the station shows was from the
//! truth, mission by mission, then the campaign against its goals. The command line exits 1
//! when a goal is not met ([`Flown::unmet`]), so a script can gate on it; the campaign's
//! inputs ([`specs`]) are the operator's, their errors bad input.

use std::fmt;
use std::path::Path;
use std::time::Instant;

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use stx_agreement::campaign::{CampaignOptions, Failed, MAX_SPEED, Summary, run, summarise};
use stx_agreement::mission::MissionSpec;
use stx_agreement::report::MissionReport;

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

/// The missions of `campaign`, the station loading the keep-out zones of the file `keep_out`.
/// Every error is in what was asked (a file, a mission, a dispersion set).
pub fn specs(
    campaign: &CampaignOptions,
    keep_out: Option<&Path>,
) -> anyhow::Result<Vec<MissionSpec>> {
    let keep_out = match keep_out {
        Some(path) => Some((
            path.display().to_string(),
            std::fs::read_to_string(path)
                .with_context(|| format!("--keep-out: cannot read {}", path.display()))?,
        )),
        None => None,
    };
    stx_agreement::campaign::specs(campaign, keep_out).context("the campaign")
}

/// A flown campaign. Its [`fmt::Display`] is the tables: one line a mission, then the campaign
/// against its goals.
pub struct Flown {
    /// Each mission's report, in the order of the specs.
    pub results: Vec<Result<MissionReport, Failed>>,
    /// The campaign's figures and goals.
    pub summary: Summary,
    /// Real time the campaign took, s.
    pub wall_time_s: f64,
}

/// Flies `specs` on `threads` threads, a progress bar on the terminal meanwhile.
pub fn fly(specs: &[MissionSpec], threads: usize) -> Flown {
    let bar = ProgressBar::new(specs.len() as u64);
    bar.set_style(
        ProgressStyle::with_template(
            "{bar:40} {pos}/{len} missions, {elapsed} elapsed, ~{eta} left",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let started = Instant::now();
    let results = run(specs, threads, &|_| bar.inc(1));
    bar.finish_and_clear();
    let summary = summarise(&results);
    Flown {
        results,
        summary,
        wall_time_s: started.elapsed().as_secs_f64(),
    }
}

impl Flown {
    /// The campaign as one JSON object: the missions flown, the summary, the wall time.
    pub fn json(&self) -> serde_json::Value {
        let reports: Vec<&MissionReport> = self
            .results
            .iter()
            .filter_map(|r| r.as_ref().ok())
            .collect();
        serde_json::json!({
            "missions": reports,
            "summary": self.summary,
            "wall_time_s": self.wall_time_s,
        })
    }

    /// The goals not met, by name.
    pub fn unmet(&self) -> Vec<&'static str> {
        self.summary
            .goals
            .iter()
            .filter(|g| !g.met)
            .map(|g| g.name)
            .collect()
    }
}

impl fmt::Display for Flown {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for r in self.results.iter().filter_map(|r| r.as_ref().ok()) {
            mission(f, r)?;
        }
        summary(f, &self.summary, self.wall_time_s)
    }
}

fn mission(f: &mut fmt::Formatter<'_>, r: &MissionReport) -> fmt::Result {
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
    writeln!(
        f,
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
    )
}

fn summary(f: &mut fmt::Formatter<'_>, s: &Summary, wall_s: f64) -> fmt::Result {
    writeln!(
        f,
        "{} missions flown, {} failed, in {wall_s:.0} s: phase agreed over {:.3} % of all parafoil flight (lowest mission {:.3} %), longest disagreement {:.2} s, {} away from a transition",
        s.missions,
        s.failed.len(),
        100.0 * s.phase_agreed_all,
        100.0 * s.phase_agreed_min,
        s.longest_phase_span_s,
        s.phase_spans_away_from_transitions
    )?;
    for x in &s.failed {
        writeln!(
            f,
            "  FAILED {} seed {} at {}x, heard {}: {}",
            x.mission, x.seed, x.speed, x.delivery, x.error
        )?;
    }
    for p in &s.predictions {
        writeln!(
            f,
            "  predicted landing at {:.0} m above the ground vs the drone's touchdown: station p50 {:.1} m, p95 {:.1} m, max {:.1} m; the drone's own p50 {:.1} m, p95 {:.1} m, max {:.1} m; the station worse by at most {:.1} m",
            p.height_m,
            p.station_error_m.p50,
            p.station_error_m.p95,
            p.station_error_m.max,
            p.onboard_error_m.p50,
            p.onboard_error_m.p95,
            p.onboard_error_m.max,
            p.worst_excess_over_onboard_m
        )?;
    }
    writeln!(
        f,
        "  the station's miss against the drone body's true one: p50 {:.1} m, p95 {:.1} m, max {:.1} m (the GPS's error)",
        s.station_miss_error_m.p50, s.station_miss_error_m.p95, s.station_miss_error_m.max
    )?;
    for g in &s.goals {
        writeln!(
            f,
            "  {} {}: {:.3} (bound {})",
            if g.met { "MET    " } else { "NOT MET" },
            g.name,
            g.measured,
            g.bound
        )?;
    }
    Ok(())
}
