//! `stx bench`: measured speed figures, printed as a table or JSON.
//!
//! `stx bench dynamics` measures derivative evaluations per second on one core, and the
//! real-time factor of the whole `stratospheric` descent for each integrator with its loosest
//! setting whose landing point stays within 1 m of a reference run at a 10× tighter setting
//! (a 10× smaller tolerance for Dormand–Prince, a 10× smaller step for RK4).

use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, bail};
use clap::{Args, Subcommand};
use serde::Serialize;
use stx_dynamics::atmosphere::StandardAtmosphere;
use stx_dynamics::integrate::{DormandPrince54, Hooks, Rk4, Stepper, integrate};
use stx_dynamics::model::{Environment, Kinematics, ParafoilModel};
use stx_dynamics::state::StateVector;
use stx_dynamics::vehicle::Vehicle;
use stx_dynamics::wind::Calm;
use stx_sim::open_loop::{height_above_ground_m, lowest_point};
use stx_sim::scenario::Scenario;

#[derive(Args)]
pub struct BenchArgs {
    #[command(subcommand)]
    what: BenchWhat,
}

#[derive(Subcommand)]
enum BenchWhat {
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
    },
}

/// An integrator setting: a tolerance or a step.
#[derive(Clone, Copy, Serialize)]
#[serde(tag = "method", rename_all = "snake_case")]
enum Setting {
    DormandPrince { rel_tol: f64, abs_tol: f64 },
    Rk4 { step_s: f64 },
}

impl Setting {
    fn tighter(self) -> Self {
        match self {
            Setting::DormandPrince { rel_tol, abs_tol } => Setting::DormandPrince {
                rel_tol: rel_tol / 10.0,
                abs_tol: abs_tol / 10.0,
            },
            Setting::Rk4 { step_s } => Setting::Rk4 {
                step_s: step_s / 10.0,
            },
        }
    }

    fn describe(self) -> String {
        match self {
            Setting::DormandPrince { rel_tol, .. } => {
                format!("Dormand–Prince rel_tol {rel_tol:.0e}")
            }
            Setting::Rk4 { step_s } => format!("RK4 step {step_s} s"),
        }
    }
}

#[derive(Clone, Serialize)]
struct DescentRun {
    setting: Setting,
    sim_time_s: f64,
    wall_time_s: f64,
    real_time_factor: f64,
    rhs_evals: u64,
    landing_x_m: f64,
    landing_y_m: f64,
    landing_error_vs_reference_m: Option<f64>,
}

#[derive(Serialize)]
struct DynamicsReport {
    derivative_evals_per_s: f64,
    derivative_eval_ns: f64,
    /// The fastest run whose landing held within 1 m of its reference.
    best: DescentRun,
    /// Per integrator: its loosest passing setting and that setting's reference run.
    passing: Vec<(DescentRun, DescentRun)>,
    /// Settings that failed the 1 m criterion (or the integration), loosest first.
    rejected: Vec<String>,
}

fn stratospheric_model() -> (ParafoilModel, StateVector) {
    let scenario = match Scenario::builtin("stratospheric") {
        Ok(s) => s,
        Err(e) => panic!("built-in scenario is valid (tested): {e}"),
    };
    let model = ParafoilModel::new(
        Vehicle::straplex(),
        Environment {
            atmosphere: Arc::new(StandardAtmosphere),
            wind: Arc::new(Calm),
            ground_altitude_msl_m: 0.0,
        },
    );
    (model, scenario.initial.to_state())
}

fn descend(setting: Setting) -> anyhow::Result<DescentRun> {
    match setting {
        Setting::DormandPrince { rel_tol, abs_tol } => descend_with(
            setting,
            &mut DormandPrince54::new(rel_tol, abs_tol).with_max_step_s(0.5),
        ),
        Setting::Rk4 { step_s } => descend_with(setting, &mut Rk4::new(step_s)),
    }
}

