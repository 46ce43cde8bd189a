//! What the estimator learns of its own sensors, on synthetic flights: the AHRS's heading bias
//! and the pitot's scale where the flight shows them (a swinging drone turning round a
//! pattern), and an honest uncertainty where it does not (straight flight).

use std::f64::consts::FRAC_PI_2;

use stx_gnc::estimate::Estimate;

use super::synthetic_flight::{
    Flight, USUAL, deliveries, estimator, feed, horizontal, pattern, pattern_deliveries, piece_at,
};

/// A landing pattern's rhythm: 10 s straight, then quarter turns, each followed by a 12-s
/// straight leg, all turning the same way: the heading changes by 90° every 16 s.
fn square_pattern(legs: usize) -> Vec<(f64, f64)> {
    let mut pieces = vec![(10.0, 0.0)];
    for _ in 0..legs {
        pieces.extend(quarter_turn());
        pieces.push((12.0, 0.0));
    }
    pieces
}

/// A quarter turn at 0.52 rad/s, rolled into and out of over a second each way (a canopy does
/// not start turning at once, and a step would only test the GPS gate): 4.25 s.
fn quarter_turn() -> Vec<(f64, f64)> {
    let rate = FRAC_PI_2 / 3.0;
    let ramp = [0.25, 0.5, 0.75].map(|f| (0.25, f * rate));
    let mut pieces = ramp.to_vec();
    pieces.push((0.25 + 2.25, rate));
    pieces.extend(ramp.iter().rev());
    pieces
}

/// A drone with an AHRS reading `bias_deg` high and a pitot reading `scale` times the air along
/// its x axis, in a 4-m/s wind from 200°. Like the simulated one it swings under the canopy,
/// here by ±20° every 1.5 s, and yaws into its turns (15° in these quarter turns): the pitot's
/// reading then depends on the heading at first order, `∂u/∂ψ = |a|·sin β`, which is what
/// shows a heading bias, and what made it cost the estimator without a bias state 0.66 m/s of
/// wind on this pattern.
fn swinging_drone(bias_deg: f64, scale: f64) -> Flight {
    Flight {
        ahrs_heading_bias_rad: bias_deg.to_radians(),
        pitot_scale: scale,
        sideslip_per_turn_rate_s: 0.5,
        swing_rad: 20f64.to_radians(),
        swing_period_s: 1.5,
        ..Flight::straight(200.0, 4.0)
    }
}

/// The estimates of a pattern flown by `drone`, with the wind error at each.
fn fly_pattern(drone: &Flight, legs: usize) -> Vec<(f64, Estimate, f64)> {
    let pieces = pattern(drone, &square_pattern(legs));
    let mut est = estimator();
    feed(&mut est, &pattern_deliveries(&pieces, USUAL))
        .into_iter()
        .map(|(t, e)| {
            let error = horizontal(e.wind_ned_mps - piece_at(&pieces, t).wind_ned_mps);
            (t, e, error)
        })
        .collect()
}

#[test]
fn a_heading_bias_is_learnt_round_a_pattern_and_the_wind_stays_right_on_every_leg() {
    for bias_deg in [6.0, -6.0] {
        let history = fly_pattern(&swinging_drone(bias_deg, 1.0), 10);
        // After the first legs (each turn and swing shows the bias a little more).
        let worst = history
            .iter()
            .filter(|(t, _, _)| *t > 70.0)
            .map(|(_, _, error)| *error)
            .fold(0.0, f64::max);
        assert!(
            worst < 0.3,
            "bias {bias_deg}°: worst wind error {worst:.2} m/s"
        );
        let (_, last, _) = history.last().expect("estimates");
        let learnt_deg = last.heading_bias_rad.to_degrees();
        let sigma_deg = last.heading_bias_sigma_rad.to_degrees();
        let error_deg = learnt_deg - bias_deg;
        assert!(
            error_deg.abs() < 1.5 && error_deg.abs() < 3.0 * sigma_deg,
            "bias {bias_deg}°: learnt {learnt_deg:.2}° ± {sigma_deg:.2}°"
        );
    }
}

