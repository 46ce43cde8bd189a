//! Dispersions: how the world a flight meets differs from the one guidance assumes.
//!
//! A [`Dispersions`] set (a TOML file; `config/dispersions/nominal.toml` and `realistic.toml`
//! are shipped) gives the spread of each uncertain quantity: aerodynamic coefficients, masses
//! and inertias, rigging, lines, servo errors, sensor errors and the wind's shape.
//! [`DispersedFlight::draw`] draws one flight's vehicle, sensor settings and servo errors from
//! a seed, and [`WindShape::draw`] its wind's shape; the Monte Carlo and the simulated drone
//! both draw from here, so a campaign and a rehearsal fly the same world. Guidance and the
//! estimator never see a draw: they keep the nominal vehicle and learn in flight.

mod config;
mod draw;

pub use config::{
    AeroDispersions, Dispersions, DispersionsError, MassDispersions, NOMINAL_TOML, REALISTIC_TOML,
    RiggingDispersions, SensorDispersions, ServoDispersions, WindDispersions,
};
pub use draw::{DispersedFlight, DrawSummary, ServoErrors, WindShape, rotate_rigging};
