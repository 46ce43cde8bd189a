//! Time integration of ordinary differential equations, with events located between steps.
//!
//! Why it exists: the flight model is a 31-state ODE, `Ẋ = f(t, X)`, that must be advanced over
//! minutes of flight and stopped exactly at ground contact. Stopping at the end of the step that
//! went through the ground would land the stack up to a step's worth of metres underground, so
//! events are located on the step's interpolating polynomial instead.
//!
//! How the parts fit:
//! - [`OdeSystem`] is what gets integrated. It takes `&mut self` so a system can count its
//!   evaluations or cache work between them.
//! - A [`Stepper`] takes one accepted step from a [`Point`] and returns the new point with an
//!   [`Interpolant`] valid across the step: [`Rk4`] (fixed step, cubic Hermite interpolant) and
//!   [`DormandPrince54`] (adaptive, its own 4th-order continuous extension).
//! - [`integrate`] is the one driver both use: it steps from `t0` to `t_end`, calls the observer
//!   after every step, watches the event function for a sign change from positive to
//!   non-positive and, when one happens, finds the root on the interpolant and stops there.
//!
//! Cost in derivative evaluations (the system counts them; the driver does not):
//! - one at the start of every [`integrate`] call, for the derivative at `t0`;
//! - one after every step whose end the system asks to move to other coordinates
//!   ([`OdeSystem::rechart`]);
//! - [`Rk4`]: four per step (three stages plus the derivative at the new point, which is the
//!   next step's first stage);
//! - [`DormandPrince54`]: six per attempt, accepted or rejected (the seventh stage is the
//!   derivative at the new point and is reused as the next step's first, "first same as last"),
//!   plus one for the starting-step estimate when neither an initial step nor a remembered step
//!   is available;
//! - locating an event costs no evaluations of the system, only of the event function.

mod dormand_prince;
mod rk4;
mod root;
#[cfg(test)]
mod tests;

pub use dormand_prince::{DormandPrince54, TrialStep};
pub use rk4::Rk4;
pub use root::EVENT_TIME_TOLERANCE_S;

use nalgebra::SVector;
use thiserror::Error;

/// A system of `N` first-order ODEs, `ẏ = f(t, y)`.
pub trait OdeSystem<const N: usize> {
    /// The derivative of `state` at `time_s` (s). Units are those of the state per second.
    fn derivative(&mut self, time_s: f64, state: &SVector<f64, N>) -> SVector<f64, N>;

    /// The same point in other coordinates, for a system whose coordinates have a singularity
    /// it must move away from (the flight model's hanging bodies), or `None` to keep them.
    /// [`integrate`] asks after every accepted step; the default keeps every state.
    fn rechart(&self, _state: &SVector<f64, N>) -> Option<SVector<f64, N>> {
        None
    }
}

impl<const N: usize, S: OdeSystem<N> + ?Sized> OdeSystem<N> for &mut S {
    fn derivative(&mut self, time_s: f64, state: &SVector<f64, N>) -> SVector<f64, N> {
        (**self).derivative(time_s, state)
    }

    fn rechart(&self, state: &SVector<f64, N>) -> Option<SVector<f64, N>> {
        (**self).rechart(state)
    }
}

/// A point of the solution together with the derivative there, which every step starts from
/// and both methods reuse rather than evaluate twice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point<const N: usize> {
    /// Time, s.
    pub time_s: f64,
    /// State, in the system's units.
    pub state: SVector<f64, N>,
    /// Derivative of the state at this time, state units per second.
    pub derivative: SVector<f64, N>,
}

/// A polynomial in time that follows the solution across one step, used to locate events and
/// to report states between step ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Interpolant<const N: usize> {
    /// Cubic Hermite polynomial through both ends' states and derivatives: error O(h⁴).
    Hermite {
        /// Start of the step.
        start: Point<N>,
        /// End of the step.
        end: Point<N>,
    },
    /// Dormand–Prince continuous extension of 4th order: error O(h⁵) within the step.
    DormandPrince {
        /// Start time of the step, s.
        start_time_s: f64,
        /// Length of the step, s.
        step_s: f64,
        /// Coefficients `r0 … r4` of `r0 + θ(r1 + (1−θ)(r2 + θ(r3 + (1−θ) r4)))`, with
        /// `θ = (t − start)/step`; state units.
        coefficients: [SVector<f64, N>; 5],
    },
}

impl<const N: usize> Interpolant<N> {
    /// The interpolated state at `time_s` (s). Meant for times inside the step; outside it
    /// the polynomial extrapolates.
    pub fn state_at(&self, time_s: f64) -> SVector<f64, N> {
        match self {
            Self::Hermite { start, end } => {
                let h = end.time_s - start.time_s;
                let s = (time_s - start.time_s) / h;
                let s2 = s * s;
                let s3 = s2 * s;
                let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
                let h10 = s3 - 2.0 * s2 + s;
                let h01 = -2.0 * s3 + 3.0 * s2;
                let h11 = s3 - s2;
                start.state * h00
                    + start.derivative * (h10 * h)
                    + end.state * h01
                    + end.derivative * (h11 * h)
            }
            Self::DormandPrince {
                start_time_s,
                step_s,
                coefficients: [r0, r1, r2, r3, r4],
            } => {
                let theta = (time_s - start_time_s) / step_s;
                let one_minus = 1.0 - theta;
                r0 + (r1 + (r2 + (r3 + r4 * one_minus) * theta) * one_minus) * theta
            }
        }
    }
}

