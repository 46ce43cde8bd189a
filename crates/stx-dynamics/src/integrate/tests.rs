//! Tests of the integrators against problems with known solutions: the order of accuracy must
//! show in the errors, not just their smallness, so a wrong coefficient cannot pass.

use super::*;
use nalgebra::{SVector, Vector1, Vector2};
use proptest::prelude::*;

const G_MPS2: f64 = 9.80665;

/// `y' = λy`, counting evaluations.
struct Decay {
    rate_per_s: f64,
    evaluations: usize,
}

impl Decay {
    fn new(rate_per_s: f64) -> Self {
        Self {
            rate_per_s,
            evaluations: 0,
        }
    }
}

impl OdeSystem<1> for Decay {
    fn derivative(&mut self, _time_s: f64, state: &Vector1<f64>) -> Vector1<f64> {
        self.evaluations += 1;
        state * self.rate_per_s
    }
}

/// `x'' = −ω²x` as `[x, v]`; from `[1, 0]` at t = 0, `x = cos ωt`, `v = −ω sin ωt`.
struct Oscillator {
    omega_rad_per_s: f64,
}

impl OdeSystem<2> for Oscillator {
    fn derivative(&mut self, _time_s: f64, state: &Vector2<f64>) -> Vector2<f64> {
        Vector2::new(state[1], -self.omega_rad_per_s.powi(2) * state[0])
    }
}

fn oscillator_exact(omega: f64, time_s: f64) -> Vector2<f64> {
    Vector2::new((omega * time_s).cos(), -omega * (omega * time_s).sin())
}

/// Vertical fall as `[height_m, velocity_up_mps]` with quadratic drag `k·v²` opposing motion
/// (k = 0: free fall).
struct Fall {
    drag_per_m: f64,
}

impl OdeSystem<2> for Fall {
    fn derivative(&mut self, _time_s: f64, state: &Vector2<f64>) -> Vector2<f64> {
        let v = state[1];
        Vector2::new(v, -G_MPS2 - self.drag_per_m * v * v.abs())
    }
}

/// Least-squares slope of `ln y` against `ln x`.
fn log_log_slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = points.iter().map(|(x, y)| (x.ln(), y.ln())).unzip();
    let mx = lx.iter().sum::<f64>() / n;
    let my = ly.iter().sum::<f64>() / n;
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = lx.iter().map(|x| (x - mx).powi(2)).sum();
    sxy / sxx
}

fn run<const N: usize, M: Stepper, S: OdeSystem<N>>(
    stepper: &mut M,
    system: &mut S,
    t0: f64,
    y0: SVector<f64, N>,
    t_end: f64,
) -> Outcome<N> {
    integrate(stepper, system, t0, &y0, t_end, Hooks::default()).unwrap()
}

/// Integrates with Dormand–Prince trial steps of one fixed size, no error control.
fn fixed_dormand_prince<const N: usize, S: OdeSystem<N>>(
    system: &mut S,
    y0: SVector<f64, N>,
    t_end: f64,
    steps: usize,
) -> SVector<f64, N> {
    let h = t_end / steps as f64;
    let mut point = Point {
        time_s: 0.0,
        state: y0,
        derivative: system.derivative(0.0, &y0),
    };
    for _ in 0..steps {
        point = DormandPrince54::trial_step(system, &point, h).end;
    }
    point.state
}

#[test]
fn rk4_shows_fourth_order_on_decay_and_oscillator() {
    let steps = [0.2, 0.1, 0.05, 0.025, 0.0125];
    let decay_errors: Vec<(f64, f64)> = steps
        .iter()
        .map(|&h| {
            let out = run(
                &mut Rk4::new(h),
                &mut Decay::new(-1.5),
                0.0,
                Vector1::new(1.0),
                2.0,
            );
            (h, (out.state[0] - (-3.0_f64).exp()).abs())
        })
        .collect();
    let oscillator_errors: Vec<(f64, f64)> = steps
        .iter()
        .map(|&h| {
            let mut system = Oscillator {
                omega_rad_per_s: 2.0,
            };
            let out = run(
                &mut Rk4::new(h),
                &mut system,
                0.0,
                Vector2::new(1.0, 0.0),
                10.0,
            );
            (h, (out.state - oscillator_exact(2.0, 10.0)).norm())
        })
        .collect();
    for errors in [&decay_errors, &oscillator_errors] {
        for pair in errors.windows(2) {
            let ratio = pair[0].1 / pair[1].1;
            assert!((13.0..19.0).contains(&ratio), "ratio {ratio} in {errors:?}");
        }
        let slope = log_log_slope(errors);
        eprintln!("RK4 error slope {slope:.3} over h = {steps:?}");
        assert!((slope - 4.0).abs() < 0.2, "slope {slope}");
    }
}

