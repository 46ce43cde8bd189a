//! The raw-bytes channel: every MAVLink frame the station received or sent, as it was on the
//! wire, with its direction and radio.
//!
//! Encoding (chosen to stay readable by any MCAP tool): JSON like every stx channel, schema
//! `stx.MavlinkFrame`, the frame's bytes in standard base64 (RFC 4648, padded) in `data` —
//! the way Foxglove's own JSON schemas carry bytes (`"contentEncoding": "base64"`). Base64
//! costs a third more than the bytes, and JSON's field names a little more; both compress
//! away in zstd chunks, and a reader needs no stx code (`base64.b64decode(msg["data"])` in
//! Python). The frame's time is the message's log time, repeated in `timestamp`.

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD as BASE64;
use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use serde_json::{Value, json};

use crate::channel::{ChannelError, ChannelSpec};
use crate::foxglove::Timestamp;

/// Schema name of [`MavlinkFrame`].
pub const MAVLINK_FRAME: &str = "stx.MavlinkFrame";

/// Which way a frame went.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Direction {
    /// Received from the vehicle.
    Rx,
    /// Sent to the vehicle.
    Tx,
}

/// One MAVLink frame as recorded.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MavlinkFrame {
    /// When it was received or sent.
    pub timestamp: Timestamp,
    /// Received or sent.
    pub direction: Direction,
    /// Index of the radio (0: the primary, then the link's further radios in order).
    pub radio: u16,
    /// The frame's bytes, magic byte to CRC (and signature), base64 in the JSON.
    #[serde(serialize_with = "to_base64", deserialize_with = "from_base64")]
    pub data: Vec<u8>,
}

/// The same as [`MavlinkFrame`], borrowing the bytes, so recording a frame copies it once.
#[derive(Serialize)]
struct FrameRef<'a> {
    timestamp: Timestamp,
    direction: Direction,
    radio: u16,
    #[serde(serialize_with = "to_base64")]
    data: &'a [u8],
}

impl MavlinkFrame {
    /// The JSON message for `bytes` going `direction` on `radio` at `log_time_ns`
    /// (nanoseconds since the Unix epoch).
    pub fn encode(direction: Direction, radio: u16, log_time_ns: u64, bytes: &[u8]) -> Vec<u8> {
        let frame = FrameRef {
            timestamp: Timestamp::from_nanos(log_time_ns),
            direction,
            radio,
            data: bytes,
        };
        // Serialising plain numbers, enums and a string into a Vec cannot fail.
        serde_json::to_vec(&frame).unwrap_or_default()
    }
}

fn to_base64<S: Serializer>(bytes: &[u8], s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(&BASE64.encode(bytes))
}

fn from_base64<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<u8>, D::Error> {
    let text = String::deserialize(d)?;
    BASE64.decode(text.as_bytes()).map_err(D::Error::custom)
}

/// JSON Schema of [`MavlinkFrame`].
pub fn mavlink_frame_schema() -> Value {
    json!({
        "title": MAVLINK_FRAME,
        "description": "A MAVLink frame as it was on the wire",
        "type": "object",
        "properties": {
            "timestamp": {
                "type": "object",
                "title": "time",
                "properties": {
                    "sec": {"type": "integer", "minimum": 0},
                    "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999}
                },
                "required": ["sec", "nsec"]
            },
            "direction": {"type": "string", "enum": ["rx", "tx"],
                          "description": "rx: received from the vehicle; tx: sent to it"},
            "radio": {"type": "integer", "minimum": 0,
                      "description": "Radio index, 0 for the primary"},
            "data": {"type": "string", "contentEncoding": "base64",
                     "description": "The frame's bytes, magic byte to CRC and signature"}
        },
        "required": ["timestamp", "direction", "radio", "data"]
    })
}

/// A channel of [`MavlinkFrame`] messages on `topic`.
pub fn mavlink_frame_channel(topic: impl Into<String>) -> Result<ChannelSpec, ChannelError> {
    ChannelSpec::json(topic, MAVLINK_FRAME, &mavlink_frame_schema())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_round_trips_through_its_json() {
        let bytes = [0xfd, 9, 0, 0, 7, 1, 1, 0, 0, 0, 1, 2, 3, 0xff];
        let json = MavlinkFrame::encode(Direction::Tx, 1, 2_000_000_001, &bytes);
        let text = std::str::from_utf8(&json).unwrap();
        assert!(text.contains(r#""direction":"tx""#), "{text}");
        assert!(text.contains(r#""data":"/QkAAAcBAQAAAAECA/8=""#), "{text}");
        let back: MavlinkFrame = serde_json::from_slice(&json).unwrap();
        assert_eq!(back.data, bytes);
        assert_eq!(back.radio, 1);
        assert_eq!(back.timestamp.as_nanos(), 2_000_000_001);
    }

    #[test]
    fn bad_base64_is_an_error() {
        let text = r#"{"timestamp":{"sec":0,"nsec":0},"direction":"rx","radio":0,"data":"@@"}"#;
        assert!(serde_json::from_str::<MavlinkFrame>(text).is_err());
    }
}
