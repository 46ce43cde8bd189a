//! What a recording's channels are: a topic, the JSON Schema its messages follow, and the
//! handle the writer gives it.
//!
//! Every channel stx records is JSON described by a JSON Schema (MCAP's `json` message
//! encoding with a `jsonschema` schema), so any MCAP tool can decode it without our code, and
//! Foxglove recognises its well-known schemas by name ([`crate::foxglove`]).

use serde_json::Value;
use thiserror::Error;

/// MCAP schema encoding of every stx channel.
pub const SCHEMA_ENCODING: &str = "jsonschema";

/// MCAP message encoding of every stx channel.
pub const MESSAGE_ENCODING: &str = "json";

/// A channel's handle in the [`RecorderCore`](crate::RecorderCore) that registered it (and so
/// in the file adapter that runs that core). Stays valid across file rotations.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ChannelId(pub(crate) u16);

/// Why a channel was refused.
#[derive(Debug, Error, PartialEq)]
pub enum ChannelError {
    /// The topic is empty.
    #[error("a channel needs a topic")]
    EmptyTopic,
    /// The schema name is empty (Foxglove and other tools pick decoders by it).
    #[error("channel `{topic}` needs a schema name")]
    EmptySchemaName {
        /// The channel's topic.
        topic: String,
    },
    /// The JSON Schema is not a JSON object.
    #[error("channel `{topic}`: its JSON Schema must be a JSON object")]
    SchemaNotObject {
        /// The channel's topic.
        topic: String,
    },
    /// Another channel of this recorder has the same topic.
    #[error("channel `{topic}` is registered twice")]
    DuplicateTopic {
        /// The topic.
        topic: String,
    },
    /// More channels than MCAP can number.
    #[error("more than {max} channels")]
    TooMany {
        /// The limit.
        max: usize,
    },
}

/// A channel to register: topic, schema name and JSON Schema. Checked when built, so a
/// recorder never meets a malformed one.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelSpec {
    topic: String,
    schema_name: String,
    schema_text: String,
}

impl ChannelSpec {
    /// A JSON channel on `topic` whose messages follow `schema` (a JSON Schema object), known
    /// to readers as `schema_name` (e.g. `foxglove.LocationFix`, `stx.Estimate`).
    pub fn json(
        topic: impl Into<String>,
        schema_name: impl Into<String>,
        schema: &Value,
    ) -> Result<Self, ChannelError> {
        let topic = topic.into();
        let schema_name = schema_name.into();
        if topic.is_empty() {
            return Err(ChannelError::EmptyTopic);
        }
        if schema_name.is_empty() {
            return Err(ChannelError::EmptySchemaName { topic });
        }
        if !schema.is_object() {
            return Err(ChannelError::SchemaNotObject { topic });
        }
        Ok(Self {
            topic,
            schema_name,
            schema_text: schema.to_string(),
        })
    }

    /// The topic (e.g. `/vehicle/position`).
    pub fn topic(&self) -> &str {
        &self.topic
    }

    /// The schema's name.
    pub fn schema_name(&self) -> &str {
        &self.schema_name
    }

    /// The JSON Schema, as written into the recording.
    pub fn schema_text(&self) -> &str {
        &self.schema_text
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn malformed_channels_are_refused_with_their_topic() {
        let schema = json!({"type": "object"});
        assert_eq!(
            ChannelSpec::json("", "x", &schema),
            Err(ChannelError::EmptyTopic)
        );
        assert_eq!(
            ChannelSpec::json("/a", "", &schema),
            Err(ChannelError::EmptySchemaName { topic: "/a".into() })
        );
        assert_eq!(
            ChannelSpec::json("/a", "x", &json!([1, 2])),
            Err(ChannelError::SchemaNotObject { topic: "/a".into() })
        );
        let ok = ChannelSpec::json("/a", "x", &schema).unwrap();
        assert_eq!(ok.schema_text(), r#"{"type":"object"}"#);
    }
}
