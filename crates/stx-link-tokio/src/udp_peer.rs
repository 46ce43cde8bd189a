//! Which address a UDP transport sends to, and when that may change.
//!
//! `udpout:` sends to the address it was given, always. `udpin:` sends to the drone (or
//! ground station) it hears, and learns that address from the datagrams it receives — but a
//! datagram's source is only a *candidate*: anyone on the network can send one. The source
//! becomes the peer only when the endpoint found in that datagram a whole frame it accepts
//! from the system it talks to (CRC checked and, with signing on, correctly signed; see
//! `SansIo::handle_datagram_on`). Garbage, frames from other systems and refused frames
//! from another address leave the peer where it is, and are counted. A drone that reboots or
//! moves to a new port still moves the peer with its first valid frame.

use std::net::SocketAddr;

/// The peer of a UDP transport.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct UdpPeer {
    peer: Option<SocketAddr>,
    /// `udpout:`: the peer is the configured address and never moves.
    fixed: bool,
    /// Source of the datagram last received, until the endpoint's verdict on it.
    candidate: Option<SocketAddr>,
}

/// What the endpoint's verdict on a datagram did to the peer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Verdict {
    /// Nothing to decide: the datagram came from the peer, the peer is fixed, or no datagram
    /// awaited a verdict.
    Kept,
    /// The datagram's source is the peer from now on.
    Adopted(SocketAddr),
    /// The datagram came from another address and showed nothing that moves the peer there.
    Ignored(SocketAddr),
}

impl UdpPeer {
    /// `udpin:`: no peer until one is heard.
    pub(crate) fn learned() -> Self {
        Self {
            peer: None,
            fixed: false,
            candidate: None,
        }
    }

    /// `udpout:`: always `peer`.
    pub(crate) fn fixed(peer: SocketAddr) -> Self {
        Self {
            peer: Some(peer),
            fixed: true,
            candidate: None,
        }
    }

    /// Where frames go now (`None`: nobody heard yet).
    pub(crate) fn get(&self) -> Option<SocketAddr> {
        self.peer
    }

    /// A datagram arrived from `from`; it awaits [`verdict`](Self::verdict).
    pub(crate) fn received_from(&mut self, from: SocketAddr) {
        self.candidate = (!self.fixed).then_some(from);
    }

    /// The endpoint's verdict on the datagram last received: `from_expected` when it carried a
    /// frame accepted from the expected system.
    pub(crate) fn verdict(&mut self, from_expected: bool) -> Verdict {
        let Some(from) = self.candidate.take() else {
            return Verdict::Kept;
        };
        if self.peer == Some(from) {
            Verdict::Kept
        } else if from_expected {
            self.peer = Some(from);
            Verdict::Adopted(from)
        } else {
            Verdict::Ignored(from)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn addr(port: u16) -> SocketAddr {
        ([127, 0, 0, 1], port).into()
    }

    #[test]
    fn the_first_peer_is_the_first_sender_of_a_valid_frame_not_the_first_sender() {
        let mut p = UdpPeer::learned();
        p.received_from(addr(1));
        assert_eq!(p.verdict(false), Verdict::Ignored(addr(1)));
        assert_eq!(p.get(), None);
        p.received_from(addr(2));
        assert_eq!(p.verdict(true), Verdict::Adopted(addr(2)));
        assert_eq!(p.get(), Some(addr(2)));
    }

    #[test]
    fn only_a_valid_frame_from_a_new_address_moves_the_peer_and_each_move_is_reported_once() {
        let mut p = UdpPeer::learned();
        p.received_from(addr(1));
        assert_eq!(p.verdict(true), Verdict::Adopted(addr(1)));
        for _ in 0..3 {
            p.received_from(addr(9));
            assert_eq!(p.verdict(false), Verdict::Ignored(addr(9)));
            // The peer's own datagrams, valid or not, decide nothing.
            p.received_from(addr(1));
            assert_eq!(p.verdict(false), Verdict::Kept);
            p.received_from(addr(1));
            assert_eq!(p.verdict(true), Verdict::Kept);
        }
        assert_eq!(p.get(), Some(addr(1)));
        // The drone rebooted onto another port.
        p.received_from(addr(3));
        assert_eq!(p.verdict(true), Verdict::Adopted(addr(3)));
        p.received_from(addr(3));
        assert_eq!(p.verdict(true), Verdict::Kept);
        assert_eq!(p.get(), Some(addr(3)));
    }

    #[test]
    fn a_verdict_without_a_datagram_and_a_fixed_peer_change_nothing() {
        let mut p = UdpPeer::learned();
        assert_eq!(p.verdict(true), Verdict::Kept);
        assert_eq!(p.get(), None);
        let mut fixed = UdpPeer::fixed(addr(5));
        fixed.received_from(addr(6));
        assert_eq!(fixed.verdict(true), Verdict::Kept);
        assert_eq!(fixed.get(), Some(addr(5)));
    }
}
