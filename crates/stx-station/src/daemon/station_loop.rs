//! The station loop: moves messages between the link driver, the core and the pages, and
//! owns no logic of its own.
//!
//! - the link driver's reports (endpoint events, action outcomes, link statistics, socket
//!   events) go to the core's entry points;
//! - after each turn, the core's timers run and its link actions are queued for the driver,
//!   and what the core has for the pages is broadcast. Actions wait in the loop's own queue
//!   until the driver has room (`reserve`), so neither side can block the other and none is
//!   dropped;
//! - `state` follows each burst of telemetry within [`COALESCE`], and the 4 Hz timer fills
//!   the gaps so pages see the link go stale when nothing arrives;
//! - landing predictions run on a blocking thread, one at a time, whenever the core says one is
//!   due (once a second of the drone's clock: a rehearsal at 20× is predicted 20 times a
//!   second of wall time, as often per second of its flight as a real one).
//!
//! A replay station's link hears nothing: its feeder runs the recording through the core on
//! the recording's clock (`replay_feed`), link actions and statistics included. Here it only
//! gets the state sent four times a second, and the predictions and footprints, each of
//! which is dropped if a seek has replaced the core it was computed from.

use std::collections::VecDeque;
use std::sync::Arc;
use std::time::{Duration, Instant};

use stx_link::endpoint::GroundEvent;
use stx_link_tokio::{Action, DriverEvent};
use tokio::sync::{mpsc, watch};

use super::pages::{send_outbound, show_state};
use crate::core::LinkAction;
use crate::http::Shared;
use crate::link::{LinkReport, StationLink};
use crate::messages::RecordingState;

/// The state message period: 4 Hz, the drone's rate.
pub const STATE_PERIOD: Duration = Duration::from_millis(250);
/// Link statistics are sampled this often.
const STATS_PERIOD: Duration = Duration::from_millis(500);
/// The core's timers (retries, deadlines, silent sticks) run at least this often.
const TIMER_PERIOD: Duration = Duration::from_millis(100);
/// Telemetry frames arriving within this window of the first one are answered with one
/// `state` message: the drone sends its sensors in bursts, and one message per burst keeps
/// pages current without flooding them.
const COALESCE: Duration = Duration::from_millis(1);
/// The reachable footprint is refreshed this often under the parafoil (the issue asks for at
/// least every 5 s; one refresh takes tens of milliseconds).
const FOOTPRINT_PERIOD: Duration = Duration::from_secs(2);

/// The station loop's inputs and outputs.
pub(super) struct StationLoop {
    pub shared: Arc<Shared>,
    pub actions: mpsc::Sender<Action<StationLink>>,
    pub events: mpsc::Receiver<DriverEvent<LinkReport>>,
    pub stop: watch::Receiver<bool>,
}

/// The closure that applies the core's `action` in the link driver, on the mission clock of
/// `started` (the driver's own clock starts later).
fn apply(started: Instant, action: LinkAction) -> Action<StationLink> {
    Box::new(move |link: &mut StationLink, now| {
        link.apply(now, started.elapsed().as_secs_f64(), action);
    })
}

