//! The classical fixed-step Runge–Kutta method of 4th order.
//!
//! Kept beside the adaptive method because a fixed step gives a fixed cost per simulated second
//! and a step grid aligned with the 4 Hz control loop, and because it is the reference that
//! linearisation and regression tests can reproduce exactly.

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
}

impl Rk4 {
    /// A method with the given step size (s).
    pub fn new(step_s: f64) -> Self {
        Self { step_s }
    }
}

/// Remaining spans shorter than this many steps are finished in one step, so that rounding in
/// the accumulated time does not leave a sliver of a step at the end.
const FINISH_FACTOR: f64 = 1.0 + 1e-9;

impl Stepper for Rk4 {
    fn check_settings(&self) -> Result<(), IntegrateError> {
        if self.step_s.is_finite() && self.step_s > 0.0 {
            Ok(())
        } else {
            Err(IntegrateError::InvalidSetting {
                setting: "step_s",
                value: self.step_s,
                rule: "positive and finite",
            })
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
