//! Guidance flown on the point-mass parafoil: every phase of a spiral landing, landing into
//! the wind, the wind too strong to reach the target, and angles across ±180°.

use nalgebra::Vector3;
use stx_gnc::control::{LawPhase, Localizer};
use stx_gnc::estimate::Estimate;
use stx_gnc::guidance::{Guidance, GuidanceConfig, PhaseEvent, Plan};
use stx_gnc::mission::{FlightMode, GuidancePhase};
use stx_gnc::performance::GlidePerformance;
use stx_gnc::pointmass::{Conditions, PointMass};
use stx_types::rotation::wrap_pi;

struct Flight {
    mass: PointMass,
    guidance: Guidance,
    events: Vec<PhaseEvent>,
    headings: Vec<(f64, f64)>,
}

/// Wind blowing from `from_deg` at `speed`, NED.
fn wind_from(speed: f64, from_deg: f64) -> Vector3<f64> {
    let d = from_deg.to_radians();
    Vector3::new(-speed * d.cos(), -speed * d.sin(), 0.0)
}

/// Flies until the drone is at the hang height (touchdown) or `max_s` passes.
fn fly(
    start: Vector3<f64>,
    heading_deg: f64,
    mode: FlightMode,
    plan: Plan,
    wind: Vector3<f64>,
    max_s: f64,
) -> Flight {
    fly_seeing(start, heading_deg, mode, plan, wind, max_s, |_, est| est)
}

/// [`fly`], with guidance given `seen(time, perfect estimate)` instead of the perfect
/// estimate: a wind estimate that is wrong for a while, as the real estimator's can be.
fn fly_seeing(
    start: Vector3<f64>,
    heading_deg: f64,
    mode: FlightMode,
    plan: Plan,
    wind: Vector3<f64>,
    max_s: f64,
    seen: impl Fn(f64, Estimate) -> Estimate,
) -> Flight {
    let perf = GlidePerformance::default();
    let mut guidance = Guidance::new(GuidanceConfig::default());
    guidance.set_plan(plan, 0.0);
    guidance.set_mode(mode, 0.0);
    let mut f = Flight {
        mass: PointMass::new(0.0, start, heading_deg.to_radians()),
        guidance,
        events: Vec::new(),
        headings: Vec::new(),
    };
    let hang = GuidanceConfig::default().spiral.hang_height_m;
    while -f.mass.position_ned_m.z > hang && f.mass.time_s < max_s {
        let est = seen(f.mass.time_s, f.mass.estimate(&wind));
        let command = f.guidance.update(&est, 1.2);
        f.events.extend(f.guidance.drain_events());
        for _ in 0..5 {
            f.mass.step(
                &perf,
                &command.controls,
                &Conditions::nominal(wind, 1.2),
                0.05,
            );
        }
        f.headings.push((f.mass.time_s, f.mass.heading_rad));
    }
    f
}

fn target_plan(n: f64, e: f64) -> Plan {
    Plan {
        target_ned_m: Vector3::new(n, e, 0.0),
        ..Plan::default()
    }
}

fn phases(f: &Flight) -> Vec<GuidancePhase> {
    f.events.iter().map(|e| e.to).collect()
}

#[test]
fn a_spiral_landing_goes_through_every_phase_and_lands_on_the_target_into_the_wind() {
    for (speed, from) in [(0.5, 0.0), (2.0, 135.0), (4.0, 250.0)] {
        let wind = wind_from(speed, from);
        let f = fly(
            Vector3::new(0.0, 0.0, -700.0),
            0.0,
            FlightMode::SpiralLanding,
            target_plan(200.0, 100.0),
            wind,
            2000.0,
        );
        let p = phases(&f);
        for phase in [
            GuidancePhase::Approximation,
            GuidancePhase::Branch1,
            GuidancePhase::Branch2,
            GuidancePhase::FinalApproach,
            GuidancePhase::Flare,
        ] {
            assert!(
                p.contains(&phase),
                "wind {speed} from {from}: {phase:?} missing in {p:?}"
            );
        }
        let flare = p
            .iter()
            .position(|x| *x == GuidancePhase::Flare)
            .unwrap_or(0);
        let last_final = p
            .iter()
            .rposition(|x| *x == GuidancePhase::FinalApproach)
            .unwrap_or(0);
        assert!(
            last_final < flare,
            "final approach comes before the flare: {p:?}"
        );
        assert!(f.events.iter().all(|e| !e.reason.is_empty()));
        let miss = (f.mass.position_ned_m.x - 200.0).hypot(f.mass.position_ned_m.y - 100.0);
        assert!(
            miss < 15.0,
            "wind {speed} from {from}: missed by {miss:.1} m"
        );
        let upwind = from.to_radians();
        let off = wrap_pi(f.mass.heading_rad - upwind).to_degrees();
        assert!(
            off.abs() < 30.0,
            "wind {speed} from {from}: touchdown heading {off:.0}° off upwind"
        );
    }
}

