//! `stx compare FILE [--vehicle FILE] [--from S] [--to S] [--json]`: a flight against the
//! model (issue 16 item 1). Reads a station recording (MCAP) or a flight-log CSV (format:
//! `stx_analysis::flight_log::csv`, README "Flight versus model"), keeps the part between
//! `--from` and `--to` (`stx_analysis::flight_log::window`; `stx identify` takes the same
//! flags), flies the vehicle through it with the recorded commands and wind
//! (`stx_analysis::compare`) and prints the error of each channel. Files and printing only.

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;
use stx_analysis::compare::{CompareOptions, CompareReport, compare};
use stx_analysis::flight_log::FlightLog;
use stx_analysis::flight_log::window::{Window, WindowEnd, WindowError};
use stx_lab::flight_file::read_log;

use crate::BadInput;
use crate::inputs::load_vehicle;

#[derive(Args, Debug)]
pub struct CompareArgs {
    /// The flight: a station recording (`.mcap`) or a flight-log CSV (`.csv`).
    #[arg(value_name = "FILE")]
    file: PathBuf,
    /// Vehicle file to fly (default: the shipped STRAPLEX vehicle).
    #[arg(long, value_name = "FILE")]
    vehicle: Option<PathBuf>,
    #[command(flatten)]
    window: WindowArgs,
    /// Print the whole report (series and error figures) as JSON instead of the table.
    #[arg(long)]
    json: bool,
    /// Also write the flight as compared (after the stage and the window) as a flight-log CSV
    /// (`stx_analysis::flight_log::csv`), for other tools or to edit and compare again.
    #[arg(long, value_name = "FILE.csv")]
    write_log: Option<PathBuf>,
}

/// `--from S --to S`: the part of a flight to use (the ascent and a round-chute descent
/// are in a mission's recording too; the model flies the parafoil).
#[derive(Args, Debug, Clone, Copy)]
pub struct WindowArgs {
    /// Use the flight from this time on: seconds from the flight log's first sample, on the
    /// log's own clock (a recording's is the drone's). The model starts from the recorded
    /// state there.
    #[arg(long = "from", value_name = "S")]
    from_s: Option<f64>,
    /// Use the flight up to this time: seconds from the flight log's first sample.
    #[arg(long = "to", value_name = "S")]
    to_s: Option<f64>,
}

impl WindowArgs {
    /// The window, checked before any file is read; bad ends are bad input naming the flag.
    pub fn checked(&self) -> anyhow::Result<Window> {
        let window = Window::new(self.from_s, self.to_s);
        window.check().map_err(|e| flag_error(e, None))?;
        Ok(window)
    }
}

fn flag_error(e: WindowError, path: Option<&Path>) -> anyhow::Error {
    let flag = match e.end() {
        WindowEnd::From => "--from",
        WindowEnd::To => "--to",
        WindowEnd::Both => "--from/--to",
    };
    let e = anyhow::Error::new(e);
    let e = match path {
        Some(path) => e.context(format!("{flag}: {}", path.display())),
        None => e.context(flag),
    };
    BadInput(e).into()
}

/// The flight log of `path` (as the Lab reads one, `stx_lab::flight_file`) cut to `window`;
/// a file that reads as no flight log, or a window holding no flight of it, is bad input.
pub fn read_window(path: &Path, window: &Window) -> anyhow::Result<FlightLog> {
    read_log(path)
        .map_err(|e| BadInput(e.into()))?
        .cut(window)
        .map_err(|e| flag_error(e, Some(path)))
}

/// The per-channel error table.
pub fn table(report: &CompareReport) -> String {
    let mut out = match report.part {
        Some(p) => format!(
            "the recording's parafoil stage, {:.1} … {:.1} s of its {:.1} s (the rest is not the model's to fly)\n",
            p.from_s, p.to_s, p.recorded_s
        ),
        None => String::new(),
    };
    out += &format!(
        "flight of {:.1} s, {} samples; simulated − recorded:\n{:<16} {:>5} {:>10} {:>10} {:>10} {:>7}\n",
        report.duration_s,
        report.time_s.len(),
        "channel",
        "unit",
        "rms",
        "max |e|",
        "bias",
        "samples"
    );
    for c in &report.channels {
        out.push_str(&format!(
            "{:<16} {:>5} {:>10.3} {:>10.3} {:>10.3} {:>7}\n",
            c.name, c.unit, c.error.rms, c.error.max_abs, c.error.bias, c.error.count
        ));
    }
    out
}

pub fn run(args: CompareArgs) -> anyhow::Result<()> {
    let window = args.window.checked()?;
    let log = read_window(&args.file, &window)?;
    if let Some(out) = &args.write_log {
        std::fs::write(out, stx_analysis::flight_log::csv::to_csv(&log))
            .with_context(|| format!("writing {}", out.display()))?;
    }
    let vehicle = load_vehicle(args.vehicle.as_deref())?;
    let report = compare(&log, &vehicle, &CompareOptions::default())
        .with_context(|| format!("flying the model through {}", args.file.display()))
        .map_err(BadInput)?;
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        print!("{}", table(&report));
    }
    Ok(())
}
