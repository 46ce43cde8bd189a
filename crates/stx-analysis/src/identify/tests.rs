use std::sync::atomic::AtomicBool;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use stx_dynamics::vehicle::{STRAPLEX_TOML, VehicleConfig};
use stx_sim::dispersions::Dispersions;

use super::*;
use crate::flight_log::synthetic::{SlowErrors, SyntheticFlight, simulate};

fn nominal() -> VehicleConfig {
    VehicleConfig::from_toml_str(STRAPLEX_TOML).unwrap()
}

/// A vehicle whose `params` are drawn from the realistic dispersions' spread (canopy or brake
/// 1-σ fractions, clipped at ±3 σ as stx-sim clips them), the rest nominal.
fn dispersed(params: &[Param], seed: u64) -> VehicleConfig {
    let d = Dispersions::realistic();
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x1de7);
    let mut v = nominal();
    for p in params {
        let g: f64 = StandardNormal.sample(&mut rng);
        let g = g.clamp(-3.0, 3.0);
        match p {
            Param::RiggingDeg => p.set(&mut v, d.rigging.angle_sigma_deg * g),
            Param::ClDs | Param::CdDs | Param::ClDa | Param::CnDa => {
                let value = p.get(&v) * (1.0 + d.aero.brake_sigma * g);
                p.set(&mut v, value)
            }
            _ => {
                let value = p.get(&v) * (1.0 + d.aero.canopy_sigma * g);
                p.set(&mut v, value)
            }
        }
    }
    v
}

/// Trials for the coverage test: `STX_IDENTIFY_TRIALS`, or 20 (about 40 s in release).
fn trials() -> u64 {
    std::env::var("STX_IDENTIFY_TRIALS")
        .ok()
        .and_then(|t| t.parse().ok())
        .unwrap_or(20)
}

const COVERAGE_PARAMS: [Param; 3] = [Param::ClAlpha, Param::Cd0, Param::CnDa];

/// Over `n` seeds: a vehicle whose lift slope, zero-lift drag and turn term are drawn from the
/// realistic dispersions flies `flight(seed)` and is fitted from the nominal vehicle. Returns
/// how many of the `n` intervals held the truth, per parameter, and the worst errors
/// (relative for cl_alpha and cd0, absolute for cn_da).
fn coverage(
    n: u64,
    flight: &dyn Fn(u64) -> SyntheticFlight,
    options: &IdentifyOptions,
) -> ([u64; 3], [f64; 3]) {
    let params = COVERAGE_PARAMS;
    let mut covered = [0u64; 3];
    let mut worst = [0.0_f64; 3];
    for seed in 0..n {
        let truth = dispersed(&params, seed);
        let log = simulate(&truth.clone().validate().unwrap(), &flight(seed)).unwrap();
        let report = identify(
            &[log],
            &params,
            &nominal(),
            options,
            &AtomicBool::new(false),
            &mut |_| {},
        )
        .unwrap();
        for (k, (p, e)) in params.iter().zip(&report.params).enumerate() {
            let t = p.get(&truth);
            let [lo, hi] = e.interval95.unwrap();
            let inside = (lo..=hi).contains(&t);
            covered[k] += u64::from(inside);
            let err = if k == 2 {
                (e.estimate - t).abs()
            } else {
                ((e.estimate - t) / t).abs()
            };
            worst[k] = worst[k].max(err);
            eprintln!(
                "trial {seed} {}: truth {t:.5} estimate {:.5} ± {:.5} {} ({:+.2} σ)",
                e.name,
                e.estimate,
                e.interval95.map_or(f64::NAN, |[lo, hi]| 0.5 * (hi - lo)),
                if inside { "in" } else { "OUT" },
                (e.estimate - t) / e.std_error.unwrap()
            );
        }
        eprintln!(
            "trial {seed}: rms {:.2} → {:.2} after {} iterations ({:?}), lag {:?} t {:?}",
            report.residual_rms_before,
            report.residual_rms_after,
            report.iterations,
            report.stop,
            report.newey_west_lag,
            report.interval_t
        );
        assert!(report.residual_rms_after <= report.residual_rms_before);
    }
    eprintln!("inside the 95 % interval in {covered:?} of {n} trials; worst errors {worst:?}");
    (covered, worst)
}

