//! `stx record`: recordings on the command line (the files themselves are stx-record's).
//! `recover` writes a clean, finished copy of a recording cut short — a station killed in
//! flight, a disk that filled up — keeping every whole chunk up to the cut.

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::{Args, Subcommand};
use stx_record::{RecoverError, recover_file};

use crate::BadInput;

#[derive(Args)]
pub struct RecordArgs {
    #[command(subcommand)]
    command: RecordCommand,
}

#[derive(Subcommand)]
enum RecordCommand {
    /// Write a clean, finished copy of a cut recording: every whole chunk up to the cut, and
    /// the messages still readable in the chunk the cut fell in.
    Recover(RecoverArgs),
}

#[derive(Args)]
struct RecoverArgs {
    /// The recording (MCAP) to recover.
    file: PathBuf,
    /// Where to write the copy; default FILE's name with `.recovered.mcap`. An existing file
    /// is not replaced.
    #[arg(long)]
    out: Option<PathBuf>,
}

pub fn run(args: RecordArgs) -> anyhow::Result<()> {
    match args.command {
        RecordCommand::Recover(args) => recover(args),
    }
}

/// `flight.mcap` → `flight.recovered.mcap`, beside it.
fn default_out(file: &Path) -> PathBuf {
    let stem = file
        .file_stem()
        .unwrap_or(file.as_os_str())
        .to_string_lossy();
    file.with_file_name(format!("{stem}.recovered.mcap"))
}

fn recover(args: RecoverArgs) -> anyhow::Result<()> {
    let out = args.out.unwrap_or_else(|| default_out(&args.file));
    if !args.file.is_file() {
        return Err(BadInput(anyhow::anyhow!("{}: no such file", args.file.display())).into());
    }
    if out.exists() {
        return Err(BadInput(anyhow::anyhow!(
            "{} exists; choose another --out",
            out.display()
        ))
        .into());
    }
    let report = match recover_file(&args.file, &out) {
        Ok(report) => report,
        Err(e) => {
            let _ = std::fs::remove_file(&out);
            return match e {
                RecoverError::NotMcap => {
                    Err(BadInput(anyhow::anyhow!("{}: {e}", args.file.display())).into())
                }
                e => Err(e).with_context(|| format!("recovering {}", args.file.display())),
            };
        }
    };
    match report.cut_at {
        Some(at) => println!(
            "{} was cut at byte {at}: {} messages kept ({} whole chunks{}){}",
            args.file.display(),
            report.messages,
            report.chunks,
            if report.from_cut_chunk > 0 {
                format!(", {} from the chunk the cut fell in", report.from_cut_chunk)
            } else {
                String::new()
            },
            if report.bad_chunks > 0 {
                format!("; {} unreadable chunks skipped", report.bad_chunks)
            } else {
                String::new()
            },
        ),
        None => println!(
            "{} was whole: {} messages copied{}",
            args.file.display(),
            report.messages,
            if report.bad_chunks > 0 {
                format!("; {} unreadable chunks skipped", report.bad_chunks)
            } else {
                String::new()
            },
        ),
    }
    println!("wrote {}", out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_copy_goes_beside_the_file() {
        assert_eq!(
            default_out(Path::new("/r/stx-20260101T000000Z-001.mcap")),
            Path::new("/r/stx-20260101T000000Z-001.recovered.mcap")
        );
        assert_eq!(
            default_out(Path::new("cut")),
            Path::new("cut.recovered.mcap")
        );
    }
}
