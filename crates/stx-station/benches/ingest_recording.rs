//! Ingest throughput with the station recording, on one core, as frames per second (criterion
//! `Throughput::Elements`): the station's link ([`StationLink`], the ground endpoint behind
//! the recorder's frame tap) fed the drone's telemetry, every event drained, and every decoded
//! telemetry message handed to the recording (`Recording::telemetry`), as the daemon's link
//! driver and station loop do. The recording is the real one: stx-record's writer thread
//! writing MCAP files into a temporary directory.
//!
//! - `udp_datagrams`: one frame per datagram, as the station's UDP radios deliver them (one raw
//!   entry recorded per frame);
//! - `udp_datagrams_not_recording`: the same without the recording, for comparison;
//! - `stream_chunks`: 4 KiB reads, as from a serial or TCP radio (one raw entry per read) —
//!   the input of stx-link's `ingest` bench.
//!
//! The writer thread is fed through a bounded queue and never holds the link up: at these
//! rates it falls behind and counts what it could not write. After the runs the bench prints
//! the recorder's own figures (messages written and lost), so a reader sees both.

use std::hint::black_box;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use stx_link::endpoint::{GroundConfig, GroundEndpoint, GroundEvent};
use stx_link::fixtures::telemetry_sample;
use stx_link::frame::FrameEncoder;
use stx_link::sansio::SansIo;
use stx_station::config::{DEFAULT_STATION_TOML, StationConfig};
use stx_station::link::{LinkReport, StationLink};
use stx_station::recorder::Recording;

const FRAMES: u32 = 10_000;

fn frames() -> Vec<Vec<u8>> {
    let mut enc = FrameEncoder::new(1, 1);
    (0..FRAMES)
        .map(|i| {
            let mut f = Vec::new();
            enc.encode_into(Duration::ZERO, &telemetry_sample(i).to_mavlink(), &mut f);
            f
        })
        .collect()
}

fn recording(dir: &std::path::Path) -> Recording {
    let mut config = StationConfig::from_toml_str(DEFAULT_STATION_TOML).expect("shipped config");
    config.recording.enabled = true;
    config.recording.dir = Some(dir.to_owned());
    let wall_ms = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_millis() as u64);
    let recording = Recording::start(&config, Instant::now(), wall_ms);
    assert!(
        matches!(recording, Recording::On(_)),
        "the bench must record: {:?}",
        recording.view().problem
    );
    recording
}

/// Drains `link`'s events into the recording; the telemetry messages seen.
fn drain(link: &mut StationLink, recording: &Recording) -> u32 {
    let mut n = 0;
    while let Some(event) = link.poll_event() {
        if let LinkReport::Event(GroundEvent::Telemetry { telemetry, .. }) = &event {
            recording.telemetry(black_box(telemetry));
            n += 1;
        }
    }
    n
}

fn ingest_recording(c: &mut Criterion) {
    let frames = frames();
    let stream: Vec<u8> = frames.concat();
    let dir = std::env::temp_dir().join(format!("stx-bench-ingest-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let recording = recording(&dir);
    let new_link = || {
        let tap = recording.frame_tap().expect("recording on");
        StationLink::new(GroundEndpoint::new(GroundConfig::default(), Duration::ZERO)).with_tap(tap)
    };
    let mut group = c.benchmark_group("ingest_recording");
    group.throughput(Throughput::Elements(u64::from(FRAMES)));
    group.bench_function("udp_datagrams", |b| {
        b.iter(|| {
            let mut link = new_link();
            let mut now = Duration::ZERO;
            let mut n = 0;
            for f in &frames {
                now += Duration::from_micros(300);
                link.handle_datagram_on(0, now, black_box(f));
                n += drain(&mut link, &recording);
            }
            assert_eq!(n, FRAMES);
            n
        })
    });
    // The same datagrams without recording, to show what recording costs.
    group.bench_function("udp_datagrams_not_recording", |b| {
        b.iter(|| {
            let mut link =
                StationLink::new(GroundEndpoint::new(GroundConfig::default(), Duration::ZERO));
            let mut now = Duration::ZERO;
            let mut n = 0;
            for f in &frames {
                now += Duration::from_micros(300);
                link.handle_datagram_on(0, now, black_box(f));
                while let Some(event) = link.poll_event() {
                    if let LinkReport::Event(GroundEvent::Telemetry { telemetry, .. }) = &event {
                        black_box(telemetry);
                        n += 1;
                    }
                }
            }
            assert_eq!(n, FRAMES);
            n
        })
    });
    group.bench_function("stream_chunks", |b| {
        b.iter(|| {
            let mut link = new_link();
            let mut now = Duration::ZERO;
            let mut n = 0;
            for chunk in stream.chunks(4096) {
                now += Duration::from_millis(3);
                link.handle_bytes_on(0, now, black_box(chunk));
                n += drain(&mut link, &recording);
            }
            assert_eq!(n, FRAMES);
            n
        })
    });
    group.finish();
    recording.finish();
    let status = recording.view();
    eprintln!(
        "recorder: {} messages written, {} lost (queue full: the writer fell behind), {:.1} MB",
        status.messages_written,
        status.messages_lost,
        status.bytes_written as f64 / 1e6
    );
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, ingest_recording);
criterion_main!(benches);
