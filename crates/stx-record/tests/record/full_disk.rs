//! The file adapter on a disk that fills up and frees again (files in memory that refuse
//! writes past a capacity the test sets, as a real disk does with ENOSPC: part of the data,
//! then the error). What a flight needs of it: the file being written is kept, cut at its
//! last whole chunk; no file is created until the next try, the tries come after waits that
//! double up to a cap, and a try that fails leaves nothing behind; when space returns the
//! recording resumes in the next file; every message is counted written or lost.

use std::collections::BTreeMap;
use std::io::{self, Cursor};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use stx_record::{
    ChannelId, CoreOptions, IndexSource, IssueKind, Output, Recorder, RecorderConfig, RecorderCore,
    RecorderHandle, RecorderStatus, Recording, RecordingInfo, Storage, StorageFile, foxglove,
    recover,
};

const T0: u64 = 1_767_225_600_000_000_000;
const FIRST_WAIT: Duration = Duration::from_millis(40);
const MAX_WAIT: Duration = Duration::from_millis(320);

fn new_core() -> (RecorderCore, ChannelId) {
    let info = RecordingInfo::new("0.1.0", "straplex-1", "full disk test");
    let mut core = RecorderCore::new(CoreOptions::default(), info, Duration::ZERO).unwrap();
    let ch = core
        .add_channel(Duration::ZERO, foxglove::log_channel("/events").unwrap())
        .unwrap();
    (core, ch)
}

/// Bytes a file holds before its first message: header, metadata, channels.
fn header_bytes() -> u64 {
    let (mut core, _) = new_core();
    core.flush(Duration::ZERO).unwrap();
    std::iter::from_fn(|| core.poll_output())
        .map(|o| match o {
            Output::Bytes { data, .. } => data.len() as u64,
            _ => 0,
        })
        .sum()
}

/// 256 hex digits that differ for every `i`, so chunks do not compress to nothing.
fn noise(i: u64) -> String {
    let mut x = i.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    (0..16)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            format!("{x:016x}")
        })
        .collect()
}

fn log(i: u64) -> foxglove::Log {
    foxglove::Log {
        timestamp: foxglove::Timestamp::from_nanos(T0 + i),
        level: foxglove::LogLevel::Info,
        message: format!("event {i} {}", noise(i)),
        name: "test".into(),
        file: String::new(),
        line: 0,
    }
}

#[derive(Default)]
struct DiskState {
    files: BTreeMap<PathBuf, Vec<u8>>,
    capacity: u64,
    /// When each file was created, in order.
    creates: Vec<Instant>,
    /// The length of each file removed, in order.
    removed: Vec<usize>,
}

/// Files in memory sharing one capacity.
#[derive(Clone, Default)]
struct Disk(Arc<Mutex<DiskState>>);

impl Disk {
    fn with_capacity(capacity: u64) -> Self {
        let disk = Self::default();
        disk.set_capacity(capacity);
        disk
    }

    fn set_capacity(&self, capacity: u64) {
        self.0.lock().unwrap().capacity = capacity;
    }

    fn files(&self) -> BTreeMap<PathBuf, Vec<u8>> {
        self.0.lock().unwrap().files.clone()
    }

    fn creates(&self) -> Vec<Instant> {
        self.0.lock().unwrap().creates.clone()
    }

    fn removed(&self) -> Vec<usize> {
        self.0.lock().unwrap().removed.clone()
    }
}

struct DiskFile {
    disk: Disk,
    path: PathBuf,
}

impl Storage for Disk {
    fn create(&mut self, part: u32) -> io::Result<(PathBuf, Box<dyn StorageFile>)> {
        let mut state = self.0.lock().unwrap();
        let path = PathBuf::from(format!("mem-{part:03}.mcap"));
        if state.files.contains_key(&path) {
            return Err(io::Error::new(io::ErrorKind::AlreadyExists, "exists"));
        }
        // As on a real full disk, an empty file can be made.
        state.files.insert(path.clone(), Vec::new());
        state.creates.push(Instant::now());
        let file = DiskFile {
            disk: self.clone(),
            path: path.clone(),
        };
        Ok((path, Box::new(file)))
    }

    fn remove(&mut self, path: &Path) -> io::Result<()> {
        let mut state = self.0.lock().unwrap();
        let file = state.files.remove(path).ok_or_else(|| {
            io::Error::new(io::ErrorKind::NotFound, format!("{}", path.display()))
        })?;
        state.removed.push(file.len());
        Ok(())
    }
}

