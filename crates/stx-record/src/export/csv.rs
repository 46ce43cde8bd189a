//! One CSV file per channel: `log_time_s` (Unix seconds) and `utc` first, then every JSON
//! field of the channel's messages, nested objects joined with `.` and arrays indexed
//! (`velocity_ned_mps[0]`), in the order they first appear. A column's unit, when the
//! channel's JSON Schema states one at the end of the field's description (stx's documents
//! end "…, m/s." — schemars copies them into the schema) or the field's name ends in one
//! (`_m`, `_mps`, `_deg`, …), is in its header: `alt_msl_m [m]`. Files are named after the
//! topic (`/station/state` → `station_state.csv`). A `foxglove.LocationFix` that is no
//! position (at 0°, 0°: [`LocationFix::is_position`]) gets no row, and is counted.

use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::{BufWriter, Read, Seek, Write};
use std::path::{Path, PathBuf};

use serde_json::Value;

use super::{ExportError, utc};
use crate::Recording;
use crate::foxglove::{LOCATION_FIX, LocationFix};

/// What an export wrote: each file and its rows.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CsvReport {
    /// Per channel: the file and how many rows it got.
    pub files: Vec<(PathBuf, u64)>,
    /// Messages that were not JSON objects (skipped).
    pub skipped: u64,
    /// `foxglove.LocationFix` messages that are no position (at 0°, 0°: a receiver without a
    /// fix, in a recording made before stx checked the fix type or by another tool), left out
    /// so no spreadsheet or GIS tool plots them.
    pub not_positions: u64,
}

/// The file name of `topic`'s CSV.
pub fn file_name(topic: &str) -> String {
    let name: String = topic
        .trim_start_matches('/')
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect();
    format!("{}.csv", if name.is_empty() { "root" } else { &name })
}

/// Writes one CSV per channel of `recording` into `dir` (created if missing).
pub fn export_csv<R: Read + Seek>(
    recording: &mut Recording<R>,
    dir: &Path,
) -> Result<CsvReport, ExportError> {
    let write_err = |path: &Path| {
        let path = path.display().to_string();
        move |source| ExportError::Write { path, source }
    };
    std::fs::create_dir_all(dir).map_err(write_err(dir))?;
    // Pass 1: the columns of each channel.
    let mut columns: BTreeMap<String, Columns> = BTreeMap::new();
    let mut skipped = 0;
    for message in recording.messages()? {
        let message = message?;
        match serde_json::from_slice::<Value>(&message.data) {
            Ok(v @ Value::Object(_)) => {
                let cols = columns.entry(message.topic.to_string()).or_default();
                flatten("", &v, &mut |path, _| cols.add(path));
            }
            _ => skipped += 1,
        }
    }
    // Headers, with units from the schemas.
    let mut writers: HashMap<String, (PathBuf, BufWriter<File>, u64)> = HashMap::new();
    for (topic, cols) in &columns {
        let schema = recording
            .schema(topic)
            .and_then(|s| serde_json::from_slice::<Value>(s).ok())
            .unwrap_or(Value::Null);
        let path = dir.join(file_name(topic));
        let file = File::create(&path).map_err(write_err(&path))?;
        let mut w = BufWriter::new(file);
        let mut header = vec!["log_time_s [s]".to_string(), "utc".to_string()];
        header.extend(cols.names.iter().map(|c| match unit_of(&schema, c) {
            Some(u) => format!("{c} [{u}]"),
            None => c.clone(),
        }));
        write_row(&mut w, &header).map_err(write_err(&path))?;
        writers.insert(topic.clone(), (path, w, 0));
    }
    // Pass 2: the rows.
    let positions: Vec<String> = recording
        .channels()
        .iter()
        .filter(|c| c.schema_name == LOCATION_FIX)
        .map(|c| c.topic.to_string())
        .collect();
    let mut not_positions = 0;
    for message in recording.messages()? {
        let message = message?;
        let Ok(v @ Value::Object(_)) = serde_json::from_slice::<Value>(&message.data) else {
            continue;
        };
        if positions.iter().any(|t| **t == *message.topic)
            && serde_json::from_value::<LocationFix>(v.clone()).is_ok_and(|f| !f.is_position())
        {
            not_positions += 1;
            continue;
        }
        let (Some(cols), Some((path, w, rows))) = (
            columns.get(&*message.topic),
            writers.get_mut(&*message.topic),
        ) else {
            continue;
        };
        let mut row = vec![String::new(); cols.names.len() + 2];
        row[0] = format!(
            "{}.{:09}",
            message.log_time / 1_000_000_000,
            message.log_time % 1_000_000_000
        );
        row[1] = utc(message.log_time);
        flatten("", &v, &mut |p, leaf| {
            if let Some(&i) = cols.index.get(p) {
                row[i + 2] = leaf_text(leaf);
            }
        });
        write_row(w, &row).map_err(write_err(path))?;
        *rows += 1;
    }
    let mut files = Vec::new();
    for (_, (path, mut w, rows)) in writers {
        w.flush().map_err(write_err(&path))?;
        files.push((path, rows));
    }
    files.sort();
    Ok(CsvReport {
        files,
        skipped,
        not_positions,
    })
}

#[derive(Default)]
struct Columns {
    names: Vec<String>,
    index: HashMap<String, usize>,
}

impl Columns {
    fn add(&mut self, path: &str) {
        if !self.index.contains_key(path) {
            self.index.insert(path.to_owned(), self.names.len());
            self.names.push(path.to_owned());
        }
    }
}

