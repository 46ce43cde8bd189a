//! The seed's simulated behaviour (§4.6) and flight tests (§3.2.2) against the shipped
//! scenarios, and, apart from them, our model's own figures.
//!
//! Two kinds of test, never mixed (crates/stx-dynamics/MODEL_NOTES.md, "Behaviour against the
//! seed", has every figure with its measurement):
//! - `seed_…` tests assert a figure the seed states, within the tolerance its statement
//!   carries, justified where it is used. Where our model differs by more, the test asserts
//!   what of the seed's statement does hold (a bound, the sign, the behaviour), and the
//!   difference is pinned and documented.
//! - `regression_pin_…` tests pin what our model does, each within a few per cent of the
//!   figure MODEL_NOTES.md quotes: loose enough for a change of integrator or of rounding,
//!   tight enough that a change to the physics shows. They say nothing about the seed.
//!
//! The seed's own figures come from its plots and words ("approximately ten seconds"), so a
//! criterion is needed to measure ours: we read the Euler angles its figures plot, and call
//! a motion stabilised once every plotted angle stays within 1° of its steady value — on plots
//! spanning tens of degrees, the size of the trace's own width. The summary's `settle_time_s`
//! (every rate below 0.05 rad/s) is a different, coarser criterion: a 1.6 rad/s swing of
//! ±1.8° passes it. Both are measured below.

use std::sync::OnceLock;

use stx_dynamics::model::Body;
use stx_dynamics::vehicle::Vehicle;
use stx_sim::open_loop::{Run, run};
use stx_sim::scenario::{ControlStep, IntegratorConfig, Scenario};

fn flown(name: &str) -> Run {
    let scenario = Scenario::builtin(name).expect("built-in scenario");
    run(&scenario, &Vehicle::straplex()).expect("the scenario flies")
}

/// Each scenario flown once for every test of this file (the descent from 35 km takes
/// seconds).
fn scenario(name: &'static str) -> &'static Run {
    static UNCONTROLLED: OnceLock<Run> = OnceLock::new();
    static SPIRAL_EXIT: OnceLock<Run> = OnceLock::new();
    static STRATOSPHERIC: OnceLock<Run> = OnceLock::new();
    let cell = match name {
        "uncontrolled" => &UNCONTROLLED,
        "spiral-exit" => &SPIRAL_EXIT,
        "stratospheric" => &STRATOSPHERIC,
        other => panic!("no cell for scenario {other}"),
    };
    cell.get_or_init(|| flown(name))
}

/// `value` within `share` (relative) of the documented `expected`.
fn assert_close(what: &str, value: f64, expected: f64, share: f64) {
    assert!(
        (value - expected).abs() <= share * expected.abs(),
        "{what}: {value} where MODEL_NOTES.md documents {expected} (±{:.0} %)",
        share * 100.0
    );
}

/// `value` inside the seed's `[low, high]`, with the reading that gives the bounds.
fn assert_seed(what: &str, value: f64, low: f64, high: f64, reading: &str) {
    assert!(
        (low..=high).contains(&value),
        "{what}: ours {value:.3}, the seed's reading allows [{low}, {high}] ({reading})"
    );
}

/// Last sample time at which any Euler angle of `bodies` lies more than `tolerance_deg` from
/// its `reference` value, s: after it every plotted angle stays within the tolerance.
fn stabilised_after_s(
    run: &Run,
    bodies: &[Body],
    reference: impl Fn(Body) -> [f64; 3],
    tolerance_deg: f64,
) -> f64 {
    let references: Vec<[f64; 3]> = bodies.iter().map(|&b| reference(b)).collect();
    run.samples
        .iter()
        .filter(|s| {
            bodies.iter().zip(&references).any(|(&b, r)| {
                let e = s.body(b).euler_deg;
                (0..3).any(|k| (e[k] - r[k]).abs() > tolerance_deg)
            })
        })
        .map(|s| s.time_s)
        .fold(0.0, f64::max)
}

/// Mean Euler angles of `body` over samples in `[from_s, to_s)`, degrees.
fn mean_euler_deg(run: &Run, body: Body, from_s: f64, to_s: f64) -> [f64; 3] {
    let stretch: Vec<[f64; 3]> = run
        .samples
        .iter()
        .filter(|s| s.time_s >= from_s && s.time_s < to_s)
        .map(|s| s.body(body).euler_deg)
        .collect();
    assert!(!stretch.is_empty(), "no samples in [{from_s}, {to_s})");
    let n = stretch.len() as f64;
    std::array::from_fn(|k| stretch.iter().map(|e| e[k]).sum::<f64>() / n)
}

/// Largest peak-to-peak canopy pitch within any whole second from `from_s` to `to_s`,
/// degrees: the oscillation, not the slow drift of the phugoid.
fn canopy_pitch_swing_deg(run: &Run, from_s: u32, to_s: u32) -> f64 {
    (from_s..to_s)
        .map(|t| {
            let (low, high) = run
                .samples
                .iter()
                .filter(|s| s.time_s >= f64::from(t) && s.time_s < f64::from(t + 1))
                .map(|s| s.body(Body::Canopy).euler_deg[1])
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                    (lo.min(p), hi.max(p))
                });
            high - low
        })
        .fold(0.0, f64::max)
}