#[test]
fn dormand_prince_at_fixed_step_shows_fifth_order() {
    let step_counts = [20, 40, 80, 160];
    let decay_errors: Vec<(f64, f64)> = step_counts
        .iter()
        .map(|&n| {
            let y = fixed_dormand_prince(&mut Decay::new(-1.0), Vector1::new(1.0), 8.0, n);
            (
                8.0 / n as f64,
                (y[0] - (-8.0_f64).exp()).abs() / (-8.0_f64).exp(),
            )
        })
        .collect();
    let oscillator_errors: Vec<(f64, f64)> = step_counts
        .iter()
        .map(|&n| {
            let mut system = Oscillator {
                omega_rad_per_s: 1.0,
            };
            let y = fixed_dormand_prince(&mut system, Vector2::new(1.0, 0.0), 20.0, n);
            (20.0 / n as f64, (y - oscillator_exact(1.0, 20.0)).norm())
        })
        .collect();
    for errors in [&decay_errors, &oscillator_errors] {
        let slope = log_log_slope(errors);
        eprintln!("DP54 fixed-step error slope {slope:.3}: {errors:?}");
        assert!((slope - 5.0).abs() < 0.3, "slope {slope}");
    }
}

#[test]
fn adaptive_dormand_prince_global_error_follows_the_tolerance() {
    let tolerances = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10];
    let errors: Vec<(f64, f64)> = tolerances
        .iter()
        .map(|&tol| {
            let mut system = Oscillator {
                omega_rad_per_s: 1.0,
            };
            let mut method = DormandPrince54::new(tol, tol);
            let out = run(&mut method, &mut system, 0.0, Vector2::new(1.0, 0.0), 20.0);
            (tol, (out.state - oscillator_exact(1.0, 20.0)).norm())
        })
        .collect();
    let slope = log_log_slope(&errors);
    eprintln!("DP54 adaptive: global error vs tolerance slope {slope:.3}: {errors:?}");
    // Local error per step is held near the tolerance; with steps ∝ tol^(1/5) the global error
    // goes as tol^(4/5)…tol^1 depending on how errors accumulate. A slope far from that range
    // means the controller or the estimate is wrong.
    assert!((0.75..1.15).contains(&slope), "slope {slope}");
    for (tol, error) in errors {
        assert!(error < 100.0 * tol, "error {error} at tolerance {tol}");
    }
}

#[test]
fn dormand_prince_dense_output_is_fourth_order_inside_a_step() {
    // One step from the exact state: the continuous extension's error must fall as h⁵
    // (local error of a 4th-order extension) at interior points.
    let omega = 1.0;
    let steps = [0.4, 0.2, 0.1, 0.05];
    for theta in [0.3, 0.5, 0.77] {
        let errors: Vec<(f64, f64)> = steps
            .iter()
            .map(|&h| {
                let mut system = Oscillator {
                    omega_rad_per_s: omega,
                };
                let start = Point {
                    time_s: 0.0,
                    state: Vector2::new(1.0, 0.0),
                    derivative: Vector2::new(0.0, -1.0),
                };
                let trial = DormandPrince54::trial_step(&mut system, &start, h);
                let t = theta * h;
                (
                    h,
                    (trial.interpolant.state_at(t) - oscillator_exact(omega, t)).norm(),
                )
            })
            .collect();
        let slope = log_log_slope(&errors);
        eprintln!("DP54 dense output at θ = {theta}: local error slope {slope:.3}");
        assert!(
            (slope - 5.0).abs() < 0.3,
            "θ {theta}: slope {slope} {errors:?}"
        );
    }
}

