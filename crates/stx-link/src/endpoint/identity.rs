//! What the drone says it is when a ground station asks: AUTOPILOT_VERSION, sent after a
//! COMMAND_ACK in answer to `MAV_CMD_REQUEST_MESSAGE` (param1 = 148) or the older
//! `MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES` (param1 = 1). QGroundControl and MAVProxy ask when
//! they connect; from the answer they learn that the link is MAVLink 2 and how parameters are
//! encoded, so that they read the drone as a generic MAVLink vehicle.
//!
//! The answer is the link's, not the application's: the capabilities are what this crate
//! implements ([`capabilities`]), so the vehicle endpoint answers before the command server
//! hands anything to the application. A repeated request is answered again rather than
//! recognised as a retry: the answer is the same every time, and a ground station that lost
//! the first one needs it.

use std::collections::VecDeque;

use mavlink::dialects::common as mc;
use mavlink::dialects::common::{MavCmd, MavMessage, MavProtocolCapability, MavResult};

/// AUTOPILOT_VERSION's message id.
pub const AUTOPILOT_VERSION_ID: u32 = 148;

/// How the drone names itself in AUTOPILOT_VERSION.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Identity {
    /// Software version: major, minor, patch and MAVLink's `FIRMWARE_VERSION_TYPE` (0 a
    /// development build … 255 an official release).
    pub version: [u8; 4],
    /// Board vendor id, 0 if none.
    pub vendor_id: u16,
    /// Product id, 0 if none.
    pub product_id: u16,
    /// This drone's unique id, 0 if it has none.
    pub uid: u64,
}

impl Default for Identity {
    /// This crate's version as a development build, with no vendor, product or id.
    fn default() -> Self {
        let part = |s: &str| s.parse::<u8>().unwrap_or(0);
        Self {
            version: [
                part(env!("CARGO_PKG_VERSION_MAJOR")),
                part(env!("CARGO_PKG_VERSION_MINOR")),
                part(env!("CARGO_PKG_VERSION_PATCH")),
                0,
            ],
            vendor_id: 0,
            product_id: 0,
            uid: 0,
        }
    }
}

/// What this link implements, as AUTOPILOT_VERSION's bitmap says it.
///
/// Parameters of whole numbers travel as INT32 cast into PARAM_VALUE's float field (see
/// `crate::param`), which is `PARAM_ENCODE_C_CAST`; plans and keep-out fences travel as
/// MISSION_ITEM_INT (`MISSION_INT`, `MISSION_FENCE`); commands come as COMMAND_LONG or
/// COMMAND_INT; the cutdown is `MAV_CMD_DO_FLIGHTTERMINATION`.
pub fn capabilities() -> MavProtocolCapability {
    MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_MAVLINK2
        | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_C_CAST
        | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_COMMAND_INT
        | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_MISSION_INT
        | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_MISSION_FENCE
        | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_FLIGHT_TERMINATION
}

/// Answers requests for AUTOPILOT_VERSION addressed to one system and component.
#[derive(Debug)]
pub(super) struct IdentityServer {
    system_id: u8,
    component_id: u8,
    identity: Identity,
    transmit: VecDeque<MavMessage>,
}

impl IdentityServer {
    pub(super) fn new(system_id: u8, component_id: u8, identity: Identity) -> Self {
        Self {
            system_id,
            component_id,
            identity,
            transmit: VecDeque::new(),
        }
    }

    /// Feeds a received message from `from` (system, component). Returns whether it was a
    /// request for AUTOPILOT_VERSION addressed to us (then answered).
    pub(super) fn handle_message(&mut self, from: (u8, u8), msg: &MavMessage) -> bool {
        let (target_system, target_component, command, param1) = match msg {
            MavMessage::COMMAND_LONG(c) => {
                (c.target_system, c.target_component, c.command, c.param1)
            }
            MavMessage::COMMAND_INT(c) => {
                (c.target_system, c.target_component, c.command, c.param1)
            }
            _ => return false,
        };
        let for_us = (target_system == 0 || target_system == self.system_id)
            && (target_component == 0 || target_component == self.component_id);
        // Superseded by REQUEST_MESSAGE since 2019, but MAVProxy 1.8 still asks this way.
        #[allow(deprecated)]
        let asks = match command {
            MavCmd::MAV_CMD_REQUEST_MESSAGE => param1 == AUTOPILOT_VERSION_ID as f32,
            MavCmd::MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES => param1 == 1.0,
            _ => false,
        };
        if !(for_us && asks) {
            return false;
        }
        self.transmit
            .push_back(MavMessage::COMMAND_ACK(mc::COMMAND_ACK_DATA {
                command,
                result: MavResult::MAV_RESULT_ACCEPTED,
                progress: 0,
                result_param2: 0,
                target_system: from.0,
                target_component: from.1,
            }));
        self.transmit
            .push_back(MavMessage::AUTOPILOT_VERSION(self.message()));
        true
    }

