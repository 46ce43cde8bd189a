//! The surface between a sans-io endpoint and whatever moves its bytes: the [`SansIo`] trait
//! an I/O adapter drives (bytes and `now` in; frames, timers and events out), and the
//! [`IoEvent`]s and [`IoStats`] an adapter reports back. Nothing here does I/O: the tokio
//! adapter is the `stx-link-tokio` crate, and tests drive endpoints by hand.
//!
//! Datagram transports (UDP) feed each datagram whole with
//! [`SansIo::handle_datagram_on`], whose answer says whether it carried a frame accepted from
//! the expected peer system: a datagram's source address is anyone's to forge, and only the
//! endpoint can tell a frame from its peer, so a `udpin:` adapter moves its peer only on that
//! verdict.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;

use crate::endpoint::{GroundEndpoint, GroundEvent, VehicleEndpoint, VehicleEvent};

/// Something that happened on the socket; none of it is hidden from the application.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum IoEvent {
    /// Reads failed: the first failure, then at most one report per
    /// the adapter's report interval while they go on. `error` is the latest failure, `count`
    /// the total so far (`recv_errors`).
    RecvError { error: String, count: u64 },
    /// Writes failed, reported like [`IoEvent::RecvError`]; `count` is `send_errors`.
    SendError { error: String, count: u64 },
    /// UDP-in: a frame was queued because no peer has been heard yet.
    QueuedWithoutPeer { queued: usize },
    /// UDP-in: the queue was full and its oldest frame was dropped.
    DroppedWithoutPeer { dropped_total: u64 },
    /// UDP-in: replies now go to this address (the source of a datagram that carried a frame
    /// accepted from the expected peer system; see [`SansIo::handle_datagram_on`]).
    PeerChanged { peer: SocketAddr },
    /// TCP / serial: connected (peer address, or the port path).
    Connected { peer: String },
    /// TCP / serial: the connection ended.
    Disconnected { reason: String },
    /// Writing the signing timestamp file failed.
    PersistFailed { path: PathBuf, error: String },
}

/// I/O counters of one transport.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct IoStats {
    /// Bytes read.
    pub rx_bytes: u64,
    /// Bytes written.
    pub tx_bytes: u64,
    /// Failed reads.
    pub recv_errors: u64,
    /// Failed writes.
    pub send_errors: u64,
    /// Frames queued while no UDP-in peer was known.
    pub queued_without_peer: u64,
    /// Frames dropped from that queue when it overflowed.
    pub dropped_without_peer: u64,
    /// Connections (re)established.
    pub connects: u64,
    /// UDP: datagrams from an address other than the peer's that carried no frame accepted
    /// from the expected peer system (garbage, frames from other systems, unsigned or badly
    /// signed frames with signing on): their source was not taken as the peer.
    #[serde(default)]
    pub ignored_datagrams: u64,
}

/// The sans-io surface an I/O adapter needs; implemented by both endpoints.
pub trait SansIo: Send + 'static {
    /// The endpoint's event type.
    type Event: Send + 'static;
    /// Feeds bytes received on radio `path` (0 with one transport).
    fn handle_bytes_on(&mut self, path: usize, now: Duration, bytes: &[u8]);
    /// Feeds one whole datagram (UDP) received on radio `path`: frames never span datagrams.
    /// Returns whether it carried a frame accepted from the expected peer system (CRC checked
    /// and, with signing on, correctly signed): only such a datagram may move a UDP-in
    /// transport's peer to its source, so that garbage or frames from other systems cannot
    /// divert the uplink.
    fn handle_datagram_on(&mut self, path: usize, now: Duration, datagram: &[u8]) -> bool;
    /// Runs timers.
    fn handle_timeout(&mut self, now: Duration);
    /// Next timer.
    fn poll_timeout(&self) -> Option<Duration>;
    /// Next frame to send.
    fn poll_transmit(&mut self, now: Duration) -> Option<Vec<u8>>;
    /// Next event.
    fn poll_event(&mut self) -> Option<Self::Event>;
    /// The stream connection of radio `path` ended (TCP, serial): flush what can no longer
    /// complete.
    fn handle_stream_end_on(&mut self, path: usize, now: Duration);
    /// The radio that frames from [`poll_transmit`](Self::poll_transmit) go out on now.
    fn transmit_path(&self, now: Duration) -> usize;
    /// The signing timestamp high-water mark in force (`None`: signing off); an I/O adapter
    /// persists it whenever it moves, before sending frames signed under it.
    fn signing_timestamp_mark(&self) -> Option<u64>;
}

macro_rules! impl_sans_io {
    ($ty:ty, $ev:ty) => {
        impl SansIo for $ty {
            type Event = $ev;
            fn handle_bytes_on(&mut self, path: usize, now: Duration, bytes: &[u8]) {
                <$ty>::handle_bytes_on(self, path, now, bytes)
            }
            fn handle_datagram_on(&mut self, path: usize, now: Duration, datagram: &[u8]) -> bool {
                <$ty>::handle_datagram_on(self, path, now, datagram)
            }
            fn handle_timeout(&mut self, now: Duration) {
                <$ty>::handle_timeout(self, now)
            }
            fn poll_timeout(&self) -> Option<Duration> {
                <$ty>::poll_timeout(self)
            }
            fn poll_transmit(&mut self, now: Duration) -> Option<Vec<u8>> {
                <$ty>::poll_transmit(self, now)
            }
            fn poll_event(&mut self) -> Option<$ev> {
                <$ty>::poll_event(self)
            }
            fn handle_stream_end_on(&mut self, path: usize, now: Duration) {
                <$ty>::handle_stream_end_on(self, path, now)
            }
            fn transmit_path(&self, now: Duration) -> usize {
                <$ty>::transmit_path(self, now)
            }
            fn signing_timestamp_mark(&self) -> Option<u64> {
                <$ty>::signing_timestamp_mark(self)
            }
        }
    };
}

impl_sans_io!(GroundEndpoint, GroundEvent);
impl_sans_io!(VehicleEndpoint, VehicleEvent);
