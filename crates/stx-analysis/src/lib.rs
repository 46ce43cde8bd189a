//! Stability analysis and gain tuning of the STRAPLEX parafoil (seed chapter 6).
//!
//! How the parts fit:
//! - [`trim`] finds the steady glide of the nonlinear 31-state model (`stx-dynamics`) for
//!   held servo commands, pinning the states the dynamics do not depend on; [`performance`]
//!   trims a vehicle at each brake setting of the steady-glide table guidance plans with, so
//!   that guidance can plan with an identified vehicle's glide instead of the shipped stack's;
//! - [`linearize`] differentiates the model about it numerically ([`jacobian`]): `A`, `B` for
//!   the two inputs (differential main line, symmetric brake), `C`, `D` for the drone's
//!   measured outputs (seed eq. 6.4);
//! - [`lti`] gives eigenvalues, controllability and observability ranks (orthogonal staircase
//!   with an SVD tolerance) and exact discretisation;
//! - [`analysis`] assembles the report `stx analyze` prints, side by side with the seed's
//!   published values ([`seed`]);
//! - [`tune`] closes the loop with the onboard control laws of `stx-gnc` on the linear model,
//!   optimises the gains of one controller with [`nelder_mead`], and checks them with step
//!   responses of the nonlinear model flown by `stx-sim` (its parts: the controllers, the
//!   step metrics and cost, the experiments, the optimiser's driver);
//! - [`forced_response`] flies the nonlinear model and its linearisation side by side from the
//!   same perturbed trim, to show how far the linear model holds;
//! - [`svg`] draws plots; [`figures`] makes the eigenvalue map and the step responses of an
//!   analysis and of a tuning with it, and [`gains_file`] the gains file a tuning writes.
//!
//! - [`flight_log`] is a recorded flight (from a recording's telemetry or a CSV);
//!   [`compare`] flies the model through one and sets the two side by side (issue 16);
//!   [`identify`] fits the vehicle's coefficients to flights.
//!
//! Pure: no files, no clocks, no randomness. The `stx` binary reads and writes files.

pub mod analysis;
pub mod compare;
pub mod figures;
pub mod flight_log;
pub mod forced_response;
pub mod gains_file;
pub mod identify;
pub mod jacobian;
pub mod linearize;
pub mod lti;
pub mod nelder_mead;
pub mod performance;
pub mod seed;
pub mod svg;
pub mod trim;
pub mod tune;
