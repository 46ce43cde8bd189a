//! `POST /api/plan` and `GET /api/plan/defaults` ([`crate::preflight`]), `POST
//! /api/plan/forecast` (a forecast file from the page, [`crate::forecast_upload`]) and `POST
//! /api/plan/window` ([`crate::launch_window`]), for anyone: a plan reads and commands nothing. The plan is computed on a blocking thread, so the WebSocket and
//! the link never wait for it, and one at a time (`Shared::planning`); a request meanwhile
//! is told to come back, not queued.

use std::time::Instant;

use axum::Json;
use axum::body::Bytes;
use axum::extract::rejection::{JsonRejection, QueryRejection};
use axum::extract::{Query, State};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};

use super::auth::Caller;
use super::recordings::recording_path;
use super::shared::{AppState, HttpError, error, json_body};
use crate::forecast_upload::{
    self, ForecastUploadReport, UploadQuery, Uploaded, WindowBody, WindowForecast,
};
use crate::launch_window::plan_window as plan_window_over;
use crate::limits::RetryAfter;
use crate::preflight::{PreflightBody, defaults, preflight_plan};

pub(crate) async fn plan_defaults(State(state): State<AppState>, _caller: Caller) -> Response {
    let now = state.now_s();
    let guidance = state.core().state_msg_now(now).guidance;
    let target = guidance.and_then(|g| {
        let t = g.target?;
        Some(([t.lat_deg, t.lon_deg], g.target_source.unwrap_or("unknown")))
    });
    Json(defaults(&state.config, target)).into_response()
}

pub(crate) async fn make_plan(
    State(state): State<AppState>,
    caller: Caller,
    body: Result<Json<PreflightBody>, JsonRejection>,
) -> Result<Response, HttpError> {
    let PreflightBody {
        request,
        from_recording,
    } = json_body(body)?;
    let recording = match from_recording {
        Some(name) => {
            // In a plan's body an unknown recording is a bad field, not a missing page.
            let file = recording_path(&state, &name).map_err(|_| {
                error(
                    StatusCode::BAD_REQUEST,
                    "bad_request",
                    format!("from_recording: the station has no recording named {name:?}"),
                )
            })?;
            Some((name, file))
        }
        None => None,
    };
    let Ok(one) = state.planning.clone().try_lock_owned() else {
        return Err(HttpError::busy(
            "another plan is being computed: try again in a moment",
            RetryAfter(1),
        ));
    };
    let runs = request.runs;
    let started = Instant::now();
    // The guard goes with the computation: a page that gives up does not free the core early.
    let report = tokio::task::spawn_blocking(move || {
        let _one = one;
        preflight_plan(request, recording.as_ref().map(|(n, f)| (n.as_str(), &**f)))
    })
    .await
    .map_err(|e| error(StatusCode::INTERNAL_SERVER_ERROR, "internal", e.to_string()))?
    .map_err(|e| error(StatusCode::BAD_REQUEST, "bad_request", e.to_string()))?;
    // The go/no-go board's reach check reads the last plan made.
    let share = report.plan.target.as_ref().map(|t| t.reachable_probability);
    state.core().note_plan_reach(share);
    tracing::info!(
        by = caller.name,
        runs,
        ms = started.elapsed().as_millis() as u64,
        "pre-flight plan computed"
    );
    Ok(Json(report).into_response())
}

/// `POST /api/plan/forecast?lat=…&lon=…&time=…`: a GFS GRIB2 file or a sounding as the raw
/// body (at most `forecast_upload::MAX_BYTES`), read off the async workers and kept for the
/// page's windows; answered with its rows over the launch site, or 400 saying what the file
/// lacks.
pub(crate) async fn upload_forecast(
    State(state): State<AppState>,
    caller: Caller,
    query: Result<Query<UploadQuery>, QueryRejection>,
    body: Bytes,
) -> Result<Response, HttpError> {
    let Query(query) = query.map_err(|e| {
        error(
            StatusCode::BAD_REQUEST,
            "bad_request",
            format!("query: {}", e.body_text()),
        )
    })?;
    if body.is_empty() {
        return Err(error(
            StatusCode::BAD_REQUEST,
            "bad_request",
            "the body is empty: send the GRIB2 file or the sounding's text as the body",
        ));
    }
    let size = body.len();
    let upload = tokio::task::spawn_blocking(move || forecast_upload::read(&body))
        .await
        .map_err(|e| error(StatusCode::INTERNAL_SERVER_ERROR, "internal", e.to_string()))?
        .map_err(|reason| error(StatusCode::BAD_REQUEST, "bad_request", reason))?;
    let answer = forecast_upload::report(0, &upload, &query)
        .map_err(|reason| error(StatusCode::BAD_REQUEST, "bad_request", reason))?;
    let id = state.uploads().keep(upload);
    tracing::info!(
        by = caller.name,
        id,
        bytes = size,
        kind = answer.kind,
        "forecast file uploaded"
    );
    Ok(Json(ForecastUploadReport { id, ..answer }).into_response())
}

/// `POST /api/plan/window`: the plan of every launch time of a window over the configured GFS
/// forecast or an upload, one computation at a time (as plans), on all cores but one (the
/// link's).
pub(crate) async fn plan_window(
    State(state): State<AppState>,
    caller: Caller,
    body: Result<Json<WindowBody>, JsonRejection>,
) -> Result<Response, HttpError> {
    let WindowBody {
        request,
        window,
        forecast,
    } = json_body(body)?;
    let bad = |reason: String| error(StatusCode::BAD_REQUEST, "bad_request", reason);
    let upload = match forecast {
        WindowForecast::Upload(id) => Some(state.uploads().get(id).cloned().ok_or_else(|| {
            bad(format!(
                "forecast.upload: no upload {id} is kept (the station keeps the last {}): send the file again",
                forecast_upload::KEPT
            ))
        })?),
        WindowForecast::Configured => None,
    };
    let Ok(one) = state.planning.clone().try_lock_owned() else {
        return Err(HttpError::busy(
            "another plan is being computed: try again in a moment",
            RetryAfter(1),
        ));
    };
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get().saturating_sub(1));
    let launches = request.runs;
    let started = Instant::now();
    let shared = state.clone();
    let report = tokio::task::spawn_blocking(move || {
        let _one = one;
        let field = match upload {
            Some(Uploaded::Gfs(field)) => field,
            Some(Uploaded::Sounding(_)) => {
                return Err(
                    "forecast.upload: a sounding is one instant: a launch window needs GFS files"
                        .to_string(),
                );
            }
            None => shared.configured_field().ok_or_else(|| {
                "forecast: the station has no [forecast_file] gfs configured: upload a GFS file"
                    .to_string()
            })??,
        };
        plan_window_over(&field, &request, &window, threads).map_err(|e| e.to_string())
    })
    .await
    .map_err(|e| error(StatusCode::INTERNAL_SERVER_ERROR, "internal", e.to_string()))?
    .map_err(bad)?;
    tracing::info!(
        by = caller.name,
        runs = launches,
        launches = report.launches.len(),
        ms = started.elapsed().as_millis() as u64,
        "launch window computed"
    );
    Ok(Json(report).into_response())
}
