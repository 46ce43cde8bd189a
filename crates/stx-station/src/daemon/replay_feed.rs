//! The replay's feeder thread on a running station, and what the pages get from it.
//!
//! Re-run: the recorded link bytes go through [`Rerun`] into the station's core, on the
//! recording's clock. At the start and after every seek the feeder builds a fresh core from the
//! recording's beginning up to the position, beside the one the pages see (whose states are
//! held back meanwhile, `ReplayView.seeking`), then swaps it in and sends every page the
//! `history` of the new epoch (track, events, plots up to the position), the parameter table
//! and the ascent's winds, then the state. As recorded: the recorded states and events go to
//! the pages and into the replay's [`crate::replay::RecordedTimeline`], rebuilt the same way.
//!
//! The station loop keeps sending the state four times a second (what the core holds at the
//! replay's position: unchanged while paused, so nothing ages into stale).

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::Instant;

use stx_record::Recording;

use super::pages::{broadcast, send_outbound, show_state};
use crate::core::StationCore;
use crate::http::Shared;
use crate::messages::StateMsg;
use crate::replay::feeder::{ReplaySink, feed};
use crate::replay::{RecordedTimeline, ReplayControl, ReplayMode, Rerun};
use crate::replies::HistoryMsg;

/// Events a `history` carries (as a page's first).
const HISTORY_EVENTS: usize = 500;

/// The state a replay's pages get now: the core's at the replay's position (re-run) or the
/// newest recorded one; nothing while the station is being rebuilt after a seek.
pub(super) fn show_replay_state(shared: &Shared, replay: &ReplayControl) {
    if replay.seeking() {
        return;
    }
    match replay.mode() {
        ReplayMode::Rerun => {
            let state = shared.core().state_msg_now(shared.now_s());
            show_rerun_state(shared, replay, state);
        }
        ReplayMode::Recorded => {
            if let Some(state) = replay.recorded_state() {
                show_state(shared, state.to_string());
            }
        }
    }
}

fn show_rerun_state(shared: &Shared, replay: &ReplayControl, mut state: StateMsg) {
    state.replay = Some(replay.view());
    if let Ok(text) = serde_json::to_string(&state) {
        show_state(shared, text);
    }
}

/// Runs `f` with the log silenced: a rebuild runs the recording's past again, which the log
/// has told already (at the first play).
fn quietly<T>(f: impl FnOnce() -> T) -> T {
    tracing::dispatcher::with_default(&tracing::Dispatch::none(), f)
}

struct RerunSink {
    shared: Arc<Shared>,
    control: Arc<ReplayControl>,
    stop: Arc<AtomicBool>,
    origin_ns: u64,
    engine: Rerun,
    /// The core being built after a (re)start, until it has caught up with the position;
    /// then the station's own is fed.
    building: Option<StationCore>,
    epoch: u64,
    /// When the rebuild began, and the datagrams it ran.
    rebuild: (Instant, u64),
}

impl RerunSink {
    /// Runs `f` on the core being built, or on the station's (what it has for the pages is
    /// then sent).
    fn run<T>(&mut self, f: impl FnOnce(&mut Rerun, &mut StationCore) -> T) -> T {
        let engine = &mut self.engine;
        if let Some(core) = &mut self.building {
            return quietly(|| f(engine, core));
        }
        let (out, outbound) = {
            let mut core = self.shared.core();
            let out = f(engine, &mut core);
            (out, core.drain_outbound())
        };
        send_outbound(&self.shared, outbound);
        out
    }
}

impl ReplaySink for RerunSink {
    fn restart(&mut self, epoch: u64, _target_ns: u64) {
        self.engine = Rerun::new(&self.shared.config, self.origin_ns);
        self.building = Some(self.engine.fresh_core(&self.shared.core()));
        self.epoch = epoch;
        self.rebuild = (Instant::now(), 0);
    }

    fn caught_up(&mut self, target_ns: u64, release: &mut dyn FnMut()) {
        let Some(mut core) = self.building.take() else {
            return;
        };
        let engine = &mut self.engine;
        let state = quietly(|| engine.settle(&mut core, target_ns));
        // The rebuild's events are in the core's log (the history below), not news.
        core.drain_outbound();
        let now_s = state.time_s;
        let mut events = core.events_since(f64::NEG_INFINITY);
        let history = HistoryMsg {
            kind: "history",
            track: core.track(1.0),
            events: events.split_off(events.len().saturating_sub(HISTORY_EVENTS)),
            states: core.history(),
            replay_epoch: Some(self.epoch),
        };
        let params = serde_json::to_string(&core.params_msg(now_s));
        let ascent = serde_json::to_string(&core.ascent_wind_msg(now_s));
        {
            // Under the core's lock: a page connecting now gets the new core with its epoch.
            let mut shown = self.shared.core();
            *shown = core;
            release();
        }
        let (began, datagrams) = self.rebuild;
        tracing::info!(
            position_s = format!("{now_s:.1}"),
            datagrams,
            took_ms = began.elapsed().as_millis() as u64,
            "replay: the station rebuilt at the position"
        );
        for text in [serde_json::to_string(&history), params, ascent]
            .into_iter()
            .flatten()
        {
            broadcast(&self.shared, text);
        }
        show_replay_state(&self.shared, &self.control);
    }