#[test]
fn rk4_hermite_interpolant_error_falls_as_h4_inside_a_step() {
    // Cubic Hermite through the step's ends: local interpolation error O(h⁴).
    let steps = [0.4, 0.2, 0.1, 0.05];
    let errors: Vec<(f64, f64)> = steps
        .iter()
        .map(|&h| {
            let mut system = Oscillator {
                omega_rad_per_s: 1.0,
            };
            let start = Point {
                time_s: 0.0,
                state: Vector2::new(1.0, 0.0),
                derivative: Vector2::new(0.0, -1.0),
            };
            let step = Rk4::new(h).step(&mut system, &start, 10.0).unwrap();
            let t = 0.5 * h;
            (
                h,
                (step.interpolant.state_at(t) - oscillator_exact(1.0, t)).norm(),
            )
        })
        .collect();
    let slope = log_log_slope(&errors);
    eprintln!("RK4 Hermite interpolant: local error slope {slope:.3}");
    assert!((slope - 4.0).abs() < 0.3, "slope {slope} {errors:?}");
}

/// Free fall from `h0` with upward speed `v0`: lands at `(v0 + √(v0² + 2g·h0))/g`.
fn free_fall_landing(h0: f64, v0: f64) -> (f64, f64) {
    let t = (v0 + (v0 * v0 + 2.0 * G_MPS2 * h0).sqrt()) / G_MPS2;
    (t, v0 - G_MPS2 * t)
}

fn land<M: Stepper>(method: &mut M, drag_per_m: f64, h0: f64, v0: f64) -> (Outcome<2>, usize) {
    let mut height = |_t: f64, y: &Vector2<f64>| y[0];
    let mut observed = 0;
    let mut observer = |_t: f64, _y: &Vector2<f64>| observed += 1;
    let out = integrate(
        method,
        &mut Fall { drag_per_m },
        0.0,
        &Vector2::new(h0, v0),
        1_000.0,
        Hooks {
            event: Some(&mut height),
            observer: Some(&mut observer),
        },
    )
    .unwrap();
    (out, observed)
}

#[test]
fn event_stops_a_free_fall_exactly_at_the_ground_with_the_exact_state() {
    let (h0, v0) = (100.0, 7.0);
    let (t_exact, v_exact) = free_fall_landing(h0, v0);
    // Steps much longer than the root's distance to any step end: the state must come from the
    // interpolant, not from the step that passed the ground.
    let cases: [(&str, Outcome<2>, usize); 2] = [
        ("RK4", land(&mut Rk4::new(0.7), 0.0, h0, v0).0, 0),
        (
            "DP54",
            land(&mut DormandPrince54::new(1e-8, 1e-8), 0.0, h0, v0).0,
            0,
        ),
    ];
    for (name, out, _) in cases {
        let event_time = out.event_time_s.expect("event fired");
        assert_eq!(event_time, out.time_s);
        assert!(
            (event_time - t_exact).abs() < 1e-7,
            "{name}: {event_time} vs {t_exact}"
        );
        // The height is exactly zero at the true root: at the located one it is within
        // |v|·tolerance, and on the ground side.
        assert!(
            out.state[0] <= 0.0 && out.state[0] > -1e-7,
            "{name}: {:?}",
            out.state
        );
        assert!(
            (out.state[1] - v_exact).abs() < 1e-7,
            "{name}: {:?}",
            out.state
        );
    }
}

#[test]
fn event_on_a_fall_with_drag_matches_the_closed_form() {
    // Quadratic drag from rest: v = −v_t·tanh(g t/v_t), h = h0 − (v_t²/g)·ln cosh(g t/v_t).
    let drag_per_m = 0.02;
    let h0 = 250.0;
    let terminal = (G_MPS2 / drag_per_m).sqrt();
    let t_exact = terminal / G_MPS2 * (G_MPS2 * h0 / terminal.powi(2)).exp().acosh();
    let v_exact = -terminal * (G_MPS2 * t_exact / terminal).tanh();
    let (rk4, rk4_observed) = land(&mut Rk4::new(0.01), drag_per_m, h0, 0.0);
    let (dp, dp_observed) = land(&mut DormandPrince54::new(1e-12, 1e-12), drag_per_m, h0, 0.0);
    for (name, out, observed) in [("RK4", rk4, rk4_observed), ("DP54", dp, dp_observed)] {
        let t = out.event_time_s.unwrap();
        eprintln!("{name}: landing time error {:.2e} s", t - t_exact);
        assert!((t - t_exact).abs() < 1e-7, "{name}: {t} vs {t_exact}");
        assert!(
            (out.state[1] - v_exact).abs() < 1e-6,
            "{name}: {:?}",
            out.state
        );
        assert_eq!(observed, out.accepted_steps + 1);
    }
}

