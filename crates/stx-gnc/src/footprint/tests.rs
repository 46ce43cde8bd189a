//! Unit tests of the footprint against closed forms: calm air gives a disc of the still-air
//! reach, a uniform wind carries it, wind uncertainty blurs it.

use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use stx_types::atmosphere::{AirState, UniformAir};
use stx_types::controls::Controls;

use super::*;
use crate::keep_out::KeepOutZone;
use crate::pointmass::{Conditions, PointMass};

const HEIGHT_M: f64 = 1000.0;

fn estimate(wind_ne: [f64; 2], wind_sigma_mps: f64) -> Estimate {
    let perf = GlidePerformance::default();
    let wind = Vector3::new(wind_ne[0], wind_ne[1], 0.0);
    let mut mass = PointMass::new(0.0, Vector3::new(100.0, -50.0, -HEIGHT_M), 0.0);
    mass.step(
        &perf,
        &Controls::default(),
        &Conditions::nominal(wind, 1.225),
        0.01,
    );
    let mut est = mass.estimate(&wind);
    est.position_ned_m.z = -HEIGHT_M;
    est.wind_sigma_mps = Vector3::new(wind_sigma_mps, wind_sigma_mps, 0.0);
    est
}

/// No dispersion at all: every draw is the nominal vehicle.
fn exact() -> FootprintConfig {
    FootprintConfig {
        draws: 20,
        extra_wind_sigma_mps: 0.0,
        airspeed_sigma_fraction: 0.0,
        sink_sigma_fraction: 0.0,
        ..FootprintConfig::default()
    }
}

fn run(est: &Estimate, config: FootprintConfig, seed: u64) -> Footprint {
    let perf = GlidePerformance::default();
    let air = UniformAir(AirState::sea_level());
    let input = FootprintInput {
        estimate: est,
        performance: &perf,
        wind_below: None,
        atmosphere: &air,
        ground_altitude_msl_m: 0.0,
    };
    let config = config.validate().expect("valid config");
    footprint(&input, &config, &mut ChaCha8Rng::seed_from_u64(seed)).expect("footprint")
}

/// Still-air glide at released brakes in sea-level air.
fn glide() -> f64 {
    let perf = GlidePerformance::default();
    let rho = AirState::sea_level().density_kg_per_m3;
    perf.horizontal_airspeed(0.0, rho) / perf.sink_rate(0.0, 0.0, rho)
}

fn centroid_and_radii(contour: &FootprintContour) -> ([f64; 2], f64, f64) {
    let ring = &contour.polygons[0].exterior_ne_m;
    let n = ring.len() as f64;
    let c = [
        ring.iter().map(|p| p[0]).sum::<f64>() / n,
        ring.iter().map(|p| p[1]).sum::<f64>() / n,
    ];
    let radii = ring.iter().map(|p| (p[0] - c[0]).hypot(p[1] - c[1]));
    let (lo, hi) = radii.fold((f64::INFINITY, 0.0_f64), |(lo, hi), r| {
        (lo.min(r), hi.max(r))
    });
    (c, lo, hi)
}

#[test]
fn calm_air_gives_a_disc_of_the_still_air_reach_about_the_start() {
    let config = exact();
    let f = run(&estimate([0.0, 0.0], 0.0), config, 1);
    // No upwind for the final: it may be flown towards the point, so the whole height counts.
    let r = glide() * (HEIGHT_M - config.hang_height_m) - config.edge_margin_m;
    assert!(r > 1900.0, "{r}");
    assert!(
        (f.nominal_radius_m - r).abs() < 1e-6 * r,
        "{} vs {r}",
        f.nominal_radius_m
    );
    let cell = config.cell_size_m;
    for contour in &f.contours {
        assert_eq!(contour.polygons.len(), 1, "{:?}", contour.level);
        let (c, lo, hi) = centroid_and_radii(contour);
        // The traced boundary lies within 1.5 cells of the closed-form circle (cell centres
        // decide, and marching squares cut corners between them by up to a cell's diagonal).
        assert!(
            (c[0] - 100.0).abs() < 0.5 * cell && (c[1] + 50.0).abs() < 0.5 * cell,
            "{c:?}"
        );
        assert!(
            lo > r - 1.5 * cell && hi < r + 1.5 * cell,
            "{lo}…{hi} vs {r}"
        );
    }
    assert_eq!(f.probability_at([100.0 + r - cell, -50.0]), 1.0);
    assert_eq!(f.probability_at([100.0, -50.0 - r + cell]), 1.0);
    assert_eq!(f.probability_at([100.0 + r + cell, -50.0]), 0.0);
}

