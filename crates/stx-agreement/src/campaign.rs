//! A campaign of whole missions — scenarios × seeds × speeds, with a dispersion set — flown on
//! threads, summed up, and held to the goals of "one truth on every screen": the station's
//! guidance phase agrees with the drone's over ≥ 99 % of the parafoil flight (the rest only
//! around a transition, ≤ 2 s each), its final-approach course within 5°, its target identical,
//! its predicted landing at 100 m above the ground within 15 m of the touchdown at p95 and never
//! worse than the drone's own by more than 5 m, and the main-line trim its replica learns the
//! drone's — also when the station hears the drone in bursts of several control periods, as a
//! loaded station does.

use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use serde::Serialize;
use stx_sim::dispersions::{Dispersions, DispersionsError};
use stx_sim::drone::{MissionConfig, MissionError};
use stx_station::config::{DEFAULT_STATION_TOML, StationConfig};

use crate::mission::{Delivery, MissionSpec, fly};
use crate::report::{MissionReport, PREDICTION_HEIGHTS_M, Spread};

/// The ratio of mission time to station time that stands for `--sim-speed max`: a whole
/// `mission` (2 h 41 min) in about 20 s of the station's time, as the real drone flies it
/// unpaced on the development machine.
pub const MAX_SPEED: f64 = 500.0;

/// The speed flights heard in bursts fly at: the live rehearsal's.
pub const BURST_SPEED: f64 = 20.0;

/// Why a campaign cannot be set up.
#[derive(Debug, thiserror::Error)]
pub enum CampaignError {
    /// A mission name.
    #[error("mission {0}")]
    Mission(#[from] MissionError),
    /// The dispersion set.
    #[error("dispersions: {0}")]
    Dispersions(#[from] DispersionsError),
    /// The shipped station configuration.
    #[error("the shipped station configuration: {0}")]
    Station(String),
}

/// What to fly.
#[derive(Debug, Clone, PartialEq)]
pub struct CampaignOptions {
    /// Built-in mission names (`mission`, `mission-short`, …).
    pub missions: Vec<String>,
    /// Seeds, each flown with every mission and speed.
    pub seeds: Vec<u64>,
    /// Seeds of one mission in place of `seeds`: more of the cheap missions.
    pub seeds_of: Vec<(String, Vec<u64>)>,
    /// A dispersion set's name (`nominal`, `realistic`) or file; `None`: none.
    pub dispersions: Option<String>,
    /// Mission time per station time; [`MAX_SPEED`] for `max`.
    pub speeds: Vec<f64>,
    /// Whether each flight is also flown at [`BURST_SPEED`] with the station hearing the
    /// drone in bursts of several control periods ([`Delivery::Bursts`]).
    pub bursts: bool,
}

impl CampaignOptions {
    /// The short campaign of the test command: `mission-short` with realistic dispersions,
    /// two seeds, at 20× and at `max`, and at 20× heard in bursts.
    pub fn short() -> Self {
        Self {
            missions: vec!["mission-short".into()],
            seeds: vec![1, 2],
            seeds_of: Vec::new(),
            dispersions: Some("realistic".into()),
            speeds: vec![20.0, MAX_SPEED],
            bursts: true,
        }
    }

    /// The full campaign of `stx bench agreement`: twenty flights with realistic dispersions —
    /// `mission` with seeds 1–6 (each 2 h 41 min of flight) and `mission-short` with seeds
    /// 1–14 — each at 20× and at `max`, and at 20× heard in bursts.
    pub fn full() -> Self {
        Self {
            missions: vec!["mission-short".into(), "mission".into()],
            seeds: vec![1, 2, 3, 4, 5, 6],
            seeds_of: vec![("mission-short".into(), (1..=14).collect())],
            dispersions: Some("realistic".into()),
            speeds: vec![20.0, MAX_SPEED],
            bursts: true,
        }
    }
}

/// The station `stx serve --sim` runs beside `mission`: the shipped configuration, with the
/// stack the scenario flies for its flight-path prediction.
pub fn station_for(mission: &MissionConfig) -> Result<StationConfig, CampaignError> {
    let mut c = StationConfig::from_toml_str(DEFAULT_STATION_TOML)
        .map_err(|e| CampaignError::Station(e.to_string()))?;
    c.recording.enabled = false;
    c.flight_path = mission.stack_config(&stx_dynamics::vehicle::Vehicle::straplex());
    Ok(c)
}

/// Every mission of `options`, with the station's keep-out zones `keep_out` (file, text).
pub fn specs(
    options: &CampaignOptions,
    keep_out: Option<(String, String)>,
) -> Result<Vec<MissionSpec>, CampaignError> {
    let dispersions = options
        .dispersions
        .as_ref()
        .map(|name| Ok::<_, CampaignError>((name.clone(), Dispersions::load(name)?)))
        .transpose()?;
    let mut out = Vec::new();
    for name in &options.missions {
        let base = MissionConfig::builtin(name)?;
        let seeds = options
            .seeds_of
            .iter()
            .find(|(n, _)| n == name)
            .map_or(&options.seeds, |(_, s)| s);
        for &seed in seeds {
            let heard = options.speeds.iter().map(|&s| (s, Delivery::EachPeriod));
            let bursts = options.bursts.then_some((BURST_SPEED, Delivery::Bursts));
            for (speed, delivery) in heard.chain(bursts) {
                let mut mission = base.clone();
                mission.seed = seed;
                out.push(MissionSpec {
                    station: station_for(&mission)?,
                    mission,
                    dispersions: dispersions.clone(),
                    speed,
                    delivery,
                    keep_out: keep_out.clone(),
                });
            }
        }
    }
    Ok(out)
}

/// A mission that did not fly to the end.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Failed {
    /// The mission.
    pub mission: String,
    /// Its seed.
    pub seed: u64,
    /// Mission time per station time.
    pub speed: f64,
    /// How the station heard the drone.
    pub delivery: &'static str,
    /// Why.
    pub error: String,
}

/// Flies `specs` on `threads` threads; `done` is told of each as it ends (from any thread).
/// Reports come back in the order of `specs`.
pub fn run(
    specs: &[MissionSpec],
    threads: usize,
    done: &(dyn Fn(&Result<MissionReport, Failed>) + Sync),
) -> Vec<Result<MissionReport, Failed>> {
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<Result<MissionReport, Failed>>>> =
        Mutex::new(vec![None; specs.len()]);
    std::thread::scope(|scope| {
        for _ in 0..threads.clamp(1, specs.len().max(1)) {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(spec) = specs.get(i) else { break };
                    let result = fly(spec).map_err(|e| Failed {
                        mission: spec.mission.name.clone(),
                        seed: spec.mission.seed,
                        speed: spec.speed,
                        delivery: spec.delivery.name(),
                        error: e.to_string(),
                    });
                    done(&result);
                    if let Ok(mut r) = results.lock() {
                        r[i] = Some(result);
                    }
                }
            });
        }
    });
    results
        .into_inner()
        .unwrap_or_default()
        .into_iter()
        .flatten()
        .collect()
}

