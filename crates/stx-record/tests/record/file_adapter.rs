//! The file adapter: recording to a directory, and what happens when the disk will not take
//! the data — the caller is never held up, and every message is counted written or lost.
//! (A disk that fills up and frees again: full_disk.rs.)

use std::io;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::{Duration, SystemTime};

use stx_record::file::recordings_dir;
use stx_record::{
    ChannelId, CoreOptions, Directory, IssueKind, Recorder, RecorderConfig, RecorderCore,
    Recording, RecordingInfo, Storage, StorageFile, foxglove,
};

const T0: u64 = 1_767_225_600_000_000_000;

fn new_core() -> (RecorderCore, ChannelId) {
    let info = RecordingInfo::new("0.1.0", "straplex-1", "adapter test");
    let mut core = RecorderCore::new(CoreOptions::default(), info, Duration::ZERO).unwrap();
    let ch = core
        .add_channel(Duration::ZERO, foxglove::log_channel("/events").unwrap())
        .unwrap();
    (core, ch)
}

fn log(i: u64) -> foxglove::Log {
    foxglove::Log {
        timestamp: foxglove::Timestamp::from_nanos(T0 + i),
        level: foxglove::LogLevel::Info,
        message: format!("event {i}"),
        name: "test".into(),
        file: String::new(),
        line: 0,
    }
}

fn quick() -> RecorderConfig {
    RecorderConfig {
        retry_after: Duration::from_millis(10),
        retry_max: Duration::from_millis(10),
        ..RecorderConfig::default()
    }
}

#[test]
fn records_to_the_state_directory_and_reads_back() {
    let state = tempfile::tempdir().unwrap();
    let dir = recordings_dir(state.path());
    assert_eq!(dir, state.path().join("recordings"));
    // 2026-01-01T00:00:00Z.
    let started = SystemTime::UNIX_EPOCH + Duration::from_secs(1_767_225_600);
    let storage = Directory::new(&dir, started);
    assert_eq!(storage.file_name(1), "stx-20260101T000000Z-001.mcap");
    let (core, ch) = new_core();
    let recorder = Recorder::spawn(core, storage, RecorderConfig::default()).unwrap();
    let handle = recorder.handle();
    for i in 0..500 {
        assert!(handle.write_json(ch, T0 + i, &log(i)));
    }
    assert!(handle.flush(Duration::from_secs(10)), "flush answered");
    let mid = handle.status();
    assert_eq!(mid.messages_written, 500, "{mid:?}");
    let path = mid.current_file.clone().unwrap();
    assert_eq!(path, dir.join("stx-20260101T000000Z-001.mcap"));
    let status = recorder.finish();
    assert_eq!(
        (
            status.messages_written,
            status.messages_lost,
            status.files_started
        ),
        (500, 0, 1)
    );
    assert_eq!(status.current_file, None);
    assert_eq!(status.last_error, None);
    assert_eq!(
        status.bytes_written,
        std::fs::metadata(&path).unwrap().len()
    );
    let mut rec = Recording::open(&path).unwrap();
    assert_eq!(rec.message_count(), 500);
    let first = rec.messages().unwrap().next().unwrap().unwrap();
    let back: foxglove::Log = serde_json::from_slice(&first.data).unwrap();
    assert_eq!(back, log(0));
    // A second run in the same second does not overwrite the first.
    let (core, _) = new_core();
    let again = Recorder::spawn(core, Directory::new(&dir, started), quick()).unwrap();
    let second = again.status().current_file;
    let status = again.finish();
    assert_eq!(status.files_started, 1);
    assert_ne!(second, Some(path));
}

#[test]
fn an_unwritable_directory_loses_messages_counts_them_and_says_why() {
    let tmp = tempfile::tempdir().unwrap();
    // A directory inside a regular file can never be made (even by root).
    let file = tmp.path().join("not-a-directory");
    std::fs::write(&file, b"x").unwrap();
    let storage = Directory::new(file.join("recordings"), SystemTime::now());
    let (core, ch) = new_core();
    let recorder = Recorder::spawn(core, storage, quick()).unwrap();
    let handle = recorder.handle();
    for i in 0..300 {
        handle.write_json(ch, T0 + i, &log(i));
    }
    let status = recorder.finish();
    assert_eq!(status.messages_written, 0);
    assert_eq!(status.messages_lost, 300, "{status:?}");
    assert_eq!(status.files_started, 0);
    let issue = status.last_error.unwrap();
    assert_eq!(issue.kind, IssueKind::Create);
    assert!(issue.message.contains("cannot create"), "{}", issue.message);
}

