//! The simulated STRAPLEX drone: the flight model of `stx-dynamics` flown through scenarios.
//!
//! How the parts fit:
//! - [`scenario`] reads scenario files (initial conditions, wind, integrator, commands);
//! - [`open_loop`] flies a scenario's servo schedule to the ground or its end, and hands a
//!   scenario with guidance to [`guided`], which flies it in closed loop with
//!   [`closed_loop`]'s onboard software (sensors, estimator, guidance at 4 Hz); both give a
//!   [`run::Run`], and [`geometry`] says where the stack's lowest point and lines are;
//! - [`sensors`] turns the flown state into the drone's GPS, AHRS and pitot measurements, with
//!   their rates, latencies, noise, biases and dropouts, for the estimator;
//! - [`dispersions`] draws each flight's vehicle, sensor and servo errors and wind shape from a
//!   dispersion set, so that campaigns and the simulated drone fly a world guidance does not
//!   know exactly;
//! - [`anemometer`] is the ground anemometer by the target whose surface wind guidance may be
//!   given;
//! - [`summary`] reduces a run to the figures it is judged by;
//! - [`montecarlo`] flies many spiral landings from random releases and winds;
//! - [`speed`] measures the flight model's speed (`stx bench dynamics`);
//! - [`drone`] is the simulated drone flying a whole mission (balloon, round chute, parafoil)
//!   with its onboard software, telemetry, commands and injected failures, still sans-io
//!   behind its MAVLink endpoint ([`drone::link::LinkedDrone`]);
//! - `runner` (feature `runner`, the only part that needs tokio) flies that drone over a real
//!   link, paced in wall time: `stx drone`, `stx serve --sim`, the station's benchmark and the
//!   end-to-end tests all fly it.
//!
//! Pure without the `runner` feature: no sockets, no clocks other than the wall time a run
//! reports about itself.

pub mod anemometer;
pub mod closed_loop;
pub mod dispersions;
pub mod drone;
pub mod geometry;
pub mod guided;
pub mod montecarlo;
pub mod open_loop;
pub mod run;
#[cfg(feature = "runner")]
pub mod runner;
pub mod scenario;
pub mod sensors;
pub mod speed;
pub mod summary;
