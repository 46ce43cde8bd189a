//! The classical fixed-step Runge–Kutta method of 4th order.
//!
//! Kept beside the adaptive method because a fixed step gives a fixed cost per simulated second
//! and a step grid aligned with the 4 Hz control loop, and because it is the reference that
//! linearisation and regression tests can reproduce exactly.
//!
//! A fixed step has no error control, so a step that cannot follow the solution is accepted
//! as long as it stays finite: an unstable mode (a stiff one with `|λ|·h` beyond RK4's ≈ 2.8)
//! then grows by a factor each step, a state changing faster than the step can follow lands
//! anywhere, and the garbage is integrated on until it overflows, seconds later, far from its
//! cause. [`Rk4::with_max_error`] refuses such a step as it happens, so the caller can take it
//! again with shorter steps. Its check costs no evaluation: the stages and the derivative at
//! the new point (which the next step needs anyway) also give a 3rd-order solution, with
//! weights `1/6, 1/3, 1/3, 0, 1/6` on `k1 … k4` and `f(t + h, y_new)`, and the two solutions
//! differ by `h/6 · (k4 − f(t + h, y_new))`.

use nalgebra::SVector;

use super::{
    AcceptedStep, IntegrateError, Interpolant, OdeSystem, Point, Stepper, first_non_finite,
};

/// Fixed-step 4th-order Runge–Kutta. Four derivative evaluations per step; the last step of a
/// span is shortened to end exactly on the span's end.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rk4 {
    /// Step size, s. Must be positive and finite.
    pub step_s: f64,
    /// Largest difference between a step's 4th- and 3rd-order solutions accepted in any
    /// component, in that component's units; `None` accepts every finite step. Must be
    /// positive. Meant as a bound on a step gone wrong, not as a tolerance: a step that fits
    /// its solution errs by orders of magnitude less.
    pub max_error: Option<f64>,
}

impl Rk4 {
    /// A method with the given step size (s), accepting every finite step.
    pub fn new(step_s: f64) -> Self {
        Self {
            step_s,
            max_error: None,
        }
    }

    /// The same method, refusing a step whose 4th- and 3rd-order solutions differ by more than
    /// `max_error` in any component ([`IntegrateError::InaccurateStep`]).
    pub fn with_max_error(self, max_error: f64) -> Self {
        Self {
            max_error: Some(max_error),
            ..self
        }
    }
}

/// Remaining spans shorter than this many steps are finished in one step, so that rounding in
/// the accumulated time does not leave a sliver of a step at the end.
const FINISH_FACTOR: f64 = 1.0 + 1e-9;

impl Stepper for Rk4 {
    fn check_settings(&self) -> Result<(), IntegrateError> {
        if !(self.step_s.is_finite() && self.step_s > 0.0) {
            return Err(IntegrateError::InvalidSetting {
                setting: "step_s",
                value: self.step_s,
                rule: "positive and finite",
            });
        }
        match self.max_error {
            Some(max_error) if max_error.is_nan() || max_error <= 0.0 => {
                Err(IntegrateError::InvalidSetting {
                    setting: "max_error",
                    value: max_error,
                    rule: "positive",
                })
            }
            _ => Ok(()),
        }
    }

