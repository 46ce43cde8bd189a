//! `stx tune`: optimise one controller's gains on the linearised closed loop, then on stacks
//! drawn from a dispersion set flown with the sensors and estimator (`--dispersions`,
//! `--draws`), check them on the nonlinear model, write the gains file guidance reads, and
//! plot the step responses.

use std::fs;
use std::io::IsTerminal;
use std::path::PathBuf;

use anyhow::{Context, anyhow};
use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use stx_analysis::figures::tune_figure;
use stx_analysis::gains_file::gains_file;
use stx_analysis::tune::{
    Controller, DEFAULT_ALTITUDE_M, SensedSet, SensedSpec, StepMetrics, TuneReport, tune,
};
use stx_gnc::control::ControlGains;
use stx_gnc::guidance::GuidanceConfig;
use stx_sim::dispersions::Dispersions;
use stx_sim::sensors::SensorConfig;

use crate::BadInput;
use crate::inputs::{load_gains, load_vehicle};

#[derive(Args)]
pub struct TuneArgs {
    /// The controller: heading, course, localizer or vertical.
    #[arg(long)]
    controller: Controller,
    /// Vehicle file (default: the shipped STRAPLEX vehicle).
    #[arg(long)]
    vehicle: Option<PathBuf>,
    /// Altitude of the trim the loop is tuned at, m (the Monte Carlo releases at 600 m).
    #[arg(long, default_value_t = DEFAULT_ALTITUDE_M)]
    altitude: f64,
    /// Gains to start from and keep for the other controllers (default: the --out file if it
    /// exists, else the built-in defaults, which `config/gains.toml` holds).
    #[arg(long)]
    gains: Option<PathBuf>,
    /// The gains file written. The default is a build directory, not `config/`: tuned gains
    /// are flown with `--gains FILE` and become the defaults only after the Monte Carlo gate
    /// of crates/stx-analysis/ANALYSIS_NOTES.md.
    #[arg(long, default_value = DEFAULT_OUT)]
    out: PathBuf,
    /// Where tune-CONTROLLER.json and step-CONTROLLER.svg are written.
    #[arg(long, default_value = "target/analysis")]
    out_dir: PathBuf,
    /// Print the report as one JSON object on stdout.
    #[arg(long)]
    json: bool,
    /// The stacks the gains are last tuned and judged on, flown with the sensors and the
    /// estimator: `nominal`, `realistic` (config/dispersions/) or a dispersion file.
    #[arg(
        long,
        default_value = "realistic",
        value_name = "nominal|realistic|FILE"
    )]
    dispersions: String,
    /// How many stacks are drawn from --dispersions; 0 tunes and judges on the nominal model
    /// with perfect navigation only.
    #[arg(long, default_value_t = 6)]
    draws: usize,
    /// Seed of the draws and of the sensors' noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

/// Where `stx tune` writes its gains unless told: untracked, so that tuning never rewrites the
/// shipped defaults (`config/gains.toml`, which guidance's tests pin).
pub const DEFAULT_OUT: &str = "target/tune/gains.toml";

