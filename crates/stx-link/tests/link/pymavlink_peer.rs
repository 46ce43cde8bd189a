//! stx-link against an independent MAVLink implementation: pymavlink 2.4.50.
//!
//! `tests/peers/make_streams.py` writes streams (valid frames mixed with garbage, truncated
//! frames and corrupted CRCs; a signed variant with refused frames) and a manifest of every
//! valid frame. The decoder must recover exactly those frames, in order, with the same header,
//! payload and field values, and count the corrupt ones. Conversely `verify_stream.py` lets
//! pymavlink check frames that stx-link signed, and `fence_upload.py` encodes a keep-out
//! fence upload (MAV_MISSION_TYPE_FENCE, exclusion polygons) for the vehicle side to take.
//!
//! Python: `$STX_PYTHON`, or `.venv/bin/python` at the workspace root. To create it:
//! `python3 -m venv .venv && .venv/bin/pip install pymavlink==2.4.50`.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use mavlink::dialects::common::MavMessage;
use mavlink::{MavlinkVersion, Message};
use serde_json::Value;
use stx_link::frame::{Frame, FrameDecoder, FrameEncoder, WireVersion};
use stx_link::signing::{SigningConfig, SigningKey};
use stx_link::telemetry::Telemetry;

const JAN_2026: u64 = 1_767_225_600;

fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn python() -> PathBuf {
    let p = std::env::var_os("STX_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace_root().join(".venv/bin/python"));
    assert!(
        p.exists(),
        "pymavlink peer: no Python at {} (set STX_PYTHON, or create the venv at the workspace root: \
         `python3 -m venv .venv && .venv/bin/pip install pymavlink==2.4.50`)",
        p.display()
    );
    p
}

fn run_py(script: &str, args: &[&str]) -> String {
    let script = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/peers")
        .join(script);
    let out = Command::new(python())
        .env("MAVLINK20", "1")
        .arg(&script)
        .args(args)
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "{} failed ({}): {}\n(is pymavlink installed? `.venv/bin/pip install pymavlink==2.4.50`)",
        script.display(),
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Generates the streams into a directory of their own (tests run in parallel).
fn make_streams(label: &str) -> (PathBuf, Value) {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("pymavlink-streams-{label}"));
    run_py("make_streams.py", &[dir.to_str().expect("utf-8 path")]);
    let manifest: Value =
        serde_json::from_slice(&std::fs::read(dir.join("manifest.json")).expect("manifest"))
            .expect("json");
    (dir, manifest)
}

fn decode(bytes: &[u8], chunk: usize, mut dec: FrameDecoder) -> (Vec<Frame>, FrameDecoder) {
    let mut frames = Vec::new();
    let now = Duration::from_secs(1);
    for c in bytes.chunks(chunk.max(1)) {
        dec.push(c);
        while let Some(r) = dec.poll(now) {
            if let Ok(f) = r {
                frames.push(f);
            }
        }
    }
    dec.finish();
    while let Some(r) = dec.poll(now) {
        if let Ok(f) = r {
            frames.push(f);
        }
    }
    (frames, dec)
}

/// A field value of the decoded message, by MAVLink field name (only those the manifest
/// spot-checks).
fn field(msg: &MavMessage, name: &str) -> Option<f64> {
    use MavMessage as M;
    Some(match (msg, name) {
        (M::HEARTBEAT(m), "custom_mode") => m.custom_mode.into(),
        (M::GPS_RAW_INT(m), "lat") => m.lat.into(),
        (M::GPS_RAW_INT(m), "lon") => m.lon.into(),
        (M::GPS_RAW_INT(m), "alt") => m.alt.into(),
        (M::GPS_RAW_INT(m), "cog") => m.cog.into(),
        (M::GPS_RAW_INT(m), "h_acc") => m.h_acc.into(),
        (M::GLOBAL_POSITION_INT(m), "lat") => m.lat.into(),
        (M::GLOBAL_POSITION_INT(m), "lon") => m.lon.into(),
        (M::GLOBAL_POSITION_INT(m), "alt") => m.alt.into(),
        (M::GLOBAL_POSITION_INT(m), "vx") => m.vx.into(),
        (M::GLOBAL_POSITION_INT(m), "hdg") => m.hdg.into(),
        (M::ATTITUDE(m), "roll") => m.roll.into(),
        (M::ATTITUDE(m), "yaw") => m.yaw.into(),
        (M::SCALED_PRESSURE(m), "press_abs") => m.press_abs.into(),
        (M::SCALED_PRESSURE(m), "temperature") => m.temperature.into(),
        (M::SCALED_PRESSURE(m), "temperature_press_diff") => m.temperature_press_diff.into(),
        (M::VFR_HUD(m), "groundspeed") => m.groundspeed.into(),
        (M::VFR_HUD(m), "heading") => m.heading.into(),
        (M::VFR_HUD(m), "climb") => m.climb.into(),
        (M::SERVO_OUTPUT_RAW(m), "servo1_raw") => m.servo1_raw.into(),
        (M::SERVO_OUTPUT_RAW(m), "servo2_raw") => m.servo2_raw.into(),
        (M::SERVO_OUTPUT_RAW(m), "servo3_raw") => m.servo3_raw.into(),
        (M::SYS_STATUS(m), "voltage_battery") => m.voltage_battery.into(),
        (M::SYS_STATUS(m), "battery_remaining") => m.battery_remaining.into(),
        (M::WIND_COV(m), "wind_x") => m.wind_x.into(),
        (M::WIND_COV(m), "wind_alt") => m.wind_alt.into(),
        (M::NAV_CONTROLLER_OUTPUT(m), "target_bearing") => m.target_bearing.into(),
        (M::NAV_CONTROLLER_OUTPUT(m), "wp_dist") => m.wp_dist.into(),
        (M::NAV_CONTROLLER_OUTPUT(m), "xtrack_error") => m.xtrack_error.into(),
        (M::POSITION_TARGET_GLOBAL_INT(m), "lat_int") => m.lat_int.into(),
        (M::POSITION_TARGET_GLOBAL_INT(m), "lon_int") => m.lon_int.into(),
        (M::POSITION_TARGET_GLOBAL_INT(m), "alt") => m.alt.into(),
        (M::COMMAND_LONG(m), "param2") => m.param2.into(),
        (M::COMMAND_LONG(m), "confirmation") => m.confirmation.into(),
        (M::COMMAND_INT(m), "x") => m.x.into(),
        (M::COMMAND_INT(m), "y") => m.y.into(),
        (M::COMMAND_INT(m), "z") => m.z.into(),
        (M::MANUAL_CONTROL(m), "x") => m.x.into(),
        (M::MANUAL_CONTROL(m), "buttons") => m.buttons.into(),
        (M::MANUAL_CONTROL(m), "buttons2") => m.buttons2.into(),
        (M::PARAM_VALUE(m), "param_value") => m.param_value.into(),
        (M::PARAM_VALUE(m), "param_index") => m.param_index.into(),
        (M::MISSION_ITEM_INT(m), "seq") => m.seq.into(),
        (M::MISSION_ITEM_INT(m), "x") => m.x.into(),
        (M::MISSION_ITEM_INT(m), "z") => m.z.into(),
        _ => return None,
    })
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn check_frames(got: &[Frame], expected: &[Value], label: &str) {
    assert_eq!(got.len(), expected.len(), "{label}: frame count");
    for (i, (f, e)) in got.iter().zip(expected).enumerate() {
        let ctx = format!("{label} frame {i} ({})", e["name"]);
        assert_eq!(f.header.version, WireVersion::V2, "{ctx}");
        assert_eq!(
            u64::from(f.header.message_id),
            e["msgid"].as_u64().unwrap_or(u64::MAX),
            "{ctx}: id"
        );
        assert_eq!(
            f.message.message_name(),
            e["name"].as_str().unwrap_or(""),
            "{ctx}: name"
        );
        assert_eq!(
            u64::from(f.header.system_id),
            e["sysid"].as_u64().unwrap_or(0),
            "{ctx}: sysid"
        );
        assert_eq!(
            u64::from(f.header.component_id),
            e["compid"].as_u64().unwrap_or(0),
            "{ctx}: compid"
        );
        assert_eq!(
            u64::from(f.header.sequence),
            e["seq"].as_u64().unwrap_or(999),
            "{ctx}: seq"
        );
        assert_eq!(
            f.header.is_signed(),
            e["signed"].as_bool().unwrap_or(false),
            "{ctx}: signed"
        );
        // Every field: our re-encoding of the decoded message gives pymavlink's payload.
        let mut payload = [0_u8; 255];
        let n = f.message.ser(MavlinkVersion::V2, &mut payload);
        assert_eq!(
            hex(&payload[..n]),
            e["payload_hex"].as_str().unwrap_or(""),
            "{ctx}: payload"
        );
        // And a few values, compared with what pymavlink was asked to encode.
        for (name, want) in e["spot"].as_object().into_iter().flatten() {
            match (name.as_str(), &f.message) {
                ("text", MavMessage::STATUSTEXT(_)) => {
                    let Some(Telemetry::StatusText(t)) = Telemetry::from_mavlink(&f.message) else {
                        panic!("{ctx}: statustext")
                    };
                    assert_eq!(t.text_lossy(), want.as_str().unwrap_or(""), "{ctx}: text");
                }
                ("param_id", MavMessage::PARAM_VALUE(p)) => {
                    let raw: &[u8] = &p.param_id[..];
                    let end = raw.iter().position(|&b| b == 0).unwrap_or(raw.len());
                    assert_eq!(
                        std::str::from_utf8(&raw[..end]).ok(),
                        want.as_str(),
                        "{ctx}: param_id"
                    );
                }
                _ => {
                    let got = field(&f.message, name)
                        .unwrap_or_else(|| panic!("{ctx}: no accessor for {name}"));
                    let want = want.as_f64().unwrap_or(f64::NAN);
                    // pymavlink reports the double it was given; the wire holds an f32.
                    assert!(
                        (got - want).abs() <= 1e-6 * want.abs().max(1.0),
                        "{ctx}: {name} = {got}, pymavlink {want}"
                    );
                }
            }
        }
        // Telemetry messages map to stx telemetry.
        if matches!(
            f.message,
            MavMessage::HEARTBEAT(_)
                | MavMessage::GPS_RAW_INT(_)
                | MavMessage::ATTITUDE(_)
                | MavMessage::WIND_COV(_)
                | MavMessage::SERVO_OUTPUT_RAW(_)
        ) {
            assert!(
                Telemetry::from_mavlink(&f.message).is_some(),
                "{ctx}: not read as telemetry"
            );
        }
    }
}

#[test]
fn decoder_recovers_every_pymavlink_frame_and_counts_the_corrupt_ones() {
    let (dir, manifest) = make_streams("unsigned");
    let m = &manifest["unsigned"];
    let bytes = std::fs::read(dir.join(m["file"].as_str().expect("file"))).expect("stream");
    let expected = m["frames"].as_array().expect("frames");
    let corrupted = m["corrupted_crc"].as_u64().expect("count");
    let truncated = m["truncated"].as_u64().expect("count");
    let garbage = m["garbage_bytes"].as_u64().expect("count");
    assert!(
        expected.len() > 1000 && corrupted > 10 && truncated > 10 && garbage > 100,
        "stream too tame: {m:?}"
    );
    for chunk in [1, 2, 7, 64, 1500, bytes.len()] {
        let (frames, dec) = decode(&bytes, chunk, FrameDecoder::default());
        check_frames(&frames, expected, &format!("unsigned, chunk {chunk}"));
        let s = dec.stats();
        assert_eq!(s.frames_ok, expected.len() as u64);
        // Each corrupted frame fails its CRC; each truncated one fails the CRC of the bytes it
        // swallowed (or is cut by the end of the stream).
        assert!(s.crc_errors >= corrupted, "{s:?}");
        assert!(
            s.crc_errors + s.truncated + s.unknown_message_ids >= corrupted + truncated,
            "{s:?}"
        );
        assert!(s.bytes_discarded >= garbage, "{s:?}");
        assert_eq!(s.bytes_in, bytes.len() as u64);
    }
}

#[test]
fn signed_pymavlink_stream_verifies_and_refusals_are_counted() {
    let (dir, manifest) = make_streams("signed");
    let m = &manifest["signed"];
    let bytes = std::fs::read(dir.join(m["file"].as_str().expect("file"))).expect("stream");
    let key_hex = m["key_hex"].as_str().expect("key");
    let mut key = [0_u8; 32];
    for (i, b) in key.iter_mut().enumerate() {
        *b = u8::from_str_radix(&key_hex[2 * i..2 * i + 2], 16).expect("hex");
    }
    let (_, verifier) = SigningConfig::new(
        SigningKey::from_bytes(key),
        0,
        Duration::from_secs(JAN_2026),
    )
    .build(Duration::from_secs(1));
    let mut dec = FrameDecoder::default();
    dec.set_verifier(Some(verifier));
    let (frames, dec) = decode(&bytes, 13, dec);
    check_frames(&frames, m["frames"].as_array().expect("frames"), "signed");
    let s = dec.stats();
    let e = &m["expect"];
    assert_eq!(
        s.unsigned_refused,
        e["unsigned_refused"].as_u64().expect("n"),
        "{s:?}"
    );
    assert_eq!(
        s.replays_refused,
        e["replays_refused"].as_u64().expect("n"),
        "{s:?}"
    );
    assert_eq!(
        s.bad_signatures,
        e["bad_signatures"].as_u64().expect("n"),
        "{s:?}"
    );
    assert_eq!(s.v1_refused, e["v1_refused"].as_u64().expect("n"), "{s:?}");
    assert_eq!(s.signed_frames, frames.len() as u64);

    // The same stream with the wrong key: nothing gets through.
    let (_, wrong) = SigningConfig::new(
        SigningKey::from_bytes([9; 32]),
        0,
        Duration::from_secs(JAN_2026),
    )
    .build(Duration::from_secs(1));
    let mut dec = FrameDecoder::default();
    dec.set_verifier(Some(wrong));
    let (frames, dec) = decode(&bytes, bytes.len(), dec);
    assert!(frames.is_empty());
    assert!(dec.stats().bad_signatures as usize >= m["frames"].as_array().map_or(0, Vec::len));
}

#[test]
fn pymavlink_verifies_frames_signed_by_stx_link() {
    let key = [0x5A_u8; 32];
    let cfg = SigningConfig::new(
        SigningKey::from_bytes(key),
        7,
        Duration::from_secs(JAN_2026),
    );
    let (signer, _) = cfg.build(Duration::ZERO);
    let mut enc = FrameEncoder::new(1, 1);
    enc.set_signer(Some(signer));
    let mut stream = Vec::new();
    let telemetry = [
        Telemetry::Attitude(stx_link::telemetry::Attitude {
            time_boot_ms: 5,
            roll_rad: 0.1,
            pitch_rad: 0.2,
            yaw_rad: 0.3,
            roll_rate_radps: 0.0,
            pitch_rate_radps: 0.0,
            yaw_rate_radps: 0.0,
        }),
        Telemetry::PredictedLanding(stx_link::telemetry::PredictedLanding {
            time_boot_ms: 5,
            lat_deg: 41.2,
            lon_deg: -8.6,
            alt_msl_m: 95.0,
        }),
    ];
    for i in 0..50_u64 {
        let t = &telemetry[(i % 2) as usize];
        enc.encode_into(Duration::from_millis(i * 20), &t.to_mavlink(), &mut stream);
    }
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join("stx-signed.bin");
    std::fs::write(&path, &stream).expect("write");
    let key_hex = hex(&key);
    let start = (JAN_2026 - 1_420_070_400) * 100_000;
    let out = run_py(
        "verify_stream.py",
        &[path.to_str().expect("utf-8"), &key_hex, &start.to_string()],
    );
    let v: Value = serde_json::from_str(out.trim()).expect("json summary");
    assert_eq!(v["goodsig"].as_u64(), Some(50), "{v}");
    assert_eq!(v["badsig"].as_u64(), Some(0), "{v}");
    assert_eq!(v["bad"].as_u64(), Some(0), "{v}");
    assert_eq!(v["messages"].as_array().map(Vec::len), Some(50), "{v}");

    // With another key pymavlink refuses them all: the check above can fail.
    let out = run_py(
        "verify_stream.py",
        &[
            path.to_str().expect("utf-8"),
            &hex(&[1; 32]),
            &start.to_string(),
        ],
    );
    let v: Value = serde_json::from_str(out.trim()).expect("json summary");
    assert_eq!(v["goodsig"].as_u64(), Some(0), "{v}");
    assert_eq!(v["messages"].as_array().map(Vec::len), Some(0), "{v}");
}

/// A fence upload encoded by pymavlink (`fence_upload.py`) is taken by the vehicle side's
/// [`FenceServer`](stx_link::plan::FenceServer), acknowledged, and read as the polygons sent.
#[test]
fn a_fence_uploaded_by_pymavlink_is_accepted_as_its_polygons() {
    use mavlink::dialects::common::{MavMissionResult, MavMissionType};
    use stx_link::plan::{FenceServer, PlanConfig, fence_polygons};
    let file = Path::new(env!("CARGO_TARGET_TMPDIR")).join("pymavlink-fence-upload.bin");
    let printed = run_py("fence_upload.py", &[file.to_str().expect("utf-8 path")]);
    let vertices: Vec<[i64; 3]> = serde_json::from_str(printed.trim()).expect("json");
    let bytes = std::fs::read(&file).expect("frames");
    let (frames, _) = decode(&bytes, bytes.len(), FrameDecoder::default());
    assert_eq!(frames.len(), 1 + vertices.len());
    let mut server = FenceServer::new(1, 1, PlanConfig::default());
    let mut answers = Vec::new();
    for f in &frames {
        assert!(server.handle_message(Duration::ZERO, (255, 190), &f.message));
        while let Some(m) = server.poll_transmit() {
            answers.push(m);
        }
    }
    let Some(MavMessage::MISSION_ACK(ack)) = answers.last() else {
        panic!("no ack: {answers:?}")
    };
    assert_eq!(ack.mavtype, MavMissionResult::MAV_MISSION_ACCEPTED);
    assert_eq!(ack.mission_type, MavMissionType::MAV_MISSION_TYPE_FENCE);
    let fence = server.poll_plan().expect("a fence");
    let polygons = fence_polygons(&fence).expect("well formed");
    assert_eq!(polygons.iter().map(Vec::len).collect::<Vec<_>>(), [4, 3]);
    for (got, [_, lat, lon]) in polygons.iter().flatten().zip(&vertices) {
        assert!((got[0] * 1e7 - *lat as f64).abs() < 0.5, "{got:?}");
        assert!((got[1] * 1e7 - *lon as f64).abs() < 0.5, "{got:?}");
    }
}
