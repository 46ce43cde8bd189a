//! stx-link: the MAVLink 2 link between the stx ground station and the (simulated) STRAPLEX
//! parafoil drone.
//!
//! It exists so that the station, the simulated drone and any other MAVLink tool
//! (QGroundControl, MAVProxy, pymavlink) speak the same common-dialect messages, and so that
//! everything above the link works with stx's own types in SI units rather than with MAVLink's
//! scaled integers. Both ends live here: the station uses the ground side, the simulator the
//! vehicle side.
//!
//! # How the parts fit
//! The protocol logic is sans-io, in the style of quinn-proto: bytes and a monotonic `now:
//! Duration` go in, events and bytes come out, nothing here owns a socket, a clock or a sleep.
//!
//! ```text
//!  stx-link-tokio (udpin/udpout/tcp/tcpin/serial)           ← thin adapter, the only I/O
//!        │ bytes       sansio::SansIo     ▲ bytes
//!        ▼                               │
//!  endpoint::{GroundEndpoint, VehicleEndpoint}               ← heartbeats, liveness, LinkStats
//!        │ frames                        ▲ messages
//!  frame (decoder / encoder) + signing                       ← framing, CRC, resync, signatures
//!        │ MavMessage                    ▲ MavMessage
//!  telemetry · command · param · plan · manual               ← stx types ↔ MAVLink, micro-protocols
//! ```
//!
//! - [`frame`]: the sans-io decoder (any chunk in, checked frames out, resync after garbage,
//!   everything counted) and the MAVLink 2 encoder with sequence numbers (`frame/`: `format`,
//!   `crc`, `decoder`, `encoder`).
//! - [`signing`]: MAVLink 2 signing: key that never prints, constant-time check, replay
//!   refusal, outgoing timestamps monotonic across restarts.
//! - [`telemetry`]: [`telemetry::Telemetry`] and its exact two-way mapping to MAVLink messages,
//!   one file per message family (status and health, navigation, actuators, text, guidance).
//! - [`command`]: operator commands, retried until acknowledged (ground) and de-duplicated and
//!   acknowledged (vehicle).
//! - [`param`]: the PARAM_* protocol, both sides.
//! - [`plan`]: upload / download of the landing target and localizer points (mission protocol).
//!
//!   Each of these three protocols is a directory of the same shape: `client.rs` is the
//!   ground side, `server.rs` (`table.rs` for parameters) the vehicle side, and a file for
//!   what both share (`encoding.rs`: the command and its encoding; `value.rs`: a parameter
//!   on the wire; `item.rs` and `mission.rs`: a plan item and the mission messages).
//! - [`manual`]: joystick streaming and stick staleness.
//! - [`endpoint`]: the two ends composing all of the above (`ground.rs`, `vehicle.rs`) over a
//!   shared link core (`core.rs`), with [`endpoint::LinkStats`] and the per-sender loss
//!   accounting (`senders.rs`).
//! - [`forward`]: read-only forwarding to watching ground stations: mavlink-router's
//!   per-direction filters, nothing from a watcher to the drone unless allowed.
//! - [`paths`]: one link over several radios: copies dropped, sends on the radio that works,
//!   each radio's loss counted with the endpoint's per-sender accounting.
//! - [`sansio`]: the [`sansio::SansIo`] trait both endpoints implement for an I/O adapter
//!   (including the verdict on each UDP datagram that decides whether its source may become
//!   the peer: only a frame accepted from the expected system vouches for it), and the
//!   [`sansio::IoEvent`]s and [`sansio::IoStats`] adapters report;
//!   [`address`]: the link address strings such as `udpin:0.0.0.0:14550`. The adapter itself
//!   (sockets, serial ports, the driver loop) is the `stx-link-tokio` crate: this one has no
//!   tokio, so the station core and the drone's onboard logic stay pure.
//! - [`signing::persist`]: the signing timestamp kept across restarts and the one signing
//!   start-up the station and the drone share.
//!
//! # Conventions
//! Units are in names (`lat_deg`, `alt_msl_m`, `airspeed_mps`); nothing panics on data from
//! the wire; every dropped frame, lost packet or I/O error is counted and surfaced, never
//! hidden; retries and timeouts take `now` from the caller so tests run on a fake clock.
//!
//! The mission vocabulary ([`stx_types::mission`]: flight mode, flight stage, guidance phase)
//! travels in HEARTBEAT's `custom_mode` as `mode | stage << 8 | phase << 16`.

pub mod address;
pub mod command;
pub mod endpoint;
pub mod fixtures;
pub mod forward;
pub mod frame;
pub mod manual;
pub mod param;
pub mod paths;
pub mod plan;
pub mod sansio;
pub mod signing;
pub mod telemetry;

pub use mavlink::dialects::common::MavMessage;
