//! The Dormand–Prince 5(4) embedded pair with adaptive step size (the method of MATLAB's
//! `ode45` and Hairer & Wanner's DOPRI5).
//!
//! Why adaptive: a release at 35 km goes from near-vacuum, where the stack accelerates to
//! ~300 km/h and pitches to −70° in seconds, to a slow glide in thick air where nothing happens
//! quickly; a fixed step small enough for the first phase wastes most of its work in the second.
//!
//! How it works: each attempt takes seven stages; the 5th-order combination is propagated
//! (local extrapolation) and its difference from the embedded 4th-order one estimates the local
//! error. The estimate, scaled per component by `abs_tol + rel_tol·max(|y|, |y_new|)` and
//! averaged as an RMS, must be ≤ 1 to accept. A proportional–integral controller picks the next
//! step from this and the previous accepted error. The seventh stage is the derivative at the
//! new point, so it becomes the next step's first ("first same as last"), and the stages also
//! give a 4th-order continuous extension used for event location.

use nalgebra::SVector;

use super::{
    AcceptedStep, IntegrateError, Interpolant, OdeSystem, Point, Stepper, first_non_finite,
};

// Butcher tableau (Dormand & Prince 1980).
const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
// 5th-order weights; also the seventh stage's row, which is what makes FSAL possible.
const B1: f64 = 35.0 / 384.0;
const B3: f64 = 500.0 / 1113.0;
const B4: f64 = 125.0 / 192.0;
const B5: f64 = -2187.0 / 6784.0;
const B6: f64 = 11.0 / 84.0;
// 5th-order minus 4th-order weights: the local error estimate.
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
// Continuous extension (Hairer, Nørsett & Wanner, "Solving ODEs I", DOPRI5 dense output).
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

/// Fraction of the optimal step actually taken, leaving margin so the next attempt is
/// usually accepted.
const SAFETY: f64 = 0.9;
/// Largest shrink of the step in one go.
const MIN_FACTOR: f64 = 0.2;
/// Largest growth of the step in one go.
const MAX_FACTOR: f64 = 10.0;
/// PI controller exponents (Hairer & Wanner's choice for DOPRI5, β = 0.04): the step follows
/// `err^−α · err_prev^β`, which damps the step-size oscillation of a pure `err^−1/5` rule.
const BETA: f64 = 0.04;
const ALPHA: f64 = 0.2 - 0.75 * BETA;
/// Floor for the remembered error, so a step with a vanishing error estimate does not make the
/// next factor infinite.
const MIN_REMEMBERED_ERROR: f64 = 1e-4;
/// As for RK4: a remaining span within this factor of the step is finished in one step.
const FINISH_FACTOR: f64 = 1.0 + 1e-9;

/// Adaptive Dormand–Prince 5(4). Remembers its step size (and the controller's last error)
/// between [`integrate`](super::integrate) calls, so a simulation advanced in short spans does
/// not restart from a cautious step at every span.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DormandPrince54 {
    /// Relative tolerance, dimensionless, ≥ 0.
    pub rel_tol: f64,
    /// Absolute tolerance, in state units, > 0 (it also keeps the error scale positive when a
    /// component is zero).
    pub abs_tol: f64,
    /// Smallest step the error control may ask for, s (≥ 0). Asking for less is an error:
    /// it means the solution cannot be followed at the requested tolerance. The last step of a
    /// span may be shorter.
    pub min_step_s: f64,
    /// Largest step, s (> 0, may be infinite). Bounds how far the interpolant stretches, so
    /// events are not stepped over.
    pub max_step_s: f64,
    /// First step of the first integration, s; `None` estimates it from the derivative (one
    /// extra evaluation).
    pub initial_step_s: Option<f64>,
    memory: Option<Memory>,
}

/// What the controller carries from one step to the next.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Memory {
    next_step_s: f64,
    previous_error: f64,
}

impl Default for DormandPrince54 {
    /// `rel_tol` 1e-6, `abs_tol` 1e-9, `min_step_s` 1e-10, no maximum step, estimated first step.
    fn default() -> Self {
        Self::new(1e-6, 1e-9)
    }
}

/// The result of one Dormand–Prince step of a given size, without error control.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrialStep<const N: usize> {
    /// The 5th-order solution at the end of the step, with its derivative.
    pub end: Point<N>,
    /// 5th-order minus 4th-order solution: the local error estimate, state units.
    pub error_estimate: SVector<f64, N>,
    /// Continuous extension across the step.
    pub interpolant: Interpolant<N>,
}

impl DormandPrince54 {
    /// A method with the given tolerances (`rel_tol` dimensionless, `abs_tol` in state units),
    /// a minimum step of 1e-10 s, no maximum step and an estimated first step.
    pub fn new(rel_tol: f64, abs_tol: f64) -> Self {
        Self {
            rel_tol,
            abs_tol,
            min_step_s: 1e-10,
            max_step_s: f64::INFINITY,
            initial_step_s: None,
            memory: None,
        }
    }

