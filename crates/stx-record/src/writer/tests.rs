//! The writer core on a fake clock: `now` is whatever the test says.

use super::*;
use crate::foxglove;
use crate::info::{METADATA_NAME, RecordingInfo};
use serde_json::json;

const S: Duration = Duration::from_secs(1);
const T0: u64 = 1_767_225_600_000_000_000;

fn ms(n: u64) -> Duration {
    Duration::from_millis(n)
}

fn info() -> RecordingInfo {
    RecordingInfo::new("0.1.0", "straplex-1", "test flight")
}

fn core_with(options: CoreOptions) -> (RecorderCore, ChannelId, ChannelId) {
    let mut core = RecorderCore::new(options, info(), Duration::ZERO).unwrap();
    let a = core
        .add_channel(Duration::ZERO, foxglove::log_channel("/events").unwrap())
        .unwrap();
    let spec = ChannelSpec::json("/estimate", "stx.Estimate", &json!({"type": "object"})).unwrap();
    let b = core.add_channel(Duration::ZERO, spec).unwrap();
    // The channels' records leave in their own chunk, so the tests' chunks hold messages only.
    core.flush(Duration::ZERO).unwrap();
    (core, a, b)
}

fn drain(core: &mut RecorderCore) -> Vec<Output> {
    std::iter::from_fn(|| core.poll_output()).collect()
}

/// Messages in the `Bytes` outputs.
fn messages_out(outputs: &[Output]) -> Vec<u64> {
    outputs
        .iter()
        .filter_map(|o| match o {
            Output::Bytes { messages, .. } if *messages > 0 => Some(*messages),
            _ => None,
        })
        .collect()
}

/// The files the outputs describe, each as its bytes.
fn files(outputs: &[Output]) -> Vec<Vec<u8>> {
    let mut files: Vec<Vec<u8>> = Vec::new();
    for o in outputs {
        match o {
            Output::StartFile { part } => {
                assert_eq!(*part as usize, files.len() + 1, "parts count from 1");
                files.push(Vec::new());
            }
            Output::Bytes { data, .. } => {
                files.last_mut().expect("bytes before a file").extend(data)
            }
            Output::EndFile => {}
            Output::Lost { messages } => panic!("{messages} messages lost"),
        }
    }
    files
}

