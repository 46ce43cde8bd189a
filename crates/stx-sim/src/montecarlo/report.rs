//! What a campaign gave: the statistics operators judge it by ([`MonteCarloReport`]) and the
//! worst runs, named so that each can be replayed.

use serde::Serialize;

use super::run::{RunConditions, RunResult};

/// A run among the worst of a campaign, enough to replay it (`only_run`).
#[derive(Debug, Clone, Serialize)]
pub struct WorstRun {
    /// Index in the campaign.
    pub index: usize,
    /// Miss distance, m.
    pub miss_m: f64,
    /// Long (+) or short (−) along the upwind direction, m.
    pub long_short_m: f64,
    /// Right (+) or left (−) of it, m.
    pub left_right_m: f64,
    /// Heading at touchdown minus upwind, degrees.
    pub heading_vs_upwind_deg: f64,
    /// Its conditions.
    pub conditions: RunConditions,
}

/// Median, 95th percentile, maximum and mean of a sample.
#[derive(Debug, Clone, Copy, Serialize, Default)]
pub struct Stats {
    /// Median.
    pub median: f64,
    /// 95th percentile (nearest rank).
    pub p95: f64,
    /// Largest.
    pub max: f64,
    /// Mean.
    pub mean: f64,
}

impl Stats {
    /// Statistics of `values` (NaN-free).
    pub fn of(values: &[f64]) -> Self {
        if values.is_empty() {
            return Self::default();
        }
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        let rank =
            |q: f64| sorted[((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len()) - 1];
        Self {
            median: if sorted.len() % 2 == 1 {
                sorted[sorted.len() / 2]
            } else {
                0.5 * (sorted[sorted.len() / 2 - 1] + sorted[sorted.len() / 2])
            },
            p95: rank(0.95),
            max: sorted[sorted.len() - 1],
            mean: sorted.iter().sum::<f64>() / sorted.len() as f64,
        }
    }
}

/// The campaign's result (printed by `stx montecarlo --json`).
#[derive(Debug, Clone, Serialize)]
pub struct MonteCarloReport {
    /// Runs flown.
    pub runs: usize,
    /// Campaign seed.
    pub seed: u64,
    /// Largest mean wind, m/s.
    pub wind_max_mps: f64,
    /// Release height above the target, m.
    pub altitude_m: f64,
    /// Whether guidance flared.
    pub flare: bool,
    /// Distance from the target at touchdown, m.
    pub miss_m: Stats,
    /// Share of touchdowns with the heading within 30° of upwind (runs in calm air, where no
    /// upwind exists, count as into the wind).
    pub into_wind_fraction: f64,
    /// The same share with calm runs judged like the others, against the instantaneous wind
    /// (gusts included) where they touched down.
    pub into_wind_fraction_strict: f64,
    /// Runs that touched down in calm air (mean wind below [`CALM_WIND_MPS`]).
    pub calm_runs: usize,
    /// Vertical speed at touchdown, m/s.
    pub touchdown_vertical_speed_mps: Stats,
    /// RMS of the wind-estimate error from 30 s after release, over all runs, m/s.
    pub wind_estimate_rmse_mps: f64,
    /// Per-run wind-estimate RMS errors, m/s.
    pub wind_estimate_rmse_per_run_mps: Stats,
    /// Runs in which guidance found the target out of reach.
    pub unreachable_runs: usize,
    /// Over those runs, the distance from the best reachable point guidance first announced
    /// to the touchdown, m.
    pub unreachable_from_best_m: Stats,
    /// The same from the best reachable point announced last, m.
    pub unreachable_from_last_best_m: Stats,
    /// Runs that failed to fly (integration error), with their index and reason.
    pub failed_runs: Vec<(usize, String)>,
    /// Wall-clock time, s.
    pub wall_time_s: f64,
    /// The runs with the largest misses, worst first (at most [`WORST_RUNS`]).
    pub worst: Vec<WorstRun>,
    /// Every run.
    pub results: Vec<RunResult>,
}

/// Largest angle between heading and upwind at touchdown that counts as into the wind, degrees.
pub const INTO_WIND_DEG: f64 = 30.0;

/// Share of `results` that touched down into the wind (within [`INTO_WIND_DEG`] of upwind);
/// with `calm_counts`, runs in calm air count as into the wind whatever their heading.
pub fn into_wind_fraction(results: &[RunResult], calm_counts: bool) -> f64 {
    if results.is_empty() {
        return 0.0;
    }
    let into_wind = results
        .iter()
        .filter(|r| (calm_counts && r.calm) || r.heading_vs_upwind_deg.abs() <= INTO_WIND_DEG)
        .count();
    into_wind as f64 / results.len() as f64
}

/// How many of the worst runs a report names.
pub const WORST_RUNS: usize = 5;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::montecarlo::config::MonteCarloConfig;
    use crate::montecarlo::run::conditions;

    fn landed(heading_vs_upwind_deg: f64, calm: bool) -> RunResult {
        RunResult {
            index: 0,
            conditions: conditions(&MonteCarloConfig::default(), 0),
            miss_m: 1.0,
            heading_vs_upwind_deg,
            calm,
            touchdown_vertical_speed_mps: 2.5,
            wind_estimate_rmse_mps: 0.2,
            unreachable: false,
            best_reachable_ne_m: None,
            from_best_reachable_m: None,
            last_best_reachable_ne_m: None,
            from_last_best_reachable_m: None,
            flight_time_s: 200.0,
            long_short_m: 0.0,
            left_right_m: 0.0,
            events: Vec::new(),
            track: Vec::new(),
        }
    }

    #[test]
    fn into_the_wind_means_within_30_degrees_of_upwind_on_either_side() {
        let runs = [
            landed(29.0, false),
            landed(-30.0, false),
            landed(31.0, false),
            landed(-179.0, false),
        ];
        assert_eq!(into_wind_fraction(&runs, true), 0.5);
        assert_eq!(into_wind_fraction(&runs, false), 0.5);
    }

    #[test]
    fn a_calm_touchdown_counts_as_into_the_wind_whatever_its_heading_except_when_strict() {
        let runs = [landed(150.0, true), landed(150.0, false)];
        assert_eq!(into_wind_fraction(&runs, true), 0.5);
        assert_eq!(into_wind_fraction(&runs, false), 0.0);
        assert_eq!(into_wind_fraction(&[], true), 0.0);
    }
}
