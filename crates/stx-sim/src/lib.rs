//! The simulated STRAPLEX drone: the flight model of `stx-dynamics` flown through scenarios.
//!
//! - [`scenario`] reads scenario files (initial conditions, wind, integrator, commands);
//! - [`open_loop`] flies a scenario's servo schedule to the ground or its end;
//! - [`sensors`] turns the flown state into the drone's GPS, AHRS and pitot measurements, with
//!   their rates, latencies, noise, biases and dropouts, for the estimator;
//! - [`summary`] reduces a run to the figures it is judged by;
//! - [`drone`] is the simulated drone flying a whole mission (balloon, round chute, parafoil)
//!   with its onboard software, telemetry, commands and injected failures, for `stx drone`.
//!
//! Pure: no sockets, no clocks other than the wall time a run reports about itself.

pub mod closed_loop;
pub mod drone;
pub mod guided;
pub mod montecarlo;
pub mod open_loop;
pub mod scenario;
pub mod sensors;
pub mod summary;