/// One accepted step, as a [`Stepper`] hands it to the driver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AcceptedStep<const N: usize> {
    /// Where the step ended.
    pub end: Point<N>,
    /// The solution across the step.
    pub interpolant: Interpolant<N>,
    /// Attempts rejected by the error control before this one was accepted.
    pub rejected_attempts: usize,
}

/// A one-step method: the contract between the driver and [`Rk4`] or [`DormandPrince54`].
pub trait Stepper {
    /// Checks the method's settings, so a bad configuration fails before any step.
    fn check_settings(&self) -> Result<(), IntegrateError>;

    /// Takes one accepted step from `start` towards `end_time_s` (s), never beyond it; a step
    /// that reaches it must end exactly on it.
    fn step<const N: usize, S: OdeSystem<N>>(
        &mut self,
        system: &mut S,
        start: &Point<N>,
        end_time_s: f64,
    ) -> Result<AcceptedStep<N>, IntegrateError>;
}

/// An event function `g(t, state)`: integration stops where it goes from positive to zero or
/// negative, e.g. height above ground.
pub type EventFn<'a, const N: usize> = &'a mut dyn FnMut(f64, &SVector<f64, N>) -> f64;

/// An observer called with `(time_s, state)` at the start and after every accepted step.
pub type ObserverFn<'a, const N: usize> = &'a mut dyn FnMut(f64, &SVector<f64, N>);

/// Optional callbacks of one [`integrate`] call.
#[derive(Default)]
pub struct Hooks<'a, const N: usize> {
    /// Stops the integration at its first crossing from positive to non-positive. Only sign
    /// changes between step ends are seen: a function that dips below zero and comes back
    /// within one step goes unnoticed, so steps should be short compared with such dips.
    pub event: Option<EventFn<'a, N>>,
    /// Called at `t0` with the initial state, then once per accepted step with its end (or
    /// with the event's time and state for the step in which the event fired).
    pub observer: Option<ObserverFn<'a, N>>,
}

/// How an [`integrate`] call ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outcome<const N: usize> {
    /// Time reached, s: `t_end`, or the event's time if one fired.
    pub time_s: f64,
    /// State at `time_s`. For an event, taken from the step's interpolant at the located root.
    pub state: SVector<f64, N>,
    /// The event's time, s, if the event fired.
    pub event_time_s: Option<f64>,
    /// Steps accepted.
    pub accepted_steps: usize,
    /// Step attempts rejected by error control (always 0 for [`Rk4`]).
    pub rejected_steps: usize,
}

/// Why an integration failed. Times are s, steps are s.
#[derive(Clone, Copy, Debug, Error, PartialEq)]
pub enum IntegrateError {
    /// The span is not finite or runs backwards.
    #[error(
        "cannot integrate from {start_time_s} s to {end_time_s} s: times must be finite and the end not before the start"
    )]
    InvalidSpan {
        /// Requested start time, s.
        start_time_s: f64,
        /// Requested end time, s.
        end_time_s: f64,
    },
    /// A method setting breaks its rule.
    #[error("integrator setting `{setting}` = {value} is invalid: must be {rule}")]
    InvalidSetting {
        /// Name of the setting.
        setting: &'static str,
        /// The value given, in the setting's unit.
        value: f64,
        /// The rule it breaks.
        rule: &'static str,
    },
    /// The initial state, or the derivative there, has a non-finite component.
    #[error("non-finite initial state or derivative at {time_s} s (component {component})")]
    NonFiniteStart {
        /// Start time, s.
        time_s: f64,
        /// Index of the first offending component.
        component: usize,
    },
    /// A step produced a non-finite state, derivative or error estimate.
    #[error(
        "step of {step_s} s from {time_s} s produced a non-finite value (component {component})"
    )]
    NonFiniteStep {
        /// Time at the start of the step, s.
        time_s: f64,
        /// Size of the step attempted, s.
        step_s: f64,
        /// Index of the first offending component (the state size for an error estimate).
        component: usize,
    },
    /// A fixed step's 4th- and 3rd-order solutions differ by more than its method accepts
    /// ([`Rk4::with_max_error`]): the step did not follow the solution.
    #[error(
        "step of {step_s} s from {time_s} s did not follow the solution: its two orders differ by {error} in component {component}"
    )]
    InaccurateStep {
        /// Time at the start of the step, s.
        time_s: f64,
        /// Size of the step, s.
        step_s: f64,
        /// Index of the first component over the bound.
        component: usize,
        /// That component's difference, in its units.
        error: f64,
    },
    /// Adaptive error control needs a step smaller than the configured minimum.
    #[error("step size {step_s} s at {time_s} s is below the minimum {min_step_s} s")]
    StepSizeTooSmall {
        /// Time at the start of the step, s.
        time_s: f64,
        /// Step size the error control asked for, s.
        step_s: f64,
        /// Configured minimum step size, s.
        min_step_s: f64,
    },
    /// The step is too small to change the time at all in floating point.
    #[error("step of {step_s} s cannot advance the time {time_s} s in floating point")]
    StepTooSmallToAdvance {
        /// Time at the start of the step, s.
        time_s: f64,
        /// Step size, s.
        step_s: f64,
    },
    /// The event function returned a non-finite value.
    #[error("event function returned {value} at {time_s} s")]
    NonFiniteEvent {
        /// Time of the evaluation, s.
        time_s: f64,
        /// The value returned.
        value: f64,
    },
}

