//! The two ends of the link, each composing framing, signing and the micro-protocols behind
//! one sans-io surface: bytes and `now` in, events and bytes out.
//!
//! - [`GroundEndpoint`] (station): sends commands, parameter and plan requests and the
//!   joystick; receives telemetry; tracks whether the drone is connected.
//! - [`VehicleEndpoint`] (drone, simulated or not): sends telemetry and its status heartbeat;
//!   answers commands, parameters, plan transfers and requests for AUTOPILOT_VERSION; turns
//!   MANUAL_CONTROL into sticks that go stale.
//!
//! Both send a HEARTBEAT every [`LinkConfig::heartbeat_period`] and declare the peer connected
//! on its first heartbeat and lost after [`LinkConfig::link_timeout`] without one, with a
//! [`LinkEvent`] on each change. [`LinkStats`] (serde-serialisable, for the dashboard) counts
//! traffic, errors, signing refusals, per-sender packet loss from sequence-number gaps, the
//! message rate over a sliding window and the age of the last message of each kind.
//!
//! How loss is told from sequence numbers (gaps, late frames, a sender's restart) is
//! explained in `senders.rs`.
//!
//! Stream transports (TCP, serial) call [`handle_stream_end`](GroundEndpoint::handle_stream_end)
//! when a connection drops, so a frame cut off by it is counted as truncated rather than
//! waiting for bytes that will never come.
//!
//! The calling convention follows quinn-proto: after [`handle_bytes`](GroundEndpoint::handle_bytes)
//! or [`handle_timeout`](GroundEndpoint::handle_timeout), drain
//! [`poll_event`](GroundEndpoint::poll_event) and [`poll_transmit`](GroundEndpoint::poll_transmit),
//! then sleep until [`poll_timeout`](GroundEndpoint::poll_timeout). No sockets, clocks or
//! sleeps in here: `now` is a monotonic [`Duration`](std::time::Duration) from any fixed origin.
//!
//! # Files
//! - `core.rs`: [`LinkConfig`], [`LinkEvent`] and the link core both ends own (framing,
//!   signing, radios, heartbeat timer, liveness, statistics).
//! - `ground.rs`: [`GroundEndpoint`] with its [`GroundConfig`] and [`GroundEvent`].
//! - `vehicle.rs`: [`VehicleEndpoint`] with its [`VehicleConfig`] and [`VehicleEvent`];
//!   `identity.rs`: the AUTOPILOT_VERSION it answers with ([`Identity`], [`capabilities`]).
//! - `stats.rs`: [`LinkStats`]; `senders.rs`: [`SenderStats`] and the loss accounting that
//!   [`crate::paths`] applies per radio too.

mod core;
mod ground;
mod identity;
pub(crate) mod senders;
mod stats;
mod vehicle;

pub use self::core::{LinkConfig, LinkEvent};
pub use ground::{GroundConfig, GroundEndpoint, GroundEvent};
pub use identity::{AUTOPILOT_VERSION_ID, Identity, capabilities};
pub use senders::{MAX_LOSS_GAP, MAX_REORDER_DEPTH, SenderStats};
pub use stats::LinkStats;
pub use vehicle::{VehicleConfig, VehicleEndpoint, VehicleEvent};
