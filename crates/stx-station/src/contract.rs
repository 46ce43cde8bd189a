//! The API's contract: one JSON Schema (draft 7) of every message, both ways, derived from the
//! Rust types the daemon serialises ([`crate::messages`], [`crate::replies`]) and parses
//! ([`crate::requests`]). It is committed as `web/src/generated/api.schema.json` (written by
//! `cargo run -p stx-station --example api_schema`; a test fails while the file is stale), the
//! dashboard's TypeScript types are generated from it, and the browser test validates every
//! message the daemon sends against it. `API.md` explains it for people.
//!
//! What the station sends is described as it serialises it (every field present, `null` when
//! empty, nothing else); what it reads, as it parses it (optional fields may be left out,
//! unknown fields are refused).

use schemars::generate::{Contract, SchemaSettings};
use schemars::transform::RecursiveTransform;
use schemars::{JsonSchema, Schema, SchemaGenerator};
use serde_json::{Map, Value, json};
use thiserror::Error;

use crate::core::CutdownArm;
use crate::forecast_upload::{ForecastUploadReport, WindowBody};
use crate::keep_out::{KeepOutBody, KeepOutMsg};
use crate::lab::LabJobBody;
use crate::lab::bodies::{
    LabGainsBody, LabGainsListBody, LabRehearsalBody, LabSavedBody, LabStartedBody, LabVehicleBody,
};
use crate::lab::jobs::LabStatusBody;
use crate::lab::vehicle_fields::VehicleFieldsBody;
use crate::launch_window::WindowReport;
use crate::messages::{
    AscentWindMsg, CommandResultMsg, ErrorBody, EventMsg, ParamsMsg, ReadinessView, ReplayView,
    Session, StateMsg, TickBody,
};
use crate::preflight::{PreflightBody, PreflightDefaults, PreflightReport};
use crate::replies::{
    ClientsBody, CommandAccepted, EventsBody, HelloMsg, HistoryMsg, LaggedMsg, PongMsg,
    RecordingsBody, ReplayOpened, TrackBody,
};
use crate::requests::{
    ClientMessage, ConfirmBody, CourseBody, HeadingBody, LocalizerBody, ModeBody, ParamBody,
    PlanBody, ReplayBody, TargetBody,
};
use crate::tawhiri::{TawhiriAnswer, TawhiriErrorAnswer};

/// Where the schema is committed, from the workspace root.
pub const SCHEMA_PATH: &str = "web/src/generated/api.schema.json";

// Only its schema is used: the daemon serialises each message on its own.
/// Every message the station sends on the WebSocket, told apart by `type`.
#[derive(JsonSchema)]
#[schemars(untagged)]
pub enum ServerMessage {
    /// First on connecting.
    Hello(HelloMsg),
    /// At 4 Hz.
    State(Box<StateMsg>),
    /// As they happen.
    Event(EventMsg),
    /// Each step of a command.
    CommandResult(CommandResultMsg),
    /// When the parameter table changes.
    Params(ParamsMsg),
    /// When the ascent's measured wind bands change.
    AscentWind(AscentWindMsg),
    /// Once, after connecting.
    History(HistoryMsg),
    /// When the page fell behind.
    Lagged(LaggedMsg),
    /// The answer to `ping`.
    Pong(PongMsg),
    /// When the keep-out zones change.
    KeepOut(KeepOutMsg),
}

// Only its schema is used, as for the station's.
/// Every message a relay (`stx relay`) sends its viewers on its WebSocket, told apart by `type`.
#[derive(JsonSchema)]
#[schemars(untagged)]
pub enum RelayMessage {
    /// First on connecting.
    History(crate::relay::public::PublicHistoryMsg),
    /// Each new state.
    State(crate::relay::public::PublicStateMsg),
}

/// Why the contract could not be assembled (a bug in the types, caught by the tests).
#[derive(Debug, Error)]
pub enum ContractError {
    /// A type described differently as sent and as read.
    #[error("`{0}` is both sent and read, and the two descriptions differ")]
    Conflict(String),
}