pub(super) async fn station_loop(mut io: StationLoop) {
    let shared = io.shared.clone();
    let mut state_timer = tokio::time::interval(STATE_PERIOD);
    let mut stats_timer = tokio::time::interval(STATS_PERIOD);
    let mut core_timer = tokio::time::interval(TIMER_PERIOD);
    let (prediction_tx, mut prediction_rx) = mpsc::channel(1);
    let mut predicting = false;
    let mut footprint_timer = tokio::time::interval(FOOTPRINT_PERIOD);
    let (footprint_tx, mut footprint_rx) = mpsc::channel(1);
    let mut footprinting = false;
    let mut burst_deadline: Option<tokio::time::Instant> = None;
    let mut last_state = tokio::time::Instant::now();
    // For the driver, oldest first, until it has room.
    let mut outgoing: VecDeque<Action<StationLink>> = VecDeque::new();
    // The driver stopped (it panicked): actions are dropped here, and the core reports each
    // request as not sent at its deadline.
    let mut driver_gone = false;
    loop {
        let burst_due = async {
            match burst_deadline {
                Some(deadline) => tokio::time::sleep_until(deadline).await,
                None => std::future::pending().await,
            }
        };
        tokio::select! {
            event = io.events.recv() => {
                let Some(event) = event else { break };
                if shared.replay.is_none()
                    && on_driver_event(&shared, event)
                    && burst_deadline.is_none()
                {
                    burst_deadline = Some(tokio::time::Instant::now() + COALESCE);
                }
            }
            permit = io.actions.reserve(), if !outgoing.is_empty() && !driver_gone => {
                match permit {
                    Ok(permit) => {
                        if let Some(action) = outgoing.pop_front() {
                            permit.send(action);
                        }
                    }
                    Err(_) => {
                        tracing::error!("the link driver stopped: nothing more goes to the drone");
                        driver_gone = true;
                    }
                }
            }
            () = shared.link_due.notified() => {}
            () = burst_due => {
                burst_deadline = None;
                last_state = tokio::time::Instant::now();
                publish_state(&shared);
            }
            Some((epoch, prediction)) = prediction_rx.recv() => {
                predicting = false;
                if epoch == replay_epoch(&shared) {
                    shared.core().set_prediction(prediction);
                }
            }
            Some((epoch, done)) = footprint_rx.recv() => {
                footprinting = false;
                if epoch == replay_epoch(&shared) {
                    shared.core().set_footprint(done);
                }
            }
            _ = footprint_timer.tick() => {
                let now = shared.now_s();
                let job = if footprinting { None } else { shared.core().footprint_job(now) };
                if let Some(job) = job {
                    footprinting = true;
                    let tx = footprint_tx.clone();
                    let epoch = replay_epoch(&shared);
                    tokio::task::spawn_blocking(move || {
                        let _ = tx.blocking_send((epoch, job.run()));
                    });
                }
            }
            _ = stats_timer.tick(), if shared.replay.is_none() => {
                outgoing.push_back(Box::new(|link: &mut StationLink, now| link.sample_stats(now)));
            }
            _ = core_timer.tick() => {}
            _ = state_timer.tick() => {
                if last_state.elapsed() >= STATE_PERIOD {
                    last_state = tokio::time::Instant::now();
                    publish_state(&shared);
                }
            }
            _ = io.stop.changed() => break,
        }
        let now = shared.now_s();
        let (actions, outbound, prediction) = {
            let mut core = shared.core();
            let prediction = if predicting {
                None
            } else {
                core.prediction_job()
            };
            let actions = if shared.replay.is_none() {
                core.take_link_actions(now)
            } else {
                Vec::new()
            };
            (actions, core.drain_outbound(), prediction)
        };
        if let Some(job) = prediction {
            predicting = true;
            let tx = prediction_tx.clone();
            let epoch = replay_epoch(&shared);
            tokio::task::spawn_blocking(move || {
                let _ = tx.blocking_send((epoch, job.run()));
            });
        }
        outgoing.extend(actions.into_iter().map(|a| apply(shared.started, a)));
        if driver_gone {
            outgoing.clear();
        }
        send_outbound(&shared, outbound);
    }
}

/// Hands one report of the link driver to the core; true if it was telemetry (a `state` is
/// due).
fn on_driver_event(shared: &Shared, event: DriverEvent<LinkReport>) -> bool {
    let now = shared.now_s();
    let mut core = shared.core();
    match event {
        DriverEvent::Endpoint(LinkReport::Event(e)) => {
            let telemetry = if let GroundEvent::Telemetry { from, telemetry } = &e {
                // The telemetry topics are the drone's own (flight logs read the drone's
                // attitude there); a body IMU's ATTITUDE stays in the recorded link bytes,
                // which a re-run replay decodes again.
                if stx_types::stack::BodyImu::from_component_id(from.1).is_none() {
                    shared.recording.telemetry(telemetry);
                }
                true
            } else {
                false
            };
            core.on_link_event(now, e);
            telemetry
        }
        DriverEvent::Endpoint(LinkReport::Outcome { id, result }) => {
            core.on_action_outcome(now, id, result);
            false
        }
        DriverEvent::Endpoint(LinkReport::Stats(stats)) => {
            core.set_link_stats(now, stats);
            false
        }
        DriverEvent::Io { path, event } => {
            core.on_io_event(now, path, event);
            false
        }
    }
}

/// The seek a replay station's core belongs to (0 live): a job computed from another core is
/// not for this one.
fn replay_epoch(shared: &Shared) -> u64 {
    shared.replay.as_ref().map_or(0, |r| r.shown_epoch())
}

/// Ticks the core and sends what it queued, then the fresh `state`; a replay's core is
/// ticked by its feeder, and its pages get the state it holds.
fn publish_state(shared: &Shared) {
    if let Some(replay) = &shared.replay {
        super::replay_feed::show_replay_state(shared, replay);
        return;
    }
    let now = shared.now_s();
    let recording = shared.recording.view();
    let (mut state, outbound) = {
        let mut core = shared.core();
        core.set_recording_on(recording.state == RecordingState::On);
        let state = core.tick(now);
        (state, core.drain_outbound())
    };
    send_outbound(shared, outbound);
    state.recording = Some(recording);
    shared.recording.state(&state);
    if let Ok(text) = serde_json::to_string(&state) {
        show_state(shared, text);
    }
}
