//! The Lab's jobs. The station's Lab (`stx_station::lab`) decides what runs and when, and owns
//! what the pages see; the work itself needs the simulator and the analysis, which sit above
//! the station in the crates' order, so it lives here as the [`LabWorker`] the binary hands the
//! daemon ([`service`]).
//!
//! How the parts fit: this file flies a built-in scenario, a Monte Carlo batch, the stability
//! analysis and a tuning run; a recording's comparison with the model is [`compare`] and its
//! parameters' identification [`identify`], what the two share (the recording read as a flight
//! log, progress and cancel, the edits listed) is [`recording`], and [`flight_file`] reads a
//! flight log from a file as `stx compare` and `stx identify` do, so the Lab and the command
//! line read a flight alike.
//!
//! No tokio (the station without its `daemon` feature): the Lab runs each job on a blocking
//! thread of its own, and the jobs only compute.

pub mod compare;
pub mod flight_file;
pub mod identify;
pub mod recording;

use std::path::PathBuf;
use std::sync::Arc;

use stx_analysis::analysis::analyze;
use stx_analysis::flight_log::window::Window;
use stx_analysis::gains_file::gains_file;
use stx_analysis::tune::{Controller, DEFAULT_ALTITUDE_M, tune};
use stx_dynamics::vehicle::Vehicle;
use stx_gnc::estimator::EstimatorConfig;
use stx_gnc::guidance::GuidanceConfig;
use stx_gnc::params::{CATALOG, OnboardSettings};
use stx_sim::closed_loop::SensedNavigation;
use stx_sim::montecarlo::{MonteCarloConfig, MonteCarloReport, run_until};
use stx_sim::open_loop;
use stx_sim::run::Run;
use stx_sim::scenario::Scenario;
use stx_station::lab::{
    JobControl, JobInputs, LabJobBody, LabResult, LabService, LabWorker, MonteCarloSummary,
    ScenarioSeries, StabilitySummary, TuneSummary,
};

/// A Lab job's longest run, s.
pub const TIME_CAP_S: f64 = 600.0;

/// The Lab of `stx serve`, saving files in `dir`.
pub fn service(dir: PathBuf) -> Arc<LabService> {
    Arc::new(LabService::new(Arc::new(Worker), dir, TIME_CAP_S))
}

/// Runs the Lab's jobs (on the Lab's thread).
pub struct Worker;

impl LabWorker for Worker {
    fn run(
        &self,
        job: &LabJobBody,
        inputs: &JobInputs,
        control: &dyn JobControl,
    ) -> Result<LabResult, String> {
        let vehicle = &inputs.vehicle;
        match job {
            LabJobBody::Scenario { scenario, .. } => scenario_run(scenario, vehicle),
            LabJobBody::MonteCarlo {
                runs,
                seed,
                wind_max_mps,
                altitude_m,
            } => {
                let config = MonteCarloConfig {
                    runs: *runs as usize,
                    seed: *seed,
                    wind_max_mps: *wind_max_mps,
                    altitude_m: *altitude_m,
                    // One thread: the station's own work keeps the other cores.
                    threads: 1,
                    // The runs are flown around the vehicle being edited, as every other job.
                    vehicle: vehicle.clone(),
                    vehicle_name: Some("the Lab's vehicle".into()),
                    ..MonteCarloConfig::default()
                };
                monte_carlo(&config, control)
            }
            LabJobBody::Stability { altitude_m, .. } => stability(vehicle, *altitude_m),
            LabJobBody::Tune {
                controller,
                altitude_m,
            } => tuning(controller, vehicle, *altitude_m, control),
            LabJobBody::Compare {
                recording,
                vehicle: edits,
                from_s,
                to_s,
            } => {
                let window = Window::new(*from_s, *to_s);
                compare::run(recording, inputs, &window, edits, control)
            }
            LabJobBody::Identify {
                recording,
                params,
                vehicle: edits,
                from_s,
                to_s,
            } => {
                let window = Window::new(*from_s, *to_s);
                identify::run(recording, params, inputs, &window, edits, control)
            }
        }
    }

    fn check_window(&self, job: &LabJobBody, inputs: &JobInputs) -> Result<(), (String, String)> {
        recording::check_window(job, inputs)
    }
}

fn scenario_run(name: &str, vehicle: &Vehicle) -> Result<LabResult, String> {
    // Built-in scenarios only: a page names no file on the station's disk.
    let scenario = Scenario::builtin(name).map_err(|e| e.to_string())?;
    let run = open_loop::run(&scenario, vehicle).map_err(|e| format!("{e:#}"))?;
    Ok(LabResult::Scenario(series(name, &run)))
}

/// The canopy's flight as the Lab's plots draw it.
pub fn series(name: &str, run: &Run) -> ScenarioSeries {
    let mut s = ScenarioSeries {
        scenario: name.to_string(),
        ..ScenarioSeries::default()
    };
    let start_down = run
        .samples
        .first()
        .map_or(0.0, |x| x.bodies[0].position_ned_m[2]);
    for sample in &run.samples {
        let canopy = &sample.bodies[0];
        s.time_s.push(sample.time_s);
        s.north_m.push(canopy.position_ned_m[0]);
        s.east_m.push(canopy.position_ned_m[1]);
        s.height_m.push(start_down - canopy.position_ned_m[2]);
        s.roll_deg.push(canopy.euler_deg[0]);
        s.pitch_deg.push(canopy.euler_deg[1]);
        s.yaw_deg.push(canopy.euler_deg[2]);
        s.airspeed_mps.push(sample.airspeed_mps);
        s.sink_mps.push(canopy.velocity_ned_mps[2]);
    }
    s
}