#[test]
fn an_event_already_at_or_below_zero_arms_only_once_it_is_positive() {
    // Thrown up from the ground: g starts at 0, rises, and the event fires on the way down.
    let (out, _) = land(&mut DormandPrince54::default(), 0.0, 0.0, 10.0);
    let t = out.event_time_s.unwrap();
    assert!((t - 2.0 * 10.0 / G_MPS2).abs() < 1e-7, "{t}");
}

#[test]
fn without_an_event_the_integration_ends_exactly_at_t_end_and_observes_every_step() {
    let mut times = Vec::new();
    let mut observer = |t: f64, _y: &Vector1<f64>| times.push(t);
    let out = integrate(
        &mut Rk4::new(0.3),
        &mut Decay::new(-1.0),
        1.0,
        &Vector1::new(2.0),
        2.0,
        Hooks {
            event: None,
            observer: Some(&mut observer),
        },
    )
    .unwrap();
    assert_eq!(out.time_s, 2.0);
    assert_eq!(out.event_time_s, None);
    assert_eq!(out.accepted_steps, 4);
    assert_eq!(times.len(), 5);
    assert_eq!((times[0], times[4]), (1.0, 2.0));
    assert!(times.windows(2).all(|w| w[1] > w[0]));
    // A zero-length span takes no step.
    let out = run(
        &mut Rk4::new(0.3),
        &mut Decay::new(-1.0),
        1.0,
        Vector1::new(2.0),
        1.0,
    );
    assert_eq!((out.accepted_steps, out.state[0]), (0, 2.0));
}

#[test]
fn derivative_evaluations_per_step_are_as_documented() {
    let mut system = Decay::new(-1.0);
    let out = run(&mut Rk4::new(0.1), &mut system, 0.0, Vector1::new(1.0), 1.0);
    assert_eq!(system.evaluations, 1 + 4 * out.accepted_steps);

    let mut method = DormandPrince54::new(1e-9, 1e-12);
    let mut system = Decay::new(-1.0);
    let first = run(&mut method, &mut system, 0.0, Vector1::new(1.0), 1.0);
    let attempts = first.accepted_steps + first.rejected_steps;
    // One at t0, one for the starting-step estimate, six per attempt.
    assert_eq!(system.evaluations, 2 + 6 * attempts);

    // The step size carries over: the second span needs no starting-step estimate.
    let remembered = method.next_step_s().unwrap();
    assert!(remembered > 0.0, "{remembered}");
    let mut system = Decay::new(-1.0);
    let second = run(&mut method, &mut system, 1.0, first.state, 2.0);
    assert_eq!(
        system.evaluations,
        1 + 6 * (second.accepted_steps + second.rejected_steps)
    );
    method.reset();
    assert_eq!(method.next_step_s(), None);
}

#[test]
fn adaptive_steps_shrink_and_reject_where_the_solution_changes_fast() {
    // A decay much faster than the first step: the controller must reject and shrink.
    let mut method = DormandPrince54::new(1e-8, 1e-10).with_initial_step_s(1.0);
    let out = run(
        &mut method,
        &mut Decay::new(-50.0),
        0.0,
        Vector1::new(1.0),
        0.5,
    );
    assert!(out.rejected_steps > 0);
    assert!((out.state[0] - (-25.0_f64).exp()).abs() < 1e-9);
}

struct Explodes;

impl OdeSystem<1> for Explodes {
    fn derivative(&mut self, _time_s: f64, state: &Vector1<f64>) -> Vector1<f64> {
        // y' = y² from y = 1 blows up at t = 1.
        state.component_mul(state)
    }
}

struct NotANumberAfter(f64);

