//! Fuzz target for the ingest path: arbitrary bytes, cut into arbitrary chunks, through the
//! frame decoder (signing off and on) and the vehicle and ground endpoints, ending with the end
//! of the stream. Nothing may panic, and every byte must be accounted for.
#![no_main]

use std::time::Duration;

use libfuzzer_sys::fuzz_target;
use stx_link::endpoint::{GroundConfig, GroundEndpoint, VehicleConfig, VehicleEndpoint};
use stx_link::frame::{DecoderPolicy, FrameDecoder, WireVersion};
use stx_link::signing::{SigningConfig, SigningKey};
use stx_link::telemetry::Telemetry;

fuzz_target!(|data: &[u8]| {
    // First byte: flags; second: chunk size.
    let (flags, rest) = data.split_first().map_or((0, data), |(f, r)| (*f, r));
    let (chunk, rest) = rest.split_first().map_or((1, rest), |(c, r)| (usize::from(*c).max(1), r));

    let mut dec = FrameDecoder::new(DecoderPolicy { accept_v1: flags & 1 != 0 });
    if flags & 2 != 0 {
        let cfg = SigningConfig::new(SigningKey::from_bytes([0x42; 32]), 0, Duration::from_secs(1_767_225_600));
        dec.set_verifier(Some(cfg.build(Duration::ZERO).1));
    }
    let mut in_frames = 0_u64;
    let now = Duration::from_secs(1);
    for c in rest.chunks(chunk) {
        dec.push(c);
        while let Some(r) = dec.poll(now) {
            if let Ok(f) = r {
                let _ = Telemetry::from_mavlink(&f.message);
                let base = u64::from(f.header.payload_len) + 2;
                in_frames += match f.header.version {
                    WireVersion::V1 => base + 6,
                    WireVersion::V2 => base + 10 + if f.header.is_signed() { 13 } else { 0 },
                };
            }
        }
    }
    dec.finish();
    while let Some(r) = dec.poll(now) {
        if let Ok(f) = r {
            let base = u64::from(f.header.payload_len) + 2;
            in_frames += match f.header.version {
                WireVersion::V1 => base + 6,
                WireVersion::V2 => base + 10 + if f.header.is_signed() { 13 } else { 0 },
            };
        }
    }
    let s = dec.stats();
    assert_eq!(s.bytes_discarded + in_frames, s.bytes_in);

    // The same bytes through both endpoints (protocol state machines included).
    let mut v = VehicleEndpoint::new(VehicleConfig::default(), Duration::ZERO).expect("default config is valid");
    let mut g = GroundEndpoint::new(GroundConfig::default(), Duration::ZERO);
    let mut t = Duration::ZERO;
    for c in rest.chunks(chunk) {
        t += Duration::from_millis(37);
        v.handle_bytes(t, c);
        g.handle_bytes(t, c);
        v.handle_timeout(t);
        g.handle_timeout(t);
        while v.poll_transmit(t).is_some() {}
        while g.poll_transmit(t).is_some() {}
        while v.poll_event().is_some() {}
        while g.poll_event().is_some() {}
    }
    // The connection drops: whatever is buffered is flushed as truncated.
    v.handle_stream_end(t);
    g.handle_stream_end(t);
    let (vs, gs) = (v.link_stats(t).decoder, g.link_stats(t).decoder);
    for s in [vs, gs] {
        assert_eq!(s.bytes_in, rest.len() as u64);
    }
});