#[test]
fn the_final_approach_across_north_and_south_wraps_its_angles() {
    // Wind from the south: the final approach heads 180°, where headings wrap.
    let f = fly(
        Vector3::new(-300.0, 50.0, -500.0),
        -170.0,
        FlightMode::SpiralLanding,
        target_plan(0.0, 0.0),
        wind_from(3.0, 180.0),
        2000.0,
    );
    let miss = f.mass.position_ned_m.x.hypot(f.mass.position_ned_m.y);
    assert!(miss < 15.0, "missed by {miss:.1} m");
    let off = wrap_pi(f.mass.heading_rad - std::f64::consts::PI).to_degrees();
    assert!(off.abs() < 30.0, "touchdown heading {off:.0}° off south");
}

#[test]
fn heading_mode_turns_the_short_way_through_180_degrees() {
    let plan = Plan {
        heading_rad: 170f64.to_radians(),
        ..Plan::default()
    };
    let f = fly(
        Vector3::new(0.0, 0.0, -300.0),
        -170.0,
        FlightMode::Heading,
        plan,
        Vector3::zeros(),
        40.0,
    );
    // From −170° to 170° is 20° to the left: the heading never passes through 0°.
    assert!(
        f.headings
            .iter()
            .all(|(_, h)| h.abs() > 150f64.to_radians()),
        "went the long way round"
    );
    let (_, last) = f.headings.last().copied().unwrap_or_default();
    assert!(wrap_pi(last - 170f64.to_radians()).abs() < 3f64.to_radians());
}

#[test]
fn with_the_wind_stronger_than_the_airspeed_guidance_says_so_and_flies_to_the_best_point() {
    // 8 m/s from the north, the target 800 m north (upwind): unreachable.
    let wind = wind_from(8.0, 0.0);
    let target = (800.0, 0.0);
    let f = fly(
        Vector3::new(0.0, 0.0, -400.0),
        0.0,
        FlightMode::SpiralLanding,
        target_plan(target.0, target.1),
        wind,
        2000.0,
    );
    let reach = f
        .events
        .iter()
        .find(|e| e.to == GuidancePhase::BestReachable)
        .expect("guidance reports the target out of reach");
    assert!(reach.reason.contains("out of reach"), "{}", reach.reason);
    // It ends as close as the wind allows: nearer than drifting with the servos neutral.
    let guided = (f.mass.position_ned_m.x - target.0).hypot(f.mass.position_ned_m.y - target.1);
    let drifting = fly(
        Vector3::new(0.0, 0.0, -400.0),
        90.0,
        FlightMode::Uncontrolled,
        Plan::default(),
        wind,
        2000.0,
    );
    let drifted = (drifting.mass.position_ned_m.x - target.0)
        .hypot(drifting.mass.position_ned_m.y - target.1);
    assert!(
        guided < drifted - 50.0,
        "guided {guided:.0} m vs drifting {drifted:.0} m"
    );
    // And it lands facing the wind.
    let off = wrap_pi(f.mass.heading_rad - 0.0).to_degrees();
    assert!(off.abs() < 30.0, "touchdown heading {off:.0}° off upwind");
}

#[test]
fn a_new_plan_during_the_landing_restarts_the_approach_to_the_new_target() {
    let perf = GlidePerformance::default();
    let mut g = Guidance::new(GuidanceConfig::default());
    g.set_plan(target_plan(0.0, 0.0), 0.0);
    g.set_mode(FlightMode::SpiralLanding, 0.0);
    let mut mass = PointMass::new(0.0, Vector3::new(-200.0, 0.0, -500.0), 0.0);
    for _ in 0..100 {
        let c = g.update(&mass.estimate(&Vector3::zeros()), 1.2);
        mass.step(
            &perf,
            &c.controls,
            &Conditions::nominal(Vector3::zeros(), 1.2),
            0.25,
        );
    }
    g.drain_events();
    g.set_plan(target_plan(300.0, 300.0), mass.time_s);
    let events = g.drain_events();
    assert_eq!(g.phase(), GuidancePhase::Approximation);
    assert!(events.iter().any(|e| e.reason.contains("new plan")));
}