/// Every object the station sends lists all its fields: nothing else may appear.
fn closed_objects(schema: &mut Schema) {
    if schema.get("properties").is_some() && schema.get("additionalProperties").is_none() {
        schema.insert("additionalProperties".into(), Value::Bool(false));
    }
}

fn generator(contract: Contract) -> SchemaGenerator {
    let settings = SchemaSettings::draft07().with(|s| s.contract = contract);
    match settings.contract {
        // What the station reads is closed where serde refuses unknown fields
        // (`deny_unknown_fields`), and only there.
        Contract::Deserialize => settings.into_generator(),
        _ => settings
            .with_transform(RecursiveTransform(closed_objects))
            .into_generator(),
    }
}

/// `read` is `sent` with fewer fields required: those it fills in with defaults.
fn only_defaults_differ(sent: &Value, read: &Value) -> bool {
    let required =
        |v: &Value| -> Vec<Value> { v["required"].as_array().cloned().unwrap_or_default() };
    let without_required = |v: &Value| {
        let mut v = v.clone();
        if let Some(o) = v.as_object_mut() {
            o.remove("required");
        }
        v
    };
    let sent_required = required(sent);
    without_required(sent) == without_required(read)
        && required(read).iter().all(|r| sent_required.contains(r))
}

/// Points the references of a read schema to the `…Input` names of `inputs`.
fn refer_to_inputs(schema: &mut Value, inputs: &[String]) {
    match schema {
        Value::Object(o) => {
            for (key, value) in o.iter_mut() {
                let target = value
                    .as_str()
                    .and_then(|r| r.strip_prefix("#/definitions/"));
                match target {
                    Some(name) if key == "$ref" && inputs.iter().any(|i| i == name) => {
                        *value = Value::String(format!("#/definitions/{name}Input"));
                    }
                    _ => refer_to_inputs(value, inputs),
                }
            }
        }
        Value::Array(items) => items.iter_mut().for_each(|v| refer_to_inputs(v, inputs)),
        _ => {}
    }
}

