//! The simulated drone flying a chosen vehicle as its truth (`Drone::with_truth`, what `stx
//! drone --vehicle` and `stx serve --sim --sim-vehicle` fly): the physics is the given vehicle,
//! the onboard guidance keeps the mission's own polar and gains, and a dispersion set draws
//! around the given vehicle rather than the shipped one.

use stx_dynamics::vehicle::Vehicle;
use stx_sim::dispersions::Dispersions;
use stx_sim::drone::{Drone, MissionConfig};

/// The shipped vehicle with 20 % less lift slope: a canopy identified as weaker than the seed's.
fn weaker_lift() -> Vehicle {
    let mut config = Vehicle::straplex().config;
    config.canopy.aero.cl_alpha *= 0.8;
    config.validate().expect("a valid vehicle")
}

/// Mission time at which `drone` lands (the rehearsal: under the parafoil from 900 m).
fn landing_time_s(mut drone: Drone) -> f64 {
    while drone.landing().is_none() {
        assert!(drone.time_s() < 1200.0, "the rehearsal lands within 20 min");
        drone.step().expect("steps");
        while drone.poll_output().is_some() {}
    }
    drone.landing().expect("landed").time_s
}

#[test]
fn a_drone_with_a_weaker_canopy_flies_a_different_truth_with_the_same_onboard_guidance() {
    let mission = MissionConfig::builtin("rehearsal").expect("built-in mission");
    let shipped = Drone::with_truth(&mission, &Vehicle::straplex(), None).expect("builds");
    let weaker = Drone::with_truth(&mission, &weaker_lift(), None).expect("builds");
    // The truth is the vehicle given…
    assert_eq!(weaker.physics().vehicle(), &weaker_lift());
    assert_eq!(shipped.physics().vehicle(), &Vehicle::straplex());
    // …and the drone's own software is the mission's, whatever it hangs under.
    assert_eq!(weaker.onboard().settings(), shipped.onboard().settings());
    assert_eq!(
        weaker.onboard().guidance().config(),
        shipped.onboard().guidance().config()
    );
    let (t_shipped, t_weaker) = (landing_time_s(shipped), landing_time_s(weaker));
    println!("rehearsal landed at {t_shipped:.1} s (shipped), {t_weaker:.1} s (cl_alpha −20 %)");
    assert!(
        (t_shipped - t_weaker).abs() > 5.0,
        "{t_shipped} s vs {t_weaker} s: the weaker canopy should fly a different descent"
    );
}

#[test]
fn dispersions_draw_around_the_given_vehicle() {
    let mission = MissionConfig::builtin("rehearsal").expect("built-in mission");
    let vehicle = weaker_lift();
    // The nominal set scatters nothing of the vehicle: the given one is flown exactly.
    let nominal = Dispersions::load("nominal").expect("shipped set");
    let d = Drone::with_truth(&mission, &vehicle, Some(&nominal)).expect("builds");
    assert_eq!(d.physics().vehicle(), &vehicle);
    // A realistic draw around it is not the same draw around the shipped vehicle (same seed).
    let realistic = Dispersions::load("realistic").expect("shipped set");
    let around_given = Drone::with_truth(&mission, &vehicle, Some(&realistic)).expect("builds");
    let around_shipped = Drone::dispersed(&mission, Some(&realistic)).expect("builds");
    let (given, shipped) = (
        &around_given.physics().vehicle().config.canopy.aero,
        &around_shipped.physics().vehicle().config.canopy.aero,
    );
    assert_ne!(
        given.cl_alpha, vehicle.config.canopy.aero.cl_alpha,
        "a draw"
    );
    // Same seed, same relative scatter: the ratio to the centre is the same.
    let ratio = |drawn: f64, centre: f64| drawn / centre;
    assert!(
        (ratio(given.cl_alpha, vehicle.config.canopy.aero.cl_alpha)
            - ratio(
                shipped.cl_alpha,
                Vehicle::straplex().config.canopy.aero.cl_alpha
            ))
        .abs()
            < 1e-12,
        "{} vs {}",
        given.cl_alpha,
        shipped.cl_alpha
    );
    assert!((given.cl_alpha / shipped.cl_alpha - 0.8).abs() < 1e-12);
}