    /// Sets the minimum step size, s.
    pub fn with_min_step_s(mut self, min_step_s: f64) -> Self {
        self.min_step_s = min_step_s;
        self
    }

    /// Sets the maximum step size, s.
    pub fn with_max_step_s(mut self, max_step_s: f64) -> Self {
        self.max_step_s = max_step_s;
        self
    }

    /// Sets the first step size, s.
    pub fn with_initial_step_s(mut self, initial_step_s: f64) -> Self {
        self.initial_step_s = Some(initial_step_s);
        self
    }

    /// The step size the controller will try next, s, once it has taken a step.
    pub fn next_step_s(&self) -> Option<f64> {
        self.memory.map(|memory| memory.next_step_s)
    }

    /// Forgets the remembered step size, e.g. after a discontinuity in the system.
    pub fn reset(&mut self) {
        self.memory = None;
    }

    /// One step of exactly `step_s` (s) from `start`, with no error control: six derivative
    /// evaluations. For order studies and for callers that manage the step themselves.
    pub fn trial_step<const N: usize, S: OdeSystem<N>>(
        system: &mut S,
        start: &Point<N>,
        step_s: f64,
    ) -> TrialStep<N> {
        let t = start.time_s;
        let h = step_s;
        let y = &start.state;
        let k1 = start.derivative;
        let k2 = system.derivative(t + C2 * h, &(y + k1 * (h * A21)));
        let k3 = system.derivative(t + C3 * h, &(y + (k1 * A31 + k2 * A32) * h));
        let k4 = system.derivative(t + C4 * h, &(y + (k1 * A41 + k2 * A42 + k3 * A43) * h));
        let k5 = system.derivative(
            t + C5 * h,
            &(y + (k1 * A51 + k2 * A52 + k3 * A53 + k4 * A54) * h),
        );
        let k6 = system.derivative(
            t + h,
            &(y + (k1 * A61 + k2 * A62 + k3 * A63 + k4 * A64 + k5 * A65) * h),
        );
        let state: SVector<f64, N> = y + (k1 * B1 + k3 * B3 + k4 * B4 + k5 * B5 + k6 * B6) * h;
        let end_s = t + h;
        let k7 = system.derivative(end_s, &state);
        let error_estimate = (k1 * E1 + k3 * E3 + k4 * E4 + k5 * E5 + k6 * E6 + k7 * E7) * h;

        let r1 = state - y;
        let r2 = k1 * h - r1;
        let r3 = r1 - k7 * h - r2;
        let r4 = (k1 * D1 + k3 * D3 + k4 * D4 + k5 * D5 + k6 * D6 + k7 * D7) * h;
        TrialStep {
            end: Point {
                time_s: end_s,
                state,
                derivative: k7,
            },
            error_estimate,
            interpolant: Interpolant::DormandPrince {
                start_time_s: t,
                step_s: h,
                coefficients: [*y, r1, r2, r3, r4],
            },
        }
    }

    /// RMS over components of `error / (abs_tol + rel_tol·max(|y|, |y_new|))`.
    fn error_norm<const N: usize>(
        &self,
        error: &SVector<f64, N>,
        state: &SVector<f64, N>,
        new_state: &SVector<f64, N>,
    ) -> f64 {
        if N == 0 {
            return 0.0;
        }
        let sum: f64 = (0..N)
            .map(|i| {
                let scale = self.abs_tol + self.rel_tol * state[i].abs().max(new_state[i].abs());
                (error[i] / scale).powi(2)
            })
            .sum();
        (sum / N as f64).sqrt()
    }

    /// RMS of `vector` scaled like the error, for the starting-step estimate.
    fn scaled_rms<const N: usize>(&self, vector: &SVector<f64, N>, state: &SVector<f64, N>) -> f64 {
        self.error_norm(vector, state, state)
    }

    /// Hairer & Wanner's starting-step heuristic: a step over which an Euler step would change
    /// the state by ~1 % of its scale, refined by an estimate of the second derivative so that
    /// the 5th-order error term is about the tolerance. One derivative evaluation.
    fn starting_step<const N: usize, S: OdeSystem<N>>(
        &self,
        system: &mut S,
        start: &Point<N>,
        span_s: f64,
    ) -> f64 {
        let d0 = self.scaled_rms(&start.state, &start.state);
        let d1 = self.scaled_rms(&start.derivative, &start.state);
        let mut h0 = if d0 < 1e-5 || d1 < 1e-5 {
            1e-6
        } else {
            0.01 * d0 / d1
        };
        h0 = h0.min(self.max_step_s).min(span_s);
        let probe = start.state + start.derivative * h0;
        let probe_derivative = system.derivative(start.time_s + h0, &probe);
        let d2 = self.scaled_rms(&(probe_derivative - start.derivative), &start.state) / h0;
        if !d2.is_finite() {
            return h0;
        }
        let h1 = if d1.max(d2) <= 1e-15 {
            (h0 * 1e-3).max(1e-6)
        } else {
            (0.01 / d1.max(d2)).powf(0.2)
        };
        (100.0 * h0).min(h1)
    }
}

