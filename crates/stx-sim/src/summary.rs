//! The figures a run is judged by (issue "Foundation", item 4): when it settles, how it glides
//! once steady, its extremes, and where it lands.

use serde::Serialize;
use stx_dynamics::model::Body;
use stx_dynamics::output::Sample;
use stx_dynamics::state::{StateVector, idx};

use crate::scenario::Scenario;

/// What the summary needs of every accepted step, taken from the state alone.
#[derive(Debug, Clone, Copy)]
pub struct StepRecord {
    /// Time, s.
    pub time_s: f64,
    /// Canopy pitch rate, line pitch rate and the drone's rates relative to the line are all
    /// below the threshold.
    pub settled: bool,
    /// Canopy CM speed, m/s.
    pub speed_mps: f64,
    /// Canopy pitch, degrees.
    pub canopy_pitch_deg: f64,
    /// Canopy yaw rate r, rad/s.
    pub yaw_rate_rad_s: f64,
}

impl StepRecord {
    /// The record of state `x` at `time_s` with settling threshold `threshold_rad_s`.
    pub fn from_state(time_s: f64, x: &StateVector, threshold_rad_s: f64) -> Self {
        let rates = [
            x[idx::CANOPY_RATES + 1],
            x[idx::LINE_PITCH_RATE],
            x[idx::DRONE_RATES],
            x[idx::DRONE_RATES + 1],
            x[idx::DRONE_RATES + 2],
        ];
        Self {
            time_s,
            settled: rates.iter().all(|r| r.abs() < threshold_rad_s),
            speed_mps: x.fixed_rows::<3>(idx::CANOPY_VELOCITY).norm(),
            canopy_pitch_deg: x[idx::CANOPY_EULER + 1].to_degrees(),
            yaw_rate_rad_s: x[idx::CANOPY_RATES + 2],
        }
    }
}

/// Steady glide, averaged over a steady stretch.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Steady {
    /// Stretch averaged, s from the start.
    pub from_s: f64,
    /// End of the stretch, s.
    pub to_s: f64,
    /// Canopy airspeed, m/s.
    pub airspeed_mps: f64,
    /// Canopy sink rate, m/s (positive down).
    pub sink_rate_mps: f64,
    /// Horizontal ground speed over sink rate.
    pub glide_ratio: f64,
    /// Canopy angle of attack, degrees.
    pub alpha_deg: f64,
}

/// First ground contact.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Landing {
    /// North of the origin, m, of the body that touched first.
    pub x_m: f64,
    /// East of the origin, m.
    pub y_m: f64,
    /// Time of contact, s.
    pub time_s: f64,
    /// Which body touched first (the lowest hanging one).
    pub body: &'static str,
    /// Its vertical speed at contact, m/s (positive down).
    pub vertical_speed_mps: f64,
    /// How far from what guidance was asked to fly, m: from the spiral's target; from the
    /// localizer's point when a glide slope leads down to it; and for a localizer alone,
    /// which fixes a line but not where along it to land, the distance from that line
    /// (`|cross_track_m|`).
    pub miss_m: Option<f64>,
    /// In localizer mode, the touchdown's distance right (+) or left (−) of the localizer
    /// line, m.
    pub cross_track_m: Option<f64>,
    /// In localizer mode, the touchdown's distance along the line past (+) or short of (−)
    /// the localizer's point, m.
    pub along_track_m: Option<f64>,
    /// Canopy heading at contact minus the direction the wind comes from, degrees; absent in
    /// calm air.
    pub heading_vs_upwind_deg: Option<f64>,
}

/// A phase of guidance (or of a control law) and when it began.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PhaseStart {
    /// Phase name.
    pub phase: String,
    /// Its start, s.
    pub start_time_s: f64,
}

/// The run in numbers (printed by `stx sim --summary-json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    /// Scenario name.
    pub scenario: String,
    /// Simulated time, s.
    pub sim_time_s: f64,
    /// Wall-clock time of the run, s.
    pub wall_time_s: f64,
    /// Simulated seconds per wall-clock second.
    pub real_time_factor: f64,
    /// Derivative evaluations.
    pub rhs_evals: u64,
    /// First time after which the canopy pitch rate, the line pitch rate and the drone's
    /// relative rates all stay below the threshold, s; null if they never do.
    pub settle_time_s: Option<f64>,
    /// Steady glide over the last steady stretch; null if none.
    pub steady: Option<Steady>,
    /// Smallest line tension seen, N.
    pub min_line_tension_n: f64,
    /// Largest deviation of a constrained line (mean main line, capsule line, transponder
    /// line) from its length, m, measured between the model's own line ends. The model's
    /// coordinates make these lengths hold by construction, so this is the floating-point
    /// consistency of its kinematic chain (~1e-11 m), not a check of the physics; the chain
    /// itself is checked against the tabled geometry in `stx-dynamics/tests/dynamics/physics.rs`.
    pub max_line_length_error_m: f64,
    /// Largest total speed of the canopy, km/h.
    pub max_total_speed_kmh: f64,
    /// Lowest canopy pitch, degrees.
    pub min_canopy_pitch_deg: f64,
    /// Seconds after the last command change until |r| stays below the threshold; null if
    /// the scenario has no change or |r| never settles.
    pub yaw_rate_settle_s: Option<f64>,
    /// Ground contact, if the run reached the ground.
    pub landing: Option<Landing>,
    /// The payload's (the capsule's) touchdown in a guided run: the stack flies on after the
    /// transponder's contact until the capsule touches (`GuidedFlight::land_payload`), as the
    /// Monte Carlo's `payload_miss_m`; the same as `landing` when another body touched first.
    /// Absent in open loop, or when the run did not reach the ground.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub payload_landing: Option<Landing>,
    /// Seconds the run was extended past the scenario's duration to find a steady stretch.
    pub extended_s: f64,
    /// Guidance phases in order with their start times (closed-loop scenarios).
    pub phases: Vec<PhaseStart>,
}

