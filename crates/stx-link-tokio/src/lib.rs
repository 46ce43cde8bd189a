//! stx-link-tokio: the only place the MAVLink link touches sockets, serial ports and clocks.
//!
//! `stx-link` is sans-io (bytes and `now` in, events and bytes out); this crate puts its
//! endpoints on the wire with tokio, in the way quinn puts quinn-proto on UDP:
//!
//! - [`transport`]: [`Transport`], an open `udpin:`/`udpout:`/`tcp:`/`tcpin:`/`serial:`
//!   address (`stx_link::address`), with every I/O error counted and reported rate-limited;
//!   a `udpin:` transport's peer moves only to the source of a datagram its endpoint
//!   accepted a frame in from the expected system (`udp_peer.rs`);
//! - [`mod@drive`]: [`drive()`] / [`drive_paths`] run any [`SansIo`](stx_link::sansio::SansIo)
//!   endpoint over one transport or several radios, persisting the signing timestamp before
//!   frames signed under it leave.
//!
//! The station daemon, the simulated drone's paced runner and the tests use it; nothing pure
//! (`stx-types`, `stx-gnc`, the station core, the drone's onboard logic) depends on it.

pub mod drive;
pub mod transport;
mod udp_peer;

pub use drive::{Action, DriveOptions, DriverEvent, connect_and_drive, drive, drive_paths};
pub use transport::{
    IO_ERROR_REPORT_INTERVAL, MAX_QUEUED_WITHOUT_PEER, REOPEN_DELAY, Transport, TransportError,
};