/// Regression: deployed high and far from the target (the drone's `mission-short` deploys
/// 1.1 km up, some 180 m downwind and 1.3 km to the side of it in a 3.3 m/s wind), guidance
/// went for the final approach because the way across needed all the height, then found itself
/// too high for the final (which left the way across out), went back downwind, turned base at
/// once and final again: a new phase every control period. Each phase change is now one
/// decision, with its reason.
#[test]
fn a_high_deployment_far_from_the_target_does_not_chatter_between_phases() {
    for (speed, from, downwind_m, side_m, height_m) in [
        (3.3, 290.0, 184.0, 1350.0, 1077.0),
        (3.3, 290.0, 184.0, -1350.0, 1077.0),
        (0.5, 0.0, 1000.0, 0.0, 2500.0),
        (2.0, 270.0, 1000.0, 300.0, 2500.0),
        (4.0, 45.0, 1000.0, 0.0, 2500.0),
    ] {
        let wind = wind_from(speed, from);
        let along = wind.xy().normalize();
        let across = Vector3::new(-along.y, along.x, 0.0);
        let start = along.push(0.0) * downwind_m + across * side_m - Vector3::z() * height_m;
        let f = fly(
            start,
            from + 90.0,
            FlightMode::SpiralLanding,
            target_plan(0.0, 0.0),
            wind,
            5000.0,
        );
        let p = phases(&f);
        // No phase chosen by guidance lasts less than 2 s, except the last before the flare.
        for pair in f.events.windows(2).skip(1) {
            let dt = pair[1].time_s - pair[0].time_s;
            assert!(
                dt >= 2.0 || pair[1].to == GuidancePhase::Flare,
                "wind {speed} from {from}: {:?} lasted {dt:.2} s ({}) in {p:?}",
                pair[0].to,
                pair[1].reason
            );
        }
        let finals = p
            .iter()
            .filter(|x| **x == GuidancePhase::FinalApproach)
            .count();
        assert!(
            finals <= 2,
            "wind {speed} from {from}: {finals} final approaches in {p:?}"
        );
        let miss = f.mass.position_ned_m.xy().norm();
        assert!(
            miss < 15.0,
            "wind {speed} from {from}: missed by {miss:.1} m, {p:?}"
        );
    }
}

/// Regression (issue 3 audit, `stx montecarlo --seed 3 --wind-max 10`): guidance committed to
/// a base leg on the estimator's first, too light wind, and once a base leg (or an extended
/// downwind leg, or the final) was committed the reach check was off for good: winds of
/// 8–10 m/s were flown into the ground up to 1.2 km off with no word. Here the estimate says
/// 1 m/s, confidently, for the first 20 s, and the truth is 8 m/s.
#[test]
fn a_wind_found_too_strong_after_the_base_leg_was_committed_is_still_called() {
    let truth = wind_from(8.0, 0.0);
    let light = wind_from(1.0, 0.0);
    let f = fly_seeing(
        // 250 m downwind (south) and 100 m east of the target, 300 m up: short of height
        // for the pattern, so guidance goes for a base leg and the final.
        Vector3::new(-250.0, 100.0, -300.0),
        90.0,
        FlightMode::SpiralLanding,
        target_plan(0.0, 0.0),
        truth,
        2000.0,
        |t, mut est| {
            est.wind_sigma_mps = Vector3::new(0.2, 0.2, 0.0);
            if t < 20.0 {
                est.wind_ned_mps = light;
            }
            est
        },
    );
    let committed = f
        .events
        .iter()
        .position(|e| e.to == GuidancePhase::Branch2 && e.reason.contains("short of height"))
        .expect("guidance commits to a base leg on the light wind");
    let called = f
        .events
        .iter()
        .position(|e| e.to == GuidancePhase::BestReachable)
        .expect("guidance calls the target out of reach");
    assert_eq!(
        called,
        committed + 1,
        "called from the base leg: {:?}",
        f.events
    );
    assert!(
        f.events[called].reason.contains("out of reach"),
        "{}",
        f.events[called].reason
    );
    // It lands near the best reachable point it announced last (the wind is steady now).
    let announced = f
        .events
        .iter()
        .rfind(|e| e.to == GuidancePhase::BestReachable)
        .map(|e| best_point_in(&e.reason))
        .expect("announced");
    let landed = [f.mass.position_ned_m.x, f.mass.position_ned_m.y];
    let off = (landed[0] - announced[0]).hypot(landed[1] - announced[1]);
    assert!(
        off < 30.0,
        "landed {off:.0} m from the announced point {announced:?}: {:?}",
        f.events
    );
}

