//! The WebSocket of `API.md`. Each page is fed from two sources: `state` messages through a
//! `watch` channel (latest wins: a page that falls behind skips to the newest state, counted
//! as coalesced; a page that acknowledges states is sent one only when it is ready, see
//! [`super::state_flow`]), and events, command results and parameter tables through a broadcast
//! backlog of [`crate::daemon::RELIABLE_BACKLOG`] messages, never skipped silently: a page
//! that falls further behind gets a `lagged` message with the number it missed, and re-reads
//! the event log. Operators' sticks come in on it.

use std::sync::Arc;
use std::sync::atomic::Ordering;

use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::{Query, State};
use axum::response::{IntoResponse, Response};
use serde::Deserialize;
use stx_link::manual::Sticks;
use tokio::sync::broadcast;

use super::auth::Caller;
use super::rest::session_of;
use super::shared::{AppState, ClientCounters, HttpError, Shared};
use super::state_flow::StateFlow;
use crate::config::Role;
use crate::limits::RetryAfter;
use crate::messages::{EventMsg, Level};
use crate::replies::{HelloMsg, HistoryMsg, LaggedMsg, PongMsg};
use crate::requests::ClientMessage;

/// The WebSocket's query besides the token.
#[derive(Debug, Default, Deserialize)]
pub(crate) struct WsQuery {
    /// The page acknowledges every state it handles (`state_ack`), from the first.
    #[serde(default)]
    state_acks: bool,
}

pub(crate) async fn websocket(
    State(state): State<AppState>,
    caller: Caller,
    Query(query): Query<WsQuery>,
    upgrade: WebSocketUpgrade,
) -> Response {
    let pages = state
        .clients
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .len();
    let max = state.config.limits.max_websockets;
    if pages >= max {
        tracing::warn!(
            pages,
            "WebSocket refused: the station serves {max} pages at most"
        );
        return HttpError::too_many(
            format!("the station serves {max} pages at once"),
            RetryAfter(5),
        )
        .into_response();
    }
    let flow = if query.state_acks {
        StateFlow::acknowledged()
    } else {
        StateFlow::default()
    };
    upgrade.on_upgrade(move |socket| serve_socket(state, caller, flow, socket))
}

async fn serve_socket(state: AppState, caller: Caller, mut flow: StateFlow, mut socket: WebSocket) {
    let mut updates = state.broadcast.subscribe();
    let base = state.broadcast_total.load(Ordering::Relaxed);
    let mut states = state.states.subscribe();
    let mut last_seq = states.borrow_and_update().seq;
    let id = state.next_client.fetch_add(1, Ordering::Relaxed) + 1;
    let counters = Arc::new(ClientCounters {
        name: caller.name.clone(),
        role: Some(caller.role),
        connected_s: state.now_s(),
        base,
        ..ClientCounters::default()
    });
    state
        .clients
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .insert(id, counters.clone());
    let greeting = {
        let hello = HelloMsg {
            kind: "hello",
            session: session_of(&state, &caller),
            role: caller.role,
            name: caller.name.clone(),
        };
        let [state_msg, history] = match super::replay::recorded_greeting(&state) {
            Some(recorded) => recorded,
            None => {
                let now = state.now_s();
                let core = state.core();
                let mut events = core.events_since(f64::NEG_INFINITY);
                let history = HistoryMsg {
                    kind: "history",
                    track: core.track(1.0),
                    events: events.split_off(events.len().saturating_sub(500)),
                    states: core.history(),
                    replay_epoch: state.replay.as_ref().map(|r| r.shown_epoch()),
                };
                let mut state_msg = core.state_msg_now(now);
                state_msg.recording = state.replay.is_none().then(|| state.recording.view());
                state_msg.replay = state.replay.as_ref().map(|r| r.view());
                [
                    serde_json::to_string(&state_msg).unwrap_or_default(),
                    serde_json::to_string(&history).unwrap_or_default(),
                ]
            }
        };
        [
            serde_json::to_string(&hello).unwrap_or_default(),
            state_msg,
            history,
        ]
    };
    let mut open = true;
    for text in greeting {
        if socket.send(Message::Text(text.into())).await.is_err() {
            open = false;
            break;
        }
    }
    // The greeting's state.
    flow.sent(std::time::Instant::now());
    while open {
        let held_until = flow.held_until(std::time::Instant::now());
        tokio::select! {
            // Events and command results before states: they are what must not be lost.
            biased;
            update = updates.recv() => match update {
                Ok(text) => {
                    counters.messages_sent.fetch_add(1, Ordering::Relaxed);
                    open = socket.send(Message::Text(text)).await.is_ok();
                }
                Err(broadcast::error::RecvError::Lagged(missed)) => {
                    counters.messages_missed.fetch_add(missed, Ordering::Relaxed);
                    let episodes = counters.lag_episodes.fetch_add(1, Ordering::Relaxed) + 1;
                    tracing::warn!(client = id, name = %caller.name, missed, episodes,
                        "a page fell behind: it is told what it missed");
                    let notice = LaggedMsg {
                        kind: "lagged",
                        missed,
                        missed_total: counters.messages_missed.load(Ordering::Relaxed),
                        time_s: state.now_s(),
                        refetch: "/api/events",
                    };
                    let text = serde_json::to_string(&notice).unwrap_or_default();
                    open = socket.send(Message::Text(text.into())).await.is_ok();
                }
                Err(broadcast::error::RecvError::Closed) => break,
            },
            changed = states.changed(), if held_until.is_none() => {
                if changed.is_err() {
                    break;
                }
                let frame = states.borrow_and_update().clone();
                let skipped = frame.seq.saturating_sub(last_seq + 1);
                if skipped > 0 {
                    counters.states_coalesced.fetch_add(skipped, Ordering::Relaxed);
                }
                last_seq = frame.seq;
                counters.states_sent.fetch_add(1, Ordering::Relaxed);
                flow.sent(std::time::Instant::now());
                open = socket.send(Message::Text(frame.text)).await.is_ok();
            }
            // A page that stopped acknowledging gets the newest state anyway, now and then.
            () = tokio::time::sleep_until(held_until.unwrap_or_else(std::time::Instant::now).into()), if held_until.is_some() => {}
            incoming = socket.recv() => match incoming {
                Some(Ok(Message::Text(text))) => {
                    handle_client(&state, &caller, &counters, &mut socket, &mut flow, text.as_str()).await;
                }
                Some(Ok(Message::Close(_))) | None | Some(Err(_)) => break,
                Some(Ok(_)) => {}
            },
        }
    }
    state
        .clients
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .remove(&id);
}

