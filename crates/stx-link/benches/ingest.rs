//! Ingest throughput on one core, reported as frames per second (criterion
//! `Throughput::Elements`).
//!
//! - `ground_endpoint`: the station's real path — [`GroundEndpoint::handle_bytes`] (decoding,
//!   link statistics, per-sender loss, per-kind ages, the micro-protocols' dispatch) and every
//!   [`GroundEvent`] drained, as the station's link task does; the goal is
//!   1,000,000 frames/s.
//! - `two_radios`: the same stream heard on two radios (`LinkConfig::paths = 2`), each frame
//!   decoded twice and its copy dropped; elements are the frames delivered once.
//! - `bytes_to_telemetry`: the decoder and the telemetry mapping alone, for comparison.
//!
//! The stream mixes the telemetry the drone sends (attitude, position, GPS, air data, HUD,
//! actuators, wind, guidance, heartbeat) from the drone's system and component and is fed in
//! 4 KiB chunks, as a socket would.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use stx_link::endpoint::{GroundConfig, GroundEndpoint, GroundEvent, LinkConfig};
use stx_link::fixtures::telemetry_sample as sample;
use stx_link::frame::{FrameDecoder, FrameEncoder};
use stx_link::telemetry::Telemetry;

fn ingest(c: &mut Criterion) {
    const FRAMES: u32 = 10_000;
    let mut enc = FrameEncoder::new(1, 1);
    let mut stream = Vec::new();
    for i in 0..FRAMES {
        enc.encode_into(Duration::ZERO, &sample(i).to_mavlink(), &mut stream);
    }
    let mut group = c.benchmark_group("ingest");
    group.throughput(Throughput::Elements(u64::from(FRAMES)));
    group.bench_function("ground_endpoint", |b| {
        b.iter(|| {
            let mut ground = GroundEndpoint::new(GroundConfig::default(), Duration::ZERO);
            let mut now = Duration::ZERO;
            let mut n = 0_u32;
            for chunk in stream.chunks(4096) {
                // About the time 4 KiB take at the drone's telemetry rate.
                now += Duration::from_millis(3);
                ground.handle_bytes(now, black_box(chunk));
                while let Some(event) = ground.poll_event() {
                    if let GroundEvent::Telemetry { telemetry, .. } = &event {
                        black_box(telemetry);
                        n += 1;
                    }
                }
            }
            assert_eq!(n, FRAMES);
            assert_eq!(ground.link_stats(now).frames_in, u64::from(FRAMES));
            n
        })
    });
    group.bench_function("two_radios", |b| {
        b.iter(|| {
            let config = GroundConfig {
                link: LinkConfig::ground().with_paths(2),
                ..Default::default()
            };
            let mut ground = GroundEndpoint::new(config, Duration::ZERO);
            let mut now = Duration::ZERO;
            let mut n = 0_u32;
            for chunk in stream.chunks(4096) {
                now += Duration::from_millis(3);
                ground.handle_bytes_on(0, now, black_box(chunk));
                ground.handle_bytes_on(1, now, black_box(chunk));
                while let Some(event) = ground.poll_event() {
                    if let GroundEvent::Telemetry { telemetry, .. } = &event {
                        black_box(telemetry);
                        n += 1;
                    }
                }
            }
            assert_eq!(n, FRAMES);
            n
        })
    });
    group.bench_function("bytes_to_telemetry", |b| {
        b.iter(|| {
            let mut dec = FrameDecoder::default();
            let mut n = 0_u32;
            for chunk in stream.chunks(4096) {
                dec.push(black_box(chunk));
                while let Some(Ok(frame)) = dec.poll(Duration::ZERO) {
                    if let Some(t) = Telemetry::from_mavlink(&frame.message) {
                        black_box(&t);
                        n += 1;
                    }
                }
            }
            assert_eq!(n, FRAMES);
            n
        })
    });
    group.finish();
}

criterion_group!(benches, ingest);
criterion_main!(benches);
