//! The fuzz target's seed corpus (`fuzz/seeds/`): valid frames with good CRCs, so the fuzzer
//! starts past the checksum. This test regenerates the seeds deterministically and checks the
//! committed files match and decode; run with `STX_WRITE_FUZZ_SEEDS=1` to rewrite them.
//!
//! Seed layout (as the target reads it): byte 0 = flags (bit 0 accept MAVLink 1, bit 1 signing
//! on with key 0x42…), byte 1 = chunk size, then the stream.

use std::path::Path;
use std::time::Duration;

use stx_link::command::Command;
use stx_link::frame::{FrameDecoder, FrameEncoder};
use stx_link::manual::Sticks;
use stx_link::plan::PlanItem;
use stx_link::signing::{SigningConfig, SigningKey};
use stx_link::telemetry::*;
use stx_types::mission::{FlightMode, FlightStage, GuidancePhase};

fn messages() -> Vec<(&'static str, mavlink::dialects::common::MavMessage)> {
    let status = VehicleStatus {
        mode: FlightMode::Course,
        stage: FlightStage::Parafoil,
        phase: GuidancePhase::Branch1,
        state: SystemState::Active,
    };
    vec![
        ("heartbeat", Telemetry::Status(status).to_mavlink()),
        (
            "attitude",
            Telemetry::Attitude(Attitude {
                time_boot_ms: 1,
                roll_rad: 0.1,
                pitch_rad: 0.2,
                yaw_rad: 0.3,
                roll_rate_radps: 0.0,
                pitch_rate_radps: 0.0,
                yaw_rate_radps: 0.0,
            })
            .to_mavlink(),
        ),
        (
            "gps",
            Telemetry::GpsRaw(GpsRaw {
                time_usec: 1,
                fix: GpsFix::Fix3d,
                lat_deg: 41.0,
                lon_deg: -8.0,
                alt_msl_m: 100.0,
                ground_speed_mps: Some(5.0),
                course_deg: Some(90.0),
                satellites: Some(9),
                h_acc_m: Some(1.0),
                v_acc_m: None,
            })
            .to_mavlink(),
        ),
        (
            "statustext",
            Telemetry::StatusText(StatusText::single(Severity::Info, "seed")).to_mavlink(),
        ),
        (
            "landing",
            Telemetry::PredictedLanding(PredictedLanding {
                time_boot_ms: 1,
                lat_deg: 41.0,
                lon_deg: -8.0,
                alt_msl_m: 90.0,
            })
            .to_mavlink(),
        ),
        (
            "cmd_long",
            Command::SetMode(FlightMode::Manual).to_mavlink(1, 1, 0),
        ),
        (
            "cmd_int",
            Command::SetLandingTarget {
                lat_deg: 41.0,
                lon_deg: -8.0,
                alt_msl_m: 90.0,
                approach_heading_deg: None,
            }
            .to_mavlink(1, 1, 0),
        ),
        (
            "manual",
            Sticks {
                x: 0.5,
                ..Default::default()
            }
            .to_mavlink(1),
        ),
        (
            "mission_item",
            PlanItem::Waypoint {
                lat_deg: 41.0,
                lon_deg: -8.0,
                alt_msl_m: 300.0,
            }
            .to_mavlink((1, 1), 0),
        ),
    ]
}

fn seeds() -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut all = vec![0_u8, 255];
    let mut enc = FrameEncoder::new(1, 1);
    for (name, m) in messages() {
        let frame = enc.encode(Duration::ZERO, &m);
        let mut seed = vec![0_u8, 255];
        seed.extend_from_slice(&frame);
        all.extend_from_slice(&frame);
        out.push((format!("{name}.bin"), seed));
    }
    out.push(("all.bin".into(), all));
    // Signed with the target's key, at a fixed wall-clock time.
    let cfg = SigningConfig::new(
        SigningKey::from_bytes([0x42; 32]),
        0,
        Duration::from_secs(1_767_225_600),
    );
    let mut enc = FrameEncoder::new(1, 1);
    enc.set_signer(Some(cfg.build(Duration::ZERO).0));
    let mut signed = vec![2_u8, 7];
    for (_, m) in messages() {
        enc.encode_into(Duration::ZERO, &m, &mut signed);
    }
    out.push(("signed.bin".into(), signed));
    out
}

#[test]
fn fuzz_seed_corpus_is_current_and_decodes() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds");
    let write = std::env::var_os("STX_WRITE_FUZZ_SEEDS").is_some();
    for (name, bytes) in seeds() {
        let path = dir.join(&name);
        if write {
            std::fs::create_dir_all(&dir).expect("seed dir");
            std::fs::write(&path, &bytes).expect("write seed");
        }
        let committed = std::fs::read(&path).unwrap_or_else(|e| {
            panic!(
                "{}: {e} (regenerate with STX_WRITE_FUZZ_SEEDS=1)",
                path.display()
            )
        });
        assert_eq!(
            committed, bytes,
            "{name} is stale (regenerate with STX_WRITE_FUZZ_SEEDS=1)"
        );
        // Every frame in it has a good CRC (unsigned seeds: no verifier needed).
        let mut dec = FrameDecoder::default();
        dec.push(&bytes[2..]);
        let mut n = 0;
        while let Some(r) = dec.poll(Duration::ZERO) {
            r.unwrap_or_else(|e| panic!("{name}: {e}"));
            n += 1;
        }
        assert!(n >= 1);
        assert_eq!(dec.stats().crc_errors, 0);
    }
}