/// The whole contract: a schema whose `definitions` name every message.
pub fn schema() -> Result<Value, ContractError> {
    let mut sent = generator(Contract::Serialize);
    let mut read = generator(Contract::Deserialize);
    // The root names each message once: what the station sends, then what it reads (Vecs:
    // serde serializes arrays of at most 32).
    let sent_messages = vec![
        sent.subschema_for::<ServerMessage>(),
        sent.subschema_for::<Session>(),
        sent.subschema_for::<ParamsMsg>(),
        sent.subschema_for::<AscentWindMsg>(),
        sent.subschema_for::<EventsBody>(),
        sent.subschema_for::<TrackBody>(),
        sent.subschema_for::<ClientsBody>(),
        sent.subschema_for::<CommandAccepted>(),
        sent.subschema_for::<CutdownArm>(),
        sent.subschema_for::<ErrorBody>(),
        sent.subschema_for::<ReplayView>(),
        sent.subschema_for::<RecordingsBody>(),
        sent.subschema_for::<ReplayOpened>(),
        sent.subschema_for::<KeepOutMsg>(),
        sent.subschema_for::<PreflightReport>(),
        sent.subschema_for::<PreflightDefaults>(),
        sent.subschema_for::<ForecastUploadReport>(),
        sent.subschema_for::<WindowReport>(),
        sent.subschema_for::<TawhiriAnswer>(),
        sent.subschema_for::<TawhiriErrorAnswer>(),
        sent.subschema_for::<LabStatusBody>(),
        sent.subschema_for::<LabStartedBody>(),
        sent.subschema_for::<VehicleFieldsBody>(),
        sent.subschema_for::<LabGainsListBody>(),
        sent.subschema_for::<LabSavedBody>(),
        sent.subschema_for::<LabRehearsalBody>(),
        sent.subschema_for::<ReadinessView>(),
        sent.subschema_for::<crate::forward::SharingBody>(),
        sent.subschema_for::<RelayMessage>(),
        sent.subschema_for::<crate::relay::public::RelayStatusBody>(),
    ];
    let read_messages = vec![
        read.subschema_for::<ClientMessage>(),
        read.subschema_for::<ModeBody>(),
        read.subschema_for::<HeadingBody>(),
        read.subschema_for::<CourseBody>(),
        read.subschema_for::<LocalizerBody>(),
        read.subschema_for::<TargetBody>(),
        read.subschema_for::<crate::requests::SurfaceWindBody>(),
        read.subschema_for::<PlanBody>(),
        read.subschema_for::<ParamBody>(),
        read.subschema_for::<ConfirmBody>(),
        read.subschema_for::<ReplayBody>(),
        read.subschema_for::<KeepOutBody>(),
        read.subschema_for::<PreflightBody>(),
        read.subschema_for::<WindowBody>(),
        read.subschema_for::<LabJobBody>(),
        read.subschema_for::<LabVehicleBody>(),
        read.subschema_for::<LabGainsBody>(),
        read.subschema_for::<TickBody>(),
        read.subschema_for::<crate::sondehub::ChaseCarBody>(),
    ];
    let mut definitions: Map<String, Value> = sent.take_definitions(true);
    let read_definitions = read.take_definitions(true);
    // A type both sent and read must be described the same way both times, but for one
    // difference: a field the station fills in when it is left out (a serde default) is
    // required as sent and optional as read. Such a type is read under its own name, `…Input`.
    let mut inputs = Vec::new();
    for (name, schema) in &read_definitions {
        match definitions.get(name) {
            Some(other) if other == schema => {}
            Some(other) if only_defaults_differ(other, schema) => inputs.push(name.clone()),
            Some(_) => return Err(ContractError::Conflict(name.clone())),
            None => {}
        }
    }
    let mut messages: Vec<Value> = sent_messages.into_iter().map(Value::from).collect();
    for schema in read_messages {
        let mut schema = Value::from(schema);
        refer_to_inputs(&mut schema, &inputs);
        messages.push(schema);
    }
    for (name, mut schema) in read_definitions {
        refer_to_inputs(&mut schema, &inputs);
        let name = if inputs.contains(&name) {
            format!("{name}Input")
        } else {
            name
        };
        match definitions.get(&name) {
            // A type that holds an input type now differs from its sent self as well.
            Some(other) if *other != schema => return Err(ContractError::Conflict(name)),
            _ => {
                definitions.insert(name, schema);
            }
        }
    }
    inline_tagged_variants(&mut definitions);
    Ok(json!({
        "$schema": "http://json-schema.org/draft-07/schema#",
        "title": "stx station API",
        "description": "Every message of the stx station's HTTP and WebSocket API (crates/stx-station/API.md), generated from the daemon's Rust types by `cargo run -p stx-station --example api_schema`: do not edit. The root is any one of them: on the WebSocket ServerMessage (station to page) and ClientMessage (page to station); over REST the bodies the station answers (Session, StateMsg, ParamsMsg, AscentWindMsg, EventsBody, TrackBody, ClientsBody, CommandResultMsg, CommandAccepted, CutdownArm, ErrorBody, ReplayView, RecordingsBody, ReplayOpened, KeepOutMsg, PreflightReport, PreflightDefaults, ForecastUploadReport, WindowReport, TawhiriAnswer, TawhiriErrorAnswer, ReadinessView, SharingBody, the Lab's Lab*Body and VehicleFieldsBody) and the bodies of the commands (*Body).",
        "anyOf": messages,
        "definitions": definitions,
    }))
}

