//! Regression: a small campaign with realistic dispersions, flown in the test command, must not
//! get worse than the figures it gave when these bounds were set (issue 13, item 4). Our own
//! output pinned, not a reference's: the goals themselves are measured on 1,000-run campaigns
//! (see `crates/stx-gnc/GNC_NOTES.md`).

use stx_gnc::estimator::EstimatorConfig;
use stx_sim::dispersions::Dispersions;
use stx_sim::montecarlo::{MonteCarloConfig, run_sensed};

/// Bounds on the payload's (the capsule's) miss, set on 2026-11-25 from this campaign's
/// figures then (median 6.8 m, p95 41.1 m, no failed run; the first contact's: 9.3 m and 43.2 m)
/// with about 20 % of room; one failed run is allowed, as a dispersed stack can go non-finite
/// whatever the step (seen in about 0.5 % of realistic runs).
const MEDIAN_BOUND_M: f64 = 8.5;
const P95_BOUND_M: f64 = 50.0;
const FAILED_BOUND: usize = 1;

#[test]
fn regression_sixty_realistic_runs_keep_their_payload_miss_and_failures() {
    let config = MonteCarloConfig {
        runs: 60,
        seed: 2026,
        threads: 2,
        dispersions: Dispersions::realistic(),
        ..MonteCarloConfig::default()
    };
    let report = run_sensed(&config, &EstimatorConfig::default()).expect("the campaign runs");
    let m = report.payload_miss_m;
    eprintln!(
        "60 realistic runs, seed 2026: payload miss median {:.1} m, p95 {:.1} m, max {:.1} m; \
         {} failed; payload touchdown vertical speed median {:.2} m/s; wind RMS {:.2} m/s",
        m.median,
        m.p95,
        m.max,
        report.failed_runs.len(),
        report.payload_touchdown_vertical_speed_mps.median,
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