pub fn run(args: TuneArgs) -> anyhow::Result<()> {
    let vehicle = load_vehicle(args.vehicle.as_deref())?;
    let (start, source) = match (&args.gains, args.out.exists()) {
        (Some(path), _) => (load_gains(path)?, path.display().to_string()),
        (None, true) => (load_gains(&args.out)?, args.out.display().to_string()),
        (None, false) => (ControlGains::default(), "the built-in defaults".to_string()),
    };
    let base = GuidanceConfig {
        gains: start,
        ..GuidanceConfig::default()
    };
    let bar = ProgressBar::with_draw_target(
        None,
        if std::io::stderr().is_terminal() {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        },
    );
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} simulations, {elapsed} elapsed")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let sensed = if args.draws > 0 {
        let dispersions = Dispersions::load(&args.dispersions)
            .map_err(|e| BadInput(anyhow::Error::new(e).context("--dispersions")))?;
        let spec = SensedSpec {
            dispersions,
            sensors: SensorConfig::default(),
            count: args.draws,
            seed: args.seed,
        };
        let set = SensedSet::draw(args.controller, &vehicle, args.altitude, base, &spec);
        for why in &set.excluded {
            tracing::warn!("left out of the sensed check: {why}");
        }
        Some(set)
    } else {
        None
    };
    let report = tune(
        args.controller,
        &vehicle,
        args.altitude,
        base,
        sensed.as_ref(),
        |done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        },
    )
    .map_err(|e| match e {
        stx_analysis::tune::TuneError::Trim(t) => {
            BadInput(anyhow!(t).context(format!("trim at {} m", args.altitude))).into()
        }
        other => anyhow!(other),
    })?;
    bar.finish_and_clear();

    if let Some(parent) = args.out.parent().filter(|p| !p.as_os_str().is_empty()) {
        fs::create_dir_all(parent).with_context(|| format!("creating {}", parent.display()))?;
    }
    fs::write(&args.out, gains_file(&report, &source))
        .with_context(|| format!("writing {}", args.out.display()))?;
    fs::create_dir_all(&args.out_dir)
        .with_context(|| format!("creating {}", args.out_dir.display()))?;
    let name = args.controller.name();
    let json_path = args.out_dir.join(format!("tune-{name}.json"));
    fs::write(&json_path, serde_json::to_string_pretty(&report)?)
        .with_context(|| format!("writing {}", json_path.display()))?;
    let svg_path = args.out_dir.join(format!("step-{name}.svg"));
    fs::write(&svg_path, tune_figure(&report))
        .with_context(|| format!("writing {}", svg_path.display()))?;

    let wrote = format!(
        "wrote {} (from {source}), {}, {}\nfly them with --gains {0} (stx sim, stx montecarlo)",
        args.out.display(),
        json_path.display(),
        svg_path.display()
    );
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
        eprintln!("{wrote}");
    } else {
        print_report(&report);
        println!("\n{wrote}");
    }
    Ok(())
}

/// A gain with three significant figures, however small: the tuner rounds to three, and
/// 0.000226 must not read like 0.00022.
fn gain_text(value: f64) -> String {
    if value == 0.0 || !value.is_finite() {
        return format!("{value}");
    }
    let decimals = (2 - value.abs().log10().floor() as i32).max(0) as usize;
    format!("{value:.decimals$}")
}

/// A gain: the short name people use, its field name (`Controller::gain_names`), its value.
type Gain = (&'static str, &'static str, fn(&ControlGains) -> f64);

/// Every gain a candidate can change.
const GAINS: [Gain; 5] = [
    ("HK1", "hk1_m_per_rad", |g| g.hk1_m_per_rad),
    ("HK2", "hk2_m_s_per_rad", |g| g.hk2_m_s_per_rad),
    ("HK3", "hk3_m_per_m", |g| g.hk3_m_per_m),
    ("VK1", "vk1", |g| g.vk1),
    ("VK2", "vk2_per_m", |g| g.vk2_per_m),
];

/// The tuned gains' values in `gains`, then any other gain that differs from `current`'s
/// (the seed's localizer vector sets HK1 and HK2 as well as HK3).
fn gains_column(controller: Controller, current: &ControlGains, gains: &ControlGains) -> String {
    let tuned: Vec<String> = controller.get(gains).into_iter().map(gain_text).collect();
    let others: Vec<String> = GAINS
        .iter()
        .filter(|(_, field, get)| {
            !controller.gain_names().contains(field) && get(gains) != get(current)
        })
        .map(|(name, _, get)| format!("{name} {}", gain_text(get(gains))))
        .collect();
    if others.is_empty() {
        tuned.join(", ")
    } else {
        format!("{} ({})", tuned.join(", "), others.join(", "))
    }
}

fn fmt_opt(v: Option<f64>) -> String {
    v.map_or("never".into(), |t| format!("{t:.1}"))
}

fn metrics_row(m: &StepMetrics) -> String {
    format!(
        "{:>7} {:>8.1} {:>7} {:>7.2} {:>6.0} {:>7.3}",
        fmt_opt(m.rise_time_s),
        m.overshoot_pct,
        fmt_opt(m.settling_time_s),
        m.command_use,
        100.0 * m.saturated_fraction,
        m.cost
    )
}

