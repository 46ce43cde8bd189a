//! `POST /api/sondehub/chase` (any role): a recovery phone's position, which the SondeHub
//! upload sends as a chase car (`mobile: true`, at most every 10 s, the newest position
//! winning). Any role, because it shares where the phone is, not a command to the drone: the
//! recovery team's phones carry viewer tokens. Not on a replay station, which uploads nothing.

use axum::Json;
use axum::extract::State;
use axum::extract::rejection::JsonRejection;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};

use super::auth::Caller;
use super::shared::{AppState, HttpError, error, json_body};
use crate::sondehub::ChaseCarBody;

pub(crate) async fn chase_car(
    State(state): State<AppState>,
    caller: Caller,
    body: Result<Json<ChaseCarBody>, JsonRejection>,
) -> Result<Response, HttpError> {
    if caller.replay {
        return Err(HttpError::replaying());
    }
    let Some(share) = &state.sondehub else {
        return Err(error(
            StatusCode::NOT_FOUND,
            "not_found",
            "the SondeHub upload is off (no [sondehub] in the station's config)",
        ));
    };
    let b = json_body(body)?;
    if let Some(rule) = b.invalid() {
        return Err(error(StatusCode::BAD_REQUEST, "bad_request", rule));
    }
    let alt = b.alt_m.unwrap_or(state.config.origin.alt_msl_m);
    share
        .chase_car
        .send_replace(Some([b.lat_deg, b.lon_deg, alt]));
    tracing::debug!(who = %caller.name, "SondeHub: a chase car position");
    let view = share.view.lock().map(|v| v.clone()).map_err(|_| {
        error(
            StatusCode::INTERNAL_SERVER_ERROR,
            "internal",
            "the SondeHub view is unreadable",
        )
    })?;
    Ok((StatusCode::ACCEPTED, Json(view)).into_response())
}