    fn message(&self) -> mc::AUTOPILOT_VERSION_DATA {
        mc::AUTOPILOT_VERSION_DATA {
            capabilities: capabilities(),
            flight_sw_version: u32::from_be_bytes(self.identity.version),
            vendor_id: self.identity.vendor_id,
            product_id: self.identity.product_id,
            uid: self.identity.uid,
            ..Default::default()
        }
    }

    /// Next message to send.
    pub(super) fn poll_transmit(&mut self) -> Option<MavMessage> {
        self.transmit.pop_front()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn command(command: MavCmd, param1: f32, target: (u8, u8)) -> MavMessage {
        MavMessage::COMMAND_LONG(mc::COMMAND_LONG_DATA {
            command,
            param1,
            target_system: target.0,
            target_component: target.1,
            ..Default::default()
        })
    }

    fn answers(s: &mut IdentityServer) -> Vec<MavMessage> {
        std::iter::from_fn(|| s.poll_transmit()).collect()
    }

    #[test]
    #[allow(deprecated)] // the old request is still answered (see `handle_message`)
    fn both_requests_are_acknowledged_then_answered_with_the_version_and_capabilities() {
        let identity = Identity {
            version: [1, 2, 3, 255],
            vendor_id: 7,
            product_id: 9,
            uid: 42,
        };
        let mut s = IdentityServer::new(1, 1, identity);
        for (cmd, p1) in [
            (MavCmd::MAV_CMD_REQUEST_MESSAGE, 148.0),
            (MavCmd::MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 1.0),
        ] {
            assert!(s.handle_message((255, 190), &command(cmd, p1, (1, 0))));
            let out = answers(&mut s);
            let [
                MavMessage::COMMAND_ACK(ack),
                MavMessage::AUTOPILOT_VERSION(v),
            ] = &out[..]
            else {
                panic!("expected an ACK then AUTOPILOT_VERSION, got {out:?}");
            };
            assert_eq!(ack.command, cmd);
            assert_eq!(ack.result, MavResult::MAV_RESULT_ACCEPTED);
            assert_eq!((ack.target_system, ack.target_component), (255, 190));
            // MAVLink's layout: major, minor, patch, type from the most significant byte.
            assert_eq!(v.flight_sw_version, 0x0102_03ff);
            assert_eq!((v.vendor_id, v.product_id, v.uid), (7, 9, 42));
            assert!(v.capabilities.contains(
                MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_C_CAST
                    | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_MAVLINK2
            ));
            assert!(
                !v.capabilities
                    .contains(MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE)
            );
        }
    }

    #[test]
    #[allow(deprecated)]
    fn other_requests_and_other_systems_are_left_to_the_command_server() {
        let mut s = IdentityServer::new(1, 1, Identity::default());
        for msg in [
            command(MavCmd::MAV_CMD_REQUEST_MESSAGE, 242.0, (1, 1)),
            command(MavCmd::MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 0.0, (1, 1)),
            command(MavCmd::MAV_CMD_REQUEST_MESSAGE, 148.0, (2, 1)),
            command(MavCmd::MAV_CMD_REQUEST_MESSAGE, 148.0, (1, 5)),
        ] {
            assert!(!s.handle_message((255, 190), &msg), "{msg:?}");
        }
        assert!(answers(&mut s).is_empty());
    }

    #[test]
    fn the_default_version_is_this_crates_as_a_development_build() {
        let v = Identity::default().version;
        assert_eq!(
            format!("{}.{}.{}", v[0], v[1], v[2]),
            env!("CARGO_PKG_VERSION")
        );
        assert_eq!(v[3], 0);
    }
}