    fn step<const N: usize, S: OdeSystem<N>>(
        &mut self,
        system: &mut S,
        start: &Point<N>,
        end_time_s: f64,
    ) -> Result<AcceptedStep<N>, IntegrateError> {
        let t = start.time_s;
        let remaining_s = end_time_s - t;
        let (step_s, end_s) = if remaining_s <= self.step_s * FINISH_FACTOR {
            (remaining_s, end_time_s)
        } else {
            (self.step_s, t + self.step_s)
        };
        if end_s <= t {
            return Err(IntegrateError::StepTooSmallToAdvance { time_s: t, step_s });
        }
        let y = &start.state;
        let half = 0.5 * step_s;
        let k1 = start.derivative;
        let k2 = system.derivative(t + half, &(y + k1 * half));
        let k3 = system.derivative(t + half, &(y + k2 * half));
        let k4 = system.derivative(end_s, &(y + k3 * step_s));
        let state: SVector<f64, N> = y + (k1 + (k2 + k3) * 2.0 + k4) * (step_s / 6.0);
        let non_finite = |component| IntegrateError::NonFiniteStep {
            time_s: t,
            step_s,
            component,
        };
        if let Some(component) = first_non_finite(&state) {
            return Err(non_finite(component));
        }
        let derivative = system.derivative(end_s, &state);
        if let Some(component) = first_non_finite(&derivative) {
            return Err(non_finite(component));
        }
        if let Some(max_error) = self.max_error {
            let error = (k4 - derivative) * (step_s / 6.0);
            if let Some((component, error)) = error
                .iter()
                .map(|e| e.abs())
                .enumerate()
                .find(|&(_, e)| e > max_error)
            {
                return Err(IntegrateError::InaccurateStep {
                    time_s: t,
                    step_s,
                    component,
                    error,
                });
            }
        }
        let end = Point {
            time_s: end_s,
            state,
            derivative,
        };
        Ok(AcceptedStep {
            end,
            interpolant: Interpolant::Hermite { start: *start, end },
            rejected_attempts: 0,
        })
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{Vector1, Vector2};

    use super::super::{Hooks, integrate};
    use super::*;

    /// `y' = λy`.
    struct Decay(f64);

    impl OdeSystem<1> for Decay {
        fn derivative(&mut self, _time_s: f64, state: &Vector1<f64>) -> Vector1<f64> {
            state * self.0
        }
    }

    /// `x'' = −x`.
    struct Oscillator;

    impl OdeSystem<2> for Oscillator {
        fn derivative(&mut self, _time_s: f64, state: &Vector2<f64>) -> Vector2<f64> {
            Vector2::new(state[1], -state[0])
        }
    }

    #[test]
    fn a_step_beyond_the_stability_of_a_stiff_mode_is_refused_where_it_happens() {
        // λ·h = −3.5, past RK4's −2.8: each step multiplies y by 2.7 instead of 0.03.
        let y0 = Vector1::new(1.0);
        let unbounded = integrate(
            &mut Rk4::new(0.05),
            &mut Decay(-70.0),
            0.0,
            &y0,
            1.0,
            Hooks::default(),
        )
        .expect("finite garbage is accepted without a bound");
        assert!(unbounded.state[0] > 1e6, "{}", unbounded.state[0]);
        let error = integrate(
            &mut Rk4::new(0.05).with_max_error(0.01),
            &mut Decay(-70.0),
            0.0,
            &y0,
            1.0,
            Hooks::default(),
        )
        .unwrap_err();
        assert!(
            matches!(error, IntegrateError::InaccurateStep { time_s, component: 0, .. } if time_s == 0.0),
            "{error:?}"
        );
        // Five times shorter steps follow it within the bound.
        let fine = integrate(
            &mut Rk4::new(0.01).with_max_error(0.01),
            &mut Decay(-70.0),
            0.0,
            &y0,
            1.0,
            Hooks::default(),
        )
        .expect("steps that follow the decay");
        assert!(fine.state[0].abs() < 1e-20);
    }

    #[test]
    fn a_bound_that_no_step_reaches_changes_nothing() {
        let y0 = Vector2::new(1.0, 0.0);
        let plain = integrate(
            &mut Rk4::new(0.05),
            &mut Oscillator,
            0.0,
            &y0,
            20.0,
            Hooks::default(),
        );
        let bounded = integrate(
            &mut Rk4::new(0.05).with_max_error(1e-3),
            &mut Oscillator,
            0.0,
            &y0,
            20.0,
            Hooks::default(),
        );
        assert_eq!(plain, bounded);
    }

    #[test]
    fn the_difference_of_the_two_orders_falls_as_h4_as_a_3rd_order_solutions_error_does() {
        // A bound no step meets hands back the first step's difference.
        let difference = |h: f64| {
            let error = integrate(
                &mut Rk4::new(h).with_max_error(1e-300),
                &mut Decay(-1.0),
                0.0,
                &Vector1::new(1.0),
                1.0,
                Hooks::default(),
            )
            .unwrap_err();
            match error {
                IntegrateError::InaccurateStep { error, .. } => error,
                other => panic!("{other:?}"),
            }
        };
        for h in [0.1, 0.05, 0.025] {
            let ratio = difference(h) / difference(h / 2.0);
            assert!((15.0..17.0).contains(&ratio), "h = {h}: ratio {ratio}");
        }
    }

    #[test]
    fn a_bound_must_be_positive() {
        for bound in [0.0, -1.0, f64::NAN] {
            let method = Rk4::new(0.05).with_max_error(bound);
            assert!(
                matches!(
                    method.check_settings(),
                    Err(IntegrateError::InvalidSetting {
                        setting: "max_error",
                        ..
                    })
                ),
                "{bound}"
            );
        }
    }
}
