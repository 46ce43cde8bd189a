//! The flight-path planner against closed forms: a uniform wind in uniform air, where every
//! stage drifts by wind × time and the times are height over rate; the same in the standard
//! atmosphere, where the balloon's time to burst is still H/v̄ by the definition of the mean
//! rate; a two-layer wind; and the Monte Carlo's spread of the burst point, which for a wind
//! error fully correlated over altitude is σ_w × time to burst.

use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use stx_gnc::flight_path::{
    Air, Dispersion, PlanInputs, StackConfig, Start, monte_carlo, propagate,
};
use stx_gnc::performance::GlidePerformance;
use stx_types::atmosphere::{AirState, Atmosphere, StandardAtmosphere, UniformAir};
use stx_types::wind::{ConstantWind, WindField};

fn uniform_sea_level() -> UniformAir {
    UniformAir(AirState::sea_level())
}

/// 5 m/s from the west: the air moves east.
fn westerly() -> ConstantWind {
    ConstantWind::from_speed_direction(5.0, 270.0).unwrap()
}

/// The air of `wind` and `atmosphere` over ground at sea level.
fn sea_level_air<'a>(wind: &'a dyn WindField, atmosphere: &'a UniformAir) -> Air<'a> {
    Air {
        wind,
        atmosphere,
        ground_msl_m: 0.0,
    }
}

fn low_mission() -> StackConfig {
    StackConfig {
        burst_altitude_msl_m: 3000.0,
        deploy_height_m: 1200.0,
        ..StackConfig::default()
    }
}

fn inputs(
    stack: &StackConfig,
    dispersion: &Dispersion,
    runs: usize,
    target_ne_m: Option<[f64; 2]>,
) -> PlanInputs {
    PlanInputs {
        start: Start::pad(),
        stack: *stack,
        dispersion: dispersion.clone(),
        runs,
        target_ne_m,
        region_share_of_best: 0.5,
    }
}

fn no_dispersion() -> Dispersion {
    Dispersion {
        ascent_rate_sigma_mps: 0.0,
        burst_altitude_sigma_m: 0.0,
        wind_sigma: Vec::new(),
    }
}

fn close(a: f64, b: f64, tol: f64, what: &str) {
    assert!((a - b).abs() <= tol, "{what}: {a} vs {b} (tolerance {tol})");
}

#[test]
fn uniform_wind_in_uniform_air_matches_the_closed_form_at_every_stage() {
    let stack = low_mission();
    let (wind, atmosphere) = (westerly(), uniform_sea_level());
    let air = sea_level_air(&wind, &atmosphere);
    let perf = GlidePerformance::default();
    let path = propagate(Start::pad(), &stack, air, &perf).unwrap();
    // Ascent: in uniform air the rate is the mean rate all the way.
    let t_burst = 3000.0 / 5.0;
    let burst = path.burst.unwrap();
    close(burst.time_s, t_burst, 1e-6, "burst time");
    close(burst.position_ned_m[1], 5.0 * t_burst, 1e-6, "burst east");
    close(burst.position_ned_m[0], 0.0, 1e-9, "burst north");
    close(burst.position_ned_m[2], -3000.0, 1e-6, "burst height");
    // Round chute: the terminal speed of the uniform air.
    let rho = AirState::sea_level().density_kg_per_m3;
    let v_t = stack.chute().terminal_speed_mps(rho);
    let t_chute = (3000.0 - 1200.0) / v_t;
    close(path.deploy.time_s, t_burst + t_chute, 1e-6, "deploy time");
    close(
        path.deploy.position_ned_m[1],
        5.0 * (t_burst + t_chute),
        1e-6,
        "deploy east",
    );
    close(
        path.deploy.position_ned_m[2],
        -1200.0,
        1e-6,
        "deploy height",
    );
    let t_no_release = 3000.0 / v_t;
    close(
        path.round_chute_landing.position_ned_m[1],
        5.0 * (t_burst + t_no_release),
        1e-6,
        "chute landing",
    );
    // Parafoil: deploys heading downwind and glides straight at its steady glide.
    close(
        path.deploy_heading_rad,
        std::f64::consts::FRAC_PI_2,
        1e-12,
        "heading",
    );
    let (v_h, sink) = (
        perf.horizontal_airspeed(0.0, rho),
        perf.sink_rate(0.0, 0.0, rho),
    );
    let t_glide = (1200.0 - stack.hang_height_m) / sink;
    close(
        path.landing.time_s,
        t_burst + t_chute + t_glide,
        1e-6,
        "landing time",
    );
    let east = path.deploy.position_ned_m[1] + (v_h + 5.0) * t_glide;
    close(path.landing.position_ned_m[1], east, 1e-6, "landing east");
    close(path.landing.position_ned_m[0], 0.0, 1e-6, "landing north");
    // Reach: the drifted air mass's centre and the glide through the air.
    close(path.reach.radius_m, v_h * t_glide, 1e-6, "reach radius");
    close(
        path.reach.centre_ne_m[1],
        path.deploy.position_ned_m[1] + 5.0 * t_glide,
        1e-6,
        "reach centre",
    );
}

