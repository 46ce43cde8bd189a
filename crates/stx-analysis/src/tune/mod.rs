//! Gain tuning (seed §6.3): each controller's gains optimised on the linearised closed loop
//! and checked on the nonlinear model.
//!
//! The closed loop is the onboard guidance itself ([`stx_gnc::guidance::Guidance`], the same
//! code the drone runs) fed with what the drone would measure, at its 4 Hz control rate:
//! - *linear*: the plant is `ẋ = A x + B u` about the trim, discretised exactly over the
//!   simulator's 0.05 s step with the command held over each 0.25 s period; the measurements
//!   are the linear outputs `C x + D u` (drone position, NED velocity, attitude) plus the
//!   canopy's heading and heading rate, turned into an estimate the way the simulator's
//!   perfect navigation does. The laws, their phases and their saturation are not linearised.
//! - *nonlinear*: `stx-sim`'s [`GuidedFlight`](stx_sim::closed_loop::GuidedFlight) flies the
//!   31-state model from the same trim with perfect navigation (what the control loop can do).
//! - *sensed, dispersed* (optional, the default of `stx tune`): the same steps flown on stacks
//!   drawn from a dispersion set, each with its own sensors, servo errors and trim, guidance
//!   fed by the sensor models and the estimator after 60 s of settling and learning on the
//!   reference ([`SensedSet`]). The last search is on this cost and adoption is judged on it:
//!   the drone flies through the estimator on a canopy that is not the model.
//!
//! Each controller has one step experiment: a 30° heading or course change, a 6 m cross-track
//! offset onto a localizer, or starting 5 m above a glide path (with brakes trimmed at the
//! gains' `brake_trim`). A step response is scored by rise time (10–90 %), overshoot, settling
//! time (5 % band) and actuator use (RMS command deviation as a share of its authority); the
//! cost adds them with weights that make 10 % overshoot cost as much as a rise time 10 % of
//! the run, and an unsettled or unstable response a lot more. Nelder–Mead searches the
//! logarithm of the gains (they stay positive and are searched in proportion). The seed
//! minimised the distance between closed-loop eigenvalue real parts and chosen ones; the
//! closed-loop eigenvalues are reported here for comparison, but a time-domain cost is what
//! the operators feel and it handles the laws' saturation and phases, which eigenvalues do not.
//!
//! The parts: [`Controller`] says what each controller tunes and how it is stepped
//! (`controller.rs`); [`metrics()`] and [`cost()`] judge a step response (`metrics.rs`); an
//! [`Experiment`] flies one controller's step on the linear and the nonlinear model
//! (`experiment.rs`), and on a drawn stack through the estimator for the [`SensedSet`]
//! (`sensed.rs`); [`tune()`] drives the optimiser and compares the candidates
//! (`optimiser.rs`). [`forced_responses`] (the open-loop comparison of the linear and
//! nonlinear models `stx analyze` draws) lives in [`crate::forced_response`] and is
//! re-exported here for its older path.

mod controller;
mod experiment;
mod metrics;
mod optimiser;
mod sensed;

pub use crate::forced_response::{ResponseSamples, forced_responses, perturbed};
pub use controller::Controller;
pub use experiment::{Experiment, TuneError};
pub use metrics::{SETTLING_BAND, StepMetrics, StepResponse, cost, metrics};
pub use optimiser::{
    Candidate, MAX_EVALUATIONS, MAX_SENSED_EVALUATIONS, Trial, TuneReport, round_significant, tune,
};
pub use sensed::{SETTLE_S, SensedCost, SensedSet, SensedSpec, SensedSummary};

/// The altitude tuning trims at unless told, m: where the Monte Carlo releases, high enough
/// for the 14-DOF steps to finish before the ground (at 100 m they do not).
pub const DEFAULT_ALTITUDE_M: f64 = 600.0;
