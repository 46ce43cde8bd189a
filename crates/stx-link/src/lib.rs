//! stx-link: the MAVLink 2 link between the stx ground station and the (simulated) STRAPLEX
//! parafoil drone.
pub mod frame;
pub mod signing;
pub mod telemetry;
