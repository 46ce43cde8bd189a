//! Reading recordings back (from the summary, or by a scan when it is missing), seeking by
//! time through the indexes, and recovering files cut at any byte.

use crate::common;

use std::io::{Cursor, Read, Seek, SeekFrom};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use common::{Made, T0, TOPICS, Written, chunk_ends, make, read_back};
use stx_record::{Compression, IndexSource, ReadError, Recording, RecoverError, recover};

fn as_written(m: stx_record::RecordedMessage) -> Written {
    Written {
        topic: m.topic.to_string(),
        sequence: m.sequence,
        log_time: m.log_time,
        data: m.data,
    }
}

fn read_ours(file: &[u8]) -> Vec<Written> {
    let mut rec = Recording::from_reader(Cursor::new(file)).unwrap();
    rec.messages()
        .unwrap()
        .map(|m| as_written(m.unwrap()))
        .collect()
}

/// A reader that counts the bytes it hands out.
struct Counting<R> {
    inner: R,
    read: Arc<AtomicU64>,
}

impl<R: Read> Read for Counting<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.read.fetch_add(n as u64, Ordering::Relaxed);
        Ok(n)
    }
}

impl<R: Seek> Seek for Counting<R> {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.inner.seek(pos)
    }
}

#[test]
fn a_whole_file_lists_itself_from_its_summary() {
    let Made { bytes, written } = make(400, 10, 1 << 20, Compression::Zstd);
    let rec = Recording::from_reader(Cursor::new(&bytes)).unwrap();
    assert_eq!(rec.index(), IndexSource::Summary);
    assert_eq!(rec.message_count(), 400);
    assert_eq!(
        rec.time_range(),
        Some((T0, written.last().unwrap().log_time))
    );
    let topics: Vec<&str> = rec.channels().iter().map(|c| &*c.topic).collect();
    assert_eq!(topics, TOPICS);
    for c in rec.channels() {
        assert_eq!(c.message_count, 80, "{}", c.topic);
        assert_eq!(c.schema_encoding, "jsonschema");
        assert_eq!(c.message_encoding, "json");
    }
    assert_eq!(
        rec.channel("/vehicle/fix").unwrap().schema_name,
        "foxglove.LocationFix"
    );
    assert_eq!(
        rec.channel("/mavlink").unwrap().schema_name,
        "stx.MavlinkFrame"
    );
    let (info, part) = rec.info().unwrap();
    assert_eq!(
        (info.vehicle(), info.mission(), part),
        ("straplex-1", "test flight", 1)
    );
    assert_eq!(read_ours(&bytes), written);
}

#[test]
fn opening_reads_the_index_not_the_file_and_a_seek_reads_only_what_follows() {
    // 20 minutes at 20 messages a second: 1200 one-second chunks.
    let Made { bytes, written } = make(24_000, 50, 1 << 20, Compression::Zstd);
    let read = Arc::new(AtomicU64::new(0));
    let source = Counting {
        inner: Cursor::new(&bytes),
        read: read.clone(),
    };
    let mut rec = Recording::from_reader(source).unwrap();
    assert_eq!(rec.index(), IndexSource::Summary);
    assert_eq!(rec.chunk_count(), 1200);
    let opened = read.load(Ordering::Relaxed);
    assert!(
        opened * 4 < bytes.len() as u64,
        "opening read {opened} of {} B",
        bytes.len()
    );
    // The last 30 s: about 30 chunks of 1200 are read.
    let start = written[written.len() - 600].log_time;
    read.store(0, Ordering::Relaxed);
    let tail: Vec<_> = rec
        .messages_from(start)
        .unwrap()
        .map(|m| as_written(m.unwrap()))
        .collect();
    assert_eq!(tail, written[written.len() - 600..]);
    let seeked = read.load(Ordering::Relaxed);
    assert!(
        seeked * 20 < bytes.len() as u64,
        "the seek read {seeked} of {} B",
        bytes.len()
    );
}

