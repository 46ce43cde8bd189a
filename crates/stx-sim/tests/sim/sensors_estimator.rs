//! The estimator flown against the real 14-DOF model through the simulated sensors: wind,
//! airspeed, sink, heading and course errors over turning flights in turbulent wind, a GPS
//! dropout, latency compensation, determinism, and the cost per call.
//!
//! Run with `--nocapture` to see the figures each test measures (they are the ones reported
//! in the estimator's documentation).
//!
//! Turbulence: Dryden gusts as MIL-F-8785C gives them at low altitude for the landing
//! pattern's ~300 m above ground: length scales `L_u = L_w ≈ 300 m` and intensities
//! `σ_u = σ_w = 0.1 × W` (with `W` the mean wind here, at flight altitude, which overstates
//! the standard's 6-m wind `W20`); one test flies stronger, faster gusts.

use std::sync::Arc;
use std::time::Instant;

use nalgebra::Vector3;
use stx_dynamics::atmosphere::StandardAtmosphere;
use stx_dynamics::integrate::{Hooks, Rk4, integrate};
use stx_dynamics::model::{Environment, ParafoilModel};
use stx_dynamics::rotation::wrap_pi;
use stx_dynamics::state::{Controls, Pose, StateVector};
use stx_dynamics::vehicle::Vehicle;
use stx_dynamics::wind::{ConstantWind, Turbulence, TurbulenceParams, WindComposite, WindField};
use stx_gnc::estimate::Estimate;
use stx_gnc::estimator::{Estimator, EstimatorConfig, EstimatorCounters};
use stx_gnc::measurement::Measurement;
use stx_sim::sensors::{Delivery, DeliveryQueue, SensorConfig, SensorSuite, Truth};

/// Control tick and integration step, s.
const TICK_S: f64 = 0.05;

/// The project's goal for the wind estimate, RMS over the flight from 30 s on, m/s.
const WIND_GOAL_MPS: f64 = 0.3;

/// How the main line is driven.
#[derive(Clone, Copy, Debug)]
enum Turns {
    /// ±amplitude (m), switching every `period_s`, after 10 s of straight flight.
    Alternating { amplitude_m: f64, period_s: f64 },
    /// amplitude·sin(2πt/period), after 10 s of straight flight.
    Sine { amplitude_m: f64, period_s: f64 },
    /// A square pattern: `turn_s` at +amplitude, then `straight_s` straight, repeated after
    /// 10 s of straight flight (the legs of a spiral landing).
    Legs {
        amplitude_m: f64,
        turn_s: f64,
        straight_s: f64,
    },
}

impl Turns {
    const ALTERNATING: Turns = Turns::Alternating {
        amplitude_m: 0.015,
        period_s: 17.0,
    };
    const SINE: Turns = Turns::Sine {
        amplitude_m: 0.012,
        period_s: 40.0,
    };
    const LEGS: Turns = Turns::Legs {
        amplitude_m: 0.01,
        turn_s: 4.0,
        straight_s: 20.0,
    };

    fn command_m(self, t: f64) -> f64 {
        if t < 10.0 {
            return 0.0;
        }
        let s = t - 10.0;
        match self {
            Turns::Alternating {
                amplitude_m,
                period_s,
            } => {
                if (s / period_s).floor() as i64 % 2 == 0 {
                    amplitude_m
                } else {
                    -amplitude_m
                }
            }
            Turns::Sine {
                amplitude_m,
                period_s,
            } => amplitude_m * (2.0 * std::f64::consts::PI * s / period_s).sin(),
            Turns::Legs {
                amplitude_m,
                turn_s,
                straight_s,
            } => {
                if s.rem_euclid(turn_s + straight_s) < turn_s {
                    amplitude_m
                } else {
                    0.0
                }
            }
        }
    }
}

/// Dryden gust intensity (horizontal and vertical alike) and length scales.
#[derive(Clone, Copy, Debug)]
struct Gusts {
    sigma_mps: f64,
    length_scale_horizontal_m: f64,
    length_scale_vertical_m: f64,
}

impl Gusts {
    /// MIL-F-8785C at low altitude, about 300 m above ground, for a mean wind `W`.
    fn low_altitude(wind_speed_mps: f64) -> Self {
        Self {
            sigma_mps: 0.1 * wind_speed_mps,
            length_scale_horizontal_m: 300.0,
            length_scale_vertical_m: 300.0,
        }
    }
}

