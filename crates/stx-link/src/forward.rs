//! Read-only forwarding of the drone's link to watching ground stations (QGroundControl,
//! MAVProxy): which frames a forward may pass, in each direction.
//!
//! The filters follow mavlink-router's per-endpoint rules (`AllowMsgIdOut`, `BlockSrcSysIn`,
//! …): a frame passes a direction if its message id, source system and source component are
//! each allowed (no allow list: all allowed) and none is blocked. The two directions differ in
//! their default, because a watcher must not fly the drone: towards the watcher (`out`)
//! everything passes unless filtered; towards the drone (`into_link`) nothing passes unless
//! an allow list names it.
//!
//! Sans-io like the rest of the crate: [`Forward`] takes the checked frames the link accepted
//! (their wire bytes, unchanged: a signed frame stays verifiable by the watcher) and the bytes
//! a watcher sent, and returns what goes where; the station's daemon owns the sockets.

use std::time::Duration;

use crate::frame::{DecoderPolicy, FrameDecoder, MAGIC_V1, MAGIC_V2};

/// One direction's rules. Empty allow lists mean "all" only where [`Direction`] says so.
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MessageFilter {
    /// Message ids that may pass (`None`: the direction's default).
    #[serde(default)]
    pub allow_msg_id: Option<Vec<u32>>,
    /// Message ids that never pass.
    #[serde(default)]
    pub block_msg_id: Vec<u32>,
    /// Source systems whose frames may pass (`None`: any).
    #[serde(default)]
    pub allow_src_sys: Option<Vec<u8>>,
    /// Source systems whose frames never pass.
    #[serde(default)]
    pub block_src_sys: Vec<u8>,
    /// Source components whose frames may pass (`None`: any).
    #[serde(default)]
    pub allow_src_comp: Option<Vec<u8>>,
    /// Source components whose frames never pass.
    #[serde(default)]
    pub block_src_comp: Vec<u8>,
}

/// Which way a frame goes through a forward.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// From the drone's link to the watcher: message ids pass unless filtered.
    Out,
    /// From the watcher to the drone: only the message ids of an allow list pass.
    IntoLink,
}

/// The ids a MAVLink frame's header carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameIds {
    /// Message id.
    pub message_id: u32,
    /// Sender system.
    pub system_id: u8,
    /// Sender component.
    pub component_id: u8,
}

impl FrameIds {
    /// Reads the ids of a whole frame's header (MAVLink 2 or 1); `None` if `frame` does not
    /// start with one.
    pub fn of(frame: &[u8]) -> Option<Self> {
        match frame {
            [MAGIC_V2, _, _, _, _, sys, comp, id0, id1, id2, ..] => Some(Self {
                message_id: u32::from_le_bytes([*id0, *id1, *id2, 0]),
                system_id: *sys,
                component_id: *comp,
            }),
            [MAGIC_V1, _, _, sys, comp, id, ..] => Some(Self {
                message_id: u32::from(*id),
                system_id: *sys,
                component_id: *comp,
            }),
            _ => None,
        }
    }
}

impl MessageFilter {
    /// Whether a frame with `ids` passes this filter going `direction`.
    pub fn passes(&self, direction: Direction, ids: FrameIds) -> bool {
        let msg_allowed = match (&self.allow_msg_id, direction) {
            (Some(allow), _) => allow.contains(&ids.message_id),
            (None, Direction::Out) => true,
            (None, Direction::IntoLink) => false,
        };
        let allowed = |list: &Option<Vec<u8>>, v: u8| list.as_ref().is_none_or(|l| l.contains(&v));
        msg_allowed
            && !self.block_msg_id.contains(&ids.message_id)
            && allowed(&self.allow_src_sys, ids.system_id)
            && !self.block_src_sys.contains(&ids.system_id)
            && allowed(&self.allow_src_comp, ids.component_id)
            && !self.block_src_comp.contains(&ids.component_id)
    }
}

/// What one forward passed and refused, per direction.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct ForwardCounts {
    /// Frames sent to the watcher.
    pub out_passed: u64,
    /// Frames the out filter kept from the watcher.
    pub out_filtered: u64,
    /// Frames of the watcher passed on to the drone.
    pub in_passed: u64,
    /// Frames of the watcher kept from the drone.
    pub in_refused: u64,
    /// Bytes from the watcher that were no frame (noise, bad CRC, unknown ids).
    pub in_bad_bytes: u64,
}

/// One forward's filters and the decoder of what its watcher sends.
#[derive(Debug)]
pub struct Forward {
    out: MessageFilter,
    into_link: MessageFilter,
    watcher: FrameDecoder,
    counts: ForwardCounts,
}

impl Forward {
    /// A forward with filter `out` towards the watcher and `into_link` towards the drone.
    pub fn new(out: MessageFilter, into_link: MessageFilter) -> Self {
        Self {
            out,
            into_link,
            watcher: FrameDecoder::new(DecoderPolicy { accept_v1: true }),
            counts: ForwardCounts::default(),
        }
    }

    /// Whether the frame the link accepted (`frame`, its wire bytes) goes to the watcher.
    pub fn to_watcher(&mut self, frame: &[u8]) -> bool {
        let pass = FrameIds::of(frame).is_some_and(|ids| self.out.passes(Direction::Out, ids));
        if pass {
            self.counts.out_passed += 1;
        } else {
            self.counts.out_filtered += 1;
        }
        pass
    }

