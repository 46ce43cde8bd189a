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
use stx_gnc::mission::{FlightMode, FlightStage, GuidancePhase};
use stx_link::endpoint::{GroundConfig, GroundEndpoint, GroundEvent, LinkConfig};
use stx_link::frame::{FrameDecoder, FrameEncoder};
use stx_link::telemetry::*;

fn sample(i: u32) -> Telemetry {
    let f = f64::from(i);
    match i % 9 {
        0 => Telemetry::Attitude(Attitude {
            time_boot_ms: i,
            roll_rad: 0.1,
            pitch_rad: -0.05,
            yaw_rad: f * 1e-3,
            roll_rate_radps: 0.01,
            pitch_rate_radps: 0.0,
            yaw_rate_radps: 0.2,
        }),
        1 => Telemetry::Position(GlobalPosition {
            time_boot_ms: i,
            lat_deg: 41.1779 + f * 1e-7,
            lon_deg: -8.5977,
            alt_msl_m: 3000.0 - f * 0.01,
            alt_rel_m: 2900.0,
            v_north_mps: 3.0,
            v_east_mps: -1.0,
            v_down_mps: 4.5,
            heading_deg: Some(271.0),
        }),
        2 => Telemetry::GpsRaw(GpsRaw {
            time_usec: u64::from(i) * 1000,
            fix: GpsFix::Fix3d,
            lat_deg: 41.1779,
            lon_deg: -8.5977,
            alt_msl_m: 3000.0,
            ground_speed_mps: Some(12.0),
            course_deg: Some(270.0),
            satellites: Some(12),
            h_acc_m: Some(2.5),
            v_acc_m: Some(4.0),
        }),
        3 => Telemetry::AirData(AirData {
            time_boot_ms: i,
            abs_pressure_pa: 70_000.0,
            diff_pressure_pa: 120.0,
            temperature_c: -20.0,
            diff_temperature_c: None,
        }),
        4 => Telemetry::Hud(Hud {
            airspeed_mps: 14.0,
            groundspeed_mps: 12.0,
            heading_deg: 270.0,
            climb_mps: -4.5,
            alt_msl_m: 3000.0,
        }),
        5 => Telemetry::Actuators(Actuators {
            time_usec: i,
            main_line: 0.2,
            brake_right: 0.1,
            brake_left: 0.3,
        }),
        6 => Telemetry::Wind(Wind {
            time_usec: u64::from(i),
            wind_north_mps: Some(3.0),
            wind_east_mps: Some(-2.0),
            wind_down_mps: Some(0.0),
            var_horiz_mps: Some(0.5),
            var_vert_mps: Some(0.1),
            alt_msl_m: Some(3000.0),
            horiz_accuracy_mps: 0.3,
            vert_accuracy_mps: 0.1,
        }),
        7 => Telemetry::Guidance(GuidanceStatus {
            desired_roll_deg: -10.0,
            desired_heading_deg: 260.0,
            bearing_to_target_deg: 255.0,
            distance_to_target_m: 1500.0,
            alt_error_m: 10.0,
            xtrack_error_m: -20.0,
        }),
        _ => Telemetry::Status(VehicleStatus {
            mode: FlightMode::SpiralLanding,
            stage: FlightStage::Parafoil,
            phase: GuidancePhase::Branch2,
            state: SystemState::Active,
        }),
    }
}

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
