//! The reachable footprint (`stx_gnc::footprint`, issue 15 item 1) checked against the 14-DOF
//! model with the sensors, the estimator and spiral guidance in the loop: points inside its
//! 95 % contour must be reached in at least 95 % of full-model flights whose wind is drawn
//! within the uncertainty the footprint was given, and points well outside it must mostly not
//! be (so that the check can fail).
//!
//! The start is the rehearsal scenario's (`config/scenarios/rehearsal.toml`): under the
//! parafoil 900 m above the ground, 700 m south-west of the origin, in its sheared wind profile
//! (2 m/s from 300° at the ground, 3 m/s from 290° at 1,000 m). The footprint is computed from
//! the true state at release (the estimate guidance starts from), with that profile as the
//! wind below and an uncertainty of [`WIND_SIGMA_MPS`] per component. Each flight targets one
//! point with the spiral landing, in that profile offset by a constant wind drawn from the same
//! uncertainty plus Dryden turbulence (10 % of the speed, at least 0.1 m/s, as the Monte Carlo).
//!
//! "Reached" means the capsule lands within [`REACHED_M`] of the point: the bound the realistic
//! campaign's 95th-percentile capsule miss is held to (`campaign_regression.rs`, 50 m; its
//! 1,000-run figures are 29–31 m, `crates/stx-analysis/ANALYSIS_NOTES.md`). Guidance's own
//! scatter on reachable targets stays inside it (nominal p95 9–11 m), so a miss beyond it is a
//! point the stack could not reach, not guidance's scatter; and it is small beside the
//! footprint (about 2.5 km across the 95 % contour), so it does not blur what is tested.
//!
//! The footprint's default reserve (250 m) and turn margin (100 m) were set by this test: with
//! 150 m and 50 m, 51 of 56 points were reached, the misses (77–168 m short) all on the
//! downwind side, where guidance flies a downwind leg past the point and a base leg before
//! its final; with 250 m and 100 m all 56 were (20 s on this machine, two threads).

use std::sync::Arc;

use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use stx_dynamics::atmosphere::StandardAtmosphere;
use stx_dynamics::model::{Environment, ParafoilModel};
use stx_dynamics::state::idx;
use stx_dynamics::vehicle::Vehicle;
use stx_dynamics::wind::{
    ProfileRow, Turbulence, TurbulenceParams, WindComposite, WindField, WindProfile,
};
use stx_gnc::estimator::EstimatorConfig;
use stx_gnc::footprint::{Footprint, FootprintConfig, FootprintInput, footprint};
use stx_gnc::guidance::{Guidance, GuidanceConfig, Plan};
use stx_gnc::mission::FlightMode;
use stx_gnc::performance::GlidePerformance;
use stx_sim::closed_loop::{GuidedFlight, SensedNavigation, truth_estimate};
use stx_sim::guided::{CONTROL_PERIOD_S, STEP_S};
use stx_sim::montecarlo::steady_glide_state;
use stx_sim::sensors::SensorConfig;

/// The rehearsal's start: (north, east, down), m, and heading, degrees.
const START_NED_M: [f64; 3] = [-500.0, -500.0, -900.0];
const START_HEADING_DEG: f64 = 45.0;
/// The rehearsal site's ground above sea level, m.
const GROUND_MSL_M: f64 = 245.0;
/// 1-σ of the wind below, north and east alike, that the footprint is given and the flights
/// draw their wind offset from, m/s.
const WIND_SIGMA_MPS: f64 = 0.5;
/// Points drawn uniformly over the 95 % region, and points on its edge.
const UNIFORM_POINTS: usize = 40;
const EDGE_POINTS: usize = 16;
/// A capsule landing this close to its point reached it, m (see the module doc).
const REACHED_M: f64 = 50.0;

/// The rehearsal's mean wind, with `offset_ne_mps` added at every height.
fn profile(offset_ne_mps: [f64; 2]) -> WindProfile {
    let row = |altitude_m: f64, speed_mps: f64, from_deg: f64| {
        // Back to speed and direction after adding the offset to the components.
        let to = (from_deg + 180.0_f64).to_radians();
        let (n, e) = (
            speed_mps * to.cos() + offset_ne_mps[0],
            speed_mps * to.sin() + offset_ne_mps[1],
        );
        ProfileRow {
            altitude_m,
            speed_mps: n.hypot(e),
            from_deg: ((-e).atan2(-n).to_degrees()).rem_euclid(360.0),
        }
    };
    WindProfile::new(vec![row(0.0, 2.0, 300.0), row(1000.0, 3.0, 290.0)]).expect("profile")
}

