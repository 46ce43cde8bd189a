//! `GET /api/replay` and `POST /api/replay`: where the replay is, and pause, play, seek and
//! speed (operators; viewers watch). Only while the station replays a recording. Also what
//! a replay "as recorded" shows instead of its core's (which heard nothing): the recorded
//! state and history at the position.

use axum::Json;
use axum::extract::State;
use axum::extract::rejection::JsonRejection;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};

use super::auth::Caller;
use super::shared::Shared;
use super::shared::{AppState, HttpError, error, json_body};
use crate::config::Role;
use crate::replay::{ReplayControl, ReplayMode};
use crate::requests::ReplayBody;

/// The replay of a station replaying the recorded messages.
fn as_recorded(shared: &Shared) -> Option<&ReplayControl> {
    shared
        .replay
        .as_deref()
        .filter(|r| r.mode() == ReplayMode::Recorded)
}

/// In a replay "as recorded", the state at its position (`None` before the first, or in a
/// re-run or a live station: the core's).
pub(crate) fn recorded_state(shared: &Shared) -> Option<serde_json::Value> {
    as_recorded(shared)?.recorded_state()
}

/// In a replay "as recorded", a page's first `state` and `history` (JSON), from the recording
/// up to the position.
pub(crate) fn recorded_greeting(shared: &Shared) -> Option<[String; 2]> {
    let replay = as_recorded(shared)?;
    Some([
        replay.recorded_state()?.to_string(),
        replay.recorded_history().to_string(),
    ])
}

fn not_replaying() -> HttpError {
    error(
        StatusCode::NOT_FOUND,
        "not_found",
        "this station is live, not replaying a recording",
    )
}

pub(crate) async fn replay_status(State(state): State<AppState>, _caller: Caller) -> Response {
    match &state.replay {
        Some(r) => Json(r.view()).into_response(),
        None => not_replaying().into_response(),
    }
}

pub(crate) async fn replay_control(
    State(state): State<AppState>,
    caller: Caller,
    body: Result<Json<ReplayBody>, JsonRejection>,
) -> Result<Response, HttpError> {
    let replay = state.replay.as_ref().ok_or_else(not_replaying)?;
    if caller.role != Role::Operator {
        return Err(error(
            StatusCode::FORBIDDEN,
            "forbidden",
            "viewers watch the replay: operator role required to steer it",
        ));
    }
    let body = json_body(body)?;
    let view = replay
        .apply(&body)
        .map_err(|e| error(StatusCode::BAD_REQUEST, "bad_request", e.to_string()))?;
    tracing::info!(by = caller.name, ?body, "replay");
    Ok(Json(view).into_response())
}