/// Uncontrolled flight: when every body's plotted angles (seed Figs. 4.4–4.7) stay within 1°
/// of their values at the end of the 15 s.
fn uncontrolled_stabilised_after_s(r: &Run) -> f64 {
    let end = r.samples.last().expect("samples");
    stabilised_after_s(r, &Body::ALL, |b| end.body(b).euler_deg, 1.0)
}

#[test]
fn seed_4_6_uncontrolled_flight_stabilises_after_about_ten_seconds() {
    // Seed: "the system motion presents a short and damped oscillation ... due to the pendulum
    // effect of the drone, capsule and transponder. After approximately ten seconds, the
    // system stabilizes". The figure is read by eye off 15 s plots and given as
    // "approximately": ±30 %, 7 to 13 s.
    let r = scenario("uncontrolled");
    let stabilised = uncontrolled_stabilised_after_s(r);
    assert_seed(
        "every body's angles within 1° of steady, s",
        stabilised,
        7.0,
        13.0,
        "\"approximately ten seconds\", by eye: ±30 %",
    );
    // A damped oscillation: the canopy still swings by degrees between 3 and 8 s ...
    let swinging = canopy_pitch_swing_deg(r, 3, 8);
    assert!(
        swinging > 2.0,
        "pitch swing between 3 and 8 s: {swinging:.2}°"
    );
    // ... and it has faded once stabilised.
    let after = canopy_pitch_swing_deg(r, 11, 15);
    assert!(
        after < 0.3,
        "pitch swing after 11 s: {after:.2}° peak to peak"
    );
    assert!(r.summary.landing.is_none());
}

#[test]
fn seed_3_2_2_the_stack_glides_about_two_to_one() {
    // Seed §3.2.2: the flight tests flew 18 km/h forward and 10 km/h down, "approximately a
    // velocity ratio of 2:1". The seed calls 1.8 "approximately 2": [1.8, 2.2]. The flight
    // tests' speeds themselves are 21 % (forward) and 6 % (down) below ours, as they are below
    // the seed's own model (Table 6.1: 22 and 11 km/h, checked in stx-analysis'
    // seed_chapter_6.rs); ours are pinned in regression_pin_uncontrolled_flight.
    let steady = scenario("uncontrolled")
        .summary
        .steady
        .expect("a steady stretch within 15 s");
    assert_seed(
        "glide ratio",
        steady.glide_ratio,
        1.8,
        2.2,
        "18 km/h over 10 km/h, called ≈ 2:1",
    );
    // The canopy flies forwards through the air, descending.
    assert!(steady.sink_rate_mps > 0.0 && steady.alpha_deg > 0.0);
}

