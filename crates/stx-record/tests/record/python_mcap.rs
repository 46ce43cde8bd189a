//! Our recordings read by an independent implementation: the `mcap` package from PyPI,
//! version 1.6.0 (`tests/peers/read_mcap.py`). It must find every channel, schema and
//! message count we wrote, read every message (each with the fields its JSON Schema
//! requires), decode the MAVLink frames' base64 to the bytes we wrote, read a cut file with
//! its stream reader up to its last whole chunk, and read our recovered copy of it whole.
//!
//! Python: `$STX_PYTHON`, or `.venv/bin/python` at the workspace root. To set it up:
//! `python3 -m venv .venv && .venv/bin/pip install mcap==1.6.0`.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{Made, TOPICS, chunk_ends, frame_bytes, make};
use serde_json::Value;
use stx_record::Compression;

const MCAP_PY: &str = "1.6.0";

fn python() -> PathBuf {
    let p = std::env::var_os("STX_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../.venv/bin/python"));
    assert!(
        p.exists(),
        "no Python at {} (set STX_PYTHON, or create the venv at the workspace root: \
         `python3 -m venv .venv && .venv/bin/pip install mcap=={MCAP_PY}`)",
        p.display()
    );
    p
}

fn read_mcap(mode: &str, file: &Path) -> Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/peers/read_mcap.py");
    let out = Command::new(python())
        .arg(&script)
        .arg(mode)
        .arg(file)
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "read_mcap.py {mode} failed ({}): {}\n(is mcap installed? `pip install mcap=={MCAP_PY}`)",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).expect("JSON from read_mcap.py");
    assert_eq!(
        v["version"], MCAP_PY,
        "the test is pinned to mcap {MCAP_PY}"
    );
    v
}

#[test]
fn python_mcap_reads_every_channel_schema_and_message() {
    let Made { bytes, written } = make(1000, 10, 1 << 20, Compression::Zstd);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("whole.mcap");
    std::fs::write(&path, &bytes).unwrap();
    let v = read_mcap("summary", &path);
    assert_eq!(v["message_count"], 1000);
    let schemas = [
        "foxglove.LocationFix",
        "foxglove.Log",
        "stx.MavlinkFrame",
        "stx.Estimate",
        "foxglove.FrameTransform",
    ];
    let channels = v["channels"].as_array().unwrap();
    assert_eq!(channels.len(), TOPICS.len());
    for (ch, (topic, schema)) in channels.iter().zip(TOPICS.iter().zip(schemas)) {
        assert_eq!(ch["topic"], *topic);
        assert_eq!(ch["schema_name"], schema);
        assert_eq!(ch["schema_encoding"], "jsonschema");
        assert_eq!(ch["message_encoding"], "json");
        assert_eq!(ch["count"], 200, "{topic}");
        assert_eq!(v["read"][topic], 200, "{topic} read");
    }
    assert_eq!(v["missing_fields"], Value::Array(vec![]));
    let first_frame = written.iter().position(|w| w.topic == "/mavlink").unwrap() as u64;
    let hex: String = frame_bytes(first_frame)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    assert_eq!(v["first_frame_hex"], hex);
    let meta = &v["metadata"][0];
    assert_eq!(meta["name"], "stx.recording");
    assert_eq!(meta["metadata"]["vehicle"], "straplex-1");
    assert_eq!(meta["metadata"]["part"], "1");
}

#[test]
fn python_mcap_streams_a_cut_file_up_to_its_last_whole_chunk() {
    let Made { bytes, written } = make(1000, 10, 1 << 20, Compression::Zstd);
    let ends = chunk_ends(&bytes);
    let dir = tempfile::tempdir().unwrap();
    for k in [2, 5, 8] {
        // Cut in the middle of chunk k.
        let (start, end, _) = ends[k];
        let cut = ((start + end) / 2) as usize;
        let path = dir.path().join(format!("cut-{k}.mcap"));
        std::fs::write(&path, &bytes[..cut]).unwrap();
        let v = read_mcap("stream", &path);
        assert!(v["error"].is_string(), "a cut file ends in an error: {v}");
        let whole: usize = ends[..k].iter().map(|(_, _, n)| n).sum();
        let read = v["read"].as_object().unwrap();
        for topic in TOPICS {
            let expected = written[..whole].iter().filter(|w| w.topic == topic).count();
            assert_eq!(read[topic], expected as u64, "cut in chunk {k}, {topic}");
        }
        // Our recovered copy is a whole file to Python's indexed reader.
        let fixed = dir.path().join(format!("cut-{k}.recovered.mcap"));
        let report = stx_record::recover_file(&path, &fixed).unwrap();
        let v = read_mcap("summary", &fixed);
        assert_eq!(v["message_count"], report.messages);
        assert!(report.messages as usize >= whole);
        assert_eq!(v["missing_fields"], Value::Array(vec![]));
    }
}