#[test]
fn the_pitot_scale_is_learnt_beside_a_heading_bias() {
    for (bias_deg, scale) in [(6.0, 0.93), (-4.0, 1.06)] {
        let history = fly_pattern(&swinging_drone(bias_deg, scale), 10);
        let (_, last, error) = history.last().expect("estimates");
        let label = format!("bias {bias_deg}°, scale {scale}");
        let scale_error = last.pitot_scale - scale;
        assert!(
            scale_error.abs() < 0.01 && scale_error.abs() < 3.0 * last.pitot_scale_sigma,
            "{label}: learnt {:.4} ± {:.4}",
            last.pitot_scale,
            last.pitot_scale_sigma
        );
        assert!(*error < 0.3, "{label}: wind error {error:.2} m/s");
    }
}

/// Without a turn, a heading bias and the drone's own sideslip turn the air velocity (and the
/// wind) alike: nothing tells them apart, nor the bias from a turned wind. The estimate must
/// not pretend otherwise.
#[test]
fn in_straight_flight_the_heading_bias_stays_unknown_and_the_estimate_says_so() {
    let drone = swinging_drone(6.0, 1.0);
    let mut est = estimator();
    let history = feed(&mut est, &deliveries(&drone, 0.0, 60.0, USUAL, |_| true));
    let (_, last) = history.last().expect("estimates");
    let prior_deg = stx_gnc::estimator::EstimatorConfig::default().initial_heading_bias_sigma_deg;
    let sigma_deg = last.heading_bias_sigma_rad.to_degrees();
    assert!(
        sigma_deg > 0.8 * prior_deg,
        "σ {sigma_deg:.2}° of a {prior_deg}° prior"
    );
    let wind_error = last.wind_ned_mps - drone.wind_ned_mps;
    for k in 0..2 {
        assert!(
            wind_error[k].abs() < 3.0 * last.wind_sigma_mps[k],
            "component {k}: error {:.2} vs σ {:.2}",
            wind_error[k],
            last.wind_sigma_mps[k]
        );
    }
}

/// A restart for a new flight phase (the parafoil after the round chute) starts air and wind
/// afresh but keeps the heading bias and pitot scale learnt, with their uncertainty: learnt in
/// the turns before, they would otherwise be lost to the straight flight after, where they do
/// not show (and the station's replica, restarting later than the drone, would learn them
/// differently).
#[test]
fn a_restart_keeps_what_was_learnt_of_the_sensors() {
    let drone = swinging_drone(6.0, 0.95);
    let pieces = pattern(&drone, &square_pattern(10));
    let mut learnt = estimator();
    feed(&mut learnt, &pattern_deliveries(&pieces, USUAL));
    let before = learnt.estimate(f64::INFINITY);
    let mut restarted = learnt.restarted();
    let mut fresh = estimator();
    let straight = deliveries(&drone, 0.0, 30.0, USUAL, |_| true);
    let (_, kept) = feed(&mut restarted, &straight).pop().expect("estimates");
    let (_, lost) = feed(&mut fresh, &straight).pop().expect("estimates");
    let deg = f64::to_degrees;
    assert!(
        (deg(kept.heading_bias_rad) - 6.0).abs() < 1.5
            && kept.heading_bias_sigma_rad < 1.2 * before.heading_bias_sigma_rad,
        "bias {:.2}° ± {:.2}° (before the restart {:.2}° ± {:.2}°)",
        deg(kept.heading_bias_rad),
        deg(kept.heading_bias_sigma_rad),
        deg(before.heading_bias_rad),
        deg(before.heading_bias_sigma_rad)
    );
    assert!(
        (kept.pitot_scale - 0.95).abs() < 0.01,
        "{}",
        kept.pitot_scale
    );
    assert!(
        lost.heading_bias_sigma_rad > 2.0 * kept.heading_bias_sigma_rad,
        "a fresh start knows {:.2}°",
        deg(lost.heading_bias_sigma_rad)
    );
    // Air and wind are the new phase's own: the restarted filter counts as new.
    assert_eq!(restarted.counters(), fresh.counters());
}