#[test]
fn messages_come_in_log_time_order_whatever_the_file_order() {
    use std::time::Duration;
    use stx_record::{ChannelSpec, CoreOptions, Output, RecorderCore, RecordingInfo};
    let mut core = RecorderCore::new(
        CoreOptions::default(),
        RecordingInfo::default(),
        Duration::ZERO,
    )
    .unwrap();
    let spec = ChannelSpec::json("/late", "x", &serde_json::json!({"type": "object"})).unwrap();
    let ch = core.add_channel(Duration::ZERO, spec).unwrap();
    // Log times go back across a chunk boundary (a late message logged with its own time).
    let times = [50, 10, 40, 20, 30, 5, 45];
    for (i, t) in times.iter().enumerate() {
        let now = Duration::from_millis(600 * i as u64);
        core.write(now, ch, T0 + t, T0 + t, b"{}").unwrap();
    }
    core.finish().unwrap();
    let mut bytes = Vec::new();
    while let Some(out) = core.poll_output() {
        if let Output::Bytes { data, .. } = out {
            bytes.extend(data);
        }
    }
    let mut rec = Recording::from_reader(Cursor::new(&bytes)).unwrap();
    let got: Vec<u64> = rec
        .messages()
        .unwrap()
        .map(|m| m.unwrap().log_time - T0)
        .collect();
    assert_eq!(got, [5, 10, 20, 30, 40, 45, 50]);
    let from_25: Vec<u64> = rec
        .messages_from(T0 + 25)
        .unwrap()
        .map(|m| m.unwrap().log_time - T0)
        .collect();
    assert_eq!(from_25, [30, 40, 45, 50]);
}

#[test]
fn a_cut_file_is_scanned_and_reads_to_its_last_whole_chunk() {
    let Made { bytes, written } = make(400, 10, 1 << 20, Compression::Zstd);
    let ends = chunk_ends(&bytes);
    // Cut in the middle of the third chunk.
    let cut = ((ends[2].0 + ends[2].1) / 2) as usize;
    let whole: usize = ends[..2].iter().map(|(_, _, n)| n).sum();
    let mut rec = Recording::from_reader(Cursor::new(&bytes[..cut])).unwrap();
    let IndexSource::Scan { cut_at, bad_chunks } = rec.index() else {
        panic!("a cut file has no summary");
    };
    assert_eq!((cut_at, bad_chunks), (Some(ends[2].0), 0));
    assert_eq!(rec.message_count(), whole as u64);
    assert_eq!(rec.channels().len(), 5);
    assert!(rec.info().is_some(), "the metadata comes before any chunk");
    let got: Vec<_> = rec
        .messages()
        .unwrap()
        .map(|m| as_written(m.unwrap()))
        .collect();
    assert_eq!(got, written[..whole]);
    let from: Vec<_> = rec
        .messages_from(written[150].log_time)
        .unwrap()
        .map(|m| as_written(m.unwrap()))
        .collect();
    assert_eq!(from, written[150..whole]);
}

#[test]
fn what_is_not_mcap_is_refused_with_a_clear_error() {
    let err = Recording::from_reader(Cursor::new(b"not a recording at all")).err();
    assert!(matches!(err, Some(ReadError::NotMcap)), "{err:?}");
    let err = recover(&b"GIF89a"[..], Cursor::new(Vec::new())).err();
    assert!(matches!(err, Some(RecoverError::NotMcap)), "{err:?}");
}

/// Recovers `bytes[..cut]` and checks: a finished file (with summary) comes out, holding
/// every message of the chunks that end before the cut, and nothing that was not written,
/// in the order written.
fn check_recovery(bytes: &[u8], written: &[Written], ends: &[(u64, u64, usize)], cut: usize) {
    let mut out = Cursor::new(Vec::new());
    let result = recover(&bytes[..cut], &mut out);
    if cut < 8 {
        assert!(matches!(result, Err(RecoverError::NotMcap)), "cut {cut}");
        return;
    }
    let report = result.unwrap_or_else(|e| panic!("cut {cut}: {e}"));
    let out = out.into_inner();
    let got = read_back(&out);
    let must: usize = ends
        .iter()
        .filter(|(_, end, _)| *end as usize <= cut)
        .map(|(_, _, n)| n)
        .sum();
    assert!(
        got.len() >= must,
        "cut {cut}: {} recovered, {must} in whole chunks",
        got.len()
    );
    assert_eq!(
        got,
        written[..got.len()],
        "cut {cut}: invented or reordered"
    );
    assert_eq!(report.messages as usize, got.len());
    assert_eq!(report.bad_chunks, 0);
    // Whole up to its data-end record (which ends where the summary starts), or cut.
    let summary_start = mcap::read::footer(bytes).unwrap().summary_start as usize;
    assert_eq!(report.cut_at.is_none(), cut >= summary_start, "cut {cut}");
    // The copy is whole: it has a summary, and our reader reads it from there.
    let rec = Recording::from_reader(Cursor::new(&out)).unwrap();
    assert_eq!(rec.index(), IndexSource::Summary, "cut {cut}");
    assert_eq!(rec.message_count() as usize, got.len());
}