#[test]
fn in_the_standard_atmosphere_the_burst_is_the_wind_times_climb_over_mean_rate() {
    // 35 km at 5 m/s on average, the balloon slower low down and faster high up (k = 1/6):
    // the time to burst is H/v̄ by the definition of v̄ (to the Simpson rule's accuracy).
    let stack = StackConfig::default();
    let (wind, atmosphere) = (westerly(), StandardAtmosphere);
    let ground = 245.0;
    let air = Air {
        wind: &wind,
        atmosphere: &atmosphere,
        ground_msl_m: ground,
    };
    let path = propagate(Start::pad(), &stack, air, &GlidePerformance::default()).unwrap();
    let t_burst = (35_000.0 - ground) / 5.0;
    let burst = path.burst.unwrap();
    close(burst.time_s, t_burst, 1e-3 * t_burst, "burst time");
    close(
        burst.position_ned_m[1],
        5.0 * t_burst,
        1e-3 * 5.0 * t_burst,
        "burst east",
    );
    // The fall to the deploy height: T = ∫ dz / v_t(ρ(z)) by an independent 1-m quadrature.
    let chute = stack.chute();
    let mut t_fall = 0.0;
    let mut h = stack.deploy_height_m + 0.5;
    while h < 35_000.0 - ground {
        t_fall += 1.0 / chute.terminal_speed_mps(atmosphere.air_at(ground + h).density_kg_per_m3);
        h += 1.0;
    }
    let fall = path.deploy.time_s - burst.time_s;
    close(fall, t_fall, 2e-3 * t_fall, "fall time");
    let drift = path.deploy.position_ned_m[1] - burst.position_ned_m[1];
    close(drift, 5.0 * t_fall, 2e-3 * 5.0 * t_fall, "fall drift");
}

/// 3 m/s toward the east below 1000 m, 8 m/s toward the north above.
struct TwoLayers;

impl WindField for TwoLayers {
    fn wind_ned_mps(&self, _t: f64, p: &Vector3<f64>) -> Vector3<f64> {
        if -p.z < 1000.0 {
            Vector3::new(0.0, 3.0, 0.0)
        } else {
            Vector3::new(8.0, 0.0, 0.0)
        }
    }
}

#[test]
fn a_two_layer_wind_adds_the_drift_of_each_layer() {
    let stack = StackConfig {
        ascent_density_exponent: 0.0,
        burst_altitude_msl_m: 3000.0,
        deploy_height_m: 500.0,
        ..StackConfig::default()
    };
    let atmosphere = uniform_sea_level();
    let air = sea_level_air(&TwoLayers, &atmosphere);
    let path = propagate(Start::pad(), &stack, air, &GlidePerformance::default()).unwrap();
    let burst = path.burst.unwrap().position_ned_m;
    close(
        burst[1],
        3.0 * 1000.0 / 5.0,
        1e-6,
        "burst east (lower layer)",
    );
    close(
        burst[0],
        8.0 * 2000.0 / 5.0,
        1e-6,
        "burst north (upper layer)",
    );
    let v_t = stack
        .chute()
        .terminal_speed_mps(AirState::sea_level().density_kg_per_m3);
    let deploy = path.deploy.position_ned_m;
    close(deploy[0] - burst[0], 8.0 * 2000.0 / v_t, 1e-6, "fall north");
    close(deploy[1] - burst[1], 3.0 * 500.0 / v_t, 1e-6, "fall east");
    // Deployed in the lower layer: it heads east, downwind.
    close(
        path.deploy_heading_rad,
        std::f64::consts::FRAC_PI_2,
        1e-12,
        "heading",
    );
}

