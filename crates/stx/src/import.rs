//! `stx import FILE.tlog --out FILE.mcap`: a MAVLink telemetry log (QGroundControl, MAVProxy)
//! as a recording that replays and exports as the station's own do
//! (stx_station::recording::tlog).

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use stx_record::RecordingInfo;
use stx_station::recording::tlog::import_tlog;

use crate::BadInput;

#[derive(Args)]
pub struct ImportArgs {
    /// The telemetry log (.tlog).
    file: PathBuf,
    /// The recording to write (MCAP); an existing file is not replaced.
    #[arg(long)]
    out: PathBuf,
}

pub fn run(args: ImportArgs) -> anyhow::Result<()> {
    let bytes = std::fs::read(&args.file)
        .with_context(|| format!("cannot read {}", args.file.display()))
        .map_err(BadInput)?;
    if args.out.exists() {
        return Err(BadInput(anyhow::anyhow!(
            "{} exists; choose another --out",
            args.out.display()
        ))
        .into());
    }
    let mission = args
        .file
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let info = RecordingInfo::new(env!("CARGO_PKG_VERSION"), "imported", mission);
    let (mcap, report) = import_tlog(&bytes, info)
        .with_context(|| format!("{}", args.file.display()))
        .map_err(BadInput)?;
    std::fs::write(&args.out, mcap)
        .with_context(|| format!("cannot write {}", args.out.display()))?;
    println!(
        "{}: {} frames ({} decoded, {} undecodable){}",
        args.out.display(),
        report.frames,
        report.decoded,
        report.undecodable,
        report
            .stopped_at
            .map(|at| format!("; the log stops making sense at byte {at}: the rest is left out"))
            .unwrap_or_default()
    );
    Ok(())
}
