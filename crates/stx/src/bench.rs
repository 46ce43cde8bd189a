//! `stx bench`: measured speed figures, printed as a table or JSON.
//!
//! `stx bench dynamics` is `stx_sim::speed` (derivative evaluations per second, and the
//! stratospheric descent's real-time factor per integrator); `stx bench memory`,
//! `stx bench station` and `stx bench relay` measure the station daemon, and `stx bench agreement` flies whole
//! missions and holds what the station shows against the truth: the measuring is `stx_bench`'s,
//! the flags, the printing and the exit code are here.

use anyhow::{Context, bail};
use clap::{Args, Subcommand};
use stx_bench::{agreement, memory, relay, station};

use crate::BadInput;

#[derive(Args)]
pub struct BenchArgs {
    #[command(subcommand)]
    what: BenchWhat,
}

#[derive(Subcommand)]
enum BenchWhat {
    /// Whole missions, pad to landing, with the station beside the simulated drone: what the
    /// station shows held against the truth every control period (exits 1 if a goal is not
    /// met).
    Agreement {
        /// Print one JSON object instead of tables.
        #[arg(long)]
        json: bool,
        /// The short campaign of the test command instead of the full one.
        #[arg(long)]
        short: bool,
        /// Built-in missions (comma-separated); default: the campaign's.
        #[arg(long, value_delimiter = ',')]
        missions: Option<Vec<String>>,
        /// Seeds (comma-separated); default: the campaign's.
        #[arg(long, value_delimiter = ',')]
        seeds: Option<Vec<u64>>,
        /// Speeds, factors of real time or `max` (comma-separated); default: 20,max.
        #[arg(long, value_delimiter = ',', value_parser = agreement::parse_speed)]
        speeds: Option<Vec<f64>>,
        /// Dispersion set: `nominal`, `realistic` or a file; default: realistic.
        #[arg(long)]
        dispersions: Option<String>,
        /// Fly no flight with the station hearing the drone in bursts of several control
        /// periods (by default each flight is also flown so at 20×).
        #[arg(long)]
        no_bursts: bool,
        /// The station's keep-out zones.
        #[arg(long, default_value = "config/keep-out/sample.geojson")]
        keep_out: std::path::PathBuf,
        /// Threads flying missions at once.
        #[arg(long, default_value_t = 2)]
        threads: usize,
    },
    /// Flight-model evaluations per second and the stratospheric descent's real-time factor.
    Dynamics {
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
        /// Seconds spent timing derivative evaluations.
        #[arg(long, default_value_t = 2.0)]
        eval_seconds: f64,
    },
    /// The station daemon's memory after an accelerated three-hour mission (`stx serve`, the
    /// simulated drone in its own process).
    Memory {
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
        /// Length of the launch day in mission time, hours.
        #[arg(long, default_value_t = 3.0)]
        mission_hours: f64,
        /// Mission time per real time.
        #[arg(long, default_value_t = 100.0)]
        speed: f64,
        /// Dashboard pages connected throughout.
        #[arg(long, default_value_t = 5)]
        clients: usize,
    },
    /// What a public relay's audience costs the station: telemetry → station page without
    /// and with `stx relay` serving its viewers, the station's and the relay's memory (exits
    /// 1 if a goal is not met).
    Relay {
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
        /// Viewers on the relay.
        #[arg(long, default_value_t = 1000)]
        viewers: usize,
        /// Operator pages on the station timing telemetry.
        #[arg(long, default_value_t = 4)]
        pages: usize,
        /// Telemetry bursts timed in each window (without and with the relay).
        #[arg(long, default_value_t = 240)]
        frames: usize,
        /// Telemetry bursts per second (the drone's control rate).
        #[arg(long, default_value_t = 4.0)]
        frame_rate_hz: f64,
    },
    /// The station's latencies on loopback: telemetry → WebSocket pages, command → MAVLink.
    Station {
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
        /// WebSocket pages connected while telemetry flows.
        #[arg(long, default_value_t = 50)]
        clients: usize,
        /// Telemetry bursts timed (each the drone's full set for one control period).
        #[arg(long, default_value_t = 240)]
        frames: usize,
        /// Telemetry bursts per second (the drone's control rate).
        #[arg(long, default_value_t = 4.0)]
        frame_rate_hz: f64,
        /// Commands timed.
        #[arg(long, default_value_t = 200)]
        commands: usize,
        /// Record the run (MCAP) into this directory, as `stx serve` does; default: off.
        #[arg(long, value_name = "DIR")]
        record_dir: Option<std::path::PathBuf>,
        /// While telemetry is timed, flood the station from other loopback addresses: 1,000
        /// wrong-token requests and 200 WebSocket connects and disconnects a second.
        #[arg(long)]
        abuse: bool,
        /// While telemetry is timed, keep Lab Monte Carlo batches of N runs going (each started
        /// over the API as the Lab page does, the next as soon as one ends; the last cancelled
        /// after the window).
        #[arg(long, value_name = "N")]
        lab_montecarlo: Option<u32>,
    },
}

