//! What starting and seeking a replay of a 3-hour flight costs: `open_3h` opens the file
//! (summary, channels, time range — what `stx replay` does before it plays) and `seek_3h`
//! reads the first message at a pseudo-random time of the flight through the chunk index
//! (what a seek on the page's timeline does). The file is made once, at the station's
//! rates: every 250 ms six received frames, six decoded telemetry messages, a GPS fix and an
//! attitude transform; every second a ~3.9 kB `state` (JSON payloads of those sizes, varying
//! numbers so zstd does not flatter them), chunks closed each second as in flight.
//!
//! `cargo bench -p stx-record --bench replay_seek` prints the file's size beside the figures.

use std::hint::black_box;
use std::io::Write;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use serde_json::json;
use stx_record::foxglove::{self, Timestamp};
use stx_record::{
    ChannelSpec, CoreOptions, Direction, MavlinkFrame, Output, RecorderCore, Recording,
    RecordingInfo, frame,
};

const T0: u64 = 1_767_225_600_000_000_000;
const HOURS: u64 = 3;

fn make(path: &std::path::Path) {
    let mut core = RecorderCore::new(
        CoreOptions::default(),
        RecordingInfo::default(),
        Duration::ZERO,
    )
    .unwrap();
    let object = json!({"type": "object"});
    let frames = core
        .add_channel(
            Duration::ZERO,
            frame::mavlink_frame_channel("/mavlink/frames").unwrap(),
        )
        .unwrap();
    let telemetry = core
        .add_channel(
            Duration::ZERO,
            ChannelSpec::json("/telemetry/X", "stx.telemetry.X", &object).unwrap(),
        )
        .unwrap();
    let fix = core
        .add_channel(
            Duration::ZERO,
            foxglove::location_fix_channel("/vehicle/gps").unwrap(),
        )
        .unwrap();
    let state = core
        .add_channel(
            Duration::ZERO,
            ChannelSpec::json("/station/state", "stx.StateMsg", &object).unwrap(),
        )
        .unwrap();
    let mut file = std::fs::File::create(path).unwrap();
    let mut drain = |core: &mut RecorderCore| {
        while let Some(out) = core.poll_output() {
            if let Output::Bytes { data, .. } = out {
                file.write_all(&data).unwrap();
            }
        }
    };
    let ticks = HOURS * 3600 * 4;
    for k in 0..ticks {
        let now = Duration::from_millis(k * 250);
        let t = T0 + now.as_nanos() as u64;
        let x = k as f64 * 0.013;
        for i in 0..6u64 {
            let bytes: Vec<u8> = (0..40u64).map(|b| (b * 31 + k * 7 + i) as u8).collect();
            core.write(
                now,
                frames,
                t,
                t,
                &MavlinkFrame::encode(Direction::Rx, 0, t, &bytes),
            )
            .unwrap();
            let msg = json!({"time_boot_ms": k * 250, "lat_deg": 38.5 + x.sin() * 1e-3,
                "lon_deg": -7.9 + x.cos() * 1e-3, "alt_msl_m": 3000.0 - x, "vx": x.sin() * 7.0,
                "vy": x.cos() * 7.0, "vz": 3.1 + (x * 3.0).sin(), "heading_deg": (x * 40.0) % 360.0, "i": i});
            core.write(now, telemetry, t, t, msg.to_string().as_bytes())
                .unwrap();
        }
        let gps = foxglove::LocationFix {
            timestamp: Timestamp::from_nanos(t),
            frame_id: "gps".into(),
            latitude: 38.5 + x.sin() * 1e-3,
            longitude: -7.9 + x.cos() * 1e-3,
            altitude: 3000.0 - x,
            position_covariance: [2.56, 0.0, 0.0, 0.0, 2.56, 0.0, 0.0, 0.0, 6.25],
            position_covariance_type: foxglove::PositionCovarianceType::DiagonalKnown,
        };
        core.write(now, fix, t, t, &serde_json::to_vec(&gps).unwrap())
            .unwrap();
        if k % 4 == 0 {
            // About the size of the station's `state`, numbers varying.
            let fields: serde_json::Map<String, serde_json::Value> = (0..120)
                .map(|f| (format!("field_{f}"), json!((x * f as f64).sin() * 1000.0)))
                .collect();
            core.write(
                now,
                state,
                t,
                t,
                serde_json::to_string(&fields).unwrap().as_bytes(),
            )
            .unwrap();
        }
        drain(&mut core);
    }
    core.finish().unwrap();
    drain(&mut core);
}

fn bench(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("three-hours.mcap");
    make(&path);
    let size = std::fs::metadata(&path).unwrap().len();
    eprintln!(
        "a {HOURS}-hour recording at the station's rates: {:.1} MB",
        size as f64 / 1e6
    );
    let mut group = c.benchmark_group("replay");
    group.sample_size(20);
    group.bench_function("open_3h", |b| {
        b.iter(|| {
            let rec = Recording::open(&path).unwrap();
            black_box(rec.time_range())
        })
    });
    let mut rec = Recording::open(&path).unwrap();
    let span = HOURS * 3600 * 1_000_000_000;
    let mut k: u64 = 1;
    group.bench_function("seek_3h", |b| {
        b.iter(|| {
            // A pseudo-random place in the flight.
            k = k
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let at = T0 + (k >> 11) % span;
            let first = rec.messages_from(at).unwrap().next().unwrap().unwrap();
            black_box(first.log_time)
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