impl OdeSystem<1> for NotANumberAfter {
    fn derivative(&mut self, time_s: f64, _state: &Vector1<f64>) -> Vector1<f64> {
        Vector1::new(if time_s > self.0 { f64::NAN } else { 1.0 })
    }
}

#[test]
fn a_singular_solution_is_a_step_size_error_naming_the_time() {
    let mut method = DormandPrince54::new(1e-8, 1e-8).with_min_step_s(1e-9);
    let error = integrate(
        &mut method,
        &mut Explodes,
        0.0,
        &Vector1::new(1.0),
        2.0,
        Hooks::default(),
    )
    .unwrap_err();
    match error {
        IntegrateError::StepSizeTooSmall { time_s, step_s, .. } => {
            assert!((0.99..1.0).contains(&time_s), "{time_s}");
            assert!(step_s < 1e-9);
        }
        IntegrateError::NonFiniteStep { time_s, .. } => {
            assert!((0.99..1.0).contains(&time_s), "{time_s}")
        }
        other => panic!("unexpected {other:?}"),
    }
}

#[test]
fn non_finite_values_are_typed_errors() {
    let error = integrate(
        &mut Rk4::new(0.1),
        &mut NotANumberAfter(0.45),
        0.0,
        &Vector1::new(0.0),
        1.0,
        Hooks::default(),
    )
    .unwrap_err();
    assert!(
        matches!(error, IntegrateError::NonFiniteStep { time_s, component: 0, .. } if (time_s - 0.4).abs() < 1e-12),
        "{error:?}"
    );
    let error = integrate(
        &mut DormandPrince54::default(),
        &mut Decay::new(1.0),
        0.0,
        &Vector1::new(f64::NAN),
        1.0,
        Hooks::default(),
    )
    .unwrap_err();
    assert_eq!(
        error,
        IntegrateError::NonFiniteStart {
            time_s: 0.0,
            component: 0
        }
    );
    let mut bad_event = |_t: f64, _y: &Vector1<f64>| f64::NAN;
    let error = integrate(
        &mut Rk4::new(0.1),
        &mut Decay::new(1.0),
        0.0,
        &Vector1::new(1.0),
        1.0,
        Hooks {
            event: Some(&mut bad_event),
            observer: None,
        },
    )
    .unwrap_err();
    assert!(matches!(error, IntegrateError::NonFiniteEvent { .. }));
}

#[test]
fn invalid_spans_and_settings_are_refused_before_any_evaluation() {
    let mut system = Decay::new(1.0);
    let y0 = Vector1::new(1.0);
    let cases: Vec<(IntegrateError, &str)> = vec![
        (
            integrate(
                &mut Rk4::new(0.1),
                &mut system,
                1.0,
                &y0,
                0.0,
                Hooks::default(),
            )
            .unwrap_err(),
            "from 1 s to 0 s",
        ),
        (
            integrate(
                &mut Rk4::new(0.0),
                &mut system,
                0.0,
                &y0,
                1.0,
                Hooks::default(),
            )
            .unwrap_err(),
            "step_s",
        ),
        (
            integrate(
                &mut DormandPrince54::new(1e-6, 0.0),
                &mut system,
                0.0,
                &y0,
                1.0,
                Hooks::default(),
            )
            .unwrap_err(),
            "abs_tol",
        ),
        (
            integrate(
                &mut DormandPrince54::default().with_max_step_s(-1.0),
                &mut system,
                0.0,
                &y0,
                1.0,
                Hooks::default(),
            )
            .unwrap_err(),
            "max_step_s",
        ),
    ];
    for (error, expected) in cases {
        let message = error.to_string();
        assert!(message.contains(expected), "{message}");
    }
    assert_eq!(system.evaluations, 0);
}

/// Either a harmonic oscillator or a free fall with its landing as the event.
#[derive(Clone, Copy, Debug)]
enum Problem {
    Oscillator { omega: f64 },
    Fall { h0: f64, v0: f64 },
}