    /// Takes `bytes` the watcher sent (one datagram or one read of a stream); returns the
    /// frames that may go on to the drone, each as the watcher sent it.
    pub fn from_watcher(&mut self, now: Duration, bytes: &[u8]) -> Vec<Vec<u8>> {
        let discarded_before = self.watcher.stats().bytes_discarded;
        self.watcher.push(bytes);
        let mut to_link = Vec::new();
        while let Some(r) = self.watcher.poll(now) {
            let Ok(frame) = r else { continue };
            let ids = FrameIds {
                message_id: frame.header.message_id,
                system_id: frame.header.system_id,
                component_id: frame.header.component_id,
            };
            if self.into_link.passes(Direction::IntoLink, ids) {
                self.counts.in_passed += 1;
                to_link.push(self.watcher.last_frame_bytes().to_vec());
            } else {
                self.counts.in_refused += 1;
            }
        }
        self.counts.in_bad_bytes += self.watcher.stats().bytes_discarded - discarded_before;
        to_link
    }

    /// Whether the watcher has sent any whole frame yet (a `udpin:` forward answers the
    /// address that did).
    pub fn watcher_heard(&self) -> bool {
        self.watcher.stats().frames_ok > 0
    }

    /// The counts so far.
    pub fn counts(&self) -> ForwardCounts {
        self.counts
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::FrameEncoder;
    use mavlink::dialects::common::{self as mc, MavMessage};

    /// A command (COMMAND_LONG, id 76): what a watcher must not send the drone.
    fn command() -> MavMessage {
        MavMessage::COMMAND_LONG(mc::COMMAND_LONG_DATA::default())
    }

    fn heartbeat() -> MavMessage {
        MavMessage::HEARTBEAT(mc::HEARTBEAT_DATA::default())
    }

    #[test]
    fn by_default_everything_goes_out_and_nothing_comes_in() {
        let mut drone = FrameEncoder::new(1, 1);
        let mut watcher = FrameEncoder::new(255, 190);
        let mut f = Forward::new(MessageFilter::default(), MessageFilter::default());
        assert!(f.to_watcher(&drone.encode(Duration::ZERO, &heartbeat())));
        let mut bytes = watcher.encode(Duration::ZERO, &command());
        bytes.extend(watcher.encode(Duration::ZERO, &heartbeat()));
        assert!(f.from_watcher(Duration::ZERO, &bytes).is_empty());
        assert!(f.watcher_heard());
        let c = f.counts();
        assert_eq!((c.out_passed, c.in_passed, c.in_refused), (1, 0, 2));
    }

    #[test]
    fn an_allow_list_lets_named_messages_in_unchanged_and_blocks_win() {
        let mut watcher = FrameEncoder::new(255, 190);
        let into_link = MessageFilter {
            allow_msg_id: Some(vec![0, 76]),
            block_src_comp: vec![191],
            ..Default::default()
        };
        let mut f = Forward::new(MessageFilter::default(), into_link);
        let set = watcher.encode(Duration::ZERO, &command());
        let mut bytes = b"\x01noise".to_vec();
        bytes.extend_from_slice(&set);
        assert_eq!(f.from_watcher(Duration::ZERO, &bytes), vec![set]);
        assert_eq!(f.counts().in_bad_bytes, 6);
        let mut other = FrameEncoder::new(255, 191);
        assert!(
            f.from_watcher(Duration::ZERO, &other.encode(Duration::ZERO, &heartbeat()))
                .is_empty()
        );
    }

    #[test]
    fn out_filters_by_message_and_source_as_mavlink_router_does() {
        let mut drone = FrameEncoder::new(1, 1);
        let mut camera = FrameEncoder::new(1, 100);
        let out = MessageFilter {
            block_msg_id: vec![76],
            allow_src_sys: Some(vec![1]),
            block_src_comp: vec![100],
            ..Default::default()
        };
        let mut f = Forward::new(out, MessageFilter::default());
        assert!(f.to_watcher(&drone.encode(Duration::ZERO, &heartbeat())));
        assert!(!f.to_watcher(&drone.encode(Duration::ZERO, &command())));
        assert!(!f.to_watcher(&camera.encode(Duration::ZERO, &heartbeat())));
        let mut stranger = FrameEncoder::new(9, 1);
        assert!(!f.to_watcher(&stranger.encode(Duration::ZERO, &heartbeat())));
        assert!(!f.to_watcher(b"not a frame"));
        assert_eq!(f.counts().out_filtered, 4);
    }

    #[test]
    fn frame_ids_read_v1_and_v2_headers_and_refuse_short_input() {
        let mut enc = FrameEncoder::new(42, 7);
        let v2 = enc.encode(Duration::ZERO, &command());
        assert_eq!(
            FrameIds::of(&v2),
            Some(FrameIds {
                message_id: 76,
                system_id: 42,
                component_id: 7
            })
        );
        assert_eq!(
            FrameIds::of(&[MAGIC_V1, 9, 0, 5, 6, 0, 0]),
            Some(FrameIds {
                message_id: 0,
                system_id: 5,
                component_id: 6
            })
        );
        assert_eq!(FrameIds::of(&[MAGIC_V2, 1, 0]), None);
        assert_eq!(FrameIds::of(&[]), None);
    }
}
