//! The Lab: the engineering tools (a scenario, a Monte Carlo batch, the stability analysis, a
//! tuning run, a recorded flight compared with the model or its parameters identified) run from the dashboard on the station's machine, one at a time, in the
//! background, never on the telemetry path.
//!
//! The station cannot fly a scenario itself (stx-sim and stx-analysis sit above it in the
//! crates' order), so the work is a [`LabWorker`] (stx-lab's) the binary hands over when it
//! starts the daemon; the station owns what the pages see and send: the requests ([`LabJobBody`]), the
//! results ([`LabResult`]), the job's life ([`jobs::LabJobs`]: one at a time, a time cap,
//! progress, cancel, the last outcome kept), the vehicle editor ([`vehicle_fields`]) and
//! what a comparison needs of a recording ([`compare`]), the parameters an identification
//! fits ([`identify`]).

pub mod bodies;
pub mod compare;
pub mod identify;
pub mod jobs;
pub mod vehicle_fields;

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, MutexGuard};

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use stx_dynamics::vehicle::Vehicle;

pub use compare::{CompareChannel, CompareSeries};
pub use identify::{IdentifiedParam, IdentifySummary};
pub use jobs::{LabBusy, LabJobs, StopReason};

/// Largest Monte Carlo batch the Lab flies (a bigger campaign is `stx montecarlo`'s).
pub const MAX_LAB_RUNS: u32 = 500;

/// Vehicle parameters changed from the seed's (STRAPLEX) vehicle, by their dotted name as
/// `GET /api/lab/vehicle` lists them (`canopy.mass_kg`), in that field's unit.
pub type VehicleEdits = BTreeMap<String, f64>;

/// What an operator asks the Lab to run (`POST /api/lab/jobs`).
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum LabJobBody {
    /// Fly a scenario (`stx sim`) with the vehicle as edited.
    Scenario {
        /// A built-in scenario's name (`uncontrolled`, `spiral-exit`, …).
        scenario: String,
        /// Parameters changed from the seed's vehicle.
        #[serde(default)]
        vehicle: VehicleEdits,
    },
    /// A Monte Carlo batch of guided landings (`stx montecarlo`), on one thread.
    MonteCarlo {
        /// Number of runs (1 … 500).
        runs: u32,
        /// Seed of the batch: the same seed gives the same landings.
        seed: u64,
        /// Largest mean wind drawn, m/s (0 … 15).
        wind_max_mps: f64,
        /// Release height above the target, m (50 … 3000).
        altitude_m: f64,
    },
    /// Trim, linearise, eigenvalues and ranks beside the seed's (`stx analyze`).
    Stability {
        /// Altitude of the trim, m above sea level (−5000 … 86000).
        altitude_m: f64,
        /// Parameters changed from the seed's vehicle.
        #[serde(default)]
        vehicle: VehicleEdits,
    },
    /// Tune one controller's gains on its step experiment (`stx tune`; the optimiser's
    /// evaluations are bounded by the library, the job by the Lab's time cap).
    Tune {
        /// `heading`, `course`, `localizer` or `vertical`.
        controller: String,
        /// Altitude of the trim, m above sea level (−5000 … 86000).
        altitude_m: f64,
    },
    /// Fly the model through a recorded flight and compare the two (`stx compare`): from the
    /// recorded initial state, with the recorded servo commands and wind estimate.
    Compare {
        /// A recording's file name in the station's recordings directory, as
        /// `GET /api/recordings` lists it.
        recording: String,
        /// Parameters changed from the seed's vehicle.
        #[serde(default)]
        vehicle: VehicleEdits,
        /// Compare from this time on, s from the flight log's first sample, on the log's
        /// own clock (the drone's); the model starts from the recorded state there. Absent:
        /// from the start. Finite and ≥ 0, as `to_s`, and below `to_s`, in a window the
        /// flight reaches (else 400 `invalid_job`).
        #[serde(default)]
        from_s: Option<f64>,
        /// Compare up to this time, s from the flight log's first sample. Absent: to the end.
        #[serde(default)]
        to_s: Option<f64>,
    },
    /// Fit chosen vehicle parameters to a recorded flight (`stx identify`), starting from the
    /// seed's vehicle or as edited; progress per iteration, a cancel stopping after the
    /// current one.
    Identify {
        /// A recording's file name in the station's recordings directory, as
        /// `GET /api/recordings` lists it.
        recording: String,
        /// The parameters to fit, by their vehicle-file names (`cl_alpha`, `cd0`, …; see
        /// [`identify::IDENTIFY_PARAMS`]).
        params: Vec<String>,
        /// Parameters changed from the seed's vehicle.
        #[serde(default)]
        vehicle: VehicleEdits,
        /// Fit from this time on, s from the flight log's first sample (as a comparison's).
        #[serde(default)]
        from_s: Option<f64>,
        /// Fit up to this time, s from the flight log's first sample.
        #[serde(default)]
        to_s: Option<f64>,
    },
}