fn solve<M: Stepper>(
    method: &mut M,
    problem: Problem,
    t0: f64,
    span: f64,
) -> Result<Outcome<2>, IntegrateError> {
    let t_end = t0 + span;
    match problem {
        Problem::Oscillator { omega } => integrate(
            method,
            &mut Oscillator {
                omega_rad_per_s: omega,
            },
            t0,
            &Vector2::new(1.0, 0.0),
            t_end,
            Hooks::default(),
        ),
        Problem::Fall { h0, v0 } => {
            let mut height = |_t: f64, y: &Vector2<f64>| y[0];
            integrate(
                method,
                &mut Fall { drag_per_m: 0.0 },
                t0,
                &Vector2::new(h0, v0),
                t_end,
                Hooks {
                    event: Some(&mut height),
                    observer: None,
                },
            )
        }
    }
}

fn problem() -> impl Strategy<Value = Problem> {
    prop_oneof![
        (0.01..20.0_f64).prop_map(|omega| Problem::Oscillator { omega }),
        (0.0..2_000.0_f64, -60.0..60.0_f64).prop_map(|(h0, v0)| Problem::Fall { h0, v0 }),
    ]
}

fn check_ending(problem: Problem, t0: f64, span: f64, out: &Outcome<2>) {
    match (problem, out.event_time_s) {
        (_, None) => assert_eq!(out.time_s, t0 + span),
        (Problem::Fall { h0, v0 }, Some(t)) => {
            assert_eq!(out.time_s, t);
            assert!(t >= t0 && t <= t0 + span);
            assert!(out.state[0] <= 0.0);
            let (t_exact, _) = free_fall_landing(h0, v0);
            assert!(
                (t - t0 - t_exact).abs() < 1e-6 * (1.0 + t_exact),
                "{t} vs {t_exact}"
            );
        }
        (Problem::Oscillator { .. }, Some(_)) => panic!("no event was set"),
    }
    if let Problem::Fall { h0, v0 } = problem {
        // The landing must not be missed.
        let (t_exact, _) = free_fall_landing(h0, v0);
        if h0 > 0.0 && t_exact < span - 1e-6 {
            assert!(out.event_time_s.is_some());
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn adaptive_runs_end_at_t_end_or_the_event(
        rel_exp in -10.0..-2.0_f64,
        abs_exp in -12.0..-3.0_f64,
        t0 in -1_000.0..1_000.0_f64,
        span in 0.0..60.0_f64,
        problem in problem(),
    ) {
        let mut method = DormandPrince54::new(10f64.powf(rel_exp), 10f64.powf(abs_exp));
        let out = solve(&mut method, problem, t0, span).unwrap();
        check_ending(problem, t0, span, &out);
    }

    #[test]
    fn fixed_step_runs_end_at_t_end_or_the_event(
        step in 1e-3..5.0_f64,
        t0 in -1_000.0..1_000.0_f64,
        span in 0.0..60.0_f64,
        problem in problem(),
    ) {
        let out = solve(&mut Rk4::new(step), problem, t0, span);
        // A long RK4 step on a fast oscillator may legitimately blow up, but only as an error.
        match out {
            Ok(out) => check_ending(problem, t0, span, &out),
            Err(error) => {
                let blew_up = matches!(error, IntegrateError::NonFiniteStep { .. });
                prop_assert!(blew_up, "unexpected error {:?}", error);
            }
        }
    }

    #[test]
    fn hostile_systems_and_settings_give_errors_not_panics(
        rel_tol in prop_oneof![Just(0.0), Just(f64::NAN), 1e-16..1.0_f64],
        abs_tol in prop_oneof![Just(0.0), Just(-1.0), 1e-300..1.0_f64],
        min_step in prop_oneof![Just(0.0), 0.0..1.0_f64],
        max_step in prop_oneof![Just(f64::INFINITY), 1e-3..10.0_f64],
        nan_after in 0.0..3.0_f64,
        explode in any::<bool>(),
    ) {
        let mut method = DormandPrince54::new(rel_tol, abs_tol)
            .with_min_step_s(min_step)
            .with_max_step_s(max_step);
        let y0 = Vector1::new(1.0);
        let _ = if explode {
            integrate(&mut method, &mut Explodes, 0.0, &y0, 2.0, Hooks::default())
        } else {
            integrate(&mut method, &mut NotANumberAfter(nan_after), 0.0, &y0, 2.0, Hooks::default())
        };
    }
}