#[test]
fn a_uniform_wind_carries_the_reach_downwind_and_the_final_moves_it_back_upwind() {
    let config = exact();
    let wind = [2.0, -3.0];
    let f = run(&estimate(wind, 0.0), config, 1);
    let perf = GlidePerformance::default();
    let sink = perf.sink_rate(0.0, 0.0, 1.225);
    let t = (HEIGHT_M - config.hang_height_m) / sink;
    let final_run = perf.horizontal_airspeed(0.0, 1.225) * config.reserve_height_m / sink;
    let w = wind[0].hypot(wind[1]);
    let expected = [
        100.0 + wind[0] * t - wind[0] / w * final_run,
        -50.0 + wind[1] * t - wind[1] / w * final_run,
    ];
    assert!(
        (f.drift_point_ne_m[0] - expected[0]).abs() < 1.0,
        "{:?} vs {expected:?}",
        f.drift_point_ne_m
    );
    assert!(
        (f.drift_point_ne_m[1] - expected[1]).abs() < 1.0,
        "{:?} vs {expected:?}",
        f.drift_point_ne_m
    );
    let r = glide() * (HEIGHT_M - config.hang_height_m - config.reserve_height_m)
        - config.edge_margin_m;
    assert!((f.nominal_radius_m - r).abs() < 1e-6 * r);
    // The released-brake disc is inside the region; the braked finals and approaches add
    // ground downwind (a longer, slower descent drifts further): the region reaches at most
    // BRAKED_SPREAD_M further out (123 m measured with the default reserve).
    const BRAKED_SPREAD_M: f64 = 150.0;
    let cell = config.cell_size_m;
    for contour in &f.contours {
        let ring = &contour.polygons[0].exterior_ne_m;
        let d = ring
            .iter()
            .map(|p| (p[0] - expected[0]).hypot(p[1] - expected[1]));
        let (lo, hi) = d.fold((f64::INFINITY, 0.0_f64), |(lo, hi), r| {
            (lo.min(r), hi.max(r))
        });
        assert!(
            lo > r - 1.5 * cell && hi < r + BRAKED_SPREAD_M,
            "{lo}…{hi} vs {r}"
        );
    }
    // Upwind the region ends at the released disc's edge, downwind beyond it.
    let along = |k: f64| [expected[0] - wind[0] / w * k, expected[1] - wind[1] / w * k];
    assert_eq!(f.probability_at(along(r - cell)), 1.0);
    assert_eq!(f.probability_at(along(r + cell)), 0.0);
}

#[test]
fn more_wind_uncertainty_draws_the_50_and_95_percent_contours_apart() {
    let config = FootprintConfig {
        draws: 400,
        ..FootprintConfig::default()
    };
    let band = |sigma: f64| {
        let f = run(&estimate([1.0, 1.0], sigma), config, 7);
        let a50 = f.grid.area_at_least(0.5);
        let a95 = f.grid.area_at_least(0.95);
        assert!(a50 > a95, "{a50} {a95}");
        // Equal-area circles: the radial gap between the contours.
        (a50 / std::f64::consts::PI).sqrt() - (a95 / std::f64::consts::PI).sqrt()
    };
    let (narrow, wide) = (band(0.1), band(1.5));
    // A constant wind bias σ over the ~340 s descent moves the disc by σ·t: the 50–95 % gap of
    // a 2-D normal offset is about 1.6 σ·t wider for σ = 1.5 m/s than for 0.5 m/s (extra).
    assert!(wide > narrow + 300.0, "gap {narrow} m → {wide} m");
}

#[test]
fn the_same_seed_gives_the_same_footprint_and_another_seed_another() {
    let config = FootprintConfig::default();
    let est = estimate([1.0, -2.0], 0.4);
    assert_eq!(run(&est, config, 3), run(&est, config, 3));
    assert_ne!(run(&est, config, 3).grid, run(&est, config, 4).grid);
}

