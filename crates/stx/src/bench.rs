//! `stx bench`: measured speed figures, printed as a table or JSON.
//!
//! `stx bench dynamics` is `stx_sim::speed` (derivative evaluations per second, and the
//! stratospheric descent's real-time factor per integrator); `stx bench memory` and
//! `stx bench station` measure the station daemon (see their modules); `stx bench agreement`
//! flies whole missions and holds what the station shows against the truth
//! (`stx_agreement`).

use clap::{Args, Subcommand};

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
        #[arg(long, value_delimiter = ',', value_parser = crate::bench_agreement::parse_speed)]
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
            crate::bench_agreement::run_bench(crate::bench_agreement::AgreementBenchOptions {
                campaign,
                keep_out: Some(keep_out),
                threads,
                json,
            })
        }
        BenchWhat::Memory {
            json,
            mission_hours,
            speed,
            clients,
        } => {
            let report = crate::bench_memory::run(&crate::bench_memory::MemoryBenchOptions {
                mission_s: mission_hours * 3600.0,
                speed,
                clients,
            })?;
            if json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                println!(
                    "station daemon alone after {:.0} s of mission ({}, {:.0} s wall at {}x, {} pages): RSS {:.1} MB, peak {:.1} MB (after 1 min: {:.1} MB; the drone's process peaked at {:.1} MB); pages received {} messages, {:.1} MB",
                    report.mission_time_s,
                    if report.landed {
                        "landed"
                    } else {
                        "NOT landed"
                    },
                    report.wall_time_s,
                    report.speed,
                    report.clients,
                    report.rss_after_mb,
                    report.rss_peak_mb,
                    report.rss_early_mb,
                    report.drone_rss_peak_mb,
                    report.page_messages,
                    report.page_bytes as f64 / 1e6
                );
                println!(
                    "{} pages came and went; open file descriptors {} after 1 min, {} at the end; recording {:.1} MB on disk, {} messages lost",
                    report.pages_come_and_gone,
                    report.fds_early,
                    report.fds_after,
                    report.recording_mb,
                    report.recording_lost
                );
            }
            if !report.landed {
                anyhow::bail!("the simulated drone did not land in time");
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
            let report = crate::bench_station::run(&crate::bench_station::StationBenchOptions {
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
                let t = &report.telemetry_to_websocket;
                let c = &report.command_to_mavlink;
                println!(
                    "telemetry → WebSocket, {} pages, {} bursts at {} Hz, state {} bytes: p50 {:.2} ms, p99 {:.2} ms, max {:.2} ms ({} samples, {} missed)",
                    t.clients,
                    t.frames_sent,
                    t.frame_rate_hz,
                    t.state_bytes,
                    t.latency.p50_ms,
                    t.latency.p99_ms,
                    t.latency.max_ms,
                    t.latency.samples,
                    t.missed
                );
                println!(
                    "command → MAVLink bytes, {} commands: p50 {:.2} ms, p99 {:.2} ms, max {:.2} ms ({} lost)",
                    c.commands_sent, c.latency.p50_ms, c.latency.p99_ms, c.latency.max_ms, c.lost
                );
                if let Some(a) = &report.abuse {
                    println!(
                        "flood during it: {} wrong-token requests ({} answered 429, {} 401, {} other), {} WebSockets tried ({} opened and closed); process RSS {:.1} MB before, {:.1} MB after",
                        a.bad_token_requests,
                        a.answered_429,
                        a.answered_401,
                        a.other,
                        a.websockets_tried,
                        a.websockets_opened,
                        a.rss_before_mb,
                        a.rss_after_mb
                    );
                }
                if let Some(l) = &report.lab {
                    println!(
                        "Lab Monte Carlo during it: {} batch{} of {} runs started back to back ({} ended on their own), {} runs flown; the Lab busy {:.1} % of the window (longest gap {:.0} ms)",
                        l.batches,
                        if l.batches == 1 { "" } else { "es" },
                        l.runs_per_batch,
                        l.batches_finished,
                        l.runs_flown,
                        l.busy_fraction * 100.0,
                        l.longest_idle_ms
                    );
                }
                let r = &report.recording;
                println!(
                    "recording: {:?}, {} messages ({:.2} MB) written, {} lost{}",
                    r.state,
                    r.messages_written,
                    r.bytes_written as f64 / 1e6,
                    r.messages_lost,
                    r.problem
                        .as_deref()
                        .map(|p| format!(" (last problem: {p})"))
                        .unwrap_or_default()
                );
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