impl Stepper for DormandPrince54 {
    fn check_settings(&self) -> Result<(), IntegrateError> {
        let invalid = |setting, value, rule| {
            Err(IntegrateError::InvalidSetting {
                setting,
                value,
                rule,
            })
        };
        if !(self.rel_tol.is_finite() && self.rel_tol >= 0.0) {
            return invalid("rel_tol", self.rel_tol, "finite and ≥ 0");
        }
        if !(self.abs_tol.is_finite() && self.abs_tol > 0.0) {
            return invalid("abs_tol", self.abs_tol, "finite and > 0");
        }
        if !(self.min_step_s.is_finite() && self.min_step_s >= 0.0) {
            return invalid("min_step_s", self.min_step_s, "finite and ≥ 0");
        }
        if !(self.max_step_s > 0.0 && self.max_step_s >= self.min_step_s) {
            return invalid("max_step_s", self.max_step_s, "> 0 and ≥ min_step_s");
        }
        if let Some(initial) = self.initial_step_s
            && !(initial.is_finite() && initial > 0.0)
        {
            return invalid("initial_step_s", initial, "finite and > 0");
        }
        Ok(())
    }

    fn step<const N: usize, S: OdeSystem<N>>(
        &mut self,
        system: &mut S,
        start: &Point<N>,
        end_time_s: f64,
    ) -> Result<AcceptedStep<N>, IntegrateError> {
        let t = start.time_s;
        let remaining_s = end_time_s - t;
        let mut memory = match self.memory {
            Some(memory) => memory,
            None => Memory {
                next_step_s: match self.initial_step_s {
                    Some(step_s) => step_s,
                    None => self.starting_step(system, start, remaining_s),
                },
                previous_error: MIN_REMEMBERED_ERROR,
            },
        };
        let mut intended_s = memory.next_step_s.min(self.max_step_s).max(self.min_step_s);
        let mut rejected_attempts = 0;
        loop {
            let reaches_end = remaining_s <= intended_s * FINISH_FACTOR;
            let step_s = if reaches_end { remaining_s } else { intended_s };
            if !reaches_end && step_s < self.min_step_s {
                return Err(IntegrateError::StepSizeTooSmall {
                    time_s: t,
                    step_s,
                    min_step_s: self.min_step_s,
                });
            }
            if t + step_s <= t {
                return Err(IntegrateError::StepTooSmallToAdvance { time_s: t, step_s });
            }
            let mut trial = Self::trial_step(system, start, step_s);
            if reaches_end {
                trial.end.time_s = end_time_s;
            }
            let non_finite = |component| IntegrateError::NonFiniteStep {
                time_s: t,
                step_s,
                component,
            };
            if let Some(component) = first_non_finite(&trial.end.state)
                .or_else(|| first_non_finite(&trial.end.derivative))
            {
                return Err(non_finite(component));
            }
            let error = self.error_norm(&trial.error_estimate, &start.state, &trial.end.state);
            if !error.is_finite() {
                return Err(non_finite(N));
            }
            if error <= 1.0 {
                let mut factor = if error == 0.0 {
                    MAX_FACTOR
                } else {
                    SAFETY * error.powf(-ALPHA) * memory.previous_error.powf(BETA)
                };
                factor = factor.clamp(MIN_FACTOR, MAX_FACTOR);
                if rejected_attempts > 0 {
                    // Just after a rejection, growing again invites another one.
                    factor = factor.min(1.0);
                }
                let mut next_step_s = step_s * factor;
                if reaches_end {
                    // A step cut short to land on the end says little about the step the
                    // solution allows; keep the one that was intended.
                    next_step_s = next_step_s.max(intended_s);
                }
                memory.next_step_s = next_step_s.min(self.max_step_s);
                memory.previous_error = error.max(MIN_REMEMBERED_ERROR);
                self.memory = Some(memory);
                return Ok(AcceptedStep {
                    end: trial.end,
                    interpolant: trial.interpolant,
                    rejected_attempts,
                });
            }
            rejected_attempts += 1;
            let factor = (SAFETY * error.powf(-0.2)).max(MIN_FACTOR);
            intended_s = step_s * factor;
            if intended_s < self.min_step_s {
                return Err(IntegrateError::StepSizeTooSmall {
                    time_s: t,
                    step_s: intended_s,
                    min_step_s: self.min_step_s,
                });
            }
        }
    }
}
