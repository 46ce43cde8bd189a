//! `POST /api/lab/rehearse` (operators): the simulated drone beside the station flies its
//! mission again from the start with the vehicle as edited or fitted on the Lab page as its
//! truth (its onboard guidance still starts from the mission's own polar, as with
//! `stx serve --sim --sim-vehicle`). Only a station that flies one (`stx serve --sim`) can;
//! the binary does the restart ([`super::shared::Rehearsals`]), this checks the vehicle and
//! says what flies.

use axum::Json;
use axum::extract::State;
use axum::extract::rejection::JsonRejection;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};

use super::auth::Caller;
use super::shared::{AppState, HttpError, RehearsalRequest, error, json_body};
use crate::lab::bodies::{LabRehearsalBody, LabVehicleBody};
use crate::lab::vehicle_fields::edited_vehicle;

/// How long the simulated drone may take to stop and start again, s.
const RESTART_WAIT_S: u64 = 10;

pub(crate) async fn rehearse(
    State(state): State<AppState>,
    caller: Caller,
    body: Result<Json<LabVehicleBody>, JsonRejection>,
) -> Result<Response, HttpError> {
    caller.operator()?;
    let b = json_body(body)?;
    let Some(rehearsals) = state.rehearsal.get() else {
        return Err(error(
            StatusCode::CONFLICT,
            "no_simulated_drone",
            "this station flies no simulated drone to rehearse with (start it with `stx serve --sim`)",
        ));
    };
    let vehicle = match edited_vehicle(&b.vehicle) {
        Ok(v) => v,
        Err(e) => {
            let reason = format!("{}: {}", e.field, e.reason);
            return Err(error(StatusCode::BAD_REQUEST, "invalid_vehicle", reason));
        }
    };
    let (answer, answered) = tokio::sync::oneshot::channel();
    let unavailable = |why: String| error(StatusCode::SERVICE_UNAVAILABLE, "rehearsal_failed", why);
    rehearsals
        .requests
        .send(RehearsalRequest { vehicle, answer })
        .await
        .map_err(|_| unavailable("the simulated drone is no longer flown here".into()))?;
    let mission = tokio::time::timeout(std::time::Duration::from_secs(RESTART_WAIT_S), answered)
        .await
        .map_err(|_| unavailable("the simulated drone did not restart in time".into()))?
        .map_err(|_| unavailable("the simulated drone did not answer".into()))?
        .map_err(unavailable)?;
    let started = LabRehearsalBody {
        mission,
        vehicle: b.vehicle,
        started_by: caller.name.clone(),
    };
    tracing::info!(by = %caller.name, changed = ?started.vehicle, mission = %started.mission, "rehearsal restarted with the Lab's vehicle");
    *rehearsals
        .last
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner) = Some(started.clone());
    Ok(Json(started).into_response())
}
