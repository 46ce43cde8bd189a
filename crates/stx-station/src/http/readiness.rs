//! `GET /api/readiness`: the go/no-go board (any role); `POST /api/readiness/{id}`: an
//! operator ticks or unticks a checklist item. The board also rides in every `state` message.
//! `GET /api/sharing`: what the station shares with watching ground stations, chase cars and
//! SondeHub, and the public relays' audience (the board's neighbour on the Go/no-go tab).

use axum::Json;
use axum::extract::rejection::JsonRejection;
use axum::extract::{Path, State};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};

use super::auth::Caller;
use super::shared::{AppState, HttpError, error, json_body};
use crate::core::TickError;
use crate::messages::TickBody;

pub(crate) async fn board(State(state): State<AppState>, _caller: Caller) -> Response {
    let now = state.now_s();
    Json(state.core().state_msg_now(now).readiness).into_response()
}

/// `GET /api/sharing` (any role): the read-only MAVLink outputs, the chase broadcast, the
/// SondeHub upload and the public relays.
pub(crate) async fn sharing(State(state): State<AppState>, _caller: Caller) -> Response {
    let forwards = state.forwards.lock().map(|f| f.clone()).unwrap_or_default();
    let chase = state.chase.lock().ok().and_then(|c| c.clone());
    let sondehub = state
        .sondehub
        .as_ref()
        .and_then(|s| s.view.lock().ok().map(|v| v.clone()));
    let relays = state
        .clients
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .iter()
        .filter_map(|(&id, c)| {
            let viewers = (*c.relay_viewers.lock().unwrap_or_else(|e| e.into_inner()))?;
            Some(crate::forward::RelayShare {
                id,
                name: c.name.clone(),
                connected_s: c.connected_s,
                viewers,
            })
        })
        .collect();
    Json(crate::forward::SharingBody {
        forwards,
        chase,
        sondehub,
        relays,
    })
    .into_response()
}

pub(crate) async fn tick(
    State(state): State<AppState>,
    caller: Caller,
    Path(id): Path<String>,
    body: Result<Json<TickBody>, JsonRejection>,
) -> Result<Response, HttpError> {
    caller.operator()?;
    let b = json_body(body)?;
    let now = state.now_s();
    let mut core = state.core();
    match core.tick_checklist(now, &caller.name, &id, b.ticked) {
        Ok(()) => Ok(Json(core.state_msg_now(now).readiness).into_response()),
        Err(e @ TickError::UnknownItem(_)) => {
            Err(error(StatusCode::NOT_FOUND, "unknown_item", e.to_string()))
        }
    }
}