#[test]
fn regression_pin_uncontrolled_flight() {
    let r = scenario("uncontrolled");
    let s = &r.summary;
    // Every body's angles within 1° of steady after 10.48 s (the transponder's swing is the
    // last; canopy, drone and capsule by 7.3 s) ...
    assert_close(
        "angles within 1° of steady, s",
        uncontrolled_stabilised_after_s(r),
        10.48,
        0.02,
    );
    // ... while every rate the summary watches is below 0.05 rad/s after 5.56 s.
    assert_close(
        "settle time (rates < 0.05 rad/s), s",
        s.settle_time_s.expect("it settles"),
        5.56,
        0.02,
    );
    // Steady glide: 6.72 m/s airspeed, 2.95 m/s down (10.6 km/h), glide 2.04 (21.7 km/h
    // forward), α = 18.3°.
    let steady = s.steady.expect("a steady stretch within 15 s");
    assert_close("glide ratio", steady.glide_ratio, 2.04, 0.01);
    assert_close("airspeed, m/s", steady.airspeed_mps, 6.72, 0.01);
    assert_close("sink rate, m/s", steady.sink_rate_mps, 2.95, 0.01);
    assert_close("angle of attack, deg", steady.alpha_deg, 18.3, 0.01);
    assert!(
        s.min_line_tension_n > 3.0,
        "every line taut: {}",
        s.min_line_tension_n
    );
    assert!(s.max_line_length_error_m < 1e-9);
}

const SPIRAL_RELEASE_S: f64 = 10.0;

/// The spiral's yaw rate (mean |r| over the last 2 s of full main line) and the time after
/// release from which |r| stays below `share` of it, (rad/s, s).
fn spiral_exit(r: &Run, share: f64) -> (f64, f64) {
    let spiral: Vec<f64> = r
        .samples
        .iter()
        .filter(|x| x.time_s >= SPIRAL_RELEASE_S - 2.0 && x.time_s < SPIRAL_RELEASE_S)
        .map(|x| x.body(Body::Canopy).rates_deg_s[2].to_radians().abs())
        .collect();
    let spiral_rate = spiral.iter().sum::<f64>() / spiral.len() as f64;
    (spiral_rate, yaw_rate_below_after_s(r, share * spiral_rate))
}

/// Time after release from which the canopy's |r| stays below `rate_rad_s`, s.
fn yaw_rate_below_after_s(r: &Run, rate_rad_s: f64) -> f64 {
    r.samples
        .iter()
        .filter(|x| {
            x.time_s >= SPIRAL_RELEASE_S
                && x.body(Body::Canopy).rates_deg_s[2].to_radians().abs() >= rate_rad_s
        })
        .map(|x| x.time_s)
        .fold(SPIRAL_RELEASE_S, f64::max)
        - SPIRAL_RELEASE_S
}

#[test]
fn seed_4_6_the_parafoil_leaves_the_spiral_about_five_seconds_after_release() {
    // Seed: full right main line for 10 s; "5 seconds after the action of the control, it was
    // verified that the parafoil goes out of the spiral motion, without any kind of control".
    // Out of the spiral: the turn has stopped, its yaw rate below a tenth of the spiral's.
    // "5 seconds" is read by eye off Fig. 4.9: ±30 %, 3.5 to 6.5 s.
    let r = scenario("spiral-exit");
    let (spiral_rate, exit_s) = spiral_exit(r, 0.1);
    // It was a spiral: a steady turn of more than half a radian a second, nose far down.
    assert!(spiral_rate > 0.5, "spiral yaw rate {spiral_rate:.2} rad/s");
    assert!(r.summary.min_canopy_pitch_deg < -30.0);
    assert_seed(
        "yaw rate below a tenth of the spiral's after release, s",
        exit_s,
        3.5,
        6.5,
        "\"5 seconds\", by eye: ±30 %",
    );
    // By itself back into a straight glide.
    let steady = r.summary.steady.expect("steady after the spiral");
    assert!((1.8..2.2).contains(&steady.glide_ratio), "{steady:?}");
}

