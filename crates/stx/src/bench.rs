//! `stx bench`: measured speed figures, printed as a table or JSON.
//!
//! `stx bench dynamics` measures derivative evaluations per second on one core, and the
//! real-time factor of the whole `stratospheric` descent with the loosest Dormand–Prince
//! tolerance whose landing point stays within 1 m of a reference run at a 10× tighter
//! tolerance.

use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, bail};
use clap::{Args, Subcommand};
use serde::Serialize;
use stx_dynamics::atmosphere::StandardAtmosphere;
use stx_dynamics::integrate::{DormandPrince54, Hooks, integrate};
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
}

#[derive(Serialize)]
struct DescentRun {
    rel_tol: f64,
    abs_tol: f64,
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
    chosen: DescentRun,
    reference: DescentRun,
    tried: Vec<DescentRun>,
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

fn descend(rel_tol: f64) -> anyhow::Result<DescentRun> {
    let (mut model, x0) = stratospheric_model();
    let vehicle = model.vehicle.clone();
    let abs_tol = rel_tol;
    let mut stepper = DormandPrince54::new(rel_tol, abs_tol).with_max_step_s(0.5);
    let mut event = |_t: f64, x: &StateVector| height_above_ground_m(&vehicle, x);
    let started = Instant::now();
    let outcome = integrate(
        &mut stepper,
        &mut model,
        0.0,
        &x0,
        20_000.0,
        Hooks {
            event: Some(&mut event),
            observer: None,
        },
    )
    .with_context(|| format!("stratospheric descent at rel_tol {rel_tol}"))?;
    let wall = started.elapsed().as_secs_f64();
    if outcome.event_time_s.is_none() {
        bail!("the descent did not reach the ground in 20,000 s");
    }
    let k = Kinematics::new(&model.vehicle, &outcome.state, 0.0);
    let (body, _) = lowest_point(&model.vehicle, &k);
    let p = k.position_ned_m[body as usize];
    Ok(DescentRun {
        rel_tol,
        abs_tol,
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
        BenchWhat::Dynamics { json, eval_seconds } => {
            let rate = evals_per_second(eval_seconds);
            // Loosest first; stop at the first tolerance that holds the landing within 1 m of
            // its 10× tighter reference.
            let tolerances = [1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7, 1e-7];
            let mut tried = Vec::new();
            let mut chosen = None;
            for &tol in &tolerances {
                let mut run = descend(tol)?;
                let reference = descend(tol / 10.0)?;
                let error = (run.landing_x_m - reference.landing_x_m)
                    .hypot(run.landing_y_m - reference.landing_y_m);
                run.landing_error_vs_reference_m = Some(error);
                if !json {
                    eprintln!(
                        "rel_tol {tol:.0e}: landing {error:.3} m from its reference, {:.0}× real time",
                        run.real_time_factor
                    );
                }
                if error <= 1.0 {
                    chosen = Some((run, reference));
                    break;
                }
                tried.push(run);
            }
            let Some((chosen, reference)) = chosen else {
                bail!("no tolerance down to 1e-7 kept the landing within 1 m of its reference");
            };
            let report = DynamicsReport {
                derivative_evals_per_s: rate,
                derivative_eval_ns: 1e9 / rate,
                chosen,
                reference,
                tried,
            };
            if json {
                println!("{}", serde_json::to_string(&report)?);
            } else {
                println!(
                    "derivative evaluations: {:.0}/s ({:.0} ns each)",
                    report.derivative_evals_per_s, report.derivative_eval_ns
                );
                let c = &report.chosen;
                println!(
                    "stratospheric descent: {:.0} s simulated in {:.3} s = {:.0}× real time \
                     (rel_tol {:.0e}, {} evaluations, landing {:.3} m from the 10× tighter run)",
                    c.sim_time_s,
                    c.wall_time_s,
                    c.real_time_factor,
                    c.rel_tol,
                    c.rhs_evals,
                    c.landing_error_vs_reference_m.unwrap_or(f64::NAN)
                );
            }
            Ok(())
        }
    }
}