    fn link_bytes(&mut self, t_ns: u64, _radio: u16, bytes: &[u8]) {
        if self.building.is_some() {
            self.rebuild.1 += 1;
        }
        self.run(|engine, core| engine.received(core, t_ns, bytes));
    }

    fn state(&mut self, _t_ns: u64, _json: &[u8]) {}

    fn event(&mut self, _t_ns: u64, _json: &[u8]) {}

    fn deadline(&self) -> Option<u64> {
        Some(self.engine.deadline())
    }

    fn at(&mut self, t_ns: u64) {
        let playing = self.building.is_none();
        let state = self.run(|engine, core| engine.at(core, t_ns));
        if let Some(state) = state.filter(|_| playing) {
            show_rerun_state(&self.shared, &self.control, state);
        }
    }

    fn stopped(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

struct RecordedSink {
    shared: Arc<Shared>,
    control: Arc<ReplayControl>,
    stop: Arc<AtomicBool>,
    /// The timeline being built after a (re)start, until it has caught up.
    building: Option<RecordedTimeline>,
    epoch: u64,
}

impl ReplaySink for RecordedSink {
    fn restart(&mut self, epoch: u64, _target_ns: u64) {
        self.building = Some(RecordedTimeline::default());
        self.epoch = epoch;
    }

    fn caught_up(&mut self, _target_ns: u64, release: &mut dyn FnMut()) {
        let Some(timeline) = self.building.take() else {
            return;
        };
        let history = timeline.history(self.epoch).to_string();
        {
            // Under the timeline's lock, as a page's greeting reads them: they agree.
            let mut shown = self.control.recorded();
            *shown = timeline;
            release();
        }
        broadcast(&self.shared, history);
        show_replay_state(&self.shared, &self.control);
    }

    fn link_bytes(&mut self, _t_ns: u64, _radio: u16, _bytes: &[u8]) {}

    fn state(&mut self, _t_ns: u64, json: &[u8]) {
        match &mut self.building {
            Some(timeline) => {
                timeline.state(json);
            }
            None => {
                if self.control.recorded().state(json).is_some() {
                    show_replay_state(&self.shared, &self.control);
                }
            }
        }
    }

    fn event(&mut self, _t_ns: u64, json: &[u8]) {
        match &mut self.building {
            Some(timeline) => {
                timeline.event(json);
            }
            None => {
                let event = self.control.recorded().event(json).map(|e| e.to_string());
                if let Some(text) = event {
                    broadcast(&self.shared, text);
                }
            }
        }
    }

    fn deadline(&self) -> Option<u64> {
        None
    }

    fn at(&mut self, _t_ns: u64) {}

    fn stopped(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

/// Starts feeding `recording` into the station of `shared` as `control` says, until `stop`
/// is set.
pub fn spawn_replay_feeder(
    recording: Recording<std::fs::File>,
    file: PathBuf,
    control: Arc<ReplayControl>,
    shared: Arc<Shared>,
    stop: Arc<AtomicBool>,
) -> std::io::Result<JoinHandle<()>> {
    let mut sink: Box<dyn ReplaySink + Send> = match control.mode() {
        ReplayMode::Rerun => {
            let origin_ns = control.clock().range().0;
            Box::new(RerunSink {
                engine: Rerun::new(&shared.config, origin_ns),
                origin_ns,
                shared,
                control: control.clone(),
                stop,
                building: None,
                epoch: 0,
                rebuild: (Instant::now(), 0),
            })
        }
        ReplayMode::Recorded => Box::new(RecordedSink {
            shared,
            control: control.clone(),
            stop,
            building: None,
            epoch: 0,
        }),
    };
    std::thread::Builder::new()
        .name("stx-replay".into())
        .spawn(move || {
            let mut recording = recording;
            if let Err(e) = feed(&mut recording, &control, sink.as_mut()) {
                tracing::error!(file = %file.display(), error = %e, "the replay stopped: the recording could not be read further");
            }
        })
}