#[derive(Clone, Debug)]
struct Case {
    wind_speed_mps: f64,
    wind_from_deg: f64,
    gusts: Gusts,
    seed: u64,
    turns: Turns,
    duration_s: f64,
    sensors: SensorConfig,
    /// Hand GPS fixes to the estimator stamped with their arrival instead of their instant.
    naive_gps_time: bool,
}

impl Case {
    fn new(wind_speed_mps: f64, wind_from_deg: f64, seed: u64, turns: Turns) -> Self {
        Self {
            wind_speed_mps,
            wind_from_deg,
            gusts: Gusts::low_altitude(wind_speed_mps),
            seed,
            turns,
            duration_s: 200.0,
            sensors: SensorConfig::default(),
            naive_gps_time: false,
        }
    }

    fn label(&self) -> String {
        format!(
            "wind {} m/s from {:>3}°, seed {}, {:?}",
            self.wind_speed_mps, self.wind_from_deg, self.seed, self.turns
        )
    }
}

/// One instant of a run: the truth and the estimate at the same instant.
struct Sample {
    truth: Truth,
    estimate: Estimate,
}

struct Run {
    samples: Vec<Sample>,
    counters: EstimatorCounters,
    /// Every delivery with the tick it was handed over at, to replay for timing.
    deliveries: Vec<(f64, Delivery)>,
}

fn fly(case: &Case) -> Run {
    let turbulence = Turbulence::new(TurbulenceParams {
        sigma_horizontal_mps: case.gusts.sigma_mps,
        sigma_vertical_mps: case.gusts.sigma_mps,
        length_scale_horizontal_m: case.gusts.length_scale_horizontal_m,
        length_scale_vertical_m: case.gusts.length_scale_vertical_m,
        reference_airspeed_mps: 6.7,
        seed: case.seed.wrapping_add(1000),
        components: 64,
    })
    .expect("valid turbulence");
    let wind: Arc<dyn WindField> = Arc::new(WindComposite {
        mean: Box::new(
            ConstantWind::from_speed_direction(case.wind_speed_mps, case.wind_from_deg)
                .expect("valid wind"),
        ),
        turbulence: Some(turbulence),
    });
    let mut model = ParafoilModel::new(
        Vehicle::straplex(),
        Environment {
            atmosphere: Arc::new(StandardAtmosphere),
            wind,
            ground_altitude_msl_m: 0.0,
        },
    );
    // The seed's release conditions (§4.6), high enough for the whole run.
    let pose = Pose::seed_release(1500.0);
    let mut x: StateVector = pose.to_state();
    let mut sensors = SensorSuite::new(&case.sensors, case.seed).expect("valid sensors");
    let mut estimator = Estimator::new(EstimatorConfig::default()).expect("valid estimator");
    let mut queue = DeliveryQueue::new();
    let mut stepper = Rk4::new(TICK_S);
    let mut samples = Vec::new();
    let mut deliveries = Vec::new();
    let ticks = (case.duration_s / TICK_S).round() as usize;
    for tick in 0..=ticks {
        let t = tick as f64 * TICK_S;
        model.set_controls(Controls {
            main_line_m: case.turns.command_m(t),
            ..Default::default()
        });
        let truth = Truth::from_model(&model, t, &x);
        for delivery in sensors.sample(t, &truth) {
            queue.push(delivery);
        }
        while let Some(mut delivery) = queue.pop_due(t + 1e-9) {
            if case.naive_gps_time
                && let Measurement::Gps(fix) = &mut delivery.measurement
            {
                fix.time_s = delivery.arrival_s;
            }
            estimator.handle(delivery.arrival_s, &delivery.measurement);
            deliveries.push((t, delivery));
        }
        samples.push(Sample {
            truth,
            estimate: estimator.estimate(t),
        });
        if tick == ticks {
            break;
        }
        x = integrate(
            &mut stepper,
            &mut model,
            t,
            &x,
            t + TICK_S,
            Hooks::default(),
        )
        .expect("the model flies")
        .state;
    }
    Run {
        samples,
        counters: *estimator.counters(),
        deliveries,
    }
}

/// RMS of `error` over the samples in `[from_s, to_s)` for which it is defined.
fn rms(run: &Run, from_s: f64, to_s: f64, error: impl Fn(&Sample) -> Option<f64>) -> f64 {
    let (sum, n) = run
        .samples
        .iter()
        .filter(|s| s.truth.time_s >= from_s && s.truth.time_s < to_s)
        .filter_map(&error)
        .fold((0.0, 0usize), |(sum, n), e| (sum + e * e, n + 1));
    (sum / n as f64).sqrt()
}

