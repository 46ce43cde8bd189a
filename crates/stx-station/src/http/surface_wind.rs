//! `/api/surface_wind`: the wind at the target as the station holds it (`GET`), the
//! operator's reading of it (`POST`, sent to the drone at once) and its withdrawal
//! (`DELETE`). Each answers with the `surface_wind` part of the state.

use axum::Json;
use axum::extract::State;
use axum::extract::rejection::JsonRejection;

use super::auth::Caller;
use super::shared::{AppState, HttpError, json_body};
use crate::requests::SurfaceWindBody;
use crate::surface_wind::SurfaceWindView;

/// `GET`: for any caller.
pub(crate) async fn view(
    State(state): State<AppState>,
    _caller: Caller,
) -> Result<Json<SurfaceWindView>, HttpError> {
    let now = state.now_s();
    Ok(Json(state.core().state_msg_now(now).surface_wind))
}

/// `POST`: operators only; a value out of range is refused, naming the field.
pub(crate) async fn set(
    State(state): State<AppState>,
    caller: Caller,
    body: Result<Json<SurfaceWindBody>, JsonRejection>,
) -> Result<Json<SurfaceWindView>, HttpError> {
    caller.operator()?;
    let b = json_body(body)?;
    let now = state.now_s();
    let view = {
        let mut core = state.core();
        core.set_operator_surface_wind(now, &caller.name, b.speed_mps, b.from_deg)?;
        core.state_msg_now(now).surface_wind
    };
    state.link_due.notify_one();
    Ok(Json(view))
}

/// `DELETE`: operators only.
pub(crate) async fn clear(
    State(state): State<AppState>,
    caller: Caller,
) -> Result<Json<SurfaceWindView>, HttpError> {
    caller.operator()?;
    let now = state.now_s();
    let mut core = state.core();
    core.clear_operator_surface_wind(now, &caller.name);
    Ok(Json(core.state_msg_now(now).surface_wind))
}
