//! The daemon's recording (an adapter: a thread and files): starts stx-record's writer thread on the station's channels
//! (`crate::recording`), and feeds it what the station loop and the link driver see. Never
//! blocks the station: a message the writer cannot take is dropped and counted, and the
//! dashboard's `state.recording` says so — while the disk refuses the recording, since when
//! and when it is tried next, and once it resumes, when.

use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant, SystemTime};

use stx_record::frame::mavlink_frame_channel;
use stx_record::{
    ChannelId, CoreOptions, Direction, Directory, MavlinkFrame, Recorder, RecorderConfig,
    RecorderCore, RecorderHandle, RecorderStatus, RecordingInfo,
};

use crate::config::StationConfig;
use crate::core::Outbound;
use crate::link::FrameTap;
use crate::messages::{RecordingState, RecordingView, StateMsg};
use crate::recording::FRAMES;
use crate::recording::station::{StationChannels, wall_ns};
use crate::recording::telemetry::TelemetryChannels;

/// The station's recording, or why there is none.
pub enum Recording {
    /// `recording.enabled = false`.
    Off,
    /// Wanted, but it could not start (no directory known, the writer thread).
    Unavailable(String),
    /// Recording.
    On(Box<StationRecorder>),
}

/// A running recording and the channels it writes.
pub struct StationRecorder {
    recorder: Mutex<Option<Recorder>>,
    handle: RecorderHandle,
    channels: StationChannels,
    telemetry: std::sync::Arc<TelemetryChannels>,
    frames: ChannelId,
    started: Instant,
    wall_origin_ms: u64,
    ground_alt_msl_m: f64,
    /// Unix ms of the last `state` recorded.
    last_state_ms: AtomicU64,
}

/// `state` is recorded at most this often, ms: 1 Hz shows the debrief what the dashboard
/// showed, and the raw frames hold everything at the drone's own rates for a re-run.
pub const STATE_RECORD_PERIOD_MS: u64 = 1000;

impl Recording {
    /// Starts recording `config`'s run (mission time 0 at `started`, Unix ms
    /// `wall_origin_ms`), as its `[recording]` says.
    pub fn start(config: &StationConfig, started: Instant, wall_origin_ms: u64) -> Self {
        let settings = &config.recording;
        if !settings.enabled {
            return Self::Off;
        }
        let Some(dir) = settings.dir.clone() else {
            let why = "no recording directory: set recording.dir, --record-dir or a state \
                       directory ($STATE_DIRECTORY, $XDG_STATE_HOME or $HOME)";
            tracing::error!("{why}; the station runs without recording");
            return Self::Unavailable(why.into());
        };
        match StationRecorder::spawn(config, dir.clone(), started, wall_origin_ms) {
            Ok(r) => {
                tracing::info!(dir = %dir.display(), "recording");
                let (ch, payload) = r.channels.config(config);
                let t = r.now_ns();
                r.handle.write(ch, t, t, payload);
                Self::On(Box::new(r))
            }
            Err(why) => {
                tracing::error!("recording not started: {why}; the station runs without it");
                Self::Unavailable(why)
            }
        }
    }

    fn on(&self) -> Option<&StationRecorder> {
        match self {
            Self::On(r) => Some(r),
            _ => None,
        }
    }

    /// Records a `state` message.
    pub fn state(&self, state: &StateMsg) {
        if let Some(r) = self.on() {
            let last = r.last_state_ms.load(Ordering::Relaxed);
            if last != 0 && state.wall_ms < last.saturating_add(STATE_RECORD_PERIOD_MS) {
                return;
            }
            r.last_state_ms.store(state.wall_ms, Ordering::Relaxed);
            let t = wall_ns(state.wall_ms);
            for (ch, payload) in r.channels.state(state, r.ground_alt_msl_m) {
                r.handle.write(ch, t, t, payload);
            }
        }
    }

    /// Records what the core sent the pages (and the requests it accepted).
    pub fn outbound(&self, outbound: &[Outbound]) {
        let Some(r) = self.on() else { return };
        let now = r.now_ns();
        for o in outbound {
            let records = match o {
                Outbound::Event(e) => r.channels.event(e),
                Outbound::CommandResult(c) => vec![r.channels.command_result(c)],
                Outbound::Params(p) => vec![r.channels.params(p)],
                // Derived from the recorded telemetry: a replay through the station
                // measures it again.
                Outbound::AscentWind(_) => Vec::new(),
                Outbound::Command(c) => vec![r.channels.command(c)],
                // The change is in the event log, which is recorded.
                Outbound::KeepOut(_) => Vec::new(),
            };
            for (ch, payload) in records {
                r.handle.write(ch, now, now, payload);
            }
        }
    }