#[test]
fn a_small_file_cut_at_every_byte_recovers_every_whole_chunk() {
    let Made { bytes, written } = make(48, 10, 400, Compression::Zstd);
    let ends = chunk_ends(&bytes);
    assert!(ends.len() >= 8, "{} chunks", ends.len());
    for cut in 0..=bytes.len() {
        check_recovery(&bytes, &written, &ends, cut);
    }
}

#[test]
fn an_uncompressed_file_cut_inside_a_chunk_gives_up_the_messages_before_the_cut() {
    let Made { bytes, written } = make(48, 10, 400, Compression::None);
    let ends = chunk_ends(&bytes);
    for cut in (0..=bytes.len()).step_by(5) {
        check_recovery(&bytes, &written, &ends, cut);
    }
    // Cut in the middle of the fifth chunk: its first messages are whole, and kept.
    let cut = ((ends[4].0 + ends[4].1) / 2) as usize;
    let mut out = Cursor::new(Vec::new());
    let report = recover(&bytes[..cut], &mut out).unwrap();
    let before: usize = ends[..4].iter().map(|(_, _, n)| n).sum();
    assert!(report.from_cut_chunk > 0, "{report:?}");
    assert_eq!(
        report.messages as usize,
        before + report.from_cut_chunk as usize
    );
    assert_eq!(
        read_back(&out.into_inner()),
        written[..report.messages as usize]
    );
}

#[test]
fn a_larger_file_cut_at_a_stride_recovers_every_whole_chunk() {
    // 40 one-second chunks.
    let Made { bytes, written } = make(8_000, 5, 1 << 20, Compression::Zstd);
    let ends = chunk_ends(&bytes);
    assert_eq!(ends.len(), 40);
    for cut in (0..bytes.len()).step_by(1499).chain([bytes.len()]) {
        check_recovery(&bytes, &written, &ends, cut);
    }
}

#[test]
fn a_whole_chunk_with_a_bad_crc_is_skipped_not_copied() {
    for compression in [Compression::None, Compression::Zstd] {
        a_bad_chunk_is_skipped(compression);
    }
}

fn a_bad_chunk_is_skipped(compression: Compression) {
    let Made { bytes, written } = make(400, 10, 1 << 20, compression);
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let mut chunks = summary.chunk_indexes.clone();
    chunks.sort_by_key(|c| c.chunk_start_offset);
    let victim = &chunks[1];
    let in_victim = summary.stream_chunk(&bytes, victim).unwrap().count();
    let mut bad = bytes.clone();
    // A byte in the middle of the chunk's records (the payload of some message).
    let at = victim.compressed_data_offset().unwrap() + victim.compressed_size / 2;
    bad[at as usize] ^= 0x20;
    let mut out = Cursor::new(Vec::new());
    let report = recover(&bad[..], &mut out).unwrap();
    assert_eq!(report.bad_chunks, 1);
    let got = read_back(&out.into_inner());
    assert_eq!(got.len(), written.len() - in_victim);
    for m in &got {
        assert!(written.contains(m), "invented: {m:?}");
    }
}

/// A few thousand damaged copies (a byte changed, seeded): reading and recovering return
/// errors or data, never panic, and a recovery never yields a message that was not written.
#[test]
fn damaged_files_give_errors_or_data_never_a_panic() {
    let Made { bytes, written } = make(200, 10, 1 << 20, Compression::Zstd);
    let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut next = move || {
        // xorshift64*: deterministic, good enough to pick bytes.
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        state.wrapping_mul(0x2545_f491_4f6c_dd1d)
    };
    for _ in 0..3000 {
        let mut bad = bytes.clone();
        let at = (next() % bad.len() as u64) as usize;
        bad[at] ^= (next() % 255 + 1) as u8;
        if let Ok(mut rec) = Recording::from_reader(Cursor::new(&bad)) {
            let _ = rec.channels().len();
            if let Ok(messages) = rec.messages() {
                for m in messages.take(1000) {
                    if m.is_err() {
                        break;
                    }
                }
            }
        }
        let mut out = Cursor::new(Vec::new());
        if recover(&bad[..], &mut out).is_ok() {
            for m in read_back(&out.into_inner()) {
                assert!(written.contains(&m), "byte {at}: invented {m:?}");
            }
        }
    }
}
