//! The simulated drone on a real MAVLink link, paced in wall time (feature `runner`): the one
//! runner behind `stx drone`, `stx serve --sim`, the station's benchmark and the end-to-end
//! tests.
//!
//! A thin tokio adapter around the pure [`LinkedDrone`](crate::drone::link::LinkedDrone):
//! [`Flight::start`] builds the drone of [`FlyOptions::mission`], opens the transport, starts
//! signing (`stx_link::signing::persist::start_signing`, the high-water mark written before the
//! first frame) and hands the linked drone to `stx_link_tokio::drive`, which feeds it the
//! datagrams and timers on the wall monotonic clock — heartbeats, the station's liveness,
//! stick staleness and retries all run in real time whatever the simulation's speed.
//! [`Flight::run`] then sends the simulation's steps as the driver's actions, one control
//! period (0.25 s of mission time) each, paced by [`pacing::Pacer`]:
//!
//! - at [`Speed::Times`]`(N)` a step every `0.25/N` s of real time (a step late by more than a
//!   second is not made up for by running fast afterwards);
//! - at [`Speed::Max`] as fast as the driver takes them: the action channel holds
//!   [`STEPS_IN_FLIGHT`] steps, so steps queue behind the socket's traffic, never ahead of it,
//!   and the driver still serves incoming datagrams between two steps.
//!
//! Once landed the drone answers on the ground at real time, for [`FlyOptions::linger`] (or
//! until the shutdown future resolves); then the steps already handed to the link are flown,
//! their telemetry is sent, and [`Flight::run`] returns a [`FlightReport`] (what
//! `stx drone --summary-json` prints). The driver's events (texts, commands, parameters, link
//! state) are logged; each step's [`StepReport`] and each event also go to a
//! [`FlightObserver`] — a progress bar, [`ProgressLog`]'s log lines, a benchmark's clock.
//! [`FlightHandle::query`] reads the drone between two steps.
//!
//! With [`FlyOptions::anemometer_to`], the simulated world's ground anemometer by the target
//! measures the drone's true wind at each step's mission time and sends each report as an
//! NMEA MWV datagram to that address (`anemometer.rs`; counted in the report).
//!
//! Files: [`options`] (what to fly), [`pacing`] (when each step is due, sans-io), [`observe`]
//! (step reports, observers, the log), `anemometer.rs` (the ground anemometer's socket) and
//! `flight.rs` (the tokio adapter, its errors and its report).

mod anemometer;
mod flight;
pub mod observe;
pub mod options;
pub mod pacing;

pub use anemometer::AnemometerCounters;
pub use flight::{Flight, FlightHandle, FlightReport, FlyError, STEPS_IN_FLIGHT, fly};
pub use observe::{FlightObserver, ProgressLog, StepReport};
pub use options::{FlyOptions, Signing, Speed};