impl LabJobBody {
    /// The job's kind as the status names it.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Scenario { .. } => "scenario",
            Self::MonteCarlo { .. } => "monte_carlo",
            Self::Stability { .. } => "stability",
            Self::Tune { .. } => "tune",
            Self::Compare { .. } => "compare",
            Self::Identify { .. } => "identify",
        }
    }

    /// Whether the job names a window of its recording (`from_s` or `to_s`).
    pub fn has_window(&self) -> bool {
        match self {
            Self::Compare { from_s, to_s, .. } | Self::Identify { from_s, to_s, .. } => {
                from_s.is_some() || to_s.is_some()
            }
            _ => false,
        }
    }

    /// The vehicle edits the job flies with (none for the others).
    pub fn vehicle_edits(&self) -> Option<&VehicleEdits> {
        match self {
            Self::Scenario { vehicle, .. }
            | Self::Stability { vehicle, .. }
            | Self::Compare { vehicle, .. }
            | Self::Identify { vehicle, .. } => Some(vehicle),
            _ => None,
        }
    }

    /// Refuses a job out of the Lab's bounds: `(field, reason)`.
    pub fn check(&self) -> Result<(), (String, String)> {
        let range = |field: &str, v: f64, lo: f64, hi: f64| {
            if v.is_finite() && (lo..=hi).contains(&v) {
                Ok(())
            } else {
                Err((
                    field.to_string(),
                    format!("must be within {lo} … {hi}, not {v}"),
                ))
            }
        };
        match self {
            Self::Scenario { scenario, .. } if scenario.trim().is_empty() => {
                Err(("scenario".into(), "a scenario name is required".into()))
            }
            Self::Scenario { .. } => Ok(()),
            Self::Compare { recording, .. } | Self::Identify { recording, .. }
                if recording.trim().is_empty() =>
            {
                Err(("recording".into(), "a recording's name is required".into()))
            }
            Self::Compare { from_s, to_s, .. } => compare::check_window(*from_s, *to_s),
            Self::Identify {
                params,
                from_s,
                to_s,
                ..
            } => {
                identify::check_params(params).map_err(|e| ("params".into(), e))?;
                compare::check_window(*from_s, *to_s)
            }
            Self::MonteCarlo {
                runs,
                wind_max_mps,
                altitude_m,
                ..
            } => {
                range("runs", *runs as f64, 1.0, MAX_LAB_RUNS as f64)?;
                range("wind_max_mps", *wind_max_mps, 0.0, 15.0)?;
                range("altitude_m", *altitude_m, 50.0, 3000.0)
            }
            Self::Stability { altitude_m, .. } | Self::Tune { altitude_m, .. } => {
                range("altitude_m", *altitude_m, -5000.0, 86000.0)
            }
        }
    }
}

/// A finished job's result, by kind.
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum LabResult {
    /// A scenario's flight.
    Scenario(ScenarioSeries),
    /// A Monte Carlo batch's landings.
    MonteCarlo(MonteCarloSummary),
    /// The stability analysis.
    Stability(StabilitySummary),
    /// A tuning run.
    Tune(TuneSummary),
    /// A recorded flight beside the model's.
    Compare(CompareSeries),
    /// Parameters fitted to a recorded flight.
    Identify(IdentifySummary),
}

/// A scenario's flight as series for the plots (one entry per recorded sample).
#[derive(Debug, Clone, Default, Serialize, JsonSchema)]
pub struct ScenarioSeries {
    /// The scenario's name.
    pub scenario: String,
    /// Time, s.
    pub time_s: Vec<f64>,
    /// The canopy's position north of the release, m.
    pub north_m: Vec<f64>,
    /// The canopy's position east of the release, m.
    pub east_m: Vec<f64>,
    /// The canopy's height above the release, m.
    pub height_m: Vec<f64>,
    /// The canopy's roll, deg.
    pub roll_deg: Vec<f64>,
    /// The canopy's pitch, deg.
    pub pitch_deg: Vec<f64>,
    /// The canopy's yaw, deg.
    pub yaw_deg: Vec<f64>,
    /// Airspeed, m/s.
    pub airspeed_mps: Vec<f64>,
    /// The canopy's sink rate (downward speed), m/s.
    pub sink_mps: Vec<f64>,
}

/// A Monte Carlo batch's landing statistics.
#[derive(Debug, Clone, Default, Serialize, JsonSchema)]
pub struct MonteCarloSummary {
    /// Runs asked for.
    pub runs_asked: u64,
    /// Runs flown (fewer when cancelled or stopped by the time cap).
    pub runs_flown: u64,
    /// Runs that failed (counted as misses).
    pub failed_runs: u64,
    /// Distance from the target at first ground contact: median, m.
    pub miss_median_m: f64,
    /// … 95th percentile, m.
    pub miss_p95_m: f64,
    /// … largest, m.
    pub miss_max_m: f64,
    /// Share of landings within 30° of upwind (0 … 1).
    pub into_wind_fraction: f64,
    /// Median vertical speed of the payload at touchdown, m/s.
    pub touchdown_vertical_speed_median_mps: f64,
    /// Each landing from the target `[long, right]`, m: along the upwind direction
    /// (positive beyond the target) and across it (positive to the right).
    pub landings_long_right_m: Vec<[f64; 2]>,
}