/// The `event` a page gets back when its message is refused (to that page only, not logged).
fn refusal(state: &Shared, text: &str) -> Message {
    let now = state.now_s();
    let (wall_ms, mission_time_s) = {
        let core = state.core();
        (core.wall_ms(now), core.mission_time_s(now))
    };
    let reply = EventMsg {
        kind: "event",
        time_s: now,
        mission_time_s,
        wall_ms,
        level: Level::Error,
        source: "station",
        text: text.to_string(),
    };
    Message::Text(serde_json::to_string(&reply).unwrap_or_default().into())
}

async fn handle_client(
    state: &Shared,
    caller: &Caller,
    counters: &ClientCounters,
    socket: &mut WebSocket,
    flow: &mut StateFlow,
    text: &str,
) {
    let message = serde_json::from_str::<ClientMessage>(text);
    if matches!(
        message,
        Ok(ClientMessage::Manual { .. } | ClientMessage::ManualRelease)
    ) && (caller.role != Role::Operator || caller.replay)
    {
        let reply = refusal(
            state,
            if caller.replay {
                "this station is replaying a recording: there is no drone to fly"
            } else {
                "viewers cannot fly the drone: operator role required"
            },
        );
        let _ = socket.send(reply).await;
        return;
    }
    match message {
        Ok(ClientMessage::ManualRelease) => {
            let now = state.now_s();
            state.core().manual_release(now);
            state.link_due.notify_one();
        }
        Ok(ClientMessage::RelayViewers { viewers }) => {
            let mut held = counters
                .relay_viewers
                .lock()
                .unwrap_or_else(|e| e.into_inner());
            if held.is_none() {
                tracing::info!(name = %caller.name, viewers, "a public relay is on this socket");
            }
            *held = Some(viewers);
        }
        Ok(ClientMessage::StateAck) => flow.acked(),
        Ok(ClientMessage::Ping) => {
            let pong = serde_json::to_string(&PongMsg { kind: "pong" }).unwrap_or_default();
            let _ = socket.send(Message::Text(pong.into())).await;
        }
        Ok(ClientMessage::Manual {
            x,
            y,
            z,
            r,
            buttons,
        }) => {
            let now = state.now_s();
            // The core clamps each axis.
            let sticks = Sticks {
                x,
                y,
                z,
                r,
                buttons,
            };
            state.core().manual_hold(now, sticks);
            state.link_due.notify_one();
        }
        Err(e) => {
            let reply = refusal(state, &format!("malformed message refused: {e}"));
            let _ = socket.send(reply).await;
        }
    }
}