#[test]
fn bad_settings_are_refused_with_the_field_named() {
    let with = |f: fn(&mut FootprintConfig)| {
        let mut c = FootprintConfig::default();
        f(&mut c);
        c.validate()
    };
    assert_eq!(
        with(|c| c.draws = 0),
        Err(FootprintConfigError::Draws { draws: 0 })
    );
    assert_eq!(
        with(|c| c.max_cells = 0),
        Err(FootprintConfigError::MaxCells { max_cells: 0 })
    );
    assert!(matches!(
        with(|c| c.cell_size_m = f64::NAN),
        Err(FootprintConfigError::OutOfRange {
            field: "cell_size_m",
            ..
        })
    ));
    assert!(matches!(
        with(|c| c.reserve_height_m = -1.0),
        Err(FootprintConfigError::OutOfRange {
            field: "reserve_height_m",
            ..
        })
    ));
    assert!(matches!(
        with(|c| c.sink_sigma_fraction = 0.9),
        Err(FootprintConfigError::OutOfRange {
            field: "sink_sigma_fraction",
            ..
        })
    ));
    assert!(FootprintConfig::default().validate().is_ok());
}

#[test]
fn unusable_estimates_and_too_fine_grids_are_errors_not_panics() {
    let perf = GlidePerformance::default();
    let air = UniformAir(AirState::sea_level());
    let config = FootprintConfig::default().validate().unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let mut est = estimate([0.0, 0.0], f64::INFINITY);
    let input = |est: &Estimate| {
        let est = *est;
        move |rng: &mut ChaCha8Rng, config: &ValidFootprintConfig| {
            let input = FootprintInput {
                estimate: &est,
                performance: &perf,
                wind_below: None,
                atmosphere: &air,
                ground_altitude_msl_m: 0.0,
            };
            footprint(&input, config, rng).map(|f| f.draws)
        }
    };
    assert_eq!(
        input(&est)(&mut rng, &config),
        Err(FootprintError::NotFinite {
            quantity: "wind σ"
        })
    );
    est.wind_sigma_mps = Vector3::zeros();
    est.position_ned_m.z = -5.0;
    assert!(matches!(
        input(&est)(&mut rng, &config),
        Err(FootprintError::OnGround { .. })
    ));
    est.position_ned_m.z = -3000.0;
    let fine = FootprintConfig {
        cell_size_m: 1.0,
        max_cells: 1000,
        ..FootprintConfig::default()
    }
    .validate()
    .unwrap();
    assert!(matches!(
        input(&est)(&mut rng, &fine),
        Err(FootprintError::TooManyCells {
            max_cells: 1000,
            ..
        })
    ));
}

fn square(name: &str, centre_ne: [f64; 2], half_m: f64) -> KeepOutZone {
    let [n, e] = centre_ne;
    KeepOutZone {
        name: name.into(),
        rings_ne_m: vec![vec![
            [n - half_m, e - half_m],
            [n - half_m, e + half_m],
            [n + half_m, e + half_m],
            [n + half_m, e - half_m],
        ]],
    }
}

#[test]
fn zones_are_marked_with_the_highest_level_whose_region_they_overlap() {
    let config = FootprintConfig {
        draws: 400,
        ..FootprintConfig::default()
    };
    let f = run(&estimate([0.0, 0.0], 1.0), config, 11);
    // Find a point on the +north axis between the two contours, and one beyond both.
    let between = (0..4000)
        .map(|k| [100.0 + k as f64, -50.0])
        .find(|&p| (0.6..0.9).contains(&f.probability_at(p)))
        .expect("a point between the contours");
    let zones = KeepOutZones {
        zones: vec![
            square("centre", [100.0, -50.0], 100.0),
            square("between", between, 5.0),
            square("far", [100.0, 10_000.0], 200.0),
        ],
    };
    let hits = f.zone_hits(&zones);
    assert_eq!(
        hits,
        vec![
            ZoneHit {
                name: "centre".into(),
                level: 0.95
            },
            ZoneHit {
                name: "between".into(),
                level: 0.5
            },
        ]
    );
}