fn horizontal(v: Vector3<f64>) -> f64 {
    v.x.hypot(v.y)
}

fn wind_error(s: &Sample) -> Option<f64> {
    Some(horizontal(s.estimate.wind_ned_mps - s.truth.wind_ned_mps))
}

fn airspeed_error(s: &Sample) -> Option<f64> {
    Some(s.estimate.airspeed_mps - s.truth.air_velocity_body_mps.norm())
}

fn sink_error(s: &Sample) -> Option<f64> {
    Some(s.estimate.sink_rate_mps - s.truth.velocity_ned_mps.z)
}

/// The drone's yaw against its filtered AHRS yaw.
fn drone_yaw_error(s: &Sample) -> Option<f64> {
    Some(wrap_pi(s.estimate.drone_yaw_rad - s.truth.euler_rad.z))
}

/// The vehicle heading (the direction of the horizontal air velocity) against the truth's.
fn heading_error(s: &Sample) -> Option<f64> {
    let air = s.truth.velocity_ned_mps - s.truth.wind_ned_mps;
    (horizontal(air) > 2.0).then(|| wrap_pi(s.estimate.heading_rad - air.y.atan2(air.x)))
}

fn heading_rate_error(s: &Sample) -> Option<f64> {
    Some(s.estimate.drone_yaw_rate_rad_s - s.truth.euler_rate_rad_s.z)
}

/// Course error where the course means something (ground speed above 2 m/s).
fn course_error(s: &Sample) -> Option<f64> {
    let v = s.truth.velocity_ned_mps;
    (horizontal(v) > 2.0).then(|| wrap_pi(s.estimate.course_rad - v.y.atan2(v.x)))
}

fn position_error(s: &Sample) -> Option<f64> {
    Some((s.estimate.position_ned_m - s.truth.position_ned_m).norm())
}

fn velocity_error(s: &Sample) -> Option<f64> {
    Some((s.estimate.velocity_ned_mps - s.truth.velocity_ned_mps).norm())
}

/// RMS errors over a run from `from_s` on.
struct Figures {
    wind: f64,
    airspeed: f64,
    sink: f64,
    heading_deg: f64,
    drone_yaw_deg: f64,
    heading_rate: f64,
    course_deg: f64,
    position: f64,
    velocity: f64,
}

fn figures(run: &Run, from_s: f64) -> Figures {
    let end = f64::INFINITY;
    Figures {
        wind: rms(run, from_s, end, wind_error),
        airspeed: rms(run, from_s, end, airspeed_error),
        sink: rms(run, from_s, end, sink_error),
        heading_deg: rms(run, from_s, end, heading_error).to_degrees(),
        drone_yaw_deg: rms(run, from_s, end, drone_yaw_error).to_degrees(),
        heading_rate: rms(run, from_s, end, heading_rate_error),
        course_deg: rms(run, from_s, end, course_error).to_degrees(),
        position: rms(run, from_s, end, position_error),
        velocity: rms(run, from_s, end, velocity_error),
    }
}

fn print_figures(label: &str, f: &Figures) {
    println!(
        "{label}\n    RMS from 30 s: wind {:.3} m/s | airspeed {:.3} m/s | sink {:.3} m/s | \
         heading {:.1}° | drone yaw {:.1}° | drone yaw rate {:.2} rad/s | course {:.1}° | \
         position {:.2} m | velocity {:.3} m/s",
        f.wind,
        f.airspeed,
        f.sink,
        f.heading_deg,
        f.drone_yaw_deg,
        f.heading_rate,
        f.course_deg,
        f.position,
        f.velocity
    );
}