/// An internally tagged enum's newtype variant (`{"kind":"scenario", ...the struct's fields}`)
/// comes out of schemars as the tag's properties plus `allOf: [$ref struct]`; with every object
/// closed, neither half would accept the other's fields. The struct's properties are copied in
/// beside the tag instead, so the variant is one closed object.
fn inline_tagged_variants(definitions: &mut Map<String, Value>) {
    let structs = definitions.clone();
    let mut visit = |variant: &mut Value| {
        let Some(object) = variant.as_object_mut() else {
            return;
        };
        let target = match object.get("allOf").and_then(Value::as_array) {
            Some(all) if all.len() == 1 && object.contains_key("properties") => all[0]
                .get("$ref")
                .and_then(Value::as_str)
                .and_then(|r| r.strip_prefix("#/definitions/"))
                .and_then(|name| structs.get(name))
                .cloned(),
            _ => None,
        };
        let Some(target) = target else { return };
        for key in ["properties", "required"] {
            let Some(theirs) = target.get(key).cloned() else {
                continue;
            };
            match (object.get_mut(key), theirs) {
                (Some(Value::Object(ours)), Value::Object(theirs)) => ours.extend(theirs),
                (Some(Value::Array(ours)), Value::Array(theirs)) => ours.extend(theirs),
                (None, theirs) => {
                    object.insert(key.into(), theirs);
                }
                _ => {}
            }
        }
        object.remove("allOf");
    };
    for definition in definitions.values_mut() {
        for key in ["oneOf", "anyOf"] {
            if let Some(Value::Array(variants)) = definition.get_mut(key) {
                variants.iter_mut().for_each(&mut visit);
            }
        }
    }
}

/// The schema as committed: pretty JSON, one trailing newline.
pub fn schema_text() -> Result<String, ContractError> {
    let value = schema()?;
    let mut text = serde_json::to_string_pretty(&value).unwrap_or_default();
    text.push('\n');
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_committed_schema_is_the_one_the_types_give() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../..")
            .join(SCHEMA_PATH);
        let committed = std::fs::read_to_string(&path).unwrap_or_default();
        let fresh = schema_text().expect("the contract assembles");
        assert!(
            committed == fresh,
            "{} is stale: run `cargo run -p stx-station --example api_schema`, then \
             `npm run gen:api` in web/, and commit both",
            path.display()
        );
    }

    /// `API.md` is the people's reference: it must name every message of the contract, show
    /// every WebSocket message's `type`, and name no message the contract does not have.
    #[test]
    fn api_md_agrees_with_the_contract() {
        let doc_path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("API.md");
        let doc = std::fs::read_to_string(&doc_path).expect("API.md is readable");
        let schema = schema().expect("the contract assembles");
        let definitions = schema["definitions"].as_object().expect("definitions");
        let name_of = |r: &Value| {
            r["$ref"]
                .as_str()
                .and_then(|r| r.strip_prefix("#/definitions/"))
                .map(str::to_string)
        };
        let messages: Vec<String> = schema["anyOf"]
            .as_array()
            .expect("the root lists the messages")
            .iter()
            .filter_map(name_of)
            .collect();
        assert!(messages.len() > 10, "{messages:?}");
        for name in &messages {
            assert!(
                doc.contains(&format!("`{name}`")),
                "API.md does not name `{name}`"
            );
        }
        // The `type` of each WebSocket message, either way.
        let server = definitions["ServerMessage"]["anyOf"]
            .as_array()
            .expect("a union");
        let client = definitions["ClientMessage"]["oneOf"]
            .as_array()
            .expect("a union");
        let types: Vec<String> = server
            .iter()
            .filter_map(|m| name_of(&m["allOf"][0]))
            .map(|name| &definitions[&name])
            .chain(client)
            .filter_map(|m| {
                m["properties"]["type"]["const"]
                    .as_str()
                    .map(str::to_string)
            })
            .collect();
        assert_eq!(types.len(), server.len() + client.len(), "{types:?}");
        for t in &types {
            assert!(
                doc.contains(&format!(r#""type":"{t}""#)),
                "API.md shows no `{t}` message"
            );
        }
        // Every message API.md names by its schema name exists.
        // (A text between two backticks that is one such word can only be a name in backticks.)
        for name in doc.split('`') {
            let looks_like_one = name.chars().next().is_some_and(|c| c.is_ascii_uppercase())
                && name.chars().all(|c| c.is_ascii_alphanumeric())
                && ["Msg", "Body", "View", "Message"]
                    .iter()
                    .any(|e| name.ends_with(e));
            if looks_like_one {
                assert!(
                    definitions.contains_key(name),
                    "API.md names `{name}`, which the contract does not have"
                );
            }
        }
    }
}