fn print_report(r: &TuneReport) {
    println!(
        "Tuning {} ({}) at a {:.0} m trim, airspeed {:.2} m/s",
        r.controller.name(),
        r.gain_names.join(", "),
        r.altitude_m,
        r.trim_airspeed_mps
    );
    println!("experiments: {}", r.experiment);
    if let Some(set) = &r.sensed_set {
        println!(
            "sensed check: {} stacks drawn from the {} dispersions (seed {}), sensors and \
             estimator in the loop, {:.0} s on the reference before each step{}",
            set.draws.len(),
            set.dispersions,
            set.seed,
            set.settle_s,
            if set.excluded.is_empty() {
                String::new()
            } else {
                format!("; left out: {}", set.excluded.join("; "))
            }
        );
    }
    println!(
        "Nelder–Mead: {} linear simulations{}",
        r.evaluations,
        if r.converged {
            ", converged"
        } else {
            ", budget used up"
        }
    );
    println!(
        "\n{:<10} {:<32} {:<6} {:<7} {:>7} {:>8} {:>7} {:>7} {:>6} {:>7}",
        "gains", "values", "step", "model", "rise s", "over %", "settle", "use", "sat %", "cost"
    );
    let (scale, unit) = match r.controller {
        Controller::Heading | Controller::Course => (180.0 / std::f64::consts::PI, "°"),
        _ => (1.0, " m"),
    };
    for c in [&r.current, &r.tuned, &r.seed] {
        let values = gains_column(r.controller, &r.current.gains, &c.gains);
        let mut first = true;
        for trial in [&c.small, &c.large] {
            let step = format!("{:.0}{unit}", trial.step * scale);
            let (label, vals) = if first {
                (c.label.as_str(), values.as_str())
            } else {
                ("", "")
            };
            first = false;
            println!(
                "{label:<10} {vals:<32} {step:<6} {:<7} {}",
                "linear",
                metrics_row(&trial.linear)
            );
            match (&trial.nonlinear, &trial.nonlinear_error) {
                (Some(m), _) => println!(
                    "{:<10} {:<32} {:<6} {:<7} {}",
                    "",
                    "",
                    "",
                    "14-DOF",
                    metrics_row(m)
                ),
                (None, Some(e)) => println!("{:<10} {:<32} {:<6} 14-DOF  failed: {e}", "", "", ""),
                _ => {}
            }
        }
        println!(
            "{:<10} mean cost: linear {:.3}, 14-DOF {}{}; closed-loop max Re λ {:.3} 1/s",
            "",
            c.linear_cost,
            c.nonlinear_cost.map_or("-".into(), |v| format!("{v:.3}")),
            c.sensed.as_ref().map_or(String::new(), |s| format!(
                ", sensed {:.3} ({} failed steps)",
                s.mean, s.failed_steps
            )),
            c.closed_loop_max_real_part
        );
    }
    println!("\n{}", r.verdict);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gains_are_printed_to_three_significant_figures_however_small() {
        // Regression: `{:.4}` printed both of these as 0.0002.
        assert_eq!(gain_text(0.000226), "0.000226");
        assert_eq!(gain_text(0.00022), "0.000220");
        assert_eq!(gain_text(0.0168), "0.0168");
        assert_eq!(gain_text(1.67), "1.67");
        assert_eq!(gain_text(970.0), "970");
        assert_eq!(gain_text(-0.0063), "-0.00630");
    }

    #[test]
    fn the_seed_localizer_row_shows_the_heading_gains_it_changes() {
        // Regression: the row showed HK3 alone though the seed's vector also sets HK1, HK2.
        let current = ControlGains::default();
        let seed = Controller::Localizer.seed_gains(&current);
        assert_eq!(
            gains_column(Controller::Localizer, &current, &seed),
            "0.220 (HK1 0.560, HK2 0.360)"
        );
        // The current gains' own row lists only the tuned gain.
        let own = gains_column(Controller::Localizer, &current, &current);
        assert_eq!(own, gain_text(current.hk3_m_per_m));
        // Heading's row does not repeat HK1, HK2 as "others".
        let heading_seed = Controller::Heading.seed_gains(&current);
        assert_eq!(
            gains_column(Controller::Heading, &current, &heading_seed),
            "0.0160, 0.0210"
        );
    }
}