    /// Records a decoded telemetry message, received now.
    pub fn telemetry(&self, telemetry: &stx_link::telemetry::Telemetry) {
        let Some(r) = self.on() else { return };
        if r.handle.drop_if_full() {
            return;
        }
        let t = r.now_ns();
        // Encoded on the writer's thread: the station loop only moves the message there.
        let channels = r.telemetry.clone();
        let telemetry = telemetry.clone();
        r.handle
            .write_later(t, t, move || channels.records(t, &telemetry));
    }

    /// The tap that records the link's bytes, if recording.
    pub fn frame_tap(&self) -> Option<Box<dyn FrameTap>> {
        self.on().map(|r| {
            Box::new(Tap {
                handle: r.handle.clone(),
                frames: r.frames,
                started: r.started,
                wall_origin_ms: r.wall_origin_ms,
            }) as Box<dyn FrameTap>
        })
    }

    /// What the dashboard shows.
    pub fn view(&self) -> RecordingView {
        match self {
            Self::Off => not_recording(RecordingState::Off, None),
            Self::Unavailable(why) => not_recording(RecordingState::Failing, Some(why.clone())),
            Self::On(r) => view(&r.handle.status(), r.now_unix()),
        }
    }

    /// Closes the file with its summary (the station is stopping).
    pub fn finish(&self) {
        if let Some(r) = self.on()
            && let Some(recorder) = r.recorder.lock().ok().and_then(|mut g| g.take())
        {
            let status = recorder.finish();
            tracing::info!(
                bytes = status.bytes_written,
                messages = status.messages_written,
                lost = status.messages_lost,
                "recording finished"
            );
        }
    }
}

impl StationRecorder {
    fn spawn(
        config: &StationConfig,
        dir: std::path::PathBuf,
        started: Instant,
        wall_origin_ms: u64,
    ) -> Result<Self, String> {
        let settings = &config.recording;
        let options = CoreOptions {
            max_file_bytes: Some(settings.max_file_bytes()),
            max_file_duration: Some(settings.max_file_duration()),
            ..CoreOptions::default()
        };
        let info = RecordingInfo::new(
            env!("CARGO_PKG_VERSION"),
            settings.vehicle.clone(),
            settings
                .mission
                .clone()
                .unwrap_or_else(|| config.name.clone()),
        )
        .with_token_holders(&config.tokens);
        let mut core =
            RecorderCore::new(options, info, Duration::ZERO).map_err(|e| e.to_string())?;
        let channels =
            StationChannels::register(&mut core, Duration::ZERO).map_err(|e| e.to_string())?;
        let telemetry =
            TelemetryChannels::register(&mut core, Duration::ZERO).map_err(|e| e.to_string())?;
        let frames = mavlink_frame_channel(FRAMES)
            .map_err(|e| e.to_string())
            .and_then(|spec| {
                core.add_channel(Duration::ZERO, spec)
                    .map_err(|e| e.to_string())
            })?;
        let storage = Directory::new(dir, SystemTime::now());
        let recorder = Recorder::spawn(core, storage, RecorderConfig::default())
            .map_err(|e| format!("the writer thread: {e}"))?;
        Ok(Self {
            handle: recorder.handle(),
            recorder: Mutex::new(Some(recorder)),
            channels,
            telemetry: std::sync::Arc::new(telemetry),
            frames,
            started,
            wall_origin_ms,
            ground_alt_msl_m: config.origin.alt_msl_m,
            last_state_ms: AtomicU64::new(0),
        })
    }

    fn now_ns(&self) -> u64 {
        now_ns(self.started, self.wall_origin_ms)
    }

    /// Unix time now on the mission clock.
    fn now_unix(&self) -> Duration {
        Duration::from_millis(self.wall_origin_ms) + self.started.elapsed()
    }
}

/// A recording that writes nothing, and has no writer to say more.
fn not_recording(state: RecordingState, problem: Option<String>) -> RecordingView {
    RecordingView {
        state,
        file: None,
        bytes_written: 0,
        messages_written: 0,
        messages_lost: 0,
        problem,
        failing_since_ms: None,
        next_try_in_s: None,
        failed_tries: 0,
        resumed_ms: None,
        resumed_after_s: None,
    }
}

