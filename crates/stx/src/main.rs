//! `stx`: the operators' and engineers' command line. Each subcommand is a thin adapter that
//! reads files and flags, calls the pure crates, and prints results.
//!
//! Exit codes: 0 success, 1 a failure while running, 2 bad input (unknown scenario, invalid
//! file or flag).

mod analyze;
mod bench;
mod compare;
mod drone;
mod export;
mod identify;
mod import;
mod inputs;
mod logging;
mod montecarlo;
mod plan;
mod plan_window;
mod polar;
mod record;
mod relay;
mod replay;
mod serve;
mod sim;
mod token;
mod tune;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "stx",
    version,
    about = "Ground station and simulator for STRAPLEX parafoil landings"
)]
struct Cli {
    /// How log lines (on stderr) are written: `text` (coloured only on a terminal) or `json`
    /// (one object per line, for log collectors).
    #[arg(long, global = true, value_enum, default_value_t = logging::LogFormat::Text)]
    log_format: logging::LogFormat,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Fly a scenario with the flight model and report it.
    Sim(sim::SimArgs),
    /// Measure the flight model's speed.
    Bench(bench::BenchArgs),
    /// Many spiral landings from random releases and winds: landing statistics.
    Montecarlo(montecarlo::MonteCarloArgs),
    /// Run the ground station: drone link, dashboard and API.
    Serve(serve::ServeArgs),
    /// Trim, linearise, eigenvalues and ranks beside the seed's (seed chapter 6).
    Analyze(analyze::AnalyzeArgs),
    /// Tune one controller's gains and write the gains file guidance uses.
    Tune(tune::TuneArgs),
    /// The simulated drone flying a whole mission over a MAVLink link.
    Drone(drone::DroneArgs),
    /// Flight recordings (MCAP): `stx record recover FILE` repairs a cut one.
    Record(record::RecordArgs),
    /// A recording as CSV (one file per channel), KML or GPX.
    Export(export::ExportArgs),
    /// A MAVLink telemetry log (.tlog) as a recording.
    Import(import::ImportArgs),
    /// Play a recording through a station into the dashboard (pause, seek, speed; no commands).
    Replay(replay::ReplayArgs),
    /// The public face of a station for any audience: its page, public state and KML, from one
    /// connection upstream (a station or another relay), optionally delayed and coarsened.
    Relay(relay::RelayArgs),
    /// Pre-flight plan: burst, deploy and landing regions and the target's reachability from a
    /// forecast (and an earlier recording's measured ascent wind).
    Plan(plan::PlanArgs),
    /// A flight (recording or flight-log CSV) against the model: per-channel errors.
    Compare(compare::CompareArgs),
    /// Fit chosen vehicle coefficients to flights (recordings or flight-log CSVs): estimates,
    /// 95 % intervals, correlations and the fitted vehicle file.
    Identify(identify::IdentifyArgs),
    /// A vehicle file's planning polar as the drone's `PL_*` parameters (a parameter file, or
    /// `--json` for the station's API), so guidance plans the next flight with it.
    Polar(polar::PolarArgs),
    /// Station tokens: `stx token new` prints a strong random one as a `[[tokens]]` entry.
    Token(token::TokenArgs),
}

/// An error that is the user's input, not the program's failure (exit code 2).
#[derive(Debug)]
pub struct BadInput(pub anyhow::Error);

impl std::fmt::Display for BadInput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:#}", self.0)
    }
}

impl std::error::Error for BadInput {}

fn main() -> ExitCode {
    let cli = Cli::parse();
    logging::init(cli.log_format);
    if cli.command.is_offline_report() {
        default_sigpipe();
    }
    // The benches run the station in their own process: as the daemon does.
    if matches!(
        cli.command,
        Command::Serve(_) | Command::Replay(_) | Command::Relay(_) | Command::Bench(_)
    ) {
        large_buffers_back_to_the_system();
    }
    let result = match cli.command {
        Command::Sim(args) => sim::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Montecarlo(args) => montecarlo::run(args),
        Command::Serve(args) => serve::run(args),
        Command::Analyze(args) => analyze::run(args),
        Command::Tune(args) => tune::run(args),
        Command::Drone(args) => drone::run(args),
        Command::Record(args) => record::run(args),
        Command::Export(args) => export::run(args),
        Command::Import(args) => import::run(args),
        Command::Replay(args) => replay::run(args),
        Command::Relay(args) => relay::run(args),
        Command::Token(args) => token::run(args),
        Command::Plan(args) => plan::run(args),
        Command::Compare(args) => compare::run(args),
        Command::Identify(args) => identify::run(args),
        Command::Polar(args) => polar::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            if let Some(bad) = error.downcast_ref::<BadInput>() {
                eprintln!("error: {bad}");
                ExitCode::from(2)
            } else {
                eprintln!("error: {error:#}");
                ExitCode::from(1)
            }
        }
    }
}

impl Command {
    /// Commands that only compute and print (no sockets): they may end quietly when their
    /// reader goes away, as `stx analyze | head` expects.
    fn is_offline_report(&self) -> bool {
        matches!(
            self,
            Command::Sim(_)
                | Command::Montecarlo(_)
                | Command::Analyze(_)
                | Command::Tune(_)
                | Command::Record(_)
                | Command::Export(_)
                | Command::Import(_)
                | Command::Token(_)
                | Command::Plan(_)
                | Command::Compare(_)
                | Command::Identify(_)
                | Command::Polar(_)
        )
    }
}

/// A station runs for days, and each page that connects is sent a `history` of a megabyte or
/// more, through buffers as large. glibc's malloc raises its mmap threshold to the largest
/// block freed so far, so after the first such page those buffers come from the heap, and
/// pages coming and going leave it fragmented and large: `stx bench memory` (6 h of mission at
/// 100×, 20 pages coming and going) measured 23.7 MB a minute in and 37.3 MB after the landing
/// that way, and 22.2 MB → 23.7 MB with the threshold fixed at glibc's default of 128 KiB, which
/// maps every large buffer on its own and gives it back when it is freed.
fn large_buffers_back_to_the_system() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: called once at start-up, before any thread is spawned; mallopt only sets a
    // parameter of the allocator.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 128 * 1024);
    }
}

/// Rust ignores SIGPIPE, so a `println!` into a closed pipe panics. A report command gets the
/// default disposition back (ended by the signal, as `cat` would be). The daemon, the drone and
/// the benches keep it ignored: their sockets must see EPIPE as an error, not end the process.
fn default_sigpipe() {
    // SAFETY: called once at start-up, before any thread is spawned; SIG_DFL is a valid handler.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
