use std::io::Cursor;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use stx_record::frame::mavlink_frame_channel;
use stx_record::{ChannelSpec, CoreOptions, Output, RecorderCore, RecordingInfo};

use super::*;
use crate::requests::ReplayBody;

const T0: u64 = 1_800_000_000_000_000_000;
const MS: u64 = 1_000_000;

/// A recording of 200 frames 10 ms apart (every fifth one sent, the rest received) and a
/// `state` every 100 ms.
fn recording() -> Vec<u8> {
    let mut core = RecorderCore::new(
        CoreOptions::default(),
        RecordingInfo::new("t", "v", "m"),
        Duration::ZERO,
    )
    .unwrap();
    let frames = core
        .add_channel(Duration::ZERO, mavlink_frame_channel(FRAMES).unwrap())
        .unwrap();
    let state = core
        .add_channel(
            Duration::ZERO,
            ChannelSpec::json(
                STATE,
                "stx.StateMsg",
                &serde_json::json!({"type": "object"}),
            )
            .unwrap(),
        )
        .unwrap();
    for i in 0..200u64 {
        let now = Duration::from_millis(i * 10);
        let t = T0 + i * 10 * MS;
        let direction = if i % 5 == 0 {
            Direction::Tx
        } else {
            Direction::Rx
        };
        let bytes = (i as u16).to_be_bytes();
        core.write(
            now,
            frames,
            t,
            t,
            &MavlinkFrame::encode(direction, 0, t, &bytes),
        )
        .unwrap();
        if i % 10 == 0 {
            core.write(now, state, t, t, format!("{{\"i\":{i}}}").as_bytes())
                .unwrap();
        }
    }
    core.finish().unwrap();
    let mut out = Vec::new();
    while let Some(o) = core.poll_output() {
        if let Output::Bytes { data, .. } = o {
            out.extend(data);
        }
    }
    out
}

struct Sink {
    frames: Vec<u16>,
    states: Vec<String>,
    resets: usize,
    stop_after_frames: usize,
    stop: Arc<AtomicBool>,
    /// A test whose feeder never delivers what it waits for fails instead of hanging.
    until: std::time::Instant,
}

impl Default for Sink {
    fn default() -> Self {
        Self {
            frames: Vec::new(),
            states: Vec::new(),
            resets: 0,
            stop_after_frames: usize::MAX,
            stop: Arc::default(),
            until: std::time::Instant::now() + Duration::from_secs(20),
        }
    }
}

impl ReplaySink for Sink {
    fn link_bytes(&mut self, _radio: u16, bytes: &[u8]) {
        self.frames.push(u16::from_be_bytes([bytes[0], bytes[1]]));
        if self.frames.len() >= self.stop_after_frames {
            self.stop.store(true, Ordering::Relaxed);
        }
    }
    fn state(&mut self, json: &[u8]) {
        self.states.push(String::from_utf8_lossy(json).into_owned());
        if self.states.len() >= 20 {
            self.stop.store(true, Ordering::Relaxed);
        }
    }
    fn event(&mut self, _json: &[u8]) {}
    fn reset(&mut self) {
        self.resets += 1;
    }
    fn stopped(&self) -> bool {
        self.stop.load(Ordering::Relaxed) || std::time::Instant::now() > self.until
    }
}

fn control(mode: ReplayMode) -> ReplayControl {
    ReplayControl::new("test.mcap".into(), mode, T0, T0 + 1990 * MS, 64.0).unwrap()
}

#[test]
fn a_rerun_replays_every_received_frame_in_order_and_nothing_sent() {
    let mut rec = Recording::from_reader(Cursor::new(recording())).unwrap();
    let control = control(ReplayMode::Rerun);
    let mut sink = Sink {
        stop_after_frames: 160,
        ..Sink::default()
    };
    feed(&mut rec, &control, &mut sink).unwrap();
    let expected: Vec<u16> = (0..200u16).filter(|i| i % 5 != 0).collect();
    assert_eq!(sink.frames, expected);
    assert!(
        sink.states.is_empty(),
        "a re-run shows the station's own state"
    );
}

#[test]
fn as_recorded_replays_the_states() {
    let mut rec = Recording::from_reader(Cursor::new(recording())).unwrap();
    let control = control(ReplayMode::Recorded);
    let mut sink = Sink::default();
    feed(&mut rec, &control, &mut sink).unwrap();
    assert_eq!(sink.states.len(), 20);
    assert_eq!(sink.states[0], "{\"i\":0}", "from the very start");
    assert_eq!(sink.states[3], "{\"i\":30}");
    assert!(sink.frames.is_empty());
}

#[test]
fn a_seek_while_paused_starts_again_from_the_new_place() {
    let mut rec = Recording::from_reader(Cursor::new(recording())).unwrap();
    let control = Arc::new(control(ReplayMode::Rerun));
    control
        .apply(&ReplayBody {
            paused: Some(true),
            ..ReplayBody::default()
        })
        .unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let c = control.clone();
    let s = stop.clone();
    let operator = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(50));
        c.apply(&ReplayBody {
            position_ms: Some(1000),
            paused: Some(false),
            ..ReplayBody::default()
        })
        .unwrap();
        drop(s);
    });
    let mut sink = Sink {
        stop_after_frames: 5,
        stop,
        ..Sink::default()
    };
    feed(&mut rec, &control, &mut sink).unwrap();
    assert!(sink.resets >= 1, "the sink hears of the jump");
    assert_eq!(sink.frames, [101, 102, 103, 104, 106], "from 1000 ms on");
    operator.join().unwrap();
}