/// The planning wind's filter started from the estimator's first wind (zero) and still read
/// a 9 m/s wind as 6 when the estimate had converged, so the target looked reachable. Here
/// the estimate starts at zero with a large uncertainty and converges in 15 s.
#[test]
fn a_strong_wind_is_called_as_soon_as_the_estimate_has_converged() {
    let truth = wind_from(9.0, 90.0);
    let f = fly_seeing(
        Vector3::new(0.0, -300.0, -600.0),
        0.0,
        FlightMode::SpiralLanding,
        target_plan(0.0, 0.0),
        truth,
        2000.0,
        |t, mut est| {
            let converged = (t / 15.0).min(1.0);
            est.wind_ned_mps *= converged;
            let sigma = if t < 15.0 {
                5.0 * (1.0 - converged) + 0.7
            } else {
                0.2
            };
            est.wind_sigma_mps = Vector3::new(sigma, sigma, 0.0);
            est
        },
    );
    let called = f
        .events
        .iter()
        .find(|e| e.to == GuidancePhase::BestReachable)
        .expect("guidance calls the target out of reach");
    // The estimate is trusted from 15 s and decisions wait 10 s more for it to settle.
    assert!(called.time_s <= 26.0, "called at {} s", called.time_s);
}

/// The point "(N north, E east)" of a best-reachable event's reason (other parentheses,
/// such as the reach ratio's, may follow it).
fn best_point_in(reason: &str) -> [f64; 2] {
    let point = reason.rfind(" N, ").unwrap_or(reason.len());
    let start = reason[..point].rfind('(').unwrap_or(0) + 1;
    let numbers: Vec<f64> = reason[start..]
        .split(|c: char| !(c.is_ascii_digit() || c == '-' || c == '.'))
        .filter_map(|w| w.parse().ok())
        .collect();
    [numbers[0], numbers[1]]
}

/// The seed's two-point localizer (`Localizer::through`) in closed loop: from off the line,
/// an approach at up to 45°, then the following phase on the line from the first point
/// through the second.
#[test]
fn the_two_point_localizer_is_intercepted_and_followed_through_both_points() {
    let from = [50.0, -100.0];
    let to = [350.0, 200.0];
    let line = Localizer::through(from, to);
    assert!((line.course_rad - 45f64.to_radians()).abs() < 1e-12);
    let plan = Plan {
        localizer: line,
        ..Plan::default()
    };
    let mut guidance = Guidance::new(GuidanceConfig::default());
    guidance.set_plan(plan, 0.0);
    guidance.set_mode(FlightMode::Localizer, 0.0);
    let perf = GlidePerformance::default();
    let wind = wind_from(2.0, 270.0);
    // Starts 150 m left of the line, heading north.
    let mut mass = PointMass::new(0.0, Vector3::new(150.0, -150.0, -600.0), 0.0);
    let mut law_phases = Vec::new();
    let mut passed_second = false;
    let mut overshoot_m = 0.0_f64;
    while mass.time_s < 200.0 {
        let command = guidance.update(&mass.estimate(&wind), 1.2);
        if let Some((horizontal, _)) = guidance.law_phases()
            && law_phases.last() != Some(&horizontal)
        {
            law_phases.push(horizontal);
        }
        for _ in 0..5 {
            mass.step(
                &perf,
                &command.controls,
                &Conditions::nominal(wind, 1.2),
                0.05,
            );
        }
        let p = [mass.position_ned_m.x, mass.position_ned_m.y];
        // Past the line (it starts on the negative side): the capture's overshoot.
        overshoot_m = overshoot_m.max(line.cross_track_m(p));
        if line.along_track_m(p) > line.along_track_m(to) {
            passed_second = true;
            assert!(
                line.cross_track_m(p).abs() < 3.0,
                "{:.1} m off the line past the second point",
                line.cross_track_m(p)
            );
            let course = mass.velocity_ned_mps.y.atan2(mass.velocity_ned_mps.x);
            assert!(wrap_pi(course - line.course_rad).abs() < 5f64.to_radians());
        }
    }
    assert!(passed_second, "flew past the second point");
    // The capture overshoots by 8.3 m with the heading gains of 2026-11-28 (three quarters of
    // the earlier ones, which stayed inside the 8 m where the law is back in its approach
    // phase): one return to the approach phase is allowed, the overshoot bounded.
    assert!(
        overshoot_m < 10.0,
        "overshot the line by {overshoot_m:.1} m"
    );
    assert_eq!(law_phases[..2], [LawPhase::Approach, LawPhase::Following]);
    assert!(law_phases.len() <= 4, "{law_phases:?}");
    assert_eq!(law_phases.last(), Some(&LawPhase::Following));
}