/// Index of the first non-finite component, if any.
pub(crate) fn first_non_finite<const N: usize>(vector: &SVector<f64, N>) -> Option<usize> {
    vector.iter().position(|x| !x.is_finite())
}

/// Advances `system` from `(start_time_s, initial_state)` to `end_time_s` (s) with `stepper`,
/// stopping early at the event in `hooks` if it fires.
///
/// A span of zero length returns the initial state without stepping; the observer still sees
/// the initial point. The event is armed only while its function is positive: starting at or
/// below zero, it fires at the first crossing after it has become positive.
pub fn integrate<const N: usize, M: Stepper, S: OdeSystem<N>>(
    stepper: &mut M,
    system: &mut S,
    start_time_s: f64,
    initial_state: &SVector<f64, N>,
    end_time_s: f64,
    mut hooks: Hooks<'_, N>,
) -> Result<Outcome<N>, IntegrateError> {
    if !(start_time_s.is_finite() && end_time_s.is_finite() && end_time_s >= start_time_s) {
        return Err(IntegrateError::InvalidSpan {
            start_time_s,
            end_time_s,
        });
    }
    stepper.check_settings()?;
    if let Some(component) = first_non_finite(initial_state) {
        return Err(IntegrateError::NonFiniteStart {
            time_s: start_time_s,
            component,
        });
    }
    let derivative = system.derivative(start_time_s, initial_state);
    if let Some(component) = first_non_finite(&derivative) {
        return Err(IntegrateError::NonFiniteStart {
            time_s: start_time_s,
            component,
        });
    }
    let mut point = Point {
        time_s: start_time_s,
        state: *initial_state,
        derivative,
    };
    if let Some(observe) = hooks.observer.as_mut() {
        observe(point.time_s, &point.state);
    }
    let mut event_value = match hooks.event.as_mut() {
        Some(event) => Some(checked_event(event, point.time_s, &point.state)?),
        None => None,
    };
    let mut outcome = Outcome {
        time_s: point.time_s,
        state: point.state,
        event_time_s: None,
        accepted_steps: 0,
        rejected_steps: 0,
    };

    while point.time_s < end_time_s {
        let step = stepper.step(system, &point, end_time_s)?;
        outcome.accepted_steps += 1;
        outcome.rejected_steps += step.rejected_attempts;

        if let (Some(event), Some(value_before)) = (hooks.event.as_mut(), event_value) {
            let value_after = checked_event(event, step.end.time_s, &step.end.state)?;
            if value_before > 0.0 && value_after <= 0.0 {
                let interpolant = &step.interpolant;
                let time_s = root::locate_crossing(
                    |t| checked_event(event, t, &interpolant.state_at(t)),
                    (point.time_s, value_before),
                    (step.end.time_s, value_after),
                )?;
                let state = interpolant.state_at(time_s);
                if let Some(observe) = hooks.observer.as_mut() {
                    observe(time_s, &state);
                }
                outcome.time_s = time_s;
                outcome.state = state;
                outcome.event_time_s = Some(time_s);
                return Ok(outcome);
            }
            event_value = Some(value_after);
        }

        point = step.end;
        if let Some(state) = system.rechart(&point.state) {
            // The next step starts from the new coordinates' own derivative.
            point.derivative = system.derivative(point.time_s, &state);
            point.state = state;
        }
        if let Some(observe) = hooks.observer.as_mut() {
            observe(point.time_s, &point.state);
        }
    }
    outcome.time_s = point.time_s;
    outcome.state = point.state;
    Ok(outcome)
}

fn checked_event<const N: usize>(
    event: &mut EventFn<'_, N>,
    time_s: f64,
    state: &SVector<f64, N>,
) -> Result<f64, IntegrateError> {
    let value = event(time_s, state);
    if value.is_finite() {
        Ok(value)
    } else {
        Err(IntegrateError::NonFiniteEvent { time_s, value })
    }
}