pub fn run(args: BenchArgs) -> anyhow::Result<()> {
    match args.what {
        BenchWhat::Agreement {
            json,
            short,
            missions,
            seeds,
            speeds,
            dispersions,
            no_bursts,
            keep_out,
            threads,
        } => {
            let mut campaign = if short {
                stx_agreement::campaign::CampaignOptions::short()
            } else {
                stx_agreement::campaign::CampaignOptions::full()
            };
            if let Some(m) = missions {
                campaign.missions = m;
            }
            if let Some(s) = seeds {
                campaign.seeds = s;
                campaign.seeds_of.clear();
            }
            if let Some(s) = speeds {
                campaign.speeds = s;
            }
            if let Some(d) = dispersions {
                campaign.dispersions = Some(d);
            }
            campaign.bursts &= !no_bursts;
            let specs = agreement::specs(&campaign, Some(&keep_out)).map_err(BadInput)?;
            let flown = agreement::fly(&specs, threads);
            if json {
                println!("{}", serde_json::to_string_pretty(&flown.json())?);
            } else {
                print!("{flown}");
            }
            let unmet = flown.unmet();
            if !unmet.is_empty() {
                bail!("goals not met: {}", unmet.join("; "));
            }
            Ok(())
        }
        BenchWhat::Memory {
            json,
            mission_hours,
            speed,
            clients,
        } => {
            let report = memory::run(&memory::MemoryBenchOptions {
                stx: std::env::current_exe().context("this program's path")?,
                mission_s: mission_hours * 3600.0,
                speed,
                clients,
            })?;
            if json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                print!("{report}");
            }
            if !report.landed {
                bail!("the simulated drone did not land in time");
            }
            Ok(())
        }
        BenchWhat::Station {
            json,
            clients,
            frames,
            frame_rate_hz,
            commands,
            record_dir,
            abuse,
            lab_montecarlo,
        } => {
            let report = station::run(&station::StationBenchOptions {
                clients,
                frames,
                frame_rate_hz,
                commands,
                record_dir,
                abuse,
                lab_montecarlo,
            })?;
            if json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                print!("{report}");
            }
            Ok(())
        }
        BenchWhat::Relay {
            json,
            viewers,
            pages,
            frames,
            frame_rate_hz,
        } => {
            let report = relay::run(&relay::RelayBenchOptions {
                stx: std::env::current_exe().context("this program's path")?,
                viewers,
                pages,
                frames,
                frame_rate_hz,
            })?;
            if json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                print!("{report}");
            }
            let unmet = report.unmet();
            if !unmet.is_empty() {
                bail!("goals not met: {}", unmet.join("; "));
            }
            Ok(())
        }
        BenchWhat::Dynamics { json, eval_seconds } => {
            let report = stx_sim::speed::measure(eval_seconds, |run| {
                if !json {
                    eprintln!(
                        "{}: landing {:.3} m from its reference, {:.0}× real time",
                        run.setting.describe(),
                        run.landing_error_vs_reference_m.unwrap_or(f64::NAN),
                        run.real_time_factor
                    );
                }
            })?;
            if json {
                println!("{}", serde_json::to_string(&report)?);
            } else {
                println!(
                    "derivative evaluations: {:.0}/s ({:.0} ns each)",
                    report.derivative_evals_per_s, report.derivative_eval_ns
                );
                for (run, _) in &report.passing {
                    println!(
                        "stratospheric descent, {}: {:.0} s simulated in {:.3} s = {:.0}× real \
                         time ({} evaluations, landing {:.3} m from the 10× tighter run)",
                        run.setting.describe(),
                        run.sim_time_s,
                        run.wall_time_s,
                        run.real_time_factor,
                        run.rhs_evals,
                        run.landing_error_vs_reference_m.unwrap_or(f64::NAN)
                    );
                }
                println!(
                    "best: {} at {:.0}× real time",
                    report.best.setting.describe(),
                    report.best.real_time_factor
                );
            }
            Ok(())
        }
    }
}
