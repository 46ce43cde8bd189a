//! Regression: a small campaign with realistic dispersions, flown in the test command, must not
//! get worse than the figures it gave when these bounds were set (issue 13, item 4). Our own
//! output pinned, not a reference's: the goals themselves are measured on 1,000-run campaigns
//! (see `crates/stx-gnc/GNC_NOTES.md`).

use stx_gnc::estimator::EstimatorConfig;
use stx_sim::closed_loop::SensedNavigation;
use stx_sim::dispersions::Dispersions;
use stx_sim::montecarlo::{MonteCarloConfig, run_all};

/// Bounds set on 2026-11-25 from this campaign's figures then (median 9.6 m, p95 54.0 m, one
/// failed run: run 24, whose dispersed stack goes non-finite at 174.3 s whatever the step,
/// down to 0.8 ms) with about 20 % of room.
const MEDIAN_BOUND_M: f64 = 11.5;
const P95_BOUND_M: f64 = 65.0;
const FAILED_BOUND: usize = 1;

#[test]
fn regression_sixty_realistic_runs_keep_their_miss_and_failures() {
    let config = MonteCarloConfig {
        runs: 60,
        seed: 2026,
        threads: 2,
        dispersions: Dispersions::realistic(),
        ..MonteCarloConfig::default()
    };
    let report = run_all(
        &config,
        |c, sensors| {
            SensedNavigation::new(sensors, EstimatorConfig::default(), c.seed)
                .map_err(|e| e.to_string())
        },
        |_| {},
    )
    .expect("the campaign runs");
    let m = report.miss_m;
    eprintln!(
        "60 realistic runs, seed 2026: miss (first contact) median {:.1} m, p95 {:.1} m, max {:.1} m; \
         {} failed; touchdown vertical speed median {:.2} m/s; wind RMS {:.2} m/s",
        m.median,
        m.p95,
        m.max,
        report.failed_runs.len(),
        report.touchdown_vertical_speed_mps.median,
        report.wind_estimate_rmse_mps
    );
    assert_eq!(report.runs, 60);
    assert!(
        report.failed_runs.len() <= FAILED_BOUND,
        "{:?}",
        report.failed_runs
    );
    assert!(m.median <= MEDIAN_BOUND_M, "median {:.1} m", m.median);
    assert!(m.p95 <= P95_BOUND_M, "p95 {:.1} m", m.p95);
}
