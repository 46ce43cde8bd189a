//! Guidance, navigation and control of the STRAPLEX parafoil, the same code onboard the
//! (simulated) drone and in the ground station.
//!
//! - [`mission`] names the flight stages, the operator-selectable control modes and the phases
//!   of spiral-landing guidance: the vocabulary shared with the link and the dashboard;
//! - [`measurement`] is what the drone's sensors report, [`estimate`] what the estimator makes
//!   of it;
//! - [`estimator`] turns measurements (late, out of order, with gaps) into that estimate: the
//!   wind, airspeed, heading and position with their uncertainties, onboard and in the station
//!   alike.
pub mod estimate;
pub mod estimator;
pub mod measurement;
pub mod mission;
