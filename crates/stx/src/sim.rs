//! `stx sim`: fly a scenario and write its trajectory and summary.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, anyhow};
use clap::Args;
use stx_sim::open_loop;

use crate::BadInput;
use crate::inputs::{load_gains, load_scenario, load_vehicle};

#[derive(Args)]
pub struct SimArgs {
    /// A built-in scenario name (uncontrolled, spiral-exit, stratospheric) or a path to a
    /// scenario TOML file.
    #[arg(long)]
    scenario: String,
    /// Vehicle file (default: the shipped STRAPLEX vehicle).
    #[arg(long)]
    vehicle: Option<PathBuf>,
    /// Write the trajectory to FILE.csv or FILE.json.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Print the summary as one JSON object on stdout.
    #[arg(long)]
    summary_json: bool,
    /// Control gains file (as `stx tune` writes) replacing the scenario's guidance gains.
    #[arg(long)]
    gains: Option<PathBuf>,
}

pub fn run(args: SimArgs) -> anyhow::Result<()> {
    let mut scenario = load_scenario(&args.scenario)?;
    if let Some(path) = &args.gains {
        let gains = load_gains(path)?;
        match scenario.guidance.as_mut() {
            Some(guidance) => guidance.config.gains = gains,
            None => {
                return Err(BadInput(anyhow!(
                    "--gains: scenario {} flies open loop (no [guidance] section)",
                    scenario.name
                ))
                .into());
            }
        }
    }
    let vehicle = load_vehicle(args.vehicle.as_deref())?;
    let format = match &args.out {
        None => None,
        Some(path) => match path.extension().and_then(|e| e.to_str()) {
            Some("csv") => Some(OutFormat::Csv),
            Some("json") => Some(OutFormat::Json),
            _ => {
                return Err(BadInput(anyhow!(
                    "--out {}: the file must end in .csv or .json",
                    path.display()
                ))
                .into());
            }
        },
    };
    let run = open_loop::run(&scenario, &vehicle)
        .with_context(|| format!("running scenario {}", scenario.name))?;
    if let (Some(path), Some(format)) = (&args.out, format) {
        write_trajectory(path, format, &run)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    let summary = &run.summary;
    if args.summary_json {
        println!("{}", serde_json::to_string(summary)?);
    } else {
        println!("{}", serde_json::to_string_pretty(summary)?);
    }
    Ok(())
}

#[derive(Clone, Copy)]
enum OutFormat {
    Csv,
    Json,
}

fn write_trajectory(path: &Path, format: OutFormat, run: &open_loop::Run) -> anyhow::Result<()> {
    let mut out = std::io::BufWriter::new(fs::File::create(path)?);
    match format {
        OutFormat::Csv => {
            writeln!(out, "{}", stx_dynamics::output::Sample::csv_header())?;
            for s in &run.samples {
                writeln!(out, "{}", s.csv_row())?;
            }
        }
        OutFormat::Json => serde_json::to_writer(&mut out, run)?,
    }
    out.flush()?;
    Ok(())
}
