//! Flight model of the STRAPLEX descent: the seed thesis' 14-DOF, 31-state multibody model of
//! canopy, drone, capsule and transponder (seed chapter 4), with the environment it flies in.
//!
//! How the parts fit:
//! - [`vehicle`] loads and validates the vehicle's parameters (masses, geometry, aerodynamic
//!   coefficients, servos) from TOML;
//! - [`atmosphere`] gives air density, pressure, temperature and speed of sound (US Standard
//!   Atmosphere 1976) and [`wind`] the air's velocity over position and time, turbulence
//!   included;
//! - [`model`] evaluates the equations of motion `M [Ẋ; F_C] = N`: the state derivative and
//!   the four line tensions, for a state, the control inputs and the environment;
//! - [`integrate`] advances any [`integrate::OdeSystem`] in time (fixed-step RK4, adaptive
//!   Dormand–Prince 5(4)) and finds events such as ground contact between steps;
//! - [`state`] lays out the 31 states and the controls, [`rotation`] holds the frames' rotation
//!   matrices and Euler kinematics in the seed's conventions, and [`output`] turns a state into
//!   what a run reports (per-body positions, velocities, angles, tensions, air data, servos).
//!
//! The onboard guidance flies through the same air and commands the same servos without this
//! model, so the atmosphere, the rotations, the controls and the wind's trait and mean winds
//! live in `stx-types` at the bottom of the crate graph; they are re-exported here under their
//! old paths (`stx_dynamics::atmosphere`, `::rotation`, `::state::Controls`, `::wind`).
//!
//! Nothing here does I/O beyond parsing a string, knows about wall-clock time or draws
//! randomness it was not given a seed for: callers own time and files.

pub mod integrate;
pub mod model;
pub mod output;
pub mod state;
pub mod vehicle;
pub mod wind;

pub use stx_types::{atmosphere, invalid_into, rotation, validate};
