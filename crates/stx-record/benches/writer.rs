//! Writer core throughput, reported as messages per second (criterion
//! `Throughput::Elements`): what the recorder's thread can take before its queue fills.
//!
//! - `core_zstd`: the default — JSON payloads of the station's kinds (positions, MAVLink
//!   frames in base64, events, frame transforms, an estimate), a clock advancing 5 ms a
//!   message (chunks close each second, as in flight), zstd chunks, every output drained.
//! - `core_uncompressed`: the same without compression, to see what zstd costs.
//!
//! Run by hand (`cargo bench -p stx-record`); figures are the lead's to take on a quiet
//! machine.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use serde_json::json;
use stx_record::foxglove::{self, Timestamp};
use stx_record::{
    ChannelId, ChannelSpec, Compression, CoreOptions, Direction, MavlinkFrame, RecorderCore,
    RecordingInfo, frame,
};

const T0: u64 = 1_767_225_600_000_000_000;
const MESSAGES: u64 = 20_000;

fn payloads() -> Vec<Vec<u8>> {
    let ts = Timestamp::from_nanos(T0);
    vec![
        serde_json::to_vec(&foxglove::LocationFix {
            timestamp: ts,
            frame_id: "vehicle".into(),
            latitude: 41.1779,
            longitude: -8.5977,
            altitude: 2873.25,
            position_covariance: [4.0, 0.1, 0.0, 0.1, 4.0, 0.0, 0.0, 0.0, 9.0],
            position_covariance_type: foxglove::PositionCovarianceType::Known,
        })
        .unwrap(),
        MavlinkFrame::encode(Direction::Rx, 0, T0, &[0xfd; 40]),
        serde_json::to_vec(&foxglove::Log {
            timestamp: ts,
            level: foxglove::LogLevel::Info,
            message: "guidance: spiral descent".into(),
            name: "station".into(),
            file: String::new(),
            line: 0,
        })
        .unwrap(),
        serde_json::to_vec(&json!({"position_ned_m": [12.5, -40.25, -2873.0],
                                   "velocity_ned_mps": [3.1, -1.2, 4.6], "phase": "spiral"}))
        .unwrap(),
    ]
}

fn core(compression: Compression) -> (RecorderCore, Vec<ChannelId>) {
    let options = CoreOptions {
        compression,
        ..CoreOptions::default()
    };
    let mut core = RecorderCore::new(options, RecordingInfo::default(), Duration::ZERO).unwrap();
    let specs = [
        foxglove::location_fix_channel("/vehicle/fix").unwrap(),
        frame::mavlink_frame_channel("/mavlink").unwrap(),
        foxglove::log_channel("/events").unwrap(),
        ChannelSpec::json("/estimate", "stx.Estimate", &json!({"type": "object"})).unwrap(),
    ];
    let ids = specs
        .into_iter()
        .map(|s| core.add_channel(Duration::ZERO, s).unwrap())
        .collect();
    (core, ids)
}

fn run(c: &mut Criterion, name: &str, compression: Compression) {
    let payloads = payloads();
    let mut group = c.benchmark_group("writer");
    group.throughput(Throughput::Elements(MESSAGES));
    group.bench_function(name, |b| {
        b.iter(|| {
            let (mut core, ids) = core(compression);
            for i in 0..MESSAGES {
                let k = (i % 4) as usize;
                let now = Duration::from_millis(5 * i);
                let t = T0 + now.as_nanos() as u64;
                core.write(now, ids[k], t, t, &payloads[k]).unwrap();
                while let Some(out) = core.poll_output() {
                    black_box(out);
                }
            }
            core.finish().unwrap();
            while let Some(out) = core.poll_output() {
                black_box(out);
            }
        })
    });
    group.finish();
}

fn benches(c: &mut Criterion) {
    run(c, "core_zstd", Compression::Zstd);
    run(c, "core_uncompressed", Compression::None);
}

criterion_group!(benches_group, benches);
criterion_main!(benches_group);
