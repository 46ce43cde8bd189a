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

/// What the feeder did to the sink, in order (times in ms after `T0`).
#[derive(Debug, Clone, PartialEq)]
enum Seen {
    Restart(u64, u64),
    CaughtUp(u64),
    Frame(u16, u64),
    State(String),
    At(u64),
}

struct Sink {
    seen: Vec<Seen>,
    /// Stop after this many frames, or on catching up with this target (ms).
    stop_after_frames: usize,
    stop_at_target_ms: Option<u64>,
    /// A deadline every this many ms (from 5 ms), if any.
    deadline_every_ms: Option<u64>,
    next_deadline: u64,
    stop: Arc<AtomicBool>,
    /// A test whose feeder never delivers what it waits for fails instead of hanging.
    until: std::time::Instant,
}

impl Default for Sink {
    fn default() -> Self {
        Self {
            seen: Vec::new(),
            stop_after_frames: usize::MAX,
            stop_at_target_ms: None,
            deadline_every_ms: None,
            next_deadline: T0 + 5 * MS,
            stop: Arc::default(),
            until: std::time::Instant::now() + Duration::from_secs(20),
        }
    }
}

/// The frames among `seen`, by number.
fn frames_in(seen: &[Seen]) -> Vec<u16> {
    seen.iter()
        .filter_map(|s| match s {
            Seen::Frame(i, _) => Some(*i),
            _ => None,
        })
        .collect()
}

impl Sink {
    fn frames(&self) -> Vec<u16> {
        frames_in(&self.seen)
    }

    fn count(&self, f: impl Fn(&Seen) -> bool) -> usize {
        self.seen.iter().filter(|s| f(s)).count()
    }
}

impl ReplaySink for Sink {
    fn restart(&mut self, epoch: u64, target_ns: u64) {
        self.seen.push(Seen::Restart(epoch, (target_ns - T0) / MS));
        self.next_deadline = T0 + 5 * MS;
    }
    fn caught_up(&mut self, target_ns: u64, release: &mut dyn FnMut()) {
        release();
        self.seen.push(Seen::CaughtUp((target_ns - T0) / MS));
        if self.stop_at_target_ms == Some((target_ns - T0) / MS) {
            self.stop.store(true, Ordering::Relaxed);
        }
    }
    fn link_bytes(&mut self, t_ns: u64, _radio: u16, bytes: &[u8]) {
        let i = u16::from_be_bytes([bytes[0], bytes[1]]);
        self.seen.push(Seen::Frame(i, (t_ns - T0) / MS));
        if self.frames().len() >= self.stop_after_frames {
            self.stop.store(true, Ordering::Relaxed);
        }
    }
    fn state(&mut self, _t_ns: u64, json: &[u8]) {
        self.seen
            .push(Seen::State(String::from_utf8_lossy(json).into_owned()));
        if self.count(|s| matches!(s, Seen::State(_))) >= 20 {
            self.stop.store(true, Ordering::Relaxed);
        }
    }
    fn event(&mut self, _t_ns: u64, _json: &[u8]) {}
    fn deadline(&self) -> Option<u64> {
        self.deadline_every_ms.map(|_| self.next_deadline)
    }
    fn at(&mut self, t_ns: u64) {
        self.seen.push(Seen::At((t_ns - T0) / MS));
        self.next_deadline += self.deadline_every_ms.unwrap_or(1) * MS;
    }
    fn stopped(&self) -> bool {
        self.stop.load(Ordering::Relaxed) || std::time::Instant::now() > self.until
    }
}

fn control(mode: ReplayMode) -> ReplayControl {
    ReplayControl::new("test.mcap".into(), mode, T0, T0 + 1990 * MS, 64.0).unwrap()
}

