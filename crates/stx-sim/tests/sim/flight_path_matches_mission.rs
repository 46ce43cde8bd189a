//! The planner's flight path (`stx_gnc::flight_path`) against the whole simulated mission it
//! predicts: mission-short flown by the simulated drone with its servos left neutral
//! (uncontrolled mode), its burst, deployment and landing compared with the plan made from the
//! same mission settings and the same mean wind.
//!
//! The simulation differs from the plan where the plan simplifies: the round chute's full drag
//! equation against its terminal speed, the onboard estimate of the height that triggers
//! deployment against the true height, the 14-DOF parafoil's inflation and its glide against
//! the point mass's, and (in the second test) turbulence the plan does not know of.
//!
//! Measured (seed 1, `cargo test --release -p stx-sim --test sim flight_path_matches_mission:: --
//! --nocapture`): in the mean wind the burst is 1.1 m from the plan's, the deployment 9.7 m
//! and the landing 32.5 m (1166 s flown, 1167 s planned); in turbulence 58, 54 and 493 m —
//! gusts turn the unsteered parafoil, which the plan cannot know, so there the landing is
//! only held to the reach disc (it lands 65 m inside its 2433-m edge).

use stx_dynamics::atmosphere::StandardAtmosphere;
use stx_dynamics::vehicle::Vehicle;
use stx_gnc::flight_path::{Air, FlightPath, Start, propagate};
use stx_gnc::mission::{FlightMode, FlightStage};
use stx_gnc::performance::GlidePerformance;
use stx_sim::drone::{Drone, MissionConfig};

/// What the simulation flew, relative to the launch: burst, deploy and landing points (north,
/// east, m) and times (s after launch).
struct Flown {
    burst: ([f64; 2], f64),
    deploy: ([f64; 2], f64),
    landing: ([f64; 2], f64),
}

fn fly(config: &MissionConfig) -> Flown {
    let mut d = Drone::new(config, Vehicle::straplex()).expect("drone builds");
    let launch = config.start.launch_delay_s;
    let (mut burst, mut deploy) = (None, None);
    while d.landing().is_none() {
        let before = d.stage();
        d.step().expect("the flight goes on");
        while d.poll_output().is_some() {}
        let p = d.physics().truth().position_ned_m;
        let at = ([p.x, p.y], d.time_s() - launch);
        match (before, d.stage()) {
            (FlightStage::Ascent, FlightStage::RoundChute) => burst = Some(at),
            (FlightStage::RoundChute, FlightStage::ParafoilDeploy) => deploy = Some(at),
            _ => {}
        }
    }
    let landing = d.landing().unwrap();
    Flown {
        burst: burst.expect("burst"),
        deploy: deploy.expect("deployed"),
        landing: (landing.position_ne_m, landing.time_s - launch),
    }
}

fn plan(config: &MissionConfig) -> FlightPath {
    let vehicle = Vehicle::straplex();
    let stack = config.stack_config(&vehicle);
    let mut mean = config.wind.clone().expect("the mission has a wind");
    mean.turbulence = None;
    let wind = mean.build().expect("wind builds");
    let air = Air {
        wind: wind.as_ref(),
        atmosphere: &StandardAtmosphere,
        ground_msl_m: config.site.alt_msl_m,
    };
    propagate(Start::pad(), &stack, air, &GlidePerformance::default()).expect("plan")
}

fn distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Compares, prints the figures and checks them against the tolerances: burst, deploy and
/// landing distances (m), landing time (s); `None` for the landing distance checks instead
/// that the landing lies within 100 m of the plan's reach disc (wherever gusts turned the
/// unsteered parafoil, it cannot glide farther than its glide through the air).
fn compare(config: &MissionConfig, tolerances: [Option<f64>; 4]) {
    let flown = fly(config);
    let planned = plan(config);
    let burst = planned.burst.unwrap();
    let misses = [
        distance(flown.burst.0, burst.ne_m()),
        distance(flown.deploy.0, planned.deploy.ne_m()),
        distance(flown.landing.0, planned.landing.ne_m()),
    ];
    let landing_time = (flown.landing.1 - planned.landing.time_s).abs();
    let reach = planned.reach;
    let beyond_reach = distance(flown.landing.0, reach.centre_ne_m) - reach.radius_m;
    println!(
        "{}: burst {:.1} m apart ({:.0} s flown, {:.0} s planned), deploy {:.1} m ({:.0} s, \
         {:.0} s), landing {:.1} m ({:.0} s, {:.0} s), {:.0} m beyond the reach disc of \
         {:.0} m",
        config.name,
        misses[0],
        flown.burst.1,
        burst.time_s,
        misses[1],
        flown.deploy.1,
        planned.deploy.time_s,
        misses[2],
        flown.landing.1,
        planned.landing.time_s,
        beyond_reach,
        reach.radius_m,
    );
    assert!(
        beyond_reach <= 100.0,
        "landed {beyond_reach:.0} m beyond the reach disc"
    );
    for (what, miss, tol) in [
        ("burst", misses[0], tolerances[0]),
        ("deploy", misses[1], tolerances[1]),
        ("landing", misses[2], tolerances[2]),
        ("landing time", landing_time, tolerances[3]),
    ] {
        let Some(tol) = tol else { continue };
        assert!(miss <= tol, "{what}: {miss:.1} apart, tolerance {tol}");
    }
}

fn uncontrolled_short_mission(turbulence: bool) -> MissionConfig {
    let mut config = MissionConfig::builtin("mission-short").expect("built-in mission");
    config.plan.mode = FlightMode::Uncontrolled;
    if !turbulence && let Some(w) = config.wind.as_mut() {
        w.turbulence = None;
    }
    config
}

#[test]
fn the_plan_matches_the_simulated_short_mission_in_its_mean_wind() {
    compare(
        &uncontrolled_short_mission(false),
        [Some(50.0), Some(50.0), Some(100.0), Some(30.0)],
    );
}

#[test]
fn the_plan_matches_the_simulated_short_mission_in_turbulence() {
    compare(
        &uncontrolled_short_mission(true),
        [Some(100.0), Some(100.0), None, Some(40.0)],
    );
}
