//! Recordings made for tests: the writer core driven on a fake clock into memory, with the
//! list of every message written, in file order.

#![allow(dead_code)]

use std::time::Duration;

use serde_json::json;
use stx_record::{
    ChannelSpec, Compression, CoreOptions, Direction, MavlinkFrame, Output, RecorderCore,
    RecordingInfo, foxglove, frame,
};

/// 2026-01-01T00:00:00Z, ns.
pub const T0: u64 = 1_767_225_600_000_000_000;

/// A message as written: topic, sequence on its channel, log time, payload.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Written {
    pub topic: String,
    pub sequence: u32,
    pub log_time: u64,
    pub data: Vec<u8>,
}

/// One file's bytes and every message in it, in file order.
pub struct Made {
    pub bytes: Vec<u8>,
    pub written: Vec<Written>,
}

pub const TOPICS: [&str; 5] = [
    "/vehicle/fix",
    "/events",
    "/mavlink",
    "/estimate",
    "/vehicle/attitude",
];

/// `n` messages over the five channels (in turn), one every `step_ms` of the core's clock (chunks close
/// each second or at `chunk_bytes`); log times are the clock, so they rise with the file.
pub fn make(n: u64, step_ms: u64, chunk_bytes: u64, compression: Compression) -> Made {
    let options = CoreOptions {
        chunk_bytes,
        compression,
        max_file_bytes: None,
        max_file_duration: None,
        ..CoreOptions::default()
    };
    let info = RecordingInfo::new("0.1.0", "straplex-1", "test flight");
    let mut core = RecorderCore::new(options, info, Duration::ZERO).unwrap();
    let specs = [
        foxglove::location_fix_channel(TOPICS[0]).unwrap(),
        foxglove::log_channel(TOPICS[1]).unwrap(),
        frame::mavlink_frame_channel(TOPICS[2]).unwrap(),
        ChannelSpec::json(
            TOPICS[3],
            "stx.Estimate",
            &json!({"type": "object", "properties": {"i": {"type": "integer"}}}),
        )
        .unwrap(),
        foxglove::frame_transform_channel(TOPICS[4]).unwrap(),
    ];
    let ids: Vec<_> = specs
        .into_iter()
        .map(|s| core.add_channel(Duration::ZERO, s).unwrap())
        .collect();
    let mut sequences = [0u32; 5];
    let mut written = Vec::new();
    for i in 0..n {
        let now = Duration::from_millis(i * step_ms);
        let log_time = T0 + now.as_nanos() as u64;
        let k = (i % 5) as usize;
        let data = payload(k, i, log_time);
        core.write(now, ids[k], log_time, log_time, &data).unwrap();
        written.push(Written {
            topic: TOPICS[k].to_owned(),
            sequence: sequences[k],
            log_time,
            data,
        });
        sequences[k] += 1;
    }
    core.finish().unwrap();
    let mut bytes = Vec::new();
    while let Some(out) = core.poll_output() {
        match out {
            Output::Bytes { data, .. } => bytes.extend(data),
            Output::StartFile { part } => assert_eq!(part, 1, "one file"),
            Output::EndFile => {}
            Output::Lost { messages } => panic!("{messages} messages lost"),
        }
    }
    Made { bytes, written }
}

/// The bytes of the MAVLink frame written as message `i`.
pub fn frame_bytes(i: u64) -> Vec<u8> {
    (0..(12 + i % 40)).map(|b| (b * 7 + i) as u8).collect()
}

fn payload(k: usize, i: u64, log_time: u64) -> Vec<u8> {
    let ts = foxglove::Timestamp::from_nanos(log_time);
    match k {
        0 => serde_json::to_vec(&foxglove::LocationFix {
            timestamp: ts,
            frame_id: "vehicle".into(),
            latitude: 46.5 + i as f64 * 1e-5,
            longitude: 7.1,
            altitude: 3000.0 - i as f64,
            position_covariance: [4.0, 0.0, 0.0, 0.0, 4.0, 0.0, 0.0, 0.0, 9.0],
            position_covariance_type: foxglove::PositionCovarianceType::DiagonalKnown,
        })
        .unwrap(),
        1 => serde_json::to_vec(&foxglove::Log {
            timestamp: ts,
            level: foxglove::LogLevel::Info,
            message: format!("event {i}"),
            name: "station".into(),
            file: String::new(),
            line: 0,
        })
        .unwrap(),
        2 => MavlinkFrame::encode(Direction::Rx, (i % 2) as u16, log_time, &frame_bytes(i)),
        3 => serde_json::to_vec(&json!({"i": i})).unwrap(),
        _ => serde_json::to_vec(&foxglove::FrameTransform {
            timestamp: ts,
            parent_frame_id: "mission".into(),
            child_frame_id: "vehicle".into(),
            translation: foxglove::Vector3 {
                x: i as f64,
                y: 0.5,
                z: -(i as f64),
            },
            rotation: foxglove::Quaternion {
                x: 0.0,
                y: 0.0,
                z: (i as f64 * 0.01).sin(),
                w: (i as f64 * 0.01).cos(),
            },
        })
        .unwrap(),
    }
}

/// Per whole file: each chunk's start and end offsets and how many messages it holds, in file
/// order, from `mcap`'s own reading of the summary and chunks.
pub fn chunk_ends(file: &[u8]) -> Vec<(u64, u64, usize)> {
    let summary = mcap::Summary::read(file).unwrap().expect("summary");
    let mut chunks: Vec<_> = summary.chunk_indexes.clone();
    chunks.sort_by_key(|c| c.chunk_start_offset);
    chunks
        .iter()
        .map(|c| {
            let messages = summary.stream_chunk(file, c).unwrap().count();
            (
                c.chunk_start_offset,
                c.chunk_start_offset + c.chunk_length,
                messages,
            )
        })
        .collect()
}

/// Messages of a whole file by `mcap`'s own reader, in file order.
pub fn read_back(file: &[u8]) -> Vec<Written> {
    mcap::MessageStream::new(file)
        .unwrap()
        .map(|m| {
            let m = m.unwrap();
            Written {
                topic: m.channel.topic.clone(),
                sequence: m.sequence,
                log_time: m.log_time,
                data: m.data.into_owned(),
            }
        })
        .collect()
}
