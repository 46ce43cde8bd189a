//! stx-link: the MAVLink 2 link between the stx ground station and the (simulated) STRAPLEX
//! parafoil drone.
pub mod command;
pub mod endpoint;
pub mod frame;
pub mod manual;
pub mod param;
pub mod plan;
pub mod signing;
pub mod telemetry;
pub mod transport;
