//! The reading endpoints of `API.md`: session, state, parameters, ascent winds, events, track,
//! command results and connected pages; any other path under `/api/` is a 404 with a reason.

use std::sync::atomic::Ordering;

use axum::Json;
use axum::extract::{Path, Query, State};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use serde::Deserialize;
use stx_gnc::mission::FlightMode;

use super::auth::Caller;
use super::shared::{AppState, HttpError, Shared, error};
use crate::messages::{Session, StationInfo};
use crate::replies::{ClientsBody, EventsBody, TrackBody};
use crate::tile_pack::TilePack;

pub(crate) fn session_of(state: &Shared, caller: &Caller) -> Session {
    let c = &state.config;
    let pack = state.tiles.drawable().map(TilePack::info);
    let tile_url = c.tile_url.clone().or_else(|| {
        pack.map(|i| match i.format {
            Some(format) => format!("/tiles/{{z}}/{{x}}/{{y}}.{}", format.name()),
            None => "/tiles/{z}/{x}/{y}".into(),
        })
    });
    let tile_attribution = match (c.tile_attribution.is_empty(), pack) {
        (true, Some(info)) => info.attribution.clone().unwrap_or_default(),
        _ => c.tile_attribution.clone(),
    };
    // The pack's zooms and extent bound the map's requests only when every tile it shows
    // comes from the pack (no directory filling in, no online source).
    let from_station = tile_url
        .as_deref()
        .is_some_and(|u| u.starts_with("/tiles/"));
    let pack_alone = pack.filter(|_| from_station && c.tiles_dir.is_none());
    Session {
        role: caller.role,
        name: caller.name.clone(),
        station: StationInfo {
            name: c.name.clone(),
            origin: crate::messages::LatLonAlt {
                lat_deg: c.origin.lat_deg,
                lon_deg: c.origin.lon_deg,
                alt_msl_m: c.origin.alt_msl_m,
            },
            tile_url,
            tile_attribution,
            offline_tiles: c.tiles_dir.is_some() || pack.is_some(),
            offline_tiles_error: state.tiles.error.clone(),
            tile_max_zoom: pack_alone.and_then(|i| i.max_zoom),
            tile_bounds: pack_alone.and_then(|i| i.bounds),
            modes: FlightMode::ALL
                .iter()
                .map(|m| {
                    serde_json::to_value(m)
                        .ok()
                        .and_then(|v| v.as_str().map(String::from))
                        .unwrap_or_default()
                })
                .collect(),
            replay: state.replay.is_some(),
        },
    }
}

pub(crate) async fn api_not_found(uri: axum::http::Uri) -> HttpError {
    error(
        StatusCode::NOT_FOUND,
        "not_found",
        format!("no API endpoint {} (see API.md)", uri.path()),
    )
}

pub(crate) async fn clients(State(state): State<AppState>, _caller: Caller) -> Response {
    let clients = state
        .clients
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .iter()
        .map(|(id, c)| c.view(*id, state.broadcast_total.load(Ordering::Relaxed)))
        .collect();
    Json(ClientsBody { clients }).into_response()
}

pub(crate) async fn session(State(state): State<AppState>, caller: Caller) -> Json<Session> {
    Json(session_of(&state, &caller))
}

pub(crate) async fn state_now(State(state): State<AppState>, _caller: Caller) -> Response {
    if let Some(recorded) = super::replay::recorded_state(&state) {
        return Json(recorded).into_response();
    }
    let now = state.now_s();
    let mut msg = state.core().state_msg_now(now);
    msg.recording = state.replay.is_none().then(|| state.recording.view());
    msg.replay = state.replay.as_ref().map(|r| r.view());
    Json(msg).into_response()
}

pub(crate) async fn params(State(state): State<AppState>, _caller: Caller) -> Response {
    let now = state.now_s();
    Json(state.core().params_msg(now)).into_response()
}

pub(crate) async fn ascent_wind(State(state): State<AppState>, _caller: Caller) -> Response {
    let now = state.now_s();
    Json(state.core().ascent_wind_msg(now)).into_response()
}

#[derive(Deserialize)]
pub(crate) struct SinceQuery {
    since_s: Option<f64>,
}

pub(crate) async fn events(
    State(state): State<AppState>,
    _caller: Caller,
    Query(q): Query<SinceQuery>,
) -> Response {
    let events = state
        .core()
        .events_since(q.since_s.unwrap_or(f64::NEG_INFINITY));
    Json(EventsBody { events }).into_response()
}

#[derive(Deserialize)]
pub(crate) struct EveryQuery {
    every_s: Option<f64>,
}

pub(crate) async fn track(
    State(state): State<AppState>,
    _caller: Caller,
    Query(q): Query<EveryQuery>,
) -> Response {
    let points = state.core().track(q.every_s.unwrap_or(0.0).max(0.0));
    Json(TrackBody { points }).into_response()
}

pub(crate) async fn command_result(
    State(state): State<AppState>,
    _caller: Caller,
    Path(id): Path<String>,
) -> Result<Response, HttpError> {
    match state.core().command_result(&id) {
        Some(r) => Ok(Json(r).into_response()),
        None => Err(error(
            StatusCode::NOT_FOUND,
            "not_found",
            format!("no request `{id}`"),
        )),
    }
}
