//! The decoder fed by the encoder: round trips at every chunk size, resynchronisation,
//! truncation, policy, unknown ids, parse errors and signing.

use std::time::Duration;

use mavlink::dialects::common::{ATTITUDE_DATA, HEARTBEAT_DATA, MavMessage};
use mavlink::{MavlinkVersion, Message};

use super::*;
use crate::signing::{SignatureError, SigningConfig, SigningKey};

fn attitude(roll: f32) -> MavMessage {
    MavMessage::ATTITUDE(ATTITUDE_DATA {
        time_boot_ms: 7,
        roll,
        pitch: 0.5,
        yaw: -1.0,
        ..Default::default()
    })
}

fn decode_all(dec: &mut FrameDecoder) -> (Vec<Frame>, Vec<FrameError>) {
    let (mut ok, mut err) = (Vec::new(), Vec::new());
    while let Some(r) = dec.poll(Duration::ZERO) {
        match r {
            Ok(f) => ok.push(f),
            Err(e) => err.push(e),
        }
    }
    (ok, err)
}

#[test]
fn round_trip_every_chunk_size() {
    let mut enc = FrameEncoder::new(1, 1);
    let mut stream = Vec::new();
    for i in 0..5 {
        enc.encode_into(Duration::ZERO, &attitude(i as f32 * 0.1), &mut stream);
    }
    for chunk in 1..stream.len() {
        let mut dec = FrameDecoder::default();
        let mut got = Vec::new();
        for c in stream.chunks(chunk) {
            dec.push(c);
            while let Some(r) = dec.poll(Duration::ZERO) {
                got.push(r.expect("valid frame"));
            }
        }
        assert_eq!(got.len(), 5, "chunk {chunk}");
        for (i, f) in got.iter().enumerate() {
            assert_eq!(f.header.sequence, i as u8);
            assert_eq!(f.message, attitude(i as f32 * 0.1));
        }
        assert_eq!(dec.stats().bytes_discarded, 0);
    }
}

#[test]
fn resyncs_after_corrupted_crc_and_garbage() {
    let mut enc = FrameEncoder::new(1, 1);
    let a = enc.encode(Duration::ZERO, &attitude(0.1));
    let mut b = enc.encode(Duration::ZERO, &attitude(0.2));
    let c = enc.encode(Duration::ZERO, &attitude(0.3));
    let last = b.len() - 1;
    b[last] ^= 0xFF;
    let mut stream = vec![1, 2, 3];
    stream.extend(&a);
    stream.extend(&b);
    stream.extend([9, 9]);
    stream.extend(&c);
    let mut dec = FrameDecoder::default();
    dec.push(&stream);
    let (ok, err) = decode_all(&mut dec);
    assert_eq!(ok.len(), 2);
    assert_eq!(ok[1].message, attitude(0.3));
    assert!(
        err.iter()
            .any(|e| matches!(e, FrameError::BadCrc { message_id: 30, .. }))
    );
    assert_eq!(dec.stats().crc_errors, 1);
    assert_eq!(dec.stats().bytes_discarded as usize, 3 + b.len() + 2);
}

#[test]
fn truncated_frame_then_valid_frame_is_recovered() {
    let mut enc = FrameEncoder::new(1, 1);
    let a = enc.encode(Duration::ZERO, &attitude(0.1));
    let b = enc.encode(Duration::ZERO, &attitude(0.2));
    let mut stream = a[..a.len() - 5].to_vec();
    stream.extend(&b);
    let mut dec = FrameDecoder::default();
    dec.push(&stream);
    let (ok, _) = decode_all(&mut dec);
    // The truncated candidate swallows the start of `b` until enough bytes arrive.
    dec.finish();
    let (ok2, err2) = decode_all(&mut dec);
    let all: Vec<_> = ok.into_iter().chain(ok2).collect();
    assert_eq!(all.len(), 1);
    assert_eq!(all[0].message, attitude(0.2));
    assert!(
        dec.stats().crc_errors + dec.stats().truncated >= 1,
        "{err2:?}"
    );
}

#[test]
fn v1_policy_and_unknown_ids_are_counted() {
    // A MAVLink 1 heartbeat built by hand.
    let hb = MavMessage::HEARTBEAT(HEARTBEAT_DATA::default());
    let mut payload = [0_u8; 255];
    let len = hb.ser(MavlinkVersion::V1, &mut payload);
    let mut v1 = vec![MAGIC_V1, len as u8, 3, 9, 1, 0];
    v1.extend_from_slice(&payload[..len]);
    let crc = crc_mavlink(&v1[1..], MavMessage::extra_crc(0));
    v1.extend_from_slice(&crc.to_le_bytes());

    let mut dec = FrameDecoder::default();
    dec.push(&v1);
    let (ok, _) = decode_all(&mut dec);
    assert_eq!(ok.len(), 1);
    assert_eq!(ok[0].header.version, WireVersion::V1);
    assert_eq!(dec.stats().v1_accepted, 1);

    let mut dec = FrameDecoder::new(DecoderPolicy { accept_v1: false });
    dec.push(&v1);
    let (ok, err) = decode_all(&mut dec);
    assert!(ok.is_empty());
    assert_eq!(err, vec![FrameError::V1Refused { message_id: 0 }]);
    assert_eq!(dec.stats().v1_refused, 1);

    // Unknown id 0xABCDEF.
    let mut unk = vec![MAGIC_V2, 1, 0, 0, 0, 1, 1, 0xEF, 0xCD, 0xAB, 0x42, 0, 0];
    unk.extend(&v1);
    let mut dec = FrameDecoder::default();
    dec.push(&unk);
    let (ok, err) = decode_all(&mut dec);
    assert_eq!(ok.len(), 1);
    assert_eq!(
        err[0],
        FrameError::UnknownMessage {
            message_id: 0xABCDEF
        }
    );
    assert_eq!(dec.stats().unknown_message_ids, 1);
}