/// A disk that takes nothing until the test lets it.
struct StalledDisk {
    gate: Arc<Mutex<mpsc::Receiver<()>>>,
}

struct StalledFile {
    gate: Arc<Mutex<mpsc::Receiver<()>>>,
    open: bool,
}

impl Storage for StalledDisk {
    fn create(&mut self, part: u32) -> io::Result<(PathBuf, Box<dyn StorageFile>)> {
        let file = StalledFile {
            gate: self.gate.clone(),
            open: false,
        };
        Ok((PathBuf::from(format!("stalled-{part}")), Box::new(file)))
    }

    fn remove(&mut self, _path: &Path) -> io::Result<()> {
        Ok(())
    }
}

impl StorageFile for StalledFile {
    fn write_all(&mut self, _data: &[u8]) -> io::Result<()> {
        if !self.open {
            // Blocks until the test sends (or drops the sender).
            let _ = self.gate.lock().unwrap().recv();
            self.open = true;
        }
        Ok(())
    }

    fn truncate(&mut self, _len: u64) -> io::Result<()> {
        Ok(())
    }

    fn sync(&mut self) -> io::Result<()> {
        Ok(())
    }
}

#[test]
fn a_stalled_disk_never_holds_up_the_caller() {
    let (open_tx, open_rx) = mpsc::channel();
    let storage = StalledDisk {
        gate: Arc::new(Mutex::new(open_rx)),
    };
    let (core, ch) = new_core();
    let config = RecorderConfig {
        queue_capacity: 8,
        ..RecorderConfig::default()
    };
    let recorder = Recorder::spawn(core, storage, config).unwrap();
    let handle = recorder.handle();
    // The writer thread is stuck on the file's first bytes; the caller sends 10 000 messages
    // from another thread, which must finish regardless.
    let (done_tx, done_rx) = mpsc::channel();
    let producer = handle.clone();
    std::thread::spawn(move || {
        let queued = (0..10_000u64)
            .filter(|i| producer.write_json(ch, T0 + i, &log(*i)))
            .count();
        done_tx.send(queued).unwrap();
    });
    let queued = done_rx
        .recv_timeout(Duration::from_secs(60))
        .expect("the caller was held up by a stalled disk");
    assert_eq!(queued, 8, "exactly the queue's capacity got in");
    let status = handle.status();
    assert_eq!(status.messages_lost, 9_992);
    assert_eq!(status.last_error.unwrap().kind, IssueKind::QueueFull);
    // The disk comes back: the queued messages are written, nothing else is lost.
    open_tx.send(()).unwrap();
    let status = recorder.finish();
    assert_eq!(
        (status.messages_written, status.messages_lost),
        (8, 9_992),
        "{status:?}"
    );
}

#[test]
fn messages_encoded_later_are_written_by_the_writer_in_order_and_counted() {
    let state = tempfile::tempdir().unwrap();
    let started = SystemTime::UNIX_EPOCH + Duration::from_secs(1_767_225_600);
    let (core, ch) = new_core();
    let recorder = Recorder::spawn(core, Directory::new(state.path(), started), quick()).unwrap();
    let handle = recorder.handle();
    for i in 0..100 {
        if i % 2 == 0 {
            assert!(handle.write_json(ch, T0 + i, &log(i)));
        } else {
            // Two messages from one deferred encoding.
            let encode = move || {
                vec![
                    (ch, serde_json::to_vec(&log(i)).unwrap()),
                    (ch, serde_json::to_vec(&log(i)).unwrap()),
                ]
            };
            assert!(handle.write_later(T0 + i, T0 + i, encode));
        }
    }
    let status = recorder.finish();
    assert_eq!((status.messages_written, status.messages_lost), (150, 0));
    let path = std::fs::read_dir(state.path())
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    let mut rec = Recording::open(&path).unwrap();
    let read: Vec<foxglove::Log> = rec
        .messages()
        .unwrap()
        .map(|m| serde_json::from_slice(&m.unwrap().data).unwrap())
        .collect();
    let expected: Vec<foxglove::Log> = (0..100)
        .flat_map(|i| std::iter::repeat_n(log(i), if i % 2 == 0 { 1 } else { 2 }))
        .collect();
    assert_eq!(read, expected);
}