/// The writer's status as the dashboard shows it, at Unix time `now`. Failing while the
/// disk refuses the recording, even while a try has a file open: the outage ends when a
/// message reaches the disk.
fn view(s: &RecorderStatus, now: Duration) -> RecordingView {
    // In whole ns until the end, so a time an outage began reads the same in every state.
    let ago_ms = |d: Duration| now.saturating_sub(d).as_millis() as u64;
    RecordingView {
        state: if s.failing.is_some() || s.current_file.is_none() {
            RecordingState::Failing
        } else {
            RecordingState::On
        },
        file: s.current_file.as_ref().map(|p| p.display().to_string()),
        bytes_written: s.bytes_written,
        messages_written: s.messages_written,
        messages_lost: s.messages_lost,
        problem: s.last_error.as_ref().map(|e| e.message.clone()),
        failing_since_ms: s.failing.map(|f| ago_ms(f.duration)),
        next_try_in_s: s.failing.map(|f| f.next_try_in.as_secs_f64()),
        failed_tries: s.failing.map_or(0, |f| f.failed_tries),
        resumed_ms: s.resumed.map(|r| ago_ms(r.ago)),
        resumed_after_s: s.resumed.map(|r| r.after.as_secs_f64()),
    }
}

/// Unix time now on the mission clock, ns, in whole milliseconds: the resolution of
/// MAVLink's own clocks, and plenty to replay and debrief a flight. The nanoseconds of a local
/// clock are noise that does not compress — twice in every message header and once more in
/// each raw frame, they were 6 MB of a 3-hour recording. Messages of the same millisecond
/// keep their order: readers order ties as they are in the file.
fn now_ns(started: Instant, wall_origin_ms: u64) -> u64 {
    let ms = wall_origin_ms.saturating_add(started.elapsed().as_millis() as u64);
    wall_ns(ms)
}

/// Records the link's bytes from the driver's thread.
struct Tap {
    handle: RecorderHandle,
    frames: ChannelId,
    started: Instant,
    wall_origin_ms: u64,
}

impl FrameTap for Tap {
    fn frame(&mut self, path: usize, sent: bool, bytes: &[u8]) {
        if self.handle.drop_if_full() {
            return;
        }
        let t = now_ns(self.started, self.wall_origin_ms);
        let direction = if sent { Direction::Tx } else { Direction::Rx };
        let radio = u16::try_from(path).unwrap_or(u16::MAX);
        // Encoded (base64, JSON) on the writer's thread: the link's hot path copies the bytes.
        let frames = self.frames;
        let bytes = bytes.to_vec();
        self.handle.write_later(t, t, move || {
            vec![(frames, MavlinkFrame::encode(direction, radio, t, &bytes))]
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use stx_record::{Failing, Resumed};

    const NOW_MS: u64 = 1_795_000_000_000;
    const NOW: Duration = Duration::from_millis(NOW_MS);

    #[test]
    fn a_refused_disk_shows_failing_since_when_and_the_next_try_even_with_a_try_open() {
        let status = RecorderStatus {
            messages_lost: 700,
            // A try has a file open, but no message has reached it yet.
            current_file: Some("/rec/stx-20261129T064226Z-002.mcap".into()),
            failing: Some(Failing {
                duration: Duration::from_millis(75_500),
                next_try_in: Duration::from_millis(12_250),
                failed_tries: 4,
                messages_lost: 650,
            }),
            ..RecorderStatus::default()
        };
        let v = view(&status, NOW);
        assert_eq!(v.state, RecordingState::Failing);
        assert_eq!(v.failing_since_ms, Some(NOW_MS - 75_500));
        assert_eq!(v.next_try_in_s, Some(12.25));
        assert_eq!((v.failed_tries, v.messages_lost), (4, 700));
        assert_eq!((v.resumed_ms, v.resumed_after_s), (None, None));
    }

    #[test]
    fn a_resumed_recording_is_on_and_says_when_it_resumed() {
        let status = RecorderStatus {
            current_file: Some("/rec/stx-20261129T064226Z-002.mcap".into()),
            resumed: Some(Resumed {
                ago: Duration::from_secs(30),
                after: Duration::from_millis(95_000),
                messages_lost: 650,
            }),
            ..RecorderStatus::default()
        };
        let v = view(&status, NOW);
        assert_eq!(v.state, RecordingState::On);
        assert_eq!(v.resumed_ms, Some(NOW_MS - 30_000));
        assert_eq!(v.resumed_after_s, Some(95.0));
        assert_eq!(
            (v.failing_since_ms, v.next_try_in_s, v.failed_tries),
            (None, None, 0)
        );
    }
}
