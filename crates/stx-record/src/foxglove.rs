//! Foxglove's well-known message types, in their JSON form, so a recording opens in Foxglove
//! with a map (positions), a log panel (events) and a 3-D view or plots (attitude).
//!
//! Foxglove picks its panels by schema name (`foxglove.LocationFix`, …) and reads the JSON
//! fields named in its published schema definitions
//! (<https://docs.foxglove.dev/docs/visualization/message-schemas/>). The Rust types and the
//! JSON Schemas below are ours, written from those definitions: the same field names, types
//! and enum values, with only the fields stx fills (optional ones such as a fix's colour are
//! left out, which the definitions allow).

use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use serde_json::{Value, json};

use crate::channel::{ChannelError, ChannelSpec};

/// Schema name of [`LocationFix`].
pub const LOCATION_FIX: &str = "foxglove.LocationFix";
/// Schema name of [`Log`].
pub const LOG: &str = "foxglove.Log";
/// Schema name of [`FrameTransform`].
pub const FRAME_TRANSFORM: &str = "foxglove.FrameTransform";

/// A time as Foxglove writes it: whole seconds and nanoseconds since the Unix epoch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Timestamp {
    /// Whole seconds, s.
    pub sec: u32,
    /// Nanoseconds past `sec`, 0..1e9.
    pub nsec: u32,
}

impl Timestamp {
    /// From nanoseconds since the Unix epoch (MCAP's log time); the seconds saturate in 2106.
    pub fn from_nanos(ns: u64) -> Self {
        Self {
            sec: u32::try_from(ns / 1_000_000_000).unwrap_or(u32::MAX),
            nsec: (ns % 1_000_000_000) as u32,
        }
    }

    /// Nanoseconds since the Unix epoch.
    pub fn as_nanos(self) -> u64 {
        u64::from(self.sec) * 1_000_000_000 + u64::from(self.nsec)
    }
}

/// How much of a [`LocationFix`]'s covariance is known.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum PositionCovarianceType {
    /// Nothing is known.
    Unknown = 0,
    /// Approximated (e.g. from a dilution of precision).
    Approximated = 1,
    /// The diagonal (per-axis variances) is known.
    DiagonalKnown = 2,
    /// The full matrix is known.
    Known = 3,
}

/// A position on the globe, shown on Foxglove's map.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LocationFix {
    /// When the position held.
    pub timestamp: Timestamp,
    /// Frame of the sensor the position is of (e.g. `vehicle`).
    pub frame_id: String,
    /// Latitude, degrees (WGS 84).
    pub latitude: f64,
    /// Longitude, degrees (WGS 84).
    pub longitude: f64,
    /// Altitude, m.
    pub altitude: f64,
    /// Covariance of the position, m², East-North-Up, row-major 3×3.
    pub position_covariance: [f64; 9],
    /// How much of `position_covariance` is known.
    pub position_covariance_type: PositionCovarianceType,
}

impl LocationFix {
    /// Whether this can be a vehicle's position: finite, within ±90° and ±180°, and not
    /// exactly 0°, 0°, where a GNSS receiver without a fix (or an autopilot before its
    /// estimator has an origin) puts its zeros. stx writes no such point since it checks the
    /// fix type (`stx_link::telemetry::has_position_fix`, the same coordinate rule; this
    /// crate stands below stx-link); readers drop them from older recordings and other tools'.
    pub fn is_position(&self) -> bool {
        self.latitude.abs() <= 90.0
            && self.longitude.abs() <= 180.0
            && self.altitude.is_finite()
            && !(self.latitude == 0.0 && self.longitude == 0.0)
    }
}

/// Severity of a [`Log`] message.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum LogLevel {
    /// Unknown.
    Unknown = 0,
    /// Debug.
    Debug = 1,
    /// Information.
    Info = 2,
    /// Warning.
    Warning = 3,
    /// Error.
    Error = 4,
    /// Fatal.
    Fatal = 5,
}

/// An event, shown in Foxglove's log panel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Log {
    /// When it happened.
    pub timestamp: Timestamp,
    /// Severity.
    pub level: LogLevel,
    /// What happened.
    pub message: String,
    /// Who or what said it (e.g. `station`, an operator's name).
    pub name: String,
    /// Source file, or empty.
    pub file: String,
    /// Line in `file`, or 0.
    pub line: u32,
}

/// A 3-vector.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Vector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