fn monte_carlo(config: &MonteCarloConfig, control: &dyn JobControl) -> Result<LabResult, String> {
    let estimator = EstimatorConfig::default();
    let total = config.runs;
    control.progress(0, total);
    let report = run_until(
        config,
        |c, sensors| {
            SensedNavigation::new(sensors, estimator.clone(), c.seed).map_err(|e| e.to_string())
        },
        |done| control.progress(done, total),
        || control.should_stop(),
    )
    .map_err(|e| e.to_string())?;
    Ok(LabResult::MonteCarlo(batch_summary(config.runs, &report)))
}

/// A batch's report as the Lab shows it (a failed run makes the largest miss infinite, which
/// serialises as `null`).
pub fn batch_summary(asked: usize, r: &MonteCarloReport) -> MonteCarloSummary {
    MonteCarloSummary {
        runs_asked: asked as u64,
        runs_flown: r.runs as u64,
        failed_runs: r.failed_runs.len() as u64,
        miss_median_m: r.miss_m.median,
        miss_p95_m: r.miss_m.p95,
        miss_max_m: r.miss_m.max,
        into_wind_fraction: r.into_wind_fraction,
        touchdown_vertical_speed_median_mps: r.payload_touchdown_vertical_speed_mps.median,
        landings_long_right_m: r
            .results
            .iter()
            .map(|x| [x.long_short_m, x.left_right_m])
            .collect(),
    }
}

fn stability(vehicle: &Vehicle, altitude_m: f64) -> Result<LabResult, String> {
    let (r, _) =
        analyze(vehicle, altitude_m).map_err(|e| format!("trim at {altitude_m} m: {e}"))?;
    Ok(LabResult::Stability(StabilitySummary {
        altitude_m,
        airspeed_mps: r.trim.airspeed_mps,
        sink_rate_mps: r.trim.sink_rate_mps,
        glide_ratio: r.trim.glide_ratio,
        n_states: r.n_states as u64,
        eigenvalues: r.eigenvalues.clone(),
        seed_eigenvalues: r.seed.eigenvalues.clone(),
        zero_eigenvalues: r.zero_eigenvalues as u64,
        seed_zero_eigenvalues: r.seed.zero_eigenvalues as u64,
        controllability_rank: r.controllability_rank as u64,
        seed_controllability_rank: r.seed.controllability_rank as u64,
        observability_rank: r.observability_rank as u64,
        seed_observability_rank: r.seed.observability_rank as u64,
        warnings: r.warnings.clone(),
    }))
}

fn tuning(
    name: &str,
    vehicle: &Vehicle,
    altitude_m: f64,
    control: &dyn JobControl,
) -> Result<LabResult, String> {
    let controller = Controller::ALL
        .into_iter()
        .find(|c| c.name() == name)
        .ok_or_else(|| {
            let names: Vec<_> = Controller::ALL.iter().map(|c| c.name()).collect();
            format!("no controller `{name}` (one of {})", names.join(", "))
        })?;
    // The optimiser cannot be interrupted: a cancel or the cap discards its result at the end.
    let report = tune(
        controller,
        vehicle,
        altitude_m,
        GuidanceConfig::default(),
        None,
        |done, total| control.progress(done, total),
    )
    .map_err(|e| e.to_string())?;
    let mut settings = OnboardSettings::default();
    settings.guidance.gains = report.gains_out;
    // Gains the 14-DOF model has not flown are not offered for the drone: the job fails with
    // the model's reason (low down, "the stack reached the ground during the step").
    let Some(cost_tuned) = report.tuned.nonlinear_cost else {
        let t = &report.tuned;
        let why = [&t.small, &t.large]
            .into_iter()
            .find_map(|trial| trial.nonlinear_error.clone())
            .unwrap_or_else(|| "no step flown".into());
        return Err(format!(
            "the tuned gains failed the 14-DOF step at {altitude_m} m: {why} (tune at {} m, where the Monte Carlo releases, or higher)",
            DEFAULT_ALTITUDE_M
        ));
    };
    Ok(LabResult::Tune(TuneSummary {
        controller: controller.name().to_string(),
        cost_before: report.current.nonlinear_cost,
        cost_tuned,
        cost_seed: report.seed.nonlinear_cost,
        gains: CATALOG
            .iter()
            .filter(|p| p.name.starts_with("GN_"))
            .map(|p| (p.name.to_string(), p.get(&settings)))
            .collect(),
        gains_toml: gains_file(&report, "the built-in gains"),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Quiet;

    impl JobControl for Quiet {
        fn progress(&self, _done: usize, _total: usize) {}
        fn should_stop(&self) -> bool {
            false
        }
    }

    /// Regression: the page's trim altitude (100 m) reached the Lab's tuning, whose 14-DOF
    /// steps hit the ground there; the costs went out as `null` where the contract promises
    /// numbers and the page failed drawing them. Such a tuning now fails with the model's reason.
    #[test]
    fn lab_tuning_too_low_fails_with_the_model_s_reason_and_at_600_m_gives_flown_gains() {
        let vehicle = Vehicle::straplex();
        let low = tuning("course", &vehicle, 100.0, &Quiet).expect_err("fails at 100 m");
        assert!(
            low.contains("reached the ground") && low.contains("600 m"),
            "{low}"
        );
        let Ok(LabResult::Tune(t)) = tuning("course", &vehicle, 600.0, &Quiet) else {
            panic!("tunes at 600 m");
        };
        assert!(t.cost_tuned.is_finite() && t.cost_before.is_some_and(f64::is_finite));
        assert!(t.gains.values().all(|g| g.is_finite()) && !t.gains.is_empty());
    }
}