impl StorageFile for DiskFile {
    fn write_all(&mut self, data: &[u8]) -> io::Result<()> {
        let mut state = self.disk.0.lock().unwrap();
        let used: u64 = state.files.values().map(|f| f.len() as u64).sum();
        let n = (state.capacity.saturating_sub(used) as usize).min(data.len());
        let file = state.files.get_mut(&self.path).expect("file exists");
        file.extend_from_slice(&data[..n]);
        if n < data.len() {
            return Err(io::Error::new(
                io::ErrorKind::StorageFull,
                "No space left on device",
            ));
        }
        Ok(())
    }

    fn truncate(&mut self, len: u64) -> io::Result<()> {
        let mut state = self.disk.0.lock().unwrap();
        let file = state.files.get_mut(&self.path).expect("file exists");
        file.truncate(len as usize);
        Ok(())
    }

    fn sync(&mut self) -> io::Result<()> {
        Ok(())
    }
}

fn config() -> RecorderConfig {
    RecorderConfig {
        retry_after: FIRST_WAIT,
        retry_max: MAX_WAIT,
        ..RecorderConfig::default()
    }
}

/// Writes messages from `next` on, a chunk every 10 messages (as seconds passing would),
/// until `until` holds for the status (at most 20 s); returns the next message's number.
fn write_until(
    handle: &RecorderHandle,
    ch: ChannelId,
    mut next: u64,
    until: impl Fn(&RecorderStatus) -> bool,
) -> u64 {
    let deadline = Instant::now() + Duration::from_secs(20);
    loop {
        assert!(
            Instant::now() < deadline,
            "never got there: {:?}",
            handle.status()
        );
        for _ in 0..10 {
            handle.write_json(ch, T0 + next, &log(next));
            next += 1;
        }
        assert!(handle.flush(Duration::from_secs(10)), "flush answered");
        if until(&handle.status()) {
            return next;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Between files created one after the other, each of which failed at once (its creation or
/// first write): every gap at least the wait the back-off promised after it — `first`, then
/// doubling up to the cap — since a try never comes early.
fn assert_tries_back_off(creates: &[Instant], first: Duration) {
    let mut wait = first;
    for (k, pair) in creates.windows(2).enumerate() {
        let gap = pair[1] - pair[0];
        assert!(gap >= wait, "gap {} was {gap:?}, under {wait:?}", k + 1);
        wait = (wait * 2).min(MAX_WAIT);
    }
}

fn messages_in(file: &[u8]) -> (u64, IndexSource) {
    let rec = Recording::from_reader(Cursor::new(file)).expect("the file reads");
    (rec.message_count(), rec.index())
}

#[test]
fn a_disk_that_fills_keeps_one_file_tries_with_growing_waits_and_resumes_in_the_next() {
    let disk = Disk::with_capacity(40_000);
    let (core, ch) = new_core();
    let recorder = Recorder::spawn(core, disk.clone(), config()).unwrap();
    let handle = recorder.handle();
    let mut sent = write_until(&handle, ch, 0, |s| s.failing.is_some());
    // The disk stays full for a while: four tries or more.
    sent = write_until(&handle, ch, sent, |s| {
        s.failing.is_some_and(|f| f.failed_tries >= 5)
    });
    let status = handle.status();
    let failing = status.failing.expect("failing");
    assert_eq!(status.current_file, None, "{status:?}");
    assert!(failing.next_try_in <= MAX_WAIT, "{failing:?}");
    assert!(failing.duration >= FIRST_WAIT * 15, "{failing:?}");
    assert!(failing.messages_lost > 0, "{failing:?}");
    assert_eq!(status.last_error.map(|e| e.kind), Some(IssueKind::Write));
    assert_eq!(status.files_started, 1, "only the kept file counts");
    // One file on the disk: the kept one, cut at its last whole chunk.
    let files = disk.files();
    let names: Vec<_> = files.keys().cloned().collect();
    assert_eq!(
        names,
        [PathBuf::from("mem-001.mcap")],
        "no file of a failed try"
    );
    let kept = files.values().next().unwrap().clone();
    let (in_kept, index) = messages_in(&kept);
    assert!(in_kept > 0);
    assert_eq!(
        index,
        IndexSource::Scan {
            cut_at: Some(kept.len() as u64),
            bad_chunks: 0
        },
        "ends between records"
    );
    let creates = disk.creates();
    assert!(creates.len() >= 5, "{} files made", creates.len());
    // The kept file's failure waited 40 ms for the first try; each try failed in turn.
    assert_tries_back_off(&creates[1..], FIRST_WAIT * 2);
    // Space returns: recording resumes at the next try, in file 2.
    disk.set_capacity(u64::MAX);
    sent = write_until(&handle, ch, sent, |s| s.resumed.is_some());
    let status = handle.status();
    assert_eq!(status.failing, None);
    let resumed = status.resumed.expect("resumed");
    assert!(resumed.after >= failing.duration, "{resumed:?}");
    assert!(
        resumed.messages_lost >= failing.messages_lost,
        "{resumed:?}"
    );
    assert_eq!(
        status.current_file,
        Some(PathBuf::from("mem-002.mcap")),
        "the file after the kept one"
    );
    sent = write_until(&handle, ch, sent, |_| true);
    let status = recorder.finish();
    assert_eq!(
        status.messages_written + status.messages_lost,
        sent,
        "{status:?}"
    );
    assert_eq!(
        status.messages_lost, resumed.messages_lost,
        "lost only while failing"
    );
    assert_eq!(status.files_started, 2);
    let files = disk.files();
    let names: Vec<_> = files.keys().cloned().collect();
    assert_eq!(
        names,
        [PathBuf::from("mem-001.mcap"), PathBuf::from("mem-002.mcap")]
    );
    assert_eq!(files[&names[0]], kept, "the kept file is not written again");
    let (in_next, index) = messages_in(&files[&names[1]]);
    assert_eq!(
        index,
        IndexSource::Summary,
        "the file after the outage is whole"
    );
    assert_eq!(in_kept + in_next, status.messages_written);
    assert_eq!(
        status.bytes_written,
        files.values().map(|f| f.len() as u64).sum::<u64>()
    );
    // `recover` makes the kept file whole with every message it holds.
    let mut whole = Cursor::new(Vec::new());
    let report = recover(&kept[..], &mut whole).unwrap();
    assert_eq!(report.messages, in_kept);
    let (recovered, index) = messages_in(whole.get_ref());
    assert_eq!((recovered, index), (in_kept, IndexSource::Summary));
}

#[test]
fn a_disk_full_from_the_start_or_with_room_for_a_header_only_leaves_no_file_behind() {
    let disk = Disk::with_capacity(0);
    let (core, ch) = new_core();
    let recorder = Recorder::spawn(core, disk.clone(), config()).unwrap();
    let handle = recorder.handle();
    let mut sent = write_until(&handle, ch, 0, |s| {
        s.failing.is_some_and(|f| f.failed_tries >= 3)
    });
    assert!(disk.files().is_empty(), "{:?}", disk.files().keys());
    // Room for the file's header and not a chunk more: still failing, still no file.
    disk.set_capacity(header_bytes() + 100);
    let tries = handle.status().failing.expect("failing").failed_tries;
    sent = write_until(&handle, ch, sent, |s| {
        s.failing.is_some_and(|f| f.failed_tries >= tries + 2)
    });
    let status = handle.status();
    assert!(disk.files().is_empty(), "{:?}", disk.files().keys());
    assert_eq!((status.files_started, status.bytes_written), (0, 0));
    assert_eq!(status.messages_written, 0);
    let creates = disk.creates();
    assert!(creates.len() >= 4, "{} files made", creates.len());
    assert_tries_back_off(&creates, FIRST_WAIT);
    // The tries with room for a header (two or more) wrote it and removed the file.
    let with_header = disk.removed().iter().filter(|&&n| n > 0).count();
    assert!(with_header >= 2, "{:?}", disk.removed());
    // Space returns: the run's first file is file 1.
    disk.set_capacity(u64::MAX);
    sent = write_until(&handle, ch, sent, |s| s.resumed.is_some());
    let status = recorder.finish();
    let files = disk.files();
    let names: Vec<_> = files.keys().cloned().collect();
    assert_eq!(names, [PathBuf::from("mem-001.mcap")]);
    let (messages, index) = messages_in(&files[&names[0]]);
    assert_eq!(
        (messages, index),
        (status.messages_written, IndexSource::Summary)
    );
    assert_eq!(status.messages_written + status.messages_lost, sent);
    assert!(
        status.messages_lost > 0 && status.messages_written > 0,
        "{status:?}"
    );
    assert_eq!(status.files_started, 1);
}