/// The predictions of a campaign at one height.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PredictionSummary {
    /// Height above the ground, m.
    pub height_m: f64,
    /// The station's planned landing against the touchdown, m.
    pub station_error_m: Spread,
    /// The drone's own prediction against it, m.
    pub onboard_error_m: Spread,
    /// The largest excess of the station's error over the drone's in one mission, m.
    pub worst_excess_over_onboard_m: f64,
}

/// One goal, what it asks and what was measured.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Goal {
    /// What it asks.
    pub name: &'static str,
    /// The bound, in the measure's unit.
    pub bound: f64,
    /// What the campaign measured.
    pub measured: f64,
    /// Whether it holds.
    pub met: bool,
}

/// A campaign summed up.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    /// Missions flown to the landing.
    pub missions: usize,
    /// Missions that failed (each counts against every goal).
    pub failed: Vec<Failed>,
    /// The lowest share of the parafoil flight over which the phases agreed.
    pub phase_agreed_min: f64,
    /// The share over all parafoil flight.
    pub phase_agreed_all: f64,
    /// The longest phase disagreement, s.
    pub longest_phase_span_s: f64,
    /// Phase disagreements away from any transition of the drone's phase.
    pub phase_spans_away_from_transitions: usize,
    /// The final course while a spiral flies, degrees.
    pub final_course_error_deg: Spread,
    /// The target, m.
    pub target_error_m: Spread,
    /// Instants one side had a target and the other none.
    pub target_missing: u64,
    /// The predictions at each height.
    pub predictions: Vec<PredictionSummary>,
    /// The station's miss against the drone body's real one, m.
    pub station_miss_error_m: Spread,
    /// The replica's learned main-line trim against the drone's, largest in each mission, mm.
    pub trim_error_mm: Spread,
    /// The goals.
    pub goals: Vec<Goal>,
}