fn model(wind: Arc<dyn WindField>) -> ParafoilModel {
    ParafoilModel::new(
        Vehicle::straplex(),
        Environment {
            atmosphere: Arc::new(StandardAtmosphere),
            wind,
            ground_altitude_msl_m: GROUND_MSL_M,
        },
    )
}

fn start_state() -> stx_dynamics::state::StateVector {
    let mut x = steady_glide_state(&Vehicle::straplex()).expect("steady glide");
    for k in 0..3 {
        x[idx::POSITION + k] = START_NED_M[k];
    }
    x[idx::CANOPY_EULER + 2] = START_HEADING_DEG.to_radians();
    x
}

/// The footprint from the release, with the nominal profile as the wind below.
fn the_footprint() -> Footprint {
    let nominal = profile([0.0, 0.0]);
    let m = model(Arc::new(nominal.clone()));
    let mut est = truth_estimate(&m, 0.0, &start_state());
    est.wind_sigma_mps = Vector3::new(WIND_SIGMA_MPS, WIND_SIGMA_MPS, 0.0);
    let config = FootprintConfig {
        draws: 1000,
        extra_wind_sigma_mps: 0.0,
        ..FootprintConfig::default()
    }
    .validate()
    .expect("config");
    let input = FootprintInput {
        estimate: &est,
        performance: &GlidePerformance::default(),
        wind_below: Some(&nominal),
        atmosphere: &StandardAtmosphere,
        ground_altitude_msl_m: GROUND_MSL_M,
    };
    footprint(&input, &config, &mut ChaCha8Rng::seed_from_u64(15)).expect("footprint")
}

/// Flies the full model to `target_ne_m` in the profile offset by a wind drawn with `seed`;
/// returns the capsule's miss, m.
fn fly_to(target_ne_m: [f64; 2], seed: u64) -> Result<f64, String> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let normal = Normal::new(0.0, WIND_SIGMA_MPS).expect("σ");
    let offset = [normal.sample(&mut rng), normal.sample(&mut rng)];
    let mean = profile(offset);
    let speed = mean.rows().iter().map(|r| r.speed_mps).fold(0.0, f64::max);
    let sigma = (0.1 * speed).max(0.1);
    let turbulence = Turbulence::new(TurbulenceParams {
        sigma_horizontal_mps: sigma,
        sigma_vertical_mps: 0.5 * sigma,
        length_scale_horizontal_m: 200.0,
        length_scale_vertical_m: 50.0,
        reference_airspeed_mps: 6.7,
        seed,
        components: 24,
    })
    .map_err(|e| e.to_string())?;
    let wind = Arc::new(WindComposite {
        mean: Box::new(mean),
        turbulence: Some(turbulence),
    });
    let mut guidance = Guidance::new(GuidanceConfig::default());
    guidance.set_plan(
        Plan {
            target_ned_m: Vector3::new(target_ne_m[0], target_ne_m[1], 0.0),
            ..Plan::default()
        },
        0.0,
    );
    guidance.set_mode(FlightMode::SpiralLanding, 0.0);
    let navigator =
        SensedNavigation::new(&SensorConfig::default(), EstimatorConfig::default(), seed)
            .map_err(|e| e.to_string())?;
    let mut flight = GuidedFlight::new(
        model(wind),
        start_state(),
        0.0,
        guidance,
        navigator,
        STEP_S,
        CONTROL_PERIOD_S,
    );
    let first = loop {
        if let Some(t) = flight.advance().map_err(|e| e.to_string())? {
            break t;
        }
        if flight.time_s > 3600.0 {
            return Err("still flying after an hour".into());
        }
    };
    let capsule = flight.land_payload(first)?;
    Ok(
        (capsule.position_ne_m[0] - target_ne_m[0])
            .hypot(capsule.position_ne_m[1] - target_ne_m[1]),
    )
}