/// The stability analysis beside the seed's figures.
#[derive(Debug, Clone, Default, Serialize, JsonSchema)]
pub struct StabilitySummary {
    /// Altitude of the trim, m.
    pub altitude_m: f64,
    /// Trim airspeed, m/s.
    pub airspeed_mps: f64,
    /// Trim sink rate, m/s.
    pub sink_rate_mps: f64,
    /// Trim glide ratio.
    pub glide_ratio: f64,
    /// Number of states of the linear model.
    pub n_states: u64,
    /// Every eigenvalue `[re, im]`, 1/s.
    pub eigenvalues: Vec<[f64; 2]>,
    /// The seed's eigenvalues `[re, im]` (§6.2.1), 1/s.
    pub seed_eigenvalues: Vec<[f64; 2]>,
    /// Eigenvalues counted as zero.
    pub zero_eigenvalues: u64,
    /// The seed's count.
    pub seed_zero_eigenvalues: u64,
    /// Controllability rank (both inputs).
    pub controllability_rank: u64,
    /// The seed's.
    pub seed_controllability_rank: u64,
    /// Observability rank.
    pub observability_rank: u64,
    /// The seed's.
    pub seed_observability_rank: u64,
    /// Decisions close to their thresholds.
    pub warnings: Vec<String>,
}

/// A tuning run's outcome.
#[derive(Debug, Clone, Default, Serialize, JsonSchema)]
pub struct TuneSummary {
    /// The controller tuned.
    pub controller: String,
    /// Nonlinear step cost with the gains before (`null`: the 14-DOF step with them failed).
    pub cost_before: Option<f64>,
    /// … with the tuned gains (a tuning whose gains fail the 14-DOF step is a failed job).
    pub cost_tuned: f64,
    /// … with the seed's (A.13) gains (`null`: failed).
    pub cost_seed: Option<f64>,
    /// The tuned gains by parameter name.
    pub gains: BTreeMap<String, f64>,
    /// The gains file (TOML) with every controller's gains.
    pub gains_toml: String,
}

/// What a running job reports and asks: the adapter's side of [`jobs::LabJobs`].
pub trait JobControl: Sync {
    /// `done` of `total` steps finished.
    fn progress(&self, done: usize, total: usize);
    /// The job should stop now (cancelled or over its time cap).
    fn should_stop(&self) -> bool;
}

/// What the station made ready for a job from its request, checked.
#[derive(Debug, Clone)]
pub struct JobInputs {
    /// The vehicle as edited (the seed's for the jobs that take no edits).
    pub vehicle: Vehicle,
    /// A comparison's or an identification's recording: a file of the station's recordings directory holding a
    /// flight ([`compare::missing_flight`]).
    pub recording: Option<PathBuf>,
}

/// The work behind the Lab: stx-lab's, handed over by the binary (the station links neither
/// the simulator nor the analysis). Called on a blocking thread of its own.
pub trait LabWorker: Send + Sync {
    /// Runs `job` (already checked) with `inputs`; `Err` is the reason it failed.
    fn run(
        &self,
        job: &LabJobBody,
        inputs: &JobInputs,
        control: &dyn JobControl,
    ) -> Result<LabResult, String>;

    /// Refuses, before it starts, a job whose window (`from_s`, `to_s`) its recording's
    /// flight does not reach: `(field, reason)`. Only the work reads a recording as a flight
    /// log (on the drone's clock, which the recording's index does not give), so the station
    /// asks it; called on a blocking thread, for jobs that name a window. The default
    /// refuses nothing, the job then failing with the reason.
    fn check_window(&self, job: &LabJobBody, inputs: &JobInputs) -> Result<(), (String, String)> {
        let _ = (job, inputs);
        Ok(())
    }
}

/// The Lab as a live station runs it: the runner, the work, where files are saved.
pub struct LabService {
    jobs: Mutex<LabJobs>,
    worker: Arc<dyn LabWorker>,
    dir: PathBuf,
}

impl LabService {
    /// A Lab doing `worker`'s jobs, each for at most `time_cap_s`, saving files in `dir`.
    pub fn new(worker: Arc<dyn LabWorker>, dir: PathBuf, time_cap_s: f64) -> Self {
        Self {
            jobs: Mutex::new(LabJobs::new(time_cap_s)),
            worker,
            dir,
        }
    }

    /// The work.
    pub fn worker(&self) -> Arc<dyn LabWorker> {
        self.worker.clone()
    }

    /// Where files are saved.
    pub fn dir(&self) -> &std::path::Path {
        &self.dir
    }

    /// The runner, for a moment.
    pub fn jobs(&self) -> MutexGuard<'_, LabJobs> {
        self.jobs.lock().unwrap_or_else(|e| e.into_inner())
    }
}