/// Flies each case and checks the wind goal and the other figures.
fn check_cases(cases: &[Case]) {
    for case in cases {
        let run = fly(case);
        let f = figures(&run, 30.0);
        print_figures(&case.label(), &f);
        let label = case.label();
        assert!(f.wind <= WIND_GOAL_MPS, "{label}: wind RMSE {:.3}", f.wind);
        // The flown airspeed and sink vary by 2 m/s and 3 m/s between straight flight and
        // spirals; the estimate follows them within a few tenths.
        assert!(f.airspeed < 0.5, "{label}: airspeed RMSE {:.3}", f.airspeed);
        assert!(f.sink < 0.5, "{label}: sink RMSE {:.3}", f.sink);
        assert!(
            f.course_deg < 10.0,
            "{label}: course RMSE {:.1}°",
            f.course_deg
        );
        assert!(f.position < 6.0, "{label}: position RMSE {:.2}", f.position);
        assert!(f.velocity < 1.0, "{label}: velocity RMSE {:.3}", f.velocity);
        // The vehicle heading guidance steers on is the air track, smooth; the drone's yaw
        // swings at ~1 Hz and is sampled at 4 Hz: its error between samples is large (see
        // the module documentation), but it must not be lost.
        assert!(
            f.heading_deg < 10.0,
            "{label}: heading RMSE {:.1}°",
            f.heading_deg
        );
        assert!(
            f.drone_yaw_deg < 30.0,
            "{label}: drone yaw RMSE {:.1}°",
            f.drone_yaw_deg
        );
        // Nothing was refused and almost every measurement was used.
        let c = run.counters;
        assert_eq!(c.stale + c.non_finite + c.invalid + c.from_future, 0);
        assert!(c.gated.total() * 20 < c.used.total(), "{label}: {c:?}");
    }
}

#[test]
fn wind_meets_the_goal_in_alternating_turns_across_winds_and_seeds() {
    check_cases(&[
        Case::new(3.0, 300.0, 1, Turns::ALTERNATING),
        Case::new(5.0, 45.0, 2, Turns::ALTERNATING),
        Case::new(2.0, 180.0, 3, Turns::ALTERNATING),
        Case::new(4.0, 90.0, 4, Turns::ALTERNATING),
        Case::new(5.0, 250.0, 5, Turns::ALTERNATING),
    ]);
}

#[test]
fn wind_meets_the_goal_on_spiral_legs_and_in_a_slow_sine() {
    check_cases(&[
        Case::new(3.0, 300.0, 11, Turns::LEGS),
        Case::new(5.0, 45.0, 12, Turns::LEGS),
        Case::new(4.0, 160.0, 13, Turns::LEGS),
        Case::new(5.0, 200.0, 14, Turns::SINE),
        Case::new(2.0, 20.0, 15, Turns::SINE),
    ]);
}

#[test]
fn wind_meets_the_goal_on_cases_the_tuning_never_saw() {
    // Winds of 2–5 m/s from all round, each turn pattern, seeds not used while tuning.
    let turns = [Turns::LEGS, Turns::SINE, Turns::ALTERNATING];
    let cases: Vec<Case> = (0..12u64)
        .map(|k| {
            let speed = (20.0 + (k as f64 * 0.37).fract() * 30.0).round() / 10.0;
            let from = (k as f64 * 97.0) % 360.0;
            Case::new(speed, from, 100 + k, turns[k as usize % 3])
        })
        .collect();
    check_cases(&cases);
}

#[test]
fn pitot_samples_between_ahrs_samples_cost_some_accuracy_but_not_the_estimate() {
    // The default sensors sample in the same instant, as the drone's 4 Hz loop does; here the
    // pitot comes 0.05 s (then 0.1 s) after the AHRS and the estimator interpolates the
    // attitude across the drone's swing.
    let mut worst: f64 = 0.0;
    for (offset_s, speed, from, seed) in [(0.05, 3.0, 300.0, 1), (0.1, 5.0, 45.0, 2)] {
        let mut case = Case::new(speed, from, seed, Turns::ALTERNATING);
        case.sensors.pitot.phase_s = offset_s;
        case.sensors.gps.phase_s = 0.15;
        let f = figures(&fly(&case), 30.0);
        print_figures(
            &format!("pitot {offset_s} s after the AHRS: {}", case.label()),
            &f,
        );
        worst = worst.max(f.wind);
    }
    assert!(worst < 0.45, "worst wind RMSE {worst:.3}");
}

#[test]
fn stronger_and_faster_gusts_degrade_the_wind_gracefully() {
    // Beyond the standard's light turbulence: 0.2 m/s stronger, and gusts 1.5 (horizontal)
    // to 6 (vertical) times faster. The goal is not claimed here; a bound guards against the
    // filter falling apart.
    let mut worst: f64 = 0.0;
    for (speed, from, seed) in [(3.0, 300.0, 1), (5.0, 45.0, 2), (2.0, 180.0, 3)] {
        let mut case = Case::new(speed, from, seed, Turns::ALTERNATING);
        case.gusts = Gusts {
            sigma_mps: 0.1 * speed + 0.2,
            length_scale_horizontal_m: 200.0,
            length_scale_vertical_m: 50.0,
        };
        let f = figures(&fly(&case), 30.0);
        print_figures(&format!("{} in gusts {:?}", case.label(), case.gusts), &f);
        worst = worst.max(f.wind);
    }
    assert!(worst < 0.5, "worst wind RMSE {worst:.3}");
}