/// Sums up `results`.
pub fn summarise(results: &[Result<MissionReport, Failed>]) -> Summary {
    let reports: Vec<&MissionReport> = results.iter().filter_map(|r| r.as_ref().ok()).collect();
    let failed: Vec<Failed> = results
        .iter()
        .filter_map(|r| r.as_ref().err().cloned())
        .collect();
    let phase_agreed_min = reports.iter().map(|r| r.phase.agreed()).fold(1.0, f64::min);
    let (agreed, total) = reports.iter().fold((0u64, 0u64), |(a, t), r| {
        (a + r.phase.samples - r.phase.disagreed, t + r.phase.samples)
    });
    let phase_agreed_all = if total == 0 {
        1.0
    } else {
        agreed as f64 / total as f64
    };
    let spans = reports.iter().flat_map(|r| r.phase_spans.iter());
    let longest_phase_span_s = spans.clone().map(|s| s.duration_s).fold(0.0, f64::max);
    let phase_spans_away_from_transitions = spans.filter(|s| !s.near_transition).count();
    let final_course_error_deg =
        Spread::of(reports.iter().flat_map(|r| [r.final_course_error_deg.max]));
    let target_error_m = Spread::of(reports.iter().map(|r| r.target_error_m.max));
    let predictions = PREDICTION_HEIGHTS_M
        .iter()
        .map(|&h| {
            let at: Vec<_> = reports
                .iter()
                .filter_map(|r| r.predictions_at.iter().find(|p| p.height_m == h))
                .collect();
            PredictionSummary {
                height_m: h,
                station_error_m: Spread::of(at.iter().filter_map(|p| p.station_error_m)),
                onboard_error_m: Spread::of(at.iter().filter_map(|p| p.onboard_error_m)),
                worst_excess_over_onboard_m: at
                    .iter()
                    .filter_map(|p| Some(p.station_error_m? - p.onboard_error_m?))
                    .fold(f64::NEG_INFINITY, f64::max),
            }
        })
        .collect::<Vec<_>>();
    let station_miss_error_m = Spread::of(reports.iter().filter_map(|r| {
        let l = r.landing.as_ref()?;
        Some(l.station_miss_m? - l.drone_miss_m?)
    }));
    let target_missing = reports.iter().map(|r| r.target_missing).sum();
    let trim_error_mm = Spread::of(reports.iter().map(|r| r.trim_error_mm.max));
    let mut summary = Summary {
        missions: reports.len(),
        failed,
        phase_agreed_min,
        phase_agreed_all,
        longest_phase_span_s,
        phase_spans_away_from_transitions,
        final_course_error_deg,
        target_error_m,
        target_missing,
        predictions,
        station_miss_error_m,
        trim_error_mm,
        goals: Vec::new(),
    };
    summary.goals = goals(&summary);
    summary
}

/// The largest difference between the replica's learned trim and the drone's, mm. Updated at
/// the drone's instants, the replica's sums part from the drone's only by the two estimates'
/// differences: 0.10 mm at most over the full campaign's 60 missions, however heard. Updated
/// once per telemetry burst, it was 0.64 mm off in the short campaign heard in bursts, and its
/// prediction at 100 m 6 m further from the touchdown. The bound lies between the two.
const TRIM_BOUND_MM: f64 = 0.2;

/// The goals, checked on `s`; a failed mission fails them all.
fn goals(s: &Summary) -> Vec<Goal> {
    let all_flew = s.failed.is_empty();
    let goal = |name, bound: f64, measured: f64, met: bool| Goal {
        name,
        bound,
        measured,
        met: met && all_flew,
    };
    let at_100 = s.predictions.iter().find(|p| p.height_m == 100.0);
    let p95_100 = at_100.map_or(f64::INFINITY, |p| p.station_error_m.p95);
    let excess = s
        .predictions
        .iter()
        .map(|p| p.worst_excess_over_onboard_m)
        .fold(f64::NEG_INFINITY, f64::max);
    vec![
        goal(
            "guidance phase agrees over the parafoil flight (lowest share of one mission)",
            0.99,
            s.phase_agreed_min,
            s.phase_agreed_min >= 0.99,
        ),
        goal(
            "longest phase disagreement, s",
            2.0,
            s.longest_phase_span_s,
            s.longest_phase_span_s <= 2.0 && s.phase_spans_away_from_transitions == 0,
        ),
        goal(
            "final-approach course, largest error, degrees",
            5.0,
            s.final_course_error_deg.max,
            s.final_course_error_deg.max <= 5.0,
        ),
        goal(
            "target identical (largest difference, m)",
            0.05,
            s.target_error_m.max,
            s.target_error_m.max <= 0.05 && s.target_missing == 0,
        ),
        goal(
            "the replica learns the drone's main-line trim (largest difference, mm)",
            TRIM_BOUND_MM,
            s.trim_error_mm.max,
            s.trim_error_mm.max <= TRIM_BOUND_MM,
        ),
        goal(
            "predicted landing at 100 m above the ground, p95 error, m",
            15.0,
            p95_100,
            p95_100 <= 15.0,
        ),
        goal(
            "station's prediction never worse than the drone's by more than, m",
            5.0,
            excess,
            excess <= 5.0,
        ),
    ]
}