fn descend_with(setting: Setting, stepper: &mut impl Stepper) -> anyhow::Result<DescentRun> {
    let (mut model, x0) = stratospheric_model();
    let vehicle = model.vehicle.clone();
    let mut event = |_t: f64, x: &StateVector| height_above_ground_m(&vehicle, x);
    let started = Instant::now();
    let outcome = integrate(
        stepper,
        &mut model,
        0.0,
        &x0,
        20_000.0,
        Hooks {
            event: Some(&mut event),
            observer: None,
        },
    )
    .with_context(|| format!("stratospheric descent with {}", setting.describe()))?;
    let wall = started.elapsed().as_secs_f64();
    if outcome.event_time_s.is_none() {
        bail!("the descent did not reach the ground in 20,000 s");
    }
    let k = Kinematics::new(&model.vehicle, &outcome.state, 0.0);
    let (body, _) = lowest_point(&model.vehicle, &k);
    let p = k.position_ned_m[body as usize];
    Ok(DescentRun {
        setting,
        sim_time_s: outcome.time_s,
        wall_time_s: wall,
        real_time_factor: outcome.time_s / wall,
        rhs_evals: model.evaluations(),
        landing_x_m: p.x,
        landing_y_m: p.y,
        landing_error_vs_reference_m: None,
    })
}

fn evals_per_second(seconds: f64) -> f64 {
    let (mut model, x0) = stratospheric_model();
    // Steady glide near the ground: the state the model spends most of a descent in.
    let mut x = x0;
    x[2] = -500.0;
    let started = Instant::now();
    let mut n = 0_u64;
    let mut sink = 0.0;
    while started.elapsed().as_secs_f64() < seconds {
        for _ in 0..1000 {
            x[0] += 1e-9;
            sink += model.derivative(0.0, &x)[6];
        }
        n += 1000;
    }
    std::hint::black_box(sink);
    n as f64 / started.elapsed().as_secs_f64()
}

pub fn run(args: BenchArgs) -> anyhow::Result<()> {
    match args.what {
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
        } => {
            let report = crate::bench_station::run(&crate::bench_station::StationBenchOptions {
                clients,
                frames,
                frame_rate_hz,
                commands,
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
            }
            Ok(())
        }
        BenchWhat::Dynamics { json, eval_seconds } => {
            let rate = evals_per_second(eval_seconds);
            // Per integrator, loosest first; the first setting that holds the landing within
            // 1 m of its 10× tighter reference is that integrator's result.
            let ladders: [Vec<Setting>; 2] = [
                [0.08, 0.06, 0.05, 0.04, 0.03, 0.02, 0.01]
                    .map(|step_s| Setting::Rk4 { step_s })
                    .to_vec(),
                [1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6]
                    .map(|tol| Setting::DormandPrince {
                        rel_tol: tol,
                        abs_tol: tol,
                    })
                    .to_vec(),
            ];
            let mut passing = Vec::new();
            let mut rejected = Vec::new();
            for ladder in ladders {
                for setting in ladder {
                    let attempt =
                        descend(setting).and_then(|run| Ok((run, descend(setting.tighter())?)));
                    let (mut run, reference) = match attempt {
                        Ok(pair) => pair,
                        Err(error) => {
                            rejected.push(format!("{}: {error:#}", setting.describe()));
                            continue;
                        }
                    };
                    let error = (run.landing_x_m - reference.landing_x_m)
                        .hypot(run.landing_y_m - reference.landing_y_m);
                    run.landing_error_vs_reference_m = Some(error);
                    if !json {
                        eprintln!(
                            "{}: landing {error:.3} m from its reference, {:.0}× real time",
                            setting.describe(),
                            run.real_time_factor
                        );
                    }
                    if error <= 1.0 {
                        passing.push((run, reference));
                        break;
                    }
                    rejected.push(format!(
                        "{}: landing {error:.3} m from its reference",
                        setting.describe()
                    ));
                }
            }
            let Some(best_index) = (0..passing.len()).max_by(|a, b| {
                passing[*a]
                    .0
                    .real_time_factor
                    .total_cmp(&passing[*b].0.real_time_factor)
            }) else {
                bail!("no integrator setting kept the landing within 1 m of its reference");
            };
            let best = passing[best_index].0.clone();
            let report = DynamicsReport {
                derivative_evals_per_s: rate,
                derivative_eval_ns: 1e9 / rate,
                best,
                passing,
                rejected,
            };
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