/// Seeded flights logged with white sensor noise. Measured (module doc): 20, 19, 20 of 20
/// inside the 95 % interval (29, 28, 29 of 30); worst errors 0.45 %, 0.48 % and 0.00015.
#[test]
fn the_95_percent_intervals_hold_the_truth_in_at_least_9_of_10_trials() {
    let n = trials();
    let (covered, worst) = coverage(n, &SyntheticFlight::manoeuvres, &IdentifyOptions::default());
    for c in covered {
        assert!(10 * c >= 9 * n, "inside in {covered:?} of {n}");
    }
    // Against a realistic spread of 20 % (canopy) and 30 % (brakes) 1-σ.
    for (k, e) in worst.iter().enumerate() {
        assert!(*e < [0.01, 0.01, 0.0005][k], "worst errors {worst:?}");
    }
}

/// The flights of the test above with a wandering GPS and a wind estimate lagging a wind that
/// turns with height ([`SlowErrors::ublox_wind_shear`]); the GPS's white jitter is a
/// receiver's decimetres, its error being the wander.
fn wandering(seed: u64) -> SyntheticFlight {
    let mut flight = SyntheticFlight::manoeuvres(seed);
    flight.slow = Some(SlowErrors::ublox_wind_shear());
    flight.noise.horizontal_m = 0.3;
    flight.noise.vertical_m = 0.5;
    flight
}

/// Our own statistical claim, measured here (no reference figure): with slow errors in the
/// log, the intervals with the lag found from the residuals still hold the truth in 8 of 10
/// trials or more, where the white-noise sandwich (lag 0, the default before) held it in at
/// most half of them for some parameter. Measured: 9, 10, 10 of 10 against 2, 5, 1 of 10;
/// with `STX_IDENTIFY_TRIALS=20`, 18, 19, 19 of 20 against 4, 11, 3 of 20 (cl_alpha, cd0,
/// cn_da). About 35 s in release.
#[test]
fn own_claim_intervals_hold_the_truth_in_8_of_10_with_wandering_gps_and_lagging_wind() {
    let n = std::env::var("STX_IDENTIFY_TRIALS")
        .ok()
        .and_then(|t| t.parse().ok())
        .unwrap_or(10);
    let (covered, _) = coverage(n, &wandering, &IdentifyOptions::default());
    let white = IdentifyOptions {
        automatic_lag: false,
        ..IdentifyOptions::default()
    };
    let (before, _) = coverage(n, &wandering, &white);
    eprintln!("found lag: {covered:?} of {n}; lag 0: {before:?} of {n}");
    for c in covered {
        assert!(10 * c >= 8 * n, "inside in {covered:?} of {n}");
    }
    // The slow errors must matter, or the claim above tells nothing.
    assert!(
        2 * before.iter().min().unwrap() <= n,
        "lag 0 inside in {before:?} of {n}"
    );
}

#[test]
fn the_fitted_file_is_a_vehicle_and_bad_requests_are_refused() {
    let truth = dispersed(&[Param::ClAlpha], 3);
    let mut flight = SyntheticFlight::manoeuvres(3);
    flight.duration_s = 40.0;
    let log = simulate(&truth.clone().validate().unwrap(), &flight).unwrap();
    let mut heard = 0;
    let report = identify(
        std::slice::from_ref(&log),
        &[Param::ClAlpha],
        &nominal(),
        &IdentifyOptions::default(),
        &AtomicBool::new(false),
        &mut |_| heard += 1,
    )
    .unwrap();
    assert!(heard >= 1);
    let fitted = VehicleConfig::from_toml_str(&report.vehicle_toml).unwrap();
    assert_eq!(fitted.canopy.aero.cl_alpha, report.params[0].estimate);
    assert_eq!(report.correlation.as_ref().unwrap()[0][0], 1.0);
    let run = |params: &[Param], logs: &[FlightLog]| {
        identify(
            logs,
            params,
            &nominal(),
            &IdentifyOptions::default(),
            &AtomicBool::new(false),
            &mut |_| {},
        )
    };
    assert!(matches!(
        run(&[], std::slice::from_ref(&log)),
        Err(IdentifyError::NoParams)
    ));
    assert!(matches!(
        run(&[Param::Cd0], &[]),
        Err(IdentifyError::NoFlights)
    ));
    assert!(matches!(
        run(&[Param::Cd0, Param::Cd0], std::slice::from_ref(&log)),
        Err(IdentifyError::Duplicate("cd0"))
    ));
}