/// Calls `f(path, leaf)` for every leaf of `v` (nulls included, so a column exists even
/// while its value is unknown).
fn flatten(prefix: &str, v: &Value, f: &mut dyn FnMut(&str, &Value)) {
    match v {
        Value::Object(map) => {
            for (k, x) in map {
                let p = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                flatten(&p, x, f);
            }
        }
        Value::Array(items) => {
            for (i, x) in items.iter().enumerate() {
                flatten(&format!("{prefix}[{i}]"), x, f);
            }
        }
        leaf => f(prefix, leaf),
    }
}

fn leaf_text(v: &Value) -> String {
    match v {
        Value::Null => String::new(),
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// RFC 4180: a field with a comma, quote or line break is quoted, quotes doubled.
fn write_row(w: &mut impl Write, fields: &[String]) -> std::io::Result<()> {
    let mut line = String::new();
    for (i, f) in fields.iter().enumerate() {
        if i > 0 {
            line.push(',');
        }
        if f.contains([',', '"', '\n', '\r']) {
            line.push('"');
            line.push_str(&f.replace('"', "\"\""));
            line.push('"');
        } else {
            line.push_str(f);
        }
    }
    line.push_str("\r\n");
    w.write_all(line.as_bytes())
}

/// The unit of the column `path` (`a.b[2].c`): from its property's description in `schema`,
/// else from the field's name.
fn unit_of(schema: &Value, path: &str) -> Option<String> {
    let field = path.rsplit('.').next().unwrap_or(path);
    let field = field.split('[').next().unwrap_or(field);
    property(schema, schema, path)
        .and_then(|p| p.get("description"))
        .and_then(Value::as_str)
        .and_then(unit_in_description)
        .or_else(|| unit_in_name(field).map(str::to_owned))
}

/// The property schema at `path`, following `$ref`s into `$defs`/`definitions`.
fn property<'a>(root: &'a Value, mut at: &'a Value, path: &str) -> Option<&'a Value> {
    for part in path.split('.') {
        let name = part.split('[').next().unwrap_or(part);
        at = resolve(root, at);
        at = at.get("properties")?.get(name)?;
        at = resolve(root, at);
        // An optional value: `anyOf: [{$ref}, {type: null}]`; an array: its items.
        if let Some(inner) = at.get("anyOf").and_then(Value::as_array).and_then(|a| {
            a.iter()
                .find(|s| s.get("type") != Some(&Value::String("null".into())))
        }) && at.get("description").is_none()
        {
            at = resolve(root, inner);
        }
        if part.contains('[')
            && let Some(items) = at.get("items")
        {
            // The array's own description carries the unit; keep it unless the items have one.
            if items.get("description").is_some() {
                at = resolve(root, items);
            }
        }
    }
    Some(at)
}

fn resolve<'a>(root: &'a Value, v: &'a Value) -> &'a Value {
    match v.get("$ref").and_then(Value::as_str) {
        Some(r) => {
            let name = r.rsplit('/').next().unwrap_or(r);
            root.get("$defs")
                .and_then(|d| d.get(name))
                .or_else(|| root.get("definitions").and_then(|d| d.get(name)))
                .unwrap_or(v)
        }
        None => v,
    }
}

/// The unit a description states: at its end after a comma (stx's "Altitude above mean sea
/// level, m (wire: mm)." → `m`), after " in " (Foxglove's "Latitude in degrees"), or in
/// parentheses ("Covariance of the position (m^2), …"). Only known units count, so a
/// description's last words are not taken for one.
fn unit_in_description(text: &str) -> Option<String> {
    const UNITS: [&str; 30] = [
        "m",
        "m/s",
        "m/s²",
        "m²",
        "m^2",
        "s",
        "ms",
        "µs",
        "us",
        "ns",
        "degrees",
        "deg",
        "°",
        "rad",
        "rad/s",
        "deg/s",
        "degrees/s",
        "Pa",
        "hPa",
        "°C",
        "V",
        "A",
        "Ah",
        "mAh",
        "%",
        "Hz",
        "kg",
        "N",
        "B",
        "MB",
    ];
    let first = text
        .lines()
        .next()
        .unwrap_or(text)
        .trim()
        .trim_end_matches('.');
    let known = |u: &str| {
        let u = u.trim().trim_end_matches('.');
        let u = match u {
            "metres" | "meters" => "m",
            "seconds" => "s",
            other => other,
        };
        UNITS.contains(&u).then(|| u.to_owned())
    };
    let after_comma = first
        .rsplit_once(", ")
        .and_then(|(_, last)| last.split(" (").next());
    let after_in = first.rsplit_once(" in ").map(|(_, last)| last);
    let in_parens = first
        .split_once('(')
        .and_then(|(_, rest)| rest.split_once(')'))
        .map(|(inside, _)| inside);
    [after_comma, after_in, in_parens]
        .into_iter()
        .flatten()
        .find_map(known)
}

fn unit_in_name(field: &str) -> Option<&'static str> {
    const SUFFIXES: [(&str, &str); 14] = [
        ("_radps", "rad/s"),
        ("_dps", "deg/s"),
        ("_mps", "m/s"),
        ("_deg", "deg"),
        ("_rad", "rad"),
        ("_ms", "ms"),
        ("_m", "m"),
        ("_s", "s"),
        ("_hz", "Hz"),
        ("_pa", "Pa"),
        ("_v", "V"),
        ("_a", "A"),
        ("_percent", "%"),
        ("_c", "°C"),
    ];
    SUFFIXES
        .iter()
        .find(|(s, _)| field.ends_with(s))
        .map(|(_, u)| *u)
}

#[cfg(test)]
mod tests;