#[test]
fn regression_pin_spiral_exit() {
    let r = scenario("spiral-exit");
    let s = &r.summary;
    let (spiral_rate, exit_s) = spiral_exit(r, 0.1);
    // A 0.83 rad/s (47.5°/s) spiral; below a tenth of it from 5.76 s after release, below
    // 0.1 rad/s from 5.7 s and below 0.05 rad/s from 8.1 s (the lightly damped lateral mode
    // rings on).
    assert_close("spiral yaw rate, rad/s", spiral_rate, 0.829, 0.02);
    assert_close("a tenth of the spiral's yaw rate, s", exit_s, 5.76, 0.03);
    assert_close(
        "yaw rate below 0.1 rad/s after release, s",
        yaw_rate_below_after_s(r, 0.1),
        5.7,
        0.05,
    );
    assert_close(
        "yaw rate below 0.05 rad/s after release, s",
        s.yaw_rate_settle_s.expect("yaw rate settles after release"),
        8.1,
        0.02,
    );
    let steady = s.steady.expect("steady after the spiral");
    assert_close(
        "glide ratio after the spiral",
        steady.glide_ratio,
        2.04,
        0.01,
    );
    assert_close(
        "lowest canopy pitch in the spiral, deg",
        s.min_canopy_pitch_deg,
        -50.4,
        0.02,
    );
}

/// Descent from 35 km: when the canopy's plotted angles (seed Fig. 4.10) stay within 1° of
/// its steady glide (their mean from 100 to 200 s; the glide's angles hardly change as the
/// air thickens: −7.3° of pitch then, −7.5° at 400 s).
fn stratospheric_stabilised_after_s(r: &Run) -> f64 {
    stabilised_after_s(
        r,
        &[Body::Canopy],
        |b| mean_euler_deg(r, b, 100.0, 200.0),
        1.0,
    )
}

#[test]
fn seed_4_6_released_at_35_km_speed_peaks_near_300_kmh_with_the_canopy_near_minus_70_degrees() {
    // Seed: "a striking total velocity of around 300km/h" (§7.1), "the canopy reaches a high
    // negative pitch angle (-70 degrees)" (§4.6). "Around 300" is one significant figure:
    // [250, 350] km/h. −70° is read off Fig. 4.10 to the nearest ten degrees: ±5°.
    let r = scenario("stratospheric");
    let s = &r.summary;
    assert_seed(
        "peak total speed, km/h",
        s.max_total_speed_kmh,
        250.0,
        350.0,
        "\"around 300km/h\": one significant figure",
    );
    assert_seed(
        "lowest canopy pitch, deg",
        s.min_canopy_pitch_deg,
        -75.0,
        -65.0,
        "\"-70 degrees\", to the nearest ten",
    );
    // "An initial exponential increasing of the downward velocity of the canopy, followed by
    // an increasing forward velocity": the dive comes first ...
    let (dive, peak) = r.samples.iter().fold((None, None), |(dive, peak), x| {
        let v = x.body(Body::Canopy).velocity_ned_mps;
        let dive = match dive {
            Some((t, d)) if d >= v[2] => Some((t, d)),
            _ => Some((x.time_s, v[2])),
        };
        let speed = x.canopy_speed_mps();
        let peak = match peak {
            Some((t, p)) if p >= speed => Some((t, p)),
            _ => Some((x.time_s, speed)),
        };
        (dive, peak)
    });
    let ((dive_s, _), (peak_s, peak_mps)) = (dive.expect("samples"), peak.expect("samples"));
    let horizontal = |x: &stx_dynamics::output::Sample| {
        let v = x.body(Body::Canopy).velocity_ned_mps;
        v[0].hypot(v[1])
    };
    let horizontal_at = |t: f64| {
        r.samples
            .iter()
            .find(|x| x.time_s >= t)
            .map(horizontal)
            .expect("sampled")
    };
    assert!(
        horizontal_at(dive_s + 5.0) > horizontal_at(dive_s),
        "forward speed grows after the downward speed peaks at {dive_s} s"
    );
    // ... and "the velocity decreases as the system descends" after the peak.
    let at = |t: f64| {
        r.samples
            .iter()
            .find(|x| x.time_s >= t)
            .map(|x| x.canopy_speed_mps())
            .expect("sampled")
    };
    assert!(peak_s < 50.0 && at(100.0) < peak_mps && at(1000.0) < at(100.0));
}

#[test]
fn seed_4_6_released_at_35_km_the_canopy_is_stable_about_50_s_after_release() {
    // Seed: "the platform quickly (approximately after 50 seconds) reaches a stable
    // trajectory" with Fig. 4.10 plotting the canopy's kinematics. Read by eye and given as
    // "approximately": ±30 %, 35 to 65 s.
    let r = scenario("stratospheric");
    assert_seed(
        "canopy's angles within 1° of its glide, s",
        stratospheric_stabilised_after_s(r),
        35.0,
        65.0,
        "\"approximately after 50 seconds\", by eye: ±30 %",
    );
}