/// A rotation quaternion (scalar last, as Foxglove writes it).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w, the scalar part.
    pub w: f64,
}

/// Where a child frame is in its parent (stx: the vehicle's attitude and position in the
/// mission frame), shown in Foxglove's 3-D panel; its fields plot.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameTransform {
    /// When the transform held.
    pub timestamp: Timestamp,
    /// The parent frame (e.g. `mission`).
    pub parent_frame_id: String,
    /// The child frame (e.g. `vehicle`).
    pub child_frame_id: String,
    /// The child's origin in the parent frame, m.
    pub translation: Vector3,
    /// The child's orientation in the parent frame.
    pub rotation: Quaternion,
}

macro_rules! u8_enum_serde {
    ($ty:ident { $($variant:ident = $n:literal),* $(,)? }) => {
        impl Serialize for $ty {
            fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_u8(*self as u8)
            }
        }

        impl<'de> Deserialize<'de> for $ty {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                match u8::deserialize(d)? {
                    $($n => Ok(Self::$variant),)*
                    other => Err(D::Error::custom(format!(
                        concat!("{} is not a ", stringify!($ty)),
                        other
                    ))),
                }
            }
        }
    };
}

u8_enum_serde!(PositionCovarianceType {
    Unknown = 0,
    Approximated = 1,
    DiagonalKnown = 2,
    Known = 3,
});

u8_enum_serde!(LogLevel {
    Unknown = 0,
    Debug = 1,
    Info = 2,
    Warning = 3,
    Error = 4,
    Fatal = 5,
});

fn timestamp_schema(description: &str) -> Value {
    json!({
        "type": "object",
        "title": "time",
        "description": description,
        "properties": {
            "sec": {"type": "integer", "minimum": 0},
            "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999}
        },
        "required": ["sec", "nsec"]
    })
}

fn enum_schema(title: &str, description: &str, values: &[(&str, u8)]) -> Value {
    let one_of: Vec<Value> = values
        .iter()
        .map(|(name, n)| json!({"title": name, "const": n}))
        .collect();
    json!({"title": title, "description": description, "oneOf": one_of})
}

fn number(description: &str) -> Value {
    json!({"type": "number", "description": description})
}

fn string(description: &str) -> Value {
    json!({"type": "string", "description": description})
}

fn xyz_schema(title: &str, description: &str, fields: &[&str]) -> Value {
    let properties: serde_json::Map<String, Value> = fields
        .iter()
        .map(|f| ((*f).to_owned(), json!({"type": "number"})))
        .collect();
    json!({
        "type": "object",
        "title": title,
        "description": description,
        "properties": properties,
        "required": fields
    })
}

/// JSON Schema of [`LocationFix`].
pub fn location_fix_schema() -> Value {
    json!({
        "title": LOCATION_FIX,
        "description": "A position on the globe with its covariance",
        "type": "object",
        "properties": {
            "timestamp": timestamp_schema("When the position held"),
            "frame_id": string("Frame of the sensor the position is of"),
            "latitude": number("Latitude in degrees"),
            "longitude": number("Longitude in degrees"),
            "altitude": number("Altitude in metres"),
            "position_covariance": {
                "type": "array",
                "items": {"type": "number"},
                "minItems": 9,
                "maxItems": 9,
                "description": "Covariance of the position (m^2), East-North-Up, row-major"
            },
            "position_covariance_type": enum_schema(
                "foxglove.PositionCovarianceType",
                "How much of the covariance is known",
                &[("UNKNOWN", 0), ("APPROXIMATED", 1), ("DIAGONAL_KNOWN", 2), ("KNOWN", 3)],
            )
        },
        "required": ["timestamp", "frame_id", "latitude", "longitude", "altitude",
                     "position_covariance", "position_covariance_type"]
    })
}

/// JSON Schema of [`Log`].
pub fn log_schema() -> Value {
    json!({
        "title": LOG,
        "description": "An event",
        "type": "object",
        "properties": {
            "timestamp": timestamp_schema("When it happened"),
            "level": enum_schema(
                "foxglove.LogLevel",
                "Severity",
                &[("UNKNOWN", 0), ("DEBUG", 1), ("INFO", 2), ("WARNING", 3), ("ERROR", 4),
                  ("FATAL", 5)],
            ),
            "message": string("What happened"),
            "name": string("Who or what said it"),
            "file": string("Source file"),
            "line": {"type": "integer", "minimum": 0, "description": "Line in the file"}
        },
        "required": ["timestamp", "level", "message", "name", "file", "line"]
    })
}