/// Flies every (point, seed) on two threads; misses in order, failed runs as errors.
fn fly_all(points: &[([f64; 2], u64)]) -> Vec<Result<f64, String>> {
    let half = points.len().div_ceil(2);
    std::thread::scope(|s| {
        let workers: Vec<_> = points
            .chunks(half.max(1))
            .map(|chunk| {
                s.spawn(move || {
                    chunk
                        .iter()
                        .map(|&(p, seed)| fly_to(p, seed))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().expect("worker"))
            .collect()
    })
}

/// The point at bearing `bearing_deg` from the drift point where the probability last is at
/// least `level` going outwards (the contour's edge on that ray), m.
fn edge_along(f: &Footprint, bearing_deg: f64, level: f64) -> [f64; 2] {
    let (s, c) = bearing_deg.to_radians().sin_cos();
    let at = |r: f64| [f.drift_point_ne_m[0] + r * c, f.drift_point_ne_m[1] + r * s];
    let step = 0.5 * f.grid.cell_size_m;
    let mut last = at(0.0);
    for k in 0..20_000 {
        let p = at(k as f64 * step);
        if f.probability_at(p) >= level {
            last = p;
        }
    }
    last
}

/// Points inside the 95 % region: `uniform` drawn uniformly over its cells (seeded), and one on
/// its edge at each of `edge` bearings about the drift point.
fn inside_points(f: &Footprint, uniform: usize, edge: usize) -> Vec<[f64; 2]> {
    let g = &f.grid;
    let cells: Vec<[f64; 2]> = (0..g.rows)
        .flat_map(|row| (0..g.cols).map(move |col| (row, col)))
        .filter(|&(row, col)| g.probability[row * g.cols + col] >= 0.95)
        .map(|(row, col)| g.cell_centre(row, col))
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let mut points: Vec<[f64; 2]> = (0..uniform)
        .map(|_| cells[rand::RngExt::random_range(&mut rng, 0..cells.len())])
        .collect();
    points.extend((0..edge).map(|k| edge_along(f, 360.0 * k as f64 / edge as f64, 0.95)));
    points
}

#[test]
fn points_inside_the_95_percent_contour_are_reached_by_the_full_model() {
    let f = the_footprint();
    let inside: Vec<([f64; 2], u64)> = inside_points(&f, UNIFORM_POINTS, EDGE_POINTS)
        .into_iter()
        .zip(100..)
        .collect();
    for (p, _) in &inside {
        assert!(f.probability_at(*p) >= 0.95, "{p:?}");
    }
    // Well outside: 150 m beyond the last ground any draw reaches on the ray.
    let outside: Vec<([f64; 2], u64)> = (0..4)
        .map(|k| {
            let edge = edge_along(&f, 90.0 * k as f64, 1e-9);
            let d = [
                edge[0] - f.drift_point_ne_m[0],
                edge[1] - f.drift_point_ne_m[1],
            ];
            let beyond = 150.0 / d[0].hypot(d[1]);
            let p = [edge[0] + d[0] * beyond, edge[1] + d[1] * beyond];
            assert_eq!(f.probability_at(p), 0.0, "{p:?}");
            (p, 300 + k as u64)
        })
        .collect();
    let all: Vec<_> = inside.iter().chain(&outside).copied().collect();
    let results = fly_all(&all);
    let (inside_results, outside_results) = results.split_at(inside.len());
    let reached = |r: &Result<f64, String>| matches!(r, Ok(m) if *m <= REACHED_M);
    let report = |name: &str, points: &[([f64; 2], u64)], results: &[Result<f64, String>]| {
        for ((p, seed), r) in points.iter().zip(results) {
            eprintln!(
                "{name} ({:7.0}, {:7.0}) p={:.2} seed {seed}: {}",
                p[0],
                p[1],
                f.probability_at(*p),
                match r {
                    Ok(m) => format!("miss {m:.1} m"),
                    Err(e) => format!("failed: {e}"),
                }
            );
        }
    };
    report("inside", &inside, inside_results);
    report("outside", &outside, outside_results);
    let inside_reached = inside_results.iter().filter(|r| reached(r)).count();
    let edge_reached = inside_results[UNIFORM_POINTS..]
        .iter()
        .filter(|r| reached(r))
        .count();
    let outside_reached = outside_results.iter().filter(|r| reached(r)).count();
    let failed = results.iter().filter(|r| r.is_err()).count();
    eprintln!(
        "95 % region: {inside_reached}/{} reached within {REACHED_M} m ({edge_reached}/{EDGE_POINTS} \
         on its edge); well outside: {outside_reached}/{} reached; {failed} runs failed",
        inside.len(),
        outside.len()
    );
    // A failed run counts as not reached.
    assert!(
        inside_reached as f64 >= 0.95 * inside.len() as f64,
        "{inside_reached}/{} reached",
        inside.len()
    );
    assert!(
        outside_reached <= outside.len() / 4,
        "points well outside the footprint were reached"
    );
}
