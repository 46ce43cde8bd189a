//! `stx record recover` from the outside: a cut recording becomes a whole one; bad input
//! exits 2 without touching anything.

use crate::common;

use common::stx;

use std::path::{Path, PathBuf};
use std::time::Duration;

use stx_record::{
    CoreOptions, IndexSource, Output, RecorderCore, Recording, RecordingInfo, foxglove,
};

const T0: u64 = 1_767_225_600_000_000_000;

fn temp_dir(name: &str) -> PathBuf {
    common::temp_dir("record", name)
}

/// A recording of 400 events over 4 s (one-second chunks), and the offset halfway through
/// the third chunk, the last one written before `finish`: a cut there leaves two whole chunks.
fn recording() -> (Vec<u8>, usize) {
    let info = RecordingInfo::new("test", "straplex-1", "cli");
    let mut core = RecorderCore::new(CoreOptions::default(), info, Duration::ZERO).unwrap();
    let ch = core
        .add_channel(Duration::ZERO, foxglove::log_channel("/events").unwrap())
        .unwrap();
    let mut bytes = Vec::new();
    let mut last_chunk_start = 0;
    for i in 0..400u64 {
        let now = Duration::from_millis(10 * i);
        let payload = format!(r#"{{"i":{i}}}"#);
        core.write(now, ch, T0 + i, T0 + i, payload.as_bytes())
            .unwrap();
        while let Some(out) = core.poll_output() {
            if let Output::Bytes { data, .. } = out {
                last_chunk_start = bytes.len();
                bytes.extend(data);
            }
        }
    }
    core.finish().unwrap();
    let end_of_chunks = bytes.len();
    while let Some(out) = core.poll_output() {
        if let Output::Bytes { data, .. } = out {
            bytes.extend(data);
        }
    }
    (bytes, (last_chunk_start + end_of_chunks) / 2)
}

fn path_str(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

#[test]
fn a_cut_recording_is_recovered_beside_itself() {
    let dir = temp_dir("cut");
    let (bytes, cut) = recording();
    let file = dir.join("flight.mcap");
    std::fs::write(&file, &bytes[..cut]).unwrap();
    let out = stx(&["record", "recover", path_str(&file)]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("was cut at byte"), "{text}");
    let fixed = dir.join("flight.recovered.mcap");
    let rec = Recording::open(&fixed).unwrap();
    assert_eq!(rec.index(), IndexSource::Summary);
    assert!(
        (200..300).contains(&rec.message_count()),
        "{}",
        rec.message_count()
    );
    // Run again: the copy exists and is not replaced.
    let again = stx(&["record", "recover", path_str(&file)]);
    assert_eq!(again.status.code(), Some(2));
    let named = dir.join("named.mcap");
    let out = stx(&[
        "record",
        "recover",
        path_str(&file),
        "--out",
        path_str(&named),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(named.is_file());
}

#[test]
fn what_is_not_a_recording_exits_2_and_writes_nothing() {
    let dir = temp_dir("bad");
    let file = dir.join("notes.mcap");
    std::fs::write(&file, b"not a recording").unwrap();
    let out = stx(&["record", "recover", path_str(&file)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not an MCAP file"));
    assert!(!dir.join("notes.recovered.mcap").exists());
    let missing = stx(&["record", "recover", path_str(&dir.join("missing.mcap"))]);
    assert_eq!(missing.status.code(), Some(2));
}