#[test]
fn a_ten_second_gps_dropout_is_bridged_and_closed() {
    for (speed, from, seed) in [(4.0, 300.0, 21), (5.0, 80.0, 22), (2.0, 210.0, 23)] {
        let mut case = Case::new(speed, from, seed, Turns::ALTERNATING);
        case.duration_s = 120.0;
        case.sensors.gps.dropouts_s = vec![[60.0, 70.0]];
        let run = fly(&case);
        let at = |time: f64| {
            &run.samples
                .iter()
                .find(|s| (s.truth.time_s - time).abs() < 1e-6)
                .expect("a sample at that instant")
                .estimate
        };
        let error_at = |time: f64| {
            run.samples
                .iter()
                .find(|s| (s.truth.time_s - time).abs() < 1e-6)
                .and_then(position_error)
                .expect("a sample at that instant")
        };
        let before_sigma = at(59.5).position_sigma_m.x;
        let end_sigma = at(70.0).position_sigma_m.x;
        let worst_in_gap = run
            .samples
            .iter()
            .filter(|s| (60.0..71.0).contains(&s.truth.time_s))
            .filter_map(position_error)
            .fold(0.0, f64::max);
        let rms_before = rms(&run, 40.0, 60.0, position_error);
        let rms_after = rms(&run, 80.0, 120.0, position_error);
        println!(
            "GPS dropout 60–70 s, {}: position error before {rms_before:.2} m RMS, worst in \
             the gap {worst_in_gap:.2} m, at 70 s {:.2} m; σ_N {before_sigma:.2} → \
             {end_sigma:.2} m → {:.2} m at 75 s; after {rms_after:.2} m RMS",
            case.label(),
            error_at(70.0),
            at(75.0).position_sigma_m.x,
        );
        assert!(at(59.5).gps_ok);
        assert!(!at(62.0).gps_ok && at(62.0).gps_age_s > 1.5);
        assert!(at(65.0).attitude_ok && at(65.0).air_data_ok);
        assert!(end_sigma > 3.0 * before_sigma, "σ must grow");
        assert!(
            worst_in_gap < 25.0,
            "dead reckoning drifted {worst_in_gap:.1} m"
        );
        assert!(at(72.0).gps_ok, "GPS back");
        assert!(
            at(75.0).position_sigma_m.x < 0.5 * end_sigma,
            "σ must shrink"
        );
        assert!(rms_after < 1.5 * rms_before + 1.0);
    }
}

#[test]
fn latency_compensation_beats_taking_late_fixes_as_current() {
    for seed in [31, 32] {
        let mut case = Case::new(4.0, 120.0, seed, Turns::ALTERNATING);
        case.duration_s = 120.0;
        case.sensors.gps.latency_s = 0.4;
        // Without the receiver's slow wander, the lag is what the position error shows.
        case.sensors.gps.horizontal_wander_m = 0.0;
        case.sensors.gps.vertical_wander_m = 0.0;
        let compensated = fly(&case);
        case.naive_gps_time = true;
        let naive = fly(&case);
        let (c, n) = (figures(&compensated, 30.0), figures(&naive, 30.0));
        println!(
            "GPS 0.4 s late, seed {seed}: position {:.2} m vs {:.2} m taken as current; \
             velocity {:.3} vs {:.3} m/s; wind {:.3} vs {:.3} m/s",
            c.position, n.position, c.velocity, n.velocity, c.wind, n.wind
        );
        assert!(c.position < 0.8 * n.position);
        assert!(c.velocity < 0.8 * n.velocity);
        assert!(c.wind < n.wind);
    }
}

#[test]
fn sensor_dropouts_degrade_and_recover_without_failing() {
    let mut case = Case::new(4.0, 30.0, 41, Turns::ALTERNATING);
    case.duration_s = 120.0;
    case.sensors.ahrs.dropouts_s = vec![[50.0, 53.0]];
    case.sensors.pitot.dropouts_s = vec![[80.0, 90.0]];
    case.sensors.gps.dropout_probability = 0.2;
    case.sensors.pitot.dropout_probability = 0.1;
    let run = fly(&case);
    let at = |time: f64| {
        &run.samples
            .iter()
            .find(|s| (s.truth.time_s - time).abs() < 1e-6)
            .expect("a sample")
            .estimate
    };
    assert!(!at(52.5).attitude_ok && at(55.0).attitude_ok);
    assert!(!at(89.0).air_data_ok && at(92.0).air_data_ok);
    let f = figures(&run, 30.0);
    print_figures(
        &format!("AHRS and pitot gaps, random losses: {}", case.label()),
        &f,
    );
    assert!(
        f.wind < 0.4 && f.position < 6.0,
        "wind {:.3}, position {:.2}",
        f.wind,
        f.position
    );
}