#[test]
fn starting_under_the_round_chute_skips_the_ascent_and_below_the_deploy_height_deploys_at_once() {
    let (wind, atmosphere) = (westerly(), uniform_sea_level());
    let air = sea_level_air(&wind, &atmosphere);
    let perf = GlidePerformance::default();
    let stack = low_mission();
    let p0 = Vector3::new(100.0, 200.0, -2000.0);
    let path = propagate(Start::UnderRoundChute(p0), &stack, air, &perf).unwrap();
    assert!(path.burst.is_none());
    let v_t = stack
        .chute()
        .terminal_speed_mps(AirState::sea_level().density_kg_per_m3);
    close(
        path.deploy.position_ned_m[1],
        200.0 + 5.0 * 800.0 / v_t,
        1e-6,
        "deploy east",
    );
    let low = Vector3::new(0.0, 0.0, -600.0);
    let path = propagate(Start::UnderRoundChute(low), &stack, air, &perf).unwrap();
    assert_eq!(path.deploy.position_ned_m, [0.0, 0.0, -600.0]);
    assert_eq!(path.deploy.time_s, 0.0);
    let below = propagate(
        Start::Ascending(Vector3::new(0.0, 0.0, 5.0)),
        &stack,
        air,
        &perf,
    );
    assert!(below.is_err());
    let bad = StackConfig {
        mean_ascent_rate_mps: 0.0,
        ..stack
    };
    let e = propagate(Start::pad(), &bad, air, &perf)
        .unwrap_err()
        .to_string();
    assert!(e.contains("mean_ascent_rate_mps"), "{e}");
}

#[test]
fn a_wind_error_correlated_over_altitude_spreads_the_burst_by_sigma_times_time() {
    let (wind, atmosphere) = (westerly(), uniform_sea_level());
    let air = sea_level_air(&wind, &atmosphere);
    let perf = GlidePerformance::default();
    let stack = low_mission();
    let dispersion = Dispersion {
        wind_sigma: vec![(0.0, 1.0)],
        ..no_dispersion()
    };
    let runs = 2000;
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let plan = monte_carlo(
        &inputs(&stack, &dispersion, runs, None),
        air,
        &perf,
        &mut rng,
    )
    .unwrap();
    // σ = 1 m/s × 600 s on each axis: a circle of 600 m. The estimate of a standard deviation
    // from 2000 samples has a relative error of 1/√(2·2000) = 1.6 %; allow 5 %.
    let burst = plan.burst.unwrap();
    for axis in [burst.ellipse.semi_major_m, burst.ellipse.semi_minor_m] {
        close(axis, 600.0, 30.0, "burst 1-σ");
    }
    close(
        burst.mean_ne_m[1],
        3000.0,
        3.0 * 600.0 / (runs as f64).sqrt(),
        "burst mean east",
    );
    close(burst.time_sigma_s, 0.0, 1e-9, "burst time spread");
    // Same seed, same plan; the nominal is the path without dispersion.
    let mut again = ChaCha8Rng::seed_from_u64(11);
    let replay = monte_carlo(
        &inputs(&stack, &dispersion, runs, None),
        air,
        &perf,
        &mut again,
    )
    .unwrap();
    assert_eq!(plan, replay);
    assert_eq!(
        plan.nominal,
        propagate(Start::pad(), &stack, air, &perf).unwrap()
    );
    assert_eq!(
        plan.samples.len(),
        stx_gnc::flight_path::spread::MAX_SAMPLES_RETURNED
    );
}

#[test]
fn without_dispersion_the_target_is_reachable_inside_the_glide_disc_and_not_beyond() {
    let (wind, atmosphere) = (westerly(), uniform_sea_level());
    let air = sea_level_air(&wind, &atmosphere);
    let perf = GlidePerformance::default();
    let stack = low_mission();
    let none = no_dispersion();
    let nominal = propagate(Start::pad(), &stack, air, &perf).unwrap();
    let c = nominal.reach.centre_ne_m;
    let r = nominal.reach.radius_m;
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for (target, expected) in [([c[0] + 0.9 * r, c[1]], 1.0), ([c[0] - 1.1 * r, c[1]], 0.0)] {
        let plan = monte_carlo(
            &inputs(&stack, &none, 20, Some(target)),
            air,
            &perf,
            &mut rng,
        )
        .unwrap();
        assert_eq!(
            plan.target_reachable_probability,
            Some(expected),
            "{target:?}"
        );
        // Every sample is the nominal: the region is the nominal disc, reached by all, its
        // edge traced through cells of 1/160 of the disc's width.
        let region = &plan.steered_region;
        assert_eq!((region.probability, region.best_probability), (0.5, 1.0));
        assert!(region.outline_ne_m.len() > 100);
        for q in &region.outline_ne_m {
            close(
                (q[0] - c[0]).hypot(q[1] - c[1]),
                r,
                2.0 * r / 160.0,
                "region edge",
            );
        }
        close(plan.landing.ellipse.semi_major_m, 0.0, 1e-6, "no spread");
    }
    let zero_runs = monte_carlo(&inputs(&stack, &none, 0, None), air, &perf, &mut rng);
    assert!(zero_runs.is_err());
}