#[test]
fn regression_pin_stratospheric_release() {
    let r = scenario("stratospheric");
    let s = &r.summary;
    assert_close("peak speed, km/h", s.max_total_speed_kmh, 339.0, 0.01);
    assert_close(
        "lowest canopy pitch, deg",
        s.min_canopy_pitch_deg,
        -72.5,
        0.01,
    );
    // The canopy's angles within 1° of its glide after 48.5 s; the summary's rates below
    // 0.05 rad/s after 23.8 s, while the phugoid still swings the canopy by degrees.
    assert_close(
        "canopy's angles within 1° of its glide, s",
        stratospheric_stabilised_after_s(r),
        48.5,
        0.02,
    );
    assert_close(
        "settle time (rates < 0.05 rad/s), s",
        s.settle_time_s.expect("settles"),
        23.8,
        0.02,
    );
    // The lines nearly unload in the first seconds of near free fall in thin air.
    assert_close("least line tension, N", s.min_line_tension_n, 0.034, 0.05);
    let landing = s.landing.expect("reaches the ground");
    // 4838 s to the ground, 70.7 km downrange, on the centre line: no wind, no control.
    assert_close("downrange at landing, m", landing.x_m, 70_710.0, 0.01);
    assert_close("time to the ground, s", landing.time_s, 4838.0, 0.01);
    assert_eq!(landing.y_m, 0.0, "a symmetric flight stays symmetric");
    let steady = s.steady.expect("steady near the ground");
    assert_close(
        "glide ratio near the ground",
        steady.glide_ratio,
        2.04,
        0.01,
    );
}

#[test]
fn stratospheric_landing_stays_on_the_centre_line_at_a_loose_tolerance() {
    // Regression: at Dormand–Prince 3e-4 the descent landed 0.46 m to the side (rounding in
    // the tension solve, grown by steps past the roll mode's stability limit).
    let mut scenario = Scenario::builtin("stratospheric").expect("built-in");
    scenario.integrator = IntegratorConfig::DormandPrince {
        rel_tol: 3e-4,
        abs_tol: 3e-4,
        max_step_s: 0.5,
    };
    let landing = run(&scenario, &Vehicle::straplex())
        .expect("flies")
        .summary
        .landing
        .expect("lands");
    assert_eq!(landing.y_m, 0.0, "{landing:?}");
    assert_close("downrange at landing, m", landing.x_m, 70_710.0, 0.01);
}

fn fully_braked() -> stx_sim::summary::Steady {
    let mut braked = Scenario::builtin("uncontrolled").expect("built-in");
    braked.controls = vec![ControlStep {
        at_s: 0.0,
        main_line: Default::default(),
        brake_right: 1.0,
        brake_left: 1.0,
    }];
    braked.duration_s = 30.0;
    run(&braked, &Vehicle::straplex())
        .expect("flies")
        .summary
        .steady
        .expect("steady")
}

#[test]
fn seed_3_2_2_symmetric_brakes_lower_the_glide_slope() {
    // Seed §3.2.2: "If the trailing edge is deflected, pulling down both brakes, the drag
    // force increases, decreasing the glide slope." The seed gives no figure.
    let free = scenario("uncontrolled").summary.steady.expect("steady");
    let braked = fully_braked();
    assert!(braked.glide_ratio < free.glide_ratio, "{braked:?}");
}

#[test]
fn regression_pin_full_brakes() {
    // Full brakes: glide 2.04 → 1.75, airspeed 6.72 → 5.25 m/s, sink 2.95 → 2.60 m/s,
    // α 18.3° → 27.2° (brake coefficients from the literature, straplex.toml).
    let full = fully_braked();
    assert_close("braked glide ratio", full.glide_ratio, 1.75, 0.01);
    assert_close("braked airspeed, m/s", full.airspeed_mps, 5.25, 0.01);
    assert_close("braked sink rate, m/s", full.sink_rate_mps, 2.60, 0.01);
    assert_close("braked angle of attack, deg", full.alpha_deg, 27.2, 0.01);
}