fn payload(i: u64) -> Vec<u8> {
    format!(r#"{{"i":{i}}}"#).into_bytes()
}

/// Every message of a whole file, by `mcap`'s own reader: (topic, log time, payload).
fn read_all(file: &[u8]) -> Vec<(String, u64, Vec<u8>)> {
    mcap::MessageStream::new(file)
        .unwrap()
        .map(|m| {
            let m = m.unwrap();
            (m.channel.topic.clone(), m.log_time, m.data.into_owned())
        })
        .collect()
}

#[test]
fn a_quiet_chunk_closes_when_its_second_is_up() {
    let (mut core, a, _) = core_with(CoreOptions::default());
    drain(&mut core);
    core.write(ms(100), a, T0, T0, &payload(1)).unwrap();
    assert_eq!(messages_out(&drain(&mut core)), Vec::<u64>::new());
    assert_eq!(core.poll_timeout(), Some(ms(1100)));
    core.handle_timeout(ms(1099)).unwrap();
    assert!(drain(&mut core).is_empty(), "closed early");
    core.handle_timeout(ms(1100)).unwrap();
    assert_eq!(messages_out(&drain(&mut core)), vec![1]);
    assert_eq!(core.poll_timeout(), None, "nothing open after the close");
}

#[test]
fn a_busy_chunk_never_holds_more_than_a_second() {
    let (mut core, a, b) = core_with(CoreOptions::default());
    // 100 Hz for 3.5 s, the adapter never calling handle_timeout: the writes close chunks.
    for i in 0..350u64 {
        let ch = if i % 2 == 0 { a } else { b };
        core.write(ms(10 * i), ch, T0 + i, T0 + i, &payload(i))
            .unwrap();
    }
    let counts = messages_out(&drain(&mut core));
    assert_eq!(counts, vec![100, 100, 100], "one chunk per second");
    core.finish().unwrap();
    let outputs = drain(&mut core);
    assert_eq!(
        messages_out(&outputs),
        vec![50],
        "the open half second closes at finish"
    );
    assert_eq!(outputs.last(), Some(&Output::EndFile));
}

#[test]
fn a_chunk_closes_at_its_size() {
    let options = CoreOptions {
        chunk_bytes: 1000,
        ..CoreOptions::default()
    };
    let (mut core, a, _) = core_with(options);
    drain(&mut core);
    let big = vec![b'x'; 200];
    for i in 0..20 {
        core.write(Duration::ZERO, a, T0 + i, T0 + i, &big).unwrap();
    }
    // 231 B per message record: the fifth passes 1000 B.
    assert_eq!(messages_out(&drain(&mut core)), vec![5, 5, 5, 5]);
}

#[test]
fn files_rotate_at_their_size_and_each_is_whole() {
    let options = CoreOptions {
        chunk_bytes: 2000,
        max_file_bytes: Some(10_000),
        compression: Compression::None,
        ..CoreOptions::default()
    };
    let (mut core, a, b) = core_with(options);
    let mut written = Vec::new();
    for i in 0..600u64 {
        let ch = if i % 3 == 0 { a } else { b };
        let data = payload(i);
        core.write(ms(i), ch, T0 + i, T0 + i, &data).unwrap();
        written.push((
            if i % 3 == 0 { "/events" } else { "/estimate" },
            T0 + i,
            data,
        ));
    }
    core.finish().unwrap();
    let outputs = drain(&mut core);
    let files = files(&outputs);
    assert!(files.len() >= 3, "{} files", files.len());
    let mut read = Vec::new();
    for (n, file) in files.iter().enumerate() {
        // Each file has its summary, its own metadata record (with its part) and both channels.
        let summary = mcap::Summary::read(file).unwrap().expect("a summary");
        let topics: Vec<_> = summary.channels.values().map(|c| c.topic.clone()).collect();
        assert_eq!(topics.len(), 2, "{topics:?}");
        assert_eq!(summary.metadata_indexes.len(), 1);
        let meta = mcap::read::metadata(file, &summary.metadata_indexes[0]).unwrap();
        assert_eq!(meta.name, METADATA_NAME);
        assert_eq!(meta.metadata["part"], (n + 1).to_string());
        // A file's data pass its size by at most one chunk (and its record's framing); the
        // summary follows.
        let data_end = mcap::read::footer(file).unwrap().summary_start;
        assert!(
            data_end < 10_000 + 2_100 + 1_100,
            "file {n}: {data_end} B of data"
        );
        read.extend(read_all(file));
    }
    assert_eq!(read.len(), written.len());
    for ((topic, time, data), (wt, wtime, wdata)) in read.iter().zip(&written) {
        assert_eq!((topic.as_str(), *time, data), (*wt, *wtime, wdata));
    }
}

#[test]
fn files_rotate_at_their_duration() {
    let options = CoreOptions {
        max_file_duration: Some(Duration::from_secs(10)),
        ..CoreOptions::default()
    };
    let (mut core, a, _) = core_with(options);
    for i in 0..35u64 {
        core.write(S * i as u32, a, T0 + i, T0 + i, &payload(i))
            .unwrap();
    }
    core.finish().unwrap();
    let outputs = drain(&mut core);
    let starts: Vec<_> = outputs
        .iter()
        .filter(|o| matches!(o, Output::StartFile { .. }))
        .collect();
    assert_eq!(starts.len(), 4, "0-10 s, 10-20 s, 20-30 s, 30-35 s");
    let total: usize = files(&outputs).iter().map(|f| read_all(f).len()).sum();
    assert_eq!(total, 35);
}

#[test]
fn a_file_names_its_channels_and_metadata_before_any_message() {
    let (mut core, _, _) = core_with(CoreOptions::default());
    let outputs = drain(&mut core);
    assert_eq!(outputs[0], Output::StartFile { part: 1 });
    assert_eq!(messages_out(&outputs), Vec::<u64>::new());
    // The file cut right here (no summary, no footer) already says what it records.
    let file = &files(&outputs)[0];
    let records: Vec<_> = mcap::read::ChunkFlattener::new_with_options(
        file,
        mcap::read::Options::IgnoreEndMagic.into(),
    )
    .unwrap()
    .collect();
    let mut names = Vec::new();
    for r in records {
        match r {
            Ok(mcap::records::Record::Metadata(m)) => names.push(m.name),
            Ok(mcap::records::Record::Channel(c)) => names.push(c.topic),
            Ok(_) => {}
            // The end of the cut file.
            Err(_) => break,
        }
    }
    assert_eq!(names, [METADATA_NAME, "/events", "/estimate"]);
}

#[test]
fn rotation_keeps_channels_registered_in_every_file() {
    let mut core = RecorderCore::new(CoreOptions::default(), info(), Duration::ZERO).unwrap();
    let a = core
        .add_channel(Duration::ZERO, foxglove::log_channel("/events").unwrap())
        .unwrap();
    core.write(ms(1), a, T0, T0, &payload(0)).unwrap();
    core.start_new_file(ms(2)).unwrap();
    core.write(ms(3), a, T0 + 1, T0 + 1, &payload(1)).unwrap();
    core.finish().unwrap();
    let files = files(&drain(&mut core));
    assert_eq!(files.len(), 2);
    for (n, f) in files.iter().enumerate() {
        let got = read_all(f);
        assert_eq!(
            got,
            [("/events".to_owned(), T0 + n as u64, payload(n as u64))]
        );
    }
}

#[test]
fn a_file_started_again_keeps_its_number_and_its_channels() {
    let mut core = RecorderCore::new(CoreOptions::default(), info(), Duration::ZERO).unwrap();
    let a = core
        .add_channel(Duration::ZERO, foxglove::log_channel("/events").unwrap())
        .unwrap();
    core.write(ms(1), a, T0, T0, &payload(0)).unwrap();
    // The adapter removed what it had of file 1 (a full disk): the core starts it again.
    core.restart_file(ms(2)).unwrap();
    core.write(ms(3), a, T0 + 1, T0 + 1, &payload(1)).unwrap();
    core.finish().unwrap();
    let outputs = drain(&mut core);
    let parts: Vec<u32> = outputs
        .iter()
        .filter_map(|o| match o {
            Output::StartFile { part } => Some(*part),
            _ => None,
        })
        .collect();
    assert_eq!(parts, [1, 1]);
    assert_eq!(core.part(), 1);
    // The second file 1 is whole on its own and names its channel.
    let second = outputs
        .iter()
        .skip_while(|o| **o != Output::EndFile)
        .filter_map(|o| match o {
            Output::Bytes { data, .. } => Some(data.clone()),
            _ => None,
        })
        .flatten()
        .collect::<Vec<u8>>();
    assert_eq!(
        read_all(&second),
        [("/events".to_owned(), T0 + 1, payload(1))]
    );
}

#[test]
fn bad_calls_are_refused() {
    let (mut core, a, _) = core_with(CoreOptions::default());
    assert!(matches!(
        core.write(Duration::ZERO, ChannelId(9), T0, T0, b"{}"),
        Err(WriteError::UnknownChannel(ChannelId(9)))
    ));
    let again = foxglove::log_channel("/events").unwrap();
    assert!(matches!(
        core.add_channel(Duration::ZERO, again),
        Err(WriteError::Channel(ChannelError::DuplicateTopic { .. }))
    ));
    core.finish().unwrap();
    assert!(matches!(
        core.write(Duration::ZERO, a, T0, T0, b"{}"),
        Err(WriteError::Finished)
    ));
    assert!(core.finish().is_ok(), "finishing twice is harmless");
}

#[test]
fn sequence_numbers_count_per_channel() {
    let (mut core, a, b) = core_with(CoreOptions::default());
    for i in 0..6u64 {
        let ch = if i < 4 { a } else { b };
        core.write(ms(i), ch, T0 + i, T0 + i, &payload(i)).unwrap();
    }
    core.finish().unwrap();
    let file = &files(&drain(&mut core))[0];
    let seqs: Vec<(String, u32)> = mcap::MessageStream::new(file)
        .unwrap()
        .map(|m| {
            let m = m.unwrap();
            (m.channel.topic.clone(), m.sequence)
        })
        .collect();
    let expect = [
        ("/events", 0),
        ("/events", 1),
        ("/events", 2),
        ("/events", 3),
        ("/estimate", 0),
        ("/estimate", 1),
    ];
    let expect: Vec<(String, u32)> = expect.iter().map(|(t, s)| (t.to_string(), *s)).collect();
    assert_eq!(seqs, expect);
}