fn pause(control: &ReplayControl) {
    control
        .apply(&ReplayBody {
            paused: Some(true),
            ..ReplayBody::default()
        })
        .unwrap();
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
    assert_eq!(sink.frames(), expected);
    assert_eq!(sink.seen[..2], [Seen::Restart(0, 0), Seen::CaughtUp(0)]);
    assert_eq!(
        sink.count(|s| matches!(s, Seen::State(_))),
        0,
        "a re-run shows the station's own state"
    );
    assert_eq!(control.shown_epoch(), 0);
    assert!(!control.seeking(), "released from the start");
}

#[test]
fn as_recorded_replays_the_states() {
    let mut rec = Recording::from_reader(Cursor::new(recording())).unwrap();
    let control = control(ReplayMode::Recorded);
    let mut sink = Sink::default();
    feed(&mut rec, &control, &mut sink).unwrap();
    let states: Vec<_> = sink
        .seen
        .iter()
        .filter_map(|s| match s {
            Seen::State(j) => Some(j.clone()),
            _ => None,
        })
        .collect();
    assert_eq!(states.len(), 20);
    assert_eq!(states[0], "{\"i\":0}", "from the very start");
    assert_eq!(states[3], "{\"i\":30}");
    assert!(sink.frames().is_empty());
}

#[test]
fn a_seek_while_paused_rebuilds_up_to_the_new_place_at_once_and_stays_there() {
    let mut rec = Recording::from_reader(Cursor::new(recording())).unwrap();
    let control = Arc::new(control(ReplayMode::Rerun));
    pause(&control);
    let c = control.clone();
    let operator = std::thread::spawn(move || {
        // Once the start is shown, far on and back.
        while c.seeking() {
            std::thread::sleep(Duration::from_millis(5));
        }
        c.apply(&ReplayBody {
            position_ms: Some(1500),
            ..ReplayBody::default()
        })
        .unwrap();
        c.apply(&ReplayBody {
            position_ms: Some(1000),
            ..ReplayBody::default()
        })
        .unwrap();
    });
    let mut sink = Sink {
        stop_at_target_ms: Some(1000),
        ..Sink::default()
    };
    feed(&mut rec, &control, &mut sink).unwrap();
    operator.join().unwrap();
    // The start, then the rebuild at 1000 ms: every received frame up to it, none after.
    let restart = sink
        .seen
        .iter()
        .rposition(|s| matches!(s, Seen::Restart(..)))
        .unwrap();
    assert_eq!(sink.seen[..2], [Seen::Restart(0, 0), Seen::CaughtUp(0)]);
    let rebuilt = &sink.seen[restart..];
    let Seen::Restart(epoch, 1000) = rebuilt[0] else {
        panic!("{:?}", rebuilt[0]);
    };
    let frames = frames_in(rebuilt);
    let expected: Vec<u16> = (0..=100u16).filter(|i| i % 5 != 0).collect();
    assert_eq!(frames, expected, "from the start up to 1000 ms");
    assert_eq!(rebuilt.last(), Some(&Seen::CaughtUp(1000)));
    assert_eq!(control.shown_epoch(), epoch);
    assert_eq!(epoch, 2, "the seek to 1500 ms came first");
    assert!(!control.seeking());
    assert_eq!(control.view().position_ms, 1000, "still paused there");
}

#[test]
fn the_sinks_own_times_come_in_order_with_the_messages() {
    let mut rec = Recording::from_reader(Cursor::new(recording())).unwrap();
    let control = control(ReplayMode::Rerun);
    let mut sink = Sink {
        stop_after_frames: 40,
        deadline_every_ms: Some(25),
        ..Sink::default()
    };
    feed(&mut rec, &control, &mut sink).unwrap();
    let times: Vec<u64> = sink
        .seen
        .iter()
        .filter_map(|s| match s {
            Seen::Frame(_, t) | Seen::At(t) => Some(*t),
            _ => None,
        })
        .collect();
    assert!(times.windows(2).all(|w| w[0] <= w[1]), "{times:?}");
    let at: Vec<u64> = sink
        .seen
        .iter()
        .filter_map(|s| match s {
            Seen::At(t) => Some(*t),
            _ => None,
        })
        .collect();
    assert_eq!(at[..4], [5, 30, 55, 80]);
}
