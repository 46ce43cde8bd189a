//! Guidance, navigation and control of the STRAPLEX parafoil, the same code onboard the
//! (simulated) drone and in the ground station.
//!
//! - [`mission`] names the flight stages, the operator-selectable control modes and the phases
//!   of spiral-landing guidance: the vocabulary shared with the link and the dashboard;
//! - [`measurement`] is what the drone's sensors report, [`estimate`] what the estimator makes
//!   of it.
pub mod estimate;
pub mod measurement;
pub mod mission;
