//! Guidance, navigation and control of the STRAPLEX parafoil, the same code onboard the
//! (simulated) drone and in the ground station.
//!
//! - [`mission`] names the flight stages, the operator-selectable control modes and the phases
//!   of spiral-landing guidance: the vocabulary shared with the link and the dashboard.
pub mod mission;
