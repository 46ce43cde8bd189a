//! A Monte Carlo campaign stopped part-way (the Lab's cancel and time cap) reports the runs it
//! flew, the same runs as an uninterrupted campaign's first ones, and starts no further run.

use std::sync::atomic::{AtomicUsize, Ordering};

use stx_sim::closed_loop::PerfectNavigation;
use stx_sim::montecarlo::{MonteCarloConfig, run_all, run_until};

fn config() -> MonteCarloConfig {
    MonteCarloConfig {
        runs: 6,
        seed: 7,
        altitude_m: 150.0,
        release_radius_m: 100.0,
        threads: 1,
        ..MonteCarloConfig::default()
    }
}

#[test]
fn a_stopped_campaign_reports_only_the_runs_flown_before_the_stop() {
    let done = AtomicUsize::new(0);
    let stopped = run_until(
        &config(),
        |_, _| Ok(PerfectNavigation),
        |n| done.store(n, Ordering::Relaxed),
        || done.load(Ordering::Relaxed) >= 2,
    )
    .expect("runs");
    assert_eq!(stopped.runs, 2, "stop is checked before each run");
    assert_eq!(done.load(Ordering::Relaxed), 2);
    let whole = run_all(&config(), |_, _| Ok(PerfectNavigation), |_| {}).expect("runs");
    assert_eq!(whole.runs, 6);
    let first = |r: &stx_sim::montecarlo::MonteCarloReport| {
        r.results.iter().map(|x| x.index).collect::<Vec<_>>()
    };
    assert_eq!(first(&stopped), first(&whole)[..2].to_vec());
}

#[test]
fn a_campaign_stopped_before_it_starts_flies_nothing() {
    let report = run_until(&config(), |_, _| Ok(PerfectNavigation), |_| {}, || true).expect("runs");
    assert_eq!(report.runs, 0);
}