/// Regression: the unknown-id check used to wait for the whole candidate (up to 280
/// bytes), so a false start in noise held back the valid frames behind it.
#[test]
fn a_false_start_with_an_unknown_id_does_not_hold_back_the_next_frame() {
    let mut enc = FrameEncoder::new(1, 1);
    let a = enc.encode(Duration::ZERO, &attitude(0.1));
    let unknown_v1 = (0..=255_u8)
        .find(|&id| known_extra_crc(u32::from(id)).is_none())
        .expect("an id MAVLink 1 does not know");
    for false_start in [
        vec![MAGIC_V2, 255, 0, 0, 0, 1, 1, 0xEF, 0xCD, 0xAB],
        vec![MAGIC_V1, 255, 0, 1, 1, unknown_v1],
    ] {
        let mut stream = false_start.clone();
        stream.extend(&a);
        let mut dec = FrameDecoder::default();
        dec.push(&stream);
        // No finish(): the frame must come out of what has arrived.
        let (ok, err) = decode_all(&mut dec);
        assert_eq!(ok.len(), 1, "{false_start:?}: {err:?}");
        assert_eq!(ok[0].message, attitude(0.1));
        assert!(matches!(err[..], [FrameError::UnknownMessage { .. }]));
        assert_eq!(dec.stats().unknown_message_ids, 1);
        assert_eq!(dec.stats().bytes_discarded as usize, false_start.len());
        assert_eq!(dec.buffered(), 0);
    }
}

#[test]
fn invalid_enum_is_a_counted_parse_error() {
    let mut enc = FrameEncoder::new(1, 1);
    let mut f = enc.encode(
        Duration::ZERO,
        &MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: 1,
            ..Default::default()
        }),
    );
    // mavtype byte (offset 4 in the payload) set to an undefined MAV_TYPE, CRC recomputed.
    f[V2_HEADER_LEN + 4] = 250;
    let n = f.len();
    let crc = crc_mavlink(&f[1..n - 2], MavMessage::extra_crc(0));
    f[n - 2..].copy_from_slice(&crc.to_le_bytes());
    let mut dec = FrameDecoder::default();
    dec.push(&f);
    let (ok, err) = decode_all(&mut dec);
    assert!(ok.is_empty());
    assert!(matches!(err[0], FrameError::Parse { message_id: 0, .. }));
    assert_eq!(dec.stats().parse_errors, 1);
}

#[test]
fn signing_refuses_unsigned_bad_and_replayed_frames() {
    let t0 = Duration::from_secs(1_767_225_600);
    let key = SigningKey::from_bytes([7; 32]);
    let (signer, verifier) = SigningConfig::new(key, 3, t0).build(Duration::ZERO);
    let mut enc = FrameEncoder::new(1, 1);
    enc.set_signer(Some(signer));
    let signed = enc.encode(Duration::ZERO, &attitude(0.1));
    let mut plain = FrameEncoder::new(1, 1);
    let unsigned = plain.encode(Duration::ZERO, &attitude(0.1));
    let (_, wrong) =
        SigningConfig::new(SigningKey::from_bytes([8; 32]), 3, t0).build(Duration::ZERO);

    let mut dec = FrameDecoder::default();
    dec.set_verifier(Some(verifier));
    dec.push(&signed);
    dec.push(&unsigned);
    dec.push(&signed);
    let (ok, err) = decode_all(&mut dec);
    assert_eq!(ok.len(), 1);
    assert!(ok[0].header.is_signed());
    assert!(matches!(err[0], FrameError::Unsigned { .. }));
    assert!(matches!(
        err[1],
        FrameError::Signature {
            source: SignatureError::Replay { .. },
            ..
        }
    ));
    assert_eq!(dec.stats().unsigned_refused, 1);
    assert_eq!(dec.stats().replays_refused, 1);

    let mut dec = FrameDecoder::default();
    dec.set_verifier(Some(wrong));
    dec.push(&signed);
    let (ok, _) = decode_all(&mut dec);
    assert!(ok.is_empty());
    assert_eq!(dec.stats().bad_signatures, 1);

    // Without a verifier, signed frames are accepted (signature not checked).
    let mut dec = FrameDecoder::default();
    dec.push(&signed);
    let (ok, _) = decode_all(&mut dec);
    assert_eq!(ok.len(), 1);
    assert_eq!(ok[0].header.signature.map(|s| s.link_id), Some(3));
}

#[test]
fn last_frame_bytes_are_the_frame_as_received_between_noise() {
    let mut enc = FrameEncoder::new(3, 7);
    let first = enc.encode(Duration::ZERO, &attitude(0.1));
    let second = enc.encode(Duration::ZERO, &attitude(0.2));
    let mut stream = b"noise".to_vec();
    stream.extend_from_slice(&first);
    stream.extend_from_slice(b"\x00\x01");
    stream.extend_from_slice(&second);
    let mut dec = FrameDecoder::default();
    dec.push(&stream);
    assert!(dec.last_frame_bytes().is_empty());
    assert!(matches!(dec.poll(Duration::ZERO), Some(Ok(_))));
    assert_eq!(dec.last_frame_bytes(), first.as_slice());
    assert!(matches!(dec.poll(Duration::ZERO), Some(Ok(_))));
    assert_eq!(dec.last_frame_bytes(), second.as_slice());
    assert!(dec.poll(Duration::ZERO).is_none());
    assert!(dec.last_frame_bytes().is_empty());
}