/// The last stretch of `window_s` with every step settled and no command change inside.
pub fn steady_window(
    steps: &[StepRecord],
    window_s: f64,
    scenario: &Scenario,
) -> Option<(f64, f64)> {
    let last = steps.iter().rposition(|s| s.settled)?;
    let mut first = last;
    while first > 0 && steps[first - 1].settled {
        first -= 1;
    }
    let last_change = scenario
        .control_change_times()
        .into_iter()
        .filter(|t| *t <= steps[last].time_s)
        .fold(f64::NEG_INFINITY, f64::max);
    let from = steps[first].time_s.max(last_change);
    let to = steps[last].time_s;
    (to - from >= window_s).then_some((to - window_s, to))
}

/// Builds the summary of a run.
#[allow(clippy::too_many_arguments)]
pub fn summarise(
    scenario: &Scenario,
    steps: &[StepRecord],
    samples: &[Sample],
    line_errors_m: &[f64],
    landing: Option<Landing>,
    extended_s: f64,
    rhs_evals: u64,
    wall_time_s: f64,
) -> Summary {
    let sim_time_s = steps.last().map(|s| s.time_s).unwrap_or(0.0);
    let settle_time_s = match steps.iter().rposition(|s| !s.settled) {
        None => Some(0.0),
        Some(i) if i + 1 == steps.len() => None,
        Some(i) => Some(steps[i + 1].time_s),
    };
    let steady = steady_window(steps, scenario.steady.window_s, scenario).map(|(from, to)| {
        let window: Vec<&Sample> = samples
            .iter()
            .filter(|s| s.time_s >= from && s.time_s <= to)
            .collect();
        let n = window.len().max(1) as f64;
        let mean = |f: &dyn Fn(&Sample) -> f64| window.iter().map(|s| f(s)).sum::<f64>() / n;
        let sink = mean(&|s| s.body(Body::Canopy).velocity_ned_mps[2]);
        let ground = mean(&|s| {
            let v = s.body(Body::Canopy).velocity_ned_mps;
            v[0].hypot(v[1])
        });
        Steady {
            from_s: from,
            to_s: to,
            airspeed_mps: mean(&|s| s.airspeed_mps),
            sink_rate_mps: sink,
            glide_ratio: ground / sink,
            alpha_deg: mean(&|s| s.alpha_deg),
        }
    });
    let yaw_rate_settle_s = scenario
        .control_change_times()
        .last()
        .copied()
        .and_then(|change| {
            let after: Vec<&StepRecord> = steps.iter().filter(|s| s.time_s >= change).collect();
            let threshold = scenario.steady.rate_threshold_rad_s;
            match after
                .iter()
                .rposition(|s| s.yaw_rate_rad_s.abs() >= threshold)
            {
                None => Some(0.0),
                Some(i) if i + 1 == after.len() => None,
                Some(i) => Some(after[i + 1].time_s - change),
            }
        });
    Summary {
        scenario: scenario.name.clone(),
        sim_time_s,
        wall_time_s,
        real_time_factor: sim_time_s / wall_time_s.max(1e-9),
        rhs_evals,
        settle_time_s,
        steady,
        min_line_tension_n: samples
            .iter()
            .flat_map(|s| s.tensions_n)
            .fold(f64::INFINITY, f64::min),
        max_line_length_error_m: line_errors_m.iter().copied().fold(0.0, f64::max),
        max_total_speed_kmh: steps.iter().map(|s| s.speed_mps).fold(0.0, f64::max) * 3.6,
        min_canopy_pitch_deg: steps
            .iter()
            .map(|s| s.canopy_pitch_deg)
            .fold(f64::INFINITY, f64::min),
        yaw_rate_settle_s,
        landing,
        payload_landing: None,
        extended_s,
        phases: Vec::new(),
    }
}