/// JSON Schema of [`FrameTransform`].
pub fn frame_transform_schema() -> Value {
    json!({
        "title": FRAME_TRANSFORM,
        "description": "Where a child frame is in its parent frame",
        "type": "object",
        "properties": {
            "timestamp": timestamp_schema("When the transform held"),
            "parent_frame_id": string("The parent frame"),
            "child_frame_id": string("The child frame"),
            "translation": xyz_schema(
                "foxglove.Vector3", "The child's origin in the parent frame (m)", &["x", "y", "z"]),
            "rotation": xyz_schema(
                "foxglove.Quaternion",
                "The child's orientation in the parent frame",
                &["x", "y", "z", "w"]),
        },
        "required": ["timestamp", "parent_frame_id", "child_frame_id", "translation", "rotation"]
    })
}

/// A channel of [`LocationFix`] messages on `topic`.
pub fn location_fix_channel(topic: impl Into<String>) -> Result<ChannelSpec, ChannelError> {
    ChannelSpec::json(topic, LOCATION_FIX, &location_fix_schema())
}

/// A channel of [`Log`] messages on `topic`.
pub fn log_channel(topic: impl Into<String>) -> Result<ChannelSpec, ChannelError> {
    ChannelSpec::json(topic, LOG, &log_schema())
}

/// A channel of [`FrameTransform`] messages on `topic`.
pub fn frame_transform_channel(topic: impl Into<String>) -> Result<ChannelSpec, ChannelError> {
    ChannelSpec::json(topic, FRAME_TRANSFORM, &frame_transform_schema())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every required field of a schema is a field the Rust type writes, and nothing the type
    /// writes is missing from the schema: the two cannot drift apart.
    fn schema_matches(schema: &Value, message: &impl Serialize) {
        let message = serde_json::to_value(message).unwrap();
        let fields: Vec<&String> = message.as_object().unwrap().keys().collect();
        let properties = schema["properties"].as_object().unwrap();
        let required: Vec<&str> = schema["required"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap())
            .collect();
        for f in &fields {
            assert!(properties.contains_key(*f), "{f} not in the schema");
            assert!(required.contains(&f.as_str()), "{f} not required");
        }
        assert_eq!(fields.len(), required.len());
    }

    #[test]
    fn types_and_schemas_agree() {
        let t = Timestamp::from_nanos(1_767_225_600_123_456_789);
        assert_eq!((t.sec, t.nsec), (1_767_225_600, 123_456_789));
        assert_eq!(t.as_nanos(), 1_767_225_600_123_456_789);
        let fix = LocationFix {
            timestamp: t,
            frame_id: "vehicle".into(),
            latitude: 47.1,
            longitude: 8.2,
            altitude: 1200.0,
            position_covariance: [4.0, 0.0, 0.0, 0.0, 4.0, 0.0, 0.0, 0.0, 9.0],
            position_covariance_type: PositionCovarianceType::DiagonalKnown,
        };
        schema_matches(&location_fix_schema(), &fix);
        let log = Log {
            timestamp: t,
            level: LogLevel::Warning,
            message: "cutdown armed".into(),
            name: "alice".into(),
            file: String::new(),
            line: 0,
        };
        schema_matches(&log_schema(), &log);
        let tf = FrameTransform {
            timestamp: t,
            parent_frame_id: "mission".into(),
            child_frame_id: "vehicle".into(),
            translation: Vector3 {
                x: 1.0,
                y: 2.0,
                z: -3.0,
            },
            rotation: Quaternion {
                x: 0.0,
                y: 0.0,
                z: 0.0,
                w: 1.0,
            },
        };
        schema_matches(&frame_transform_schema(), &tf);
        let text = serde_json::to_string(&log).unwrap();
        assert!(text.contains(r#""level":3"#), "{text}");
        let back: Log = serde_json::from_str(&text).unwrap();
        assert_eq!(back, log);
        let fix_back: LocationFix =
            serde_json::from_str(&serde_json::to_string(&fix).unwrap()).unwrap();
        assert_eq!(fix_back, fix);
    }

    #[test]
    fn an_unknown_enum_value_is_an_error() {
        assert!(serde_json::from_str::<LogLevel>("9").is_err());
        assert_eq!(
            serde_json::from_str::<PositionCovarianceType>("1").unwrap(),
            PositionCovarianceType::Approximated
        );
    }
}
