//! `POST /api/plan` and `GET /api/plan/defaults` ([`crate::preflight`]), for anyone: a plan
//! reads and commands nothing. The plan is computed on a blocking thread, so the WebSocket and
//! the link never wait for it, and one at a time (`Shared::planning`); a request meanwhile
//! is told to come back, not queued.

use std::time::Instant;

use axum::Json;
use axum::extract::State;
use axum::extract::rejection::JsonRejection;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};

use super::auth::Caller;
use super::recordings::recording_path;
use super::shared::{AppState, HttpError, error, json_body};
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
