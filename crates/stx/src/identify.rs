//! `stx identify FILE… --params NAME,… --out FILE [--vehicle FILE] [--from S] [--to S]
//! [--json]`: fit chosen vehicle parameters to flights (issue 16 item 2). Reads recordings
//! and flight-log CSVs as `stx compare` does (the window cutting each file alike), fits with `stx_analysis::identify`, prints each parameter's nominal and
//! fitted values, standard error, 95 % interval and their correlations, and writes the
//! fitted vehicle file. Files and printing only.

use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

use anyhow::Context;
use clap::Args;
use stx_analysis::identify::{IdentifyOptions, IdentifyReport, Param, identify};

use crate::BadInput;
use crate::compare::{WindowArgs, read_window};
use crate::inputs::load_vehicle;

#[derive(Args, Debug)]
pub struct IdentifyArgs {
    /// The flights: station recordings (`.mcap`) or flight-log CSVs (`.csv`).
    #[arg(value_name = "FILE", required = true)]
    files: Vec<PathBuf>,
    /// Parameters to fit, comma-separated: cd0, cd_alpha2, cy_beta, cl0, cl_alpha, clp, cmq,
    /// cnr, cn_beta (canopy), cl_ds, cd_ds, cl_da, cn_da (brakes), rigging_deg (rigging
    /// angle change, degrees).
    #[arg(long, value_name = "NAME,NAME…")]
    params: String,
    /// Where to write the fitted vehicle file.
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
    /// Vehicle file to start from (default: the shipped STRAPLEX vehicle).
    #[arg(long, value_name = "FILE")]
    vehicle: Option<PathBuf>,
    // The same window cuts every file.
    #[command(flatten)]
    window: WindowArgs,
    /// Print the report as JSON instead of the table.
    #[arg(long)]
    json: bool,
    /// Also fit each flight's air-data scale: for recordings whose airspeed (and so whose
    /// wind estimate) reads a few per cent off, as the simulated drone's do.
    #[arg(long)]
    fit_air_scale: bool,
}

/// The parameters, their correlations and the fit's figures.
pub fn table(report: &IdentifyReport) -> String {
    let mut out = format!(
        "{} flight(s), {} residuals; {} iterations ({:?}), {} model flights; \
         residual rms {:.2} → {:.2} (multiples of the sensor noise)\n\
         {:<12} {:>11} {:>11} {:>11} {:>25}\n",
        report.flights,
        report.residuals,
        report.iterations,
        report.stop,
        report.evaluations,
        report.residual_rms_before,
        report.residual_rms_after,
        "parameter",
        "nominal",
        "fitted",
        "std error",
        "95 % interval"
    );
    for p in &report.params {
        let sd = p.std_error.map_or("-".into(), |s| format!("{s:.5}"));
        let interval = p
            .interval95
            .map_or("-".into(), |[lo, hi]| format!("[{lo:.5}, {hi:.5}]"));
        out.push_str(&format!(
            "{:<12} {:>11.5} {:>11.5} {:>11} {:>25}\n",
            p.name, p.initial, p.estimate, sd, interval
        ));
    }
    match &report.correlation {
        Some(rows) => {
            out.push_str(&format!("correlation\n{:<12}", ""));
            for p in &report.params {
                out.push_str(&format!(" {:>11}", p.name));
            }
            out.push('\n');
            for (p, row) in report.params.iter().zip(rows) {
                out.push_str(&format!("{:<12}", p.name));
                for c in row {
                    out.push_str(&format!(" {c:>11.3}"));
                }
                out.push('\n');
            }
        }
        None => out.push_str(
            "correlation: not determined (the flights do not tell the parameters apart)\n",
        ),
    }
    for (i, s) in report.air_scale_percent.iter().enumerate() {
        out.push_str(&format!(
            "flight {}: the air went {s:+.2} % faster than its recorded air data say (fitted)\n",
            i + 1
        ));
    }
    out
}

/// The fitted vehicle file, headed by where its values came from.
fn vehicle_file(report: &IdentifyReport, args: &IdentifyArgs) -> String {
    let mut text = String::from("# Fitted by `stx identify` from");
    for f in &args.files {
        text.push_str(&format!(" {}", f.display()));
    }
    text.push('\n');
    for p in &report.params {
        let sd = p
            .std_error
            .map_or("undetermined".into(), |s| format!("{s:.6}"));
        text.push_str(&format!(
            "# {} = {:.6} (was {:.6}, standard error {sd})\n",
            p.name, p.estimate, p.initial
        ));
    }
    text.push_str(&report.vehicle_toml);
    text
}

pub fn run(args: IdentifyArgs) -> anyhow::Result<()> {
    let params = Param::parse_list(&args.params)
        .context("--params")
        .map_err(BadInput)?;
    let window = args.window.checked()?;
    let vehicle = load_vehicle(args.vehicle.as_deref())?;
    let logs = args
        .files
        .iter()
        .map(|f| read_window(f, &window))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let quiet = args.json;
    let report = identify(
        &logs,
        &params,
        &vehicle.config,
        &IdentifyOptions {
            fit_air_scale: args.fit_air_scale,
            ..IdentifyOptions::default()
        },
        &AtomicBool::new(false),
        &mut |p| {
            if !quiet {
                eprintln!(
                    "iteration {}: residual rms {:.3} ({} model flights)",
                    p.iteration, p.residual_rms, p.evaluations
                );
            }
        },
    )
    .context("identifying")
    .map_err(BadInput)?;
    std::fs::write(&args.out, vehicle_file(&report, &args))
        .with_context(|| format!("writing {}", args.out.display()))?;
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        print!("{}", table(&report));
        println!("wrote {}", args.out.display());
    }
    Ok(())
}
