//! The vocabulary stx's crates share, at the bottom of the crate graph: the types that cross
//! crate boundaries and nothing that acts on them beyond pure helpers.
//!
//! Why a crate of its own: the MAVLink link (`stx-link`) names flight modes and plan points
//! but must not carry guidance with it, and the onboard guidance (`stx-gnc`) flies through the
//! standard atmosphere and commands the servos but must not carry the simulator's physics
//! (`stx-dynamics`). Both take these types from here instead, and `tests/run-all` checks that
//! the crate graph stays so (`tests/crate_graph.py`). Nothing here does I/O, draws randomness
//! or knows the time.
//!
//! How the modules fit:
//! - [`mission`] names the flight stages, the operator-selectable control modes and the
//!   phases of spiral-landing guidance, each with the code the link sends;
//! - [`geo`] is the mission's local NED frame and its link to latitude, longitude and
//!   altitude; [`plan`] (uploaded plan items) and [`keep_out`] (zones and their plane
//!   geometry) are placed in it;
//! - [`controls`] are the three servo commands guidance gives and the flight model flies;
//! - [`rotation`] holds the rotation matrices, Euler kinematics and angle wrapping in the
//!   seed's conventions;
//! - [`atmosphere`] is the air over altitude (US Standard Atmosphere 1976) and [`wind`] the
//!   air's velocity (the [`wind::WindField`] trait and the mean winds; the simulator's
//!   turbulence stays in `stx-dynamics`);
//! - [`mwv`] reads and writes NMEA 0183 `MWV`, the wind a ground anemometer reports;
//! - [`stack`] maps the bodies that carry an IMU of their own to their MAVLink components;
//! - [`table_text`] finds the data lines of a hand-edited table, with their line numbers;
//! - [`validate`] checks one setting against its rule, for every settings type of the
//!   workspace (the vehicle, the flight path, the estimator, the sensors, …).
//!
//! The crates that had these before re-export them under their old paths
//! (`stx_gnc::mission`, `stx_gnc::geo`, `stx_dynamics::atmosphere`, …), so code above them
//! did not change.

pub mod atmosphere;
pub mod controls;
pub mod geo;
pub mod keep_out;
pub mod mission;
pub mod mwv;
pub mod plan;
pub mod rotation;
pub mod stack;
pub mod table_text;
pub mod validate;
pub mod wind;