#[test]
fn the_same_seed_gives_the_same_estimates() {
    let mut case = Case::new(3.0, 10.0, 51, Turns::ALTERNATING);
    case.duration_s = 40.0;
    let a = fly(&case);
    let b = fly(&case);
    assert!(
        a.samples
            .iter()
            .zip(&b.samples)
            .all(|(x, y)| x.estimate == y.estimate)
    );
    case.seed = 52;
    let c = fly(&case);
    assert!(
        a.samples
            .iter()
            .zip(&c.samples)
            .any(|(x, y)| x.estimate != y.estimate)
    );
}

#[test]
fn cost_per_call_is_a_few_microseconds() {
    // One flight's deliveries, replayed into fresh estimators: the timing excludes the
    // flight model and the sensors.
    let mut case = Case::new(4.0, 60.0, 61, Turns::ALTERNATING);
    case.duration_s = 200.0;
    let run = fly(&case);
    let repeats = 20;
    // (handle, estimate) wall time of each repeat, s. The best repeat is the least disturbed
    // by whatever else shares the machine; the mean is what a busy machine gives.
    let mut times = Vec::with_capacity(repeats);
    let mut checksum = 0.0;
    for _ in 0..repeats {
        let mut est = Estimator::new(EstimatorConfig::default()).expect("valid");
        let (mut handle_s, mut estimate_s) = (0.0, 0.0);
        let mut i = 0;
        for s in &run.samples {
            let t = s.truth.time_s;
            let started = Instant::now();
            while i < run.deliveries.len() && run.deliveries[i].0 <= t {
                let (_, d) = &run.deliveries[i];
                est.handle(d.arrival_s, &d.measurement);
                i += 1;
            }
            handle_s += started.elapsed().as_secs_f64();
            let started = Instant::now();
            checksum += est.estimate(t).wind_ned_mps.x;
            estimate_s += started.elapsed().as_secs_f64();
        }
        times.push((handle_s, estimate_s));
    }
    let handles = run.deliveries.len() as f64;
    let estimates = run.samples.len() as f64;
    let best = times
        .iter()
        .copied()
        .fold((f64::INFINITY, f64::INFINITY), |a, b| {
            (a.0.min(b.0), a.1.min(b.1))
        });
    let mean = times.iter().fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
    let mean = (mean.0 / repeats as f64, mean.1 / repeats as f64);
    println!(
        "cost (best of {repeats} / mean): handle {:.2} / {:.2} µs per measurement ({} per \
         run), estimate {:.2} / {:.2} µs per call ({} per run); a 200-s run at 4 Hz from \
         three sensors with an estimate every 0.05-s tick: {:.1} / {:.1} ms \
         (checksum {checksum:.3})",
        best.0 / handles * 1e6,
        mean.0 / handles * 1e6,
        run.deliveries.len(),
        best.1 / estimates * 1e6,
        mean.1 / estimates * 1e6,
        run.samples.len(),
        (best.0 + best.1) * 1e3,
        (mean.0 + mean.1) * 1e3,
    );
    assert_eq!(run.deliveries.len(), 2400);
}

#[test]
fn estimator_and_sensor_settings_read_from_toml_and_refuse_unknown_keys() {
    let estimator: EstimatorConfig =
        toml::from_str("max_latency_s = 1.2\nground_altitude_msl_m = 350.0\n").expect("valid");
    assert_eq!(estimator.max_latency_s, 1.2);
    assert_eq!(
        estimator.gps_timeout_s,
        EstimatorConfig::default().gps_timeout_s
    );
    Estimator::new(estimator).expect("valid settings");
    assert!(toml::from_str::<EstimatorConfig>("max_latncy_s = 1.2\n").is_err());
    let sensors: SensorConfig = toml::from_str("[pitot]\nrate_hz = 10.0\n").expect("valid");
    SensorSuite::new(&sensors, 1).expect("valid settings");
}
