//! Property tests of the frame decoder: valid frames survive any chunking and any garbage
//! between them; arbitrary bytes never panic and every byte is accounted for.

use std::time::Duration;

use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use stx_link::frame::{Frame, FrameDecoder, FrameEncoder, WireVersion};
use stx_link::signing::{SigningConfig, SigningKey};
use stx_link::telemetry::{Attitude, GlobalPosition, Hud, Severity, StatusText, Telemetry};

fn telemetry() -> impl Strategy<Value = Telemetry> {
    prop_oneof![
        (any::<u32>(), -3.0..3.0_f64, -1.5..1.5_f64).prop_map(|(t, r, p)| Telemetry::Attitude(
            Attitude {
                time_boot_ms: t,
                roll_rad: r,
                pitch_rad: p,
                yaw_rad: 0.0,
                roll_rate_radps: 0.0,
                pitch_rate_radps: 0.0,
                yaw_rate_radps: 0.0,
            }
        )),
        (any::<u32>(), -90.0..90.0_f64, -180.0..180.0_f64).prop_map(|(t, la, lo)| {
            Telemetry::Position(GlobalPosition {
                time_boot_ms: t,
                lat_deg: la,
                lon_deg: lo,
                alt_msl_m: 1000.0,
                alt_rel_m: 900.0,
                v_north_mps: 1.0,
                v_east_mps: -2.0,
                v_down_mps: 4.0,
                heading_deg: Some(12.0),
            })
        }),
        (0.0..50.0_f64).prop_map(|a| Telemetry::Hud(Hud {
            airspeed_mps: a,
            groundspeed_mps: a,
            heading_deg: 90.0,
            climb_mps: -4.0,
            alt_msl_m: 100.0
        })),
        "[ -~]{0,50}".prop_map(|s| Telemetry::StatusText(StatusText::single(Severity::Info, &s))),
    ]
}

fn frame_len(f: &Frame) -> u64 {
    let base = u64::from(f.header.payload_len) + 2;
    match f.header.version {
        WireVersion::V1 => base + 6,
        WireVersion::V2 => base + 10 + if f.header.is_signed() { 13 } else { 0 },
    }
}

fn decode_chunks(
    bytes: &[u8],
    cuts: &[usize],
    mut dec: FrameDecoder,
) -> (Vec<Frame>, FrameDecoder) {
    let now = Duration::from_secs(1);
    let mut frames = Vec::new();
    let mut start = 0;
    let mut cuts: Vec<usize> = cuts.iter().map(|c| c % (bytes.len() + 1)).collect();
    cuts.sort_unstable();
    cuts.push(bytes.len());
    for end in cuts {
        dec.push(&bytes[start..end.max(start)]);
        start = end.max(start);
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

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, rng_seed: RngSeed::Fixed(0xF8A3E), ..ProptestConfig::default() })]

    #[test]
    fn valid_frames_survive_chunking_and_garbage(
        msgs in prop::collection::vec(telemetry(), 1..25),
        gaps in prop::collection::vec(prop::collection::vec(any::<u8>(), 0..40), 25),
        cuts in prop::collection::vec(any::<usize>(), 0..30),
    ) {
        let mut enc = FrameEncoder::new(1, 1);
        let mut stream = Vec::new();
        for (m, gap) in msgs.iter().zip(&gaps) {
            stream.extend_from_slice(gap);
            enc.encode_into(Duration::ZERO, &m.to_mavlink(), &mut stream);
        }
        let (frames, dec) = decode_chunks(&stream, &cuts, FrameDecoder::default());
        // Garbage may itself hold something frame-like, but every encoded frame comes out, in
        // order, with its sequence number.
        let ours: Vec<&Frame> = frames.iter().filter(|f| f.header.system_id == 1 && f.header.component_id == 1 && f.header.version == WireVersion::V2).collect();
        prop_assert_eq!(ours.len(), msgs.len(), "stats {:?}", dec.stats());
        for (i, (f, m)) in ours.iter().zip(&msgs).enumerate() {
            prop_assert_eq!(f.header.sequence, i as u8);
            prop_assert_eq!(&f.message, &m.to_mavlink());
        }
        let s = dec.stats();
        prop_assert_eq!(s.bytes_in, stream.len() as u64);
        prop_assert_eq!(s.bytes_discarded + frames.iter().map(frame_len).sum::<u64>(), s.bytes_in);
    }

    #[test]
    fn arbitrary_bytes_never_panic_and_are_accounted_for(
        bytes in prop::collection::vec(any::<u8>(), 0..2048),
        cuts in prop::collection::vec(any::<usize>(), 0..20),
        signing in any::<bool>(),
        v1 in any::<bool>(),
    ) {
        let mut dec = FrameDecoder::new(stx_link::frame::DecoderPolicy { accept_v1: v1 });
        if signing {
            let (_, verifier) = SigningConfig::new(SigningKey::from_bytes([1; 32]), 0, Duration::from_secs(1_767_225_600)).build(Duration::ZERO);
            dec.set_verifier(Some(verifier));
        }
        let (frames, dec) = decode_chunks(&bytes, &cuts, dec);
        let s = dec.stats();
        prop_assert_eq!(dec.buffered(), 0);
        prop_assert_eq!(s.bytes_discarded + frames.iter().map(frame_len).sum::<u64>(), s.bytes_in);
    }

    /// Magic-heavy input: mostly 0xFD / 0xFE with header-looking bytes, the worst case for
    /// resynchronisation.
    #[test]
    fn magic_heavy_bytes_never_panic(bytes in prop::collection::vec(prop_oneof![Just(0xFD_u8), Just(0xFE), Just(0x01), Just(0x00), any::<u8>()], 0..1024)) {
        let (frames, dec) = decode_chunks(&bytes, &[], FrameDecoder::default());
        prop_assert_eq!(dec.stats().bytes_discarded + frames.iter().map(frame_len).sum::<u64>(), bytes.len() as u64);
    }
}
