//! `stx export FILE --csv DIR | --kml FILE | --gpx FILE`: a recording for spreadsheets,
//! Google Earth and phones (stx_record::export).

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use stx_record::Recording;
use stx_record::export::csv::export_csv;
use stx_record::export::track::{gpx, kml, track};

use crate::BadInput;

#[derive(Args)]
#[command(group(clap::ArgGroup::new("to").required(true).multiple(true).args(["csv", "kml", "gpx"])))]
pub struct ExportArgs {
    /// The recording (MCAP).
    file: PathBuf,
    /// One CSV per channel into this directory (units in the headers).
    #[arg(long, value_name = "DIR")]
    csv: Option<PathBuf>,
    /// The track as KML (Google Earth).
    #[arg(long, value_name = "FILE")]
    kml: Option<PathBuf>,
    /// The track as GPX 1.1.
    #[arg(long, value_name = "FILE")]
    gpx: Option<PathBuf>,
}

pub fn run(args: ExportArgs) -> anyhow::Result<()> {
    let mut recording = Recording::open(&args.file)
        .with_context(|| format!("cannot read the recording {}", args.file.display()))
        .map_err(BadInput)?;
    if let Some(dir) = &args.csv {
        let report = export_csv(&mut recording, dir)
            .with_context(|| format!("CSV export to {}", dir.display()))?;
        for (path, rows) in &report.files {
            println!("{}: {rows} rows", path.display());
        }
        if report.not_positions > 0 {
            eprintln!(
                "{} positions at 0°, 0° (a GPS without a fix) were no positions: left out",
                report.not_positions
            );
        }
        if report.skipped > 0 {
            eprintln!(
                "{} messages were not JSON objects: left out",
                report.skipped
            );
        }
    }
    if args.kml.is_some() || args.gpx.is_some() {
        let (topic, points) = track(&mut recording)
            .with_context(|| format!("the track of {}", args.file.display()))
            .map_err(BadInput)?;
        let name = args
            .file
            .file_stem()
            .map_or_else(|| "stx flight".into(), |s| s.to_string_lossy().into_owned());
        for (path, text) in [
            (&args.kml, args.kml.as_ref().map(|_| kml(&name, &points))),
            (&args.gpx, args.gpx.as_ref().map(|_| gpx(&name, &points))),
        ] {
            if let (Some(path), Some(text)) = (path, text) {
                std::fs::write(path, text)
                    .with_context(|| format!("cannot write {}", path.display()))?;
                println!("{}: {} points of {topic}", path.display(), points.len());
            }
        }
    }
    Ok(())
}
