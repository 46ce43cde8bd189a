//! Identification pays off in landings (issue 16 item 2): a stack whose canopy has 20 % less
//! lift than the model guidance plans with is flown through a manoeuvre flight, its lift
//! slope and zero-lift drag are identified from that log, and guidance planning with the
//! identified vehicle's steady glide lands its payload closer, on the same seeded Monte Carlo
//! flights, than guidance planning with the nominal one.
//!
//! Measured (seed 16, 300 m, wind ≤ 4 m/s, 100 runs, realistic dispersions drawn around the
//! stack, perfect navigation): with guidance's in-flight learning of the glide frozen, mean
//! payload miss 26.52 m planning with the nominal vehicle, 22.96 m with the identified one
//! (paired improvement 3.56 ± 1.47 m, one standard error); with learning, as guidance flies,
//! 11.56 m and 10.73 m (0.83 ± 0.77 m: within the scatter). The learning recovers most of
//! what a wrong table costs.

use std::sync::atomic::AtomicBool;

use stx_analysis::flight_log::synthetic::{SyntheticFlight, simulate};
use stx_analysis::identify::{IdentifyOptions, Param, identify};
use stx_analysis::performance::glide_performance_of;
use stx_dynamics::vehicle::{Vehicle, VehicleConfig};
use stx_gnc::performance::GlidePerformance;
use stx_sim::closed_loop::PerfectNavigation;
use stx_sim::dispersions::Dispersions;
use stx_sim::montecarlo::{MonteCarloConfig, run_one, steady_glide_state};

/// Mean payload miss of guidance planning with `performance` over `runs` flights of `flown`.
/// Realistic dispersions are drawn around `flown` (the wind's shape, masses, rigging, servos,
/// coefficients); navigation is perfect, so the sensors' dispersions do not enter. Guidance
/// learns the glide in flight as it always does, from the table it is given.
fn misses(flown: &Vehicle, performance: GlidePerformance, learn: bool, runs: usize) -> Vec<f64> {
    let mut config = MonteCarloConfig {
        runs,
        seed: 16,
        altitude_m: 300.0,
        release_radius_m: 200.0,
        threads: 1,
        dispersions: Dispersions::realistic(),
        ..MonteCarloConfig::default()
    };
    config.guidance.performance = performance;
    config.guidance.freeze_learning = !learn;
    let template = steady_glide_state(flown).expect("glide");
    (0..runs)
        .map(|i| {
            run_one(&config, flown, &template, i, |_, _| Ok(PerfectNavigation))
                .expect("run")
                .payload_miss_m
        })
        .collect()
}

/// Mean of `nominal`, mean of `identified`, and the mean of their paired differences with
/// its standard error, m.
fn compare(nominal: &[f64], identified: &[f64]) -> [f64; 4] {
    let n = nominal.len() as f64;
    let mean = |v: &[f64]| v.iter().sum::<f64>() / n;
    let d: Vec<f64> = nominal.iter().zip(identified).map(|(a, b)| a - b).collect();
    let dm = mean(&d);
    let se = (d.iter().map(|x| (x - dm).powi(2)).sum::<f64>() / ((n - 1.0) * n)).sqrt();
    [mean(nominal), mean(identified), dm, se]
}

#[test]
fn guidance_with_the_identified_polar_lands_closer_than_with_the_nominal_one() {
    let nominal = Vehicle::straplex();
    let mut truth: VehicleConfig = nominal.config.clone();
    truth.canopy.aero.cl_alpha *= 0.8;
    let truth = truth.validate().expect("truth");
    let log = simulate(&truth, &SyntheticFlight::manoeuvres(16)).expect("flight");
    let report = identify(
        &[log],
        &[Param::ClAlpha, Param::Cd0],
        &nominal.config,
        &IdentifyOptions::default(),
        &AtomicBool::new(false),
        &mut |_| {},
    )
    .expect("identified");
    let identified = Vehicle::from_toml_str(&report.vehicle_toml).expect("vehicle");
    eprintln!(
        "cl_alpha {:.4} (truth {:.4}), cd0 {:.4}",
        identified.config.canopy.aero.cl_alpha,
        truth.config.canopy.aero.cl_alpha,
        identified.config.canopy.aero.cd0
    );
    // The trimmed table of the shipped vehicle is the shipped table (within 0.5 %): the
    // comparison is between vehicles, not between ways of making a table.
    let trimmed = glide_performance_of(&nominal).expect("trimmed table");
    let shipped = GlidePerformance::default();
    for k in 0..shipped.brake_points.len() {
        assert!((trimmed.airspeed_mps[k] / shipped.airspeed_mps[k] - 1.0).abs() < 0.006);
        assert!((trimmed.sink_rate_mps[k] / shipped.sink_rate_mps[k] - 1.0).abs() < 0.006);
    }
    assert!(
        (identified.config.canopy.aero.cl_alpha / truth.config.canopy.aero.cl_alpha - 1.0).abs()
            < 0.01
    );
    let runs = std::env::var("STX_LANDING_RUNS").map_or(100, |r| r.parse().expect("runs"));
    let mut figures = Vec::new();
    for learn in [false, true] {
        let a = misses(&truth, trimmed, learn, runs);
        let b = misses(
            &truth,
            glide_performance_of(&identified).expect("identified table"),
            learn,
            runs,
        );
        let f = compare(&a, &b);
        eprintln!(
            "learning {learn}: mean payload miss over {runs} runs planning with the nominal \
             vehicle {:.2} m, with the identified one {:.2} m; paired improvement {:.2} ± {:.2} m",
            f[0], f[1], f[2], f[3]
        );
        figures.push(f);
    }
    // With learning frozen the table is all guidance knows of the glide: the identified one
    // lands closer by more than two standard errors of the paired difference (measured 2.4).
    let [_, _, gain, se] = figures[0];
    assert!(gain > 2.0 * se, "{figures:?}");
    // Learning in flight recovers most of it; what is left is within the runs' scatter
    // (regression pin of seed 16: still closer on the mean).
    assert!(figures[1][1] < figures[1][0], "{figures:?}");
}
