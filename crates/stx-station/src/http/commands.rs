//! The commanding endpoints of `API.md` (operators only): each body is checked JSON that
//! becomes a [`CommandRequest`] for the core, answered `202` with the request id at once; the
//! outcome follows as a `command_result`. The cutdown is armed, then confirmed.

use axum::Json;
use axum::extract::rejection::JsonRejection;
use axum::extract::{Path, State};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use serde::de::DeserializeOwned;
use stx_link::plan::PlanItem;

use super::auth::Caller;
use super::shared::{AppState, HttpError, Shared, json_body};
use crate::core::CommandRequest;
use crate::replies::CommandAccepted;
use crate::requests::{
    ConfirmBody, CourseBody, HeadingBody, LocalizerBody, ModeBody, ParamBody, PlanBody,
    PlanItemBody, TargetBody,
};

/// Records a request in the core, which queues it for the link; answers 202 with its id.
fn submit(state: &Shared, caller: &Caller, request: CommandRequest) -> Result<Response, HttpError> {
    caller.operator()?;
    let now = state.now_s();
    let request_id = state.core().request(now, &caller.name, request)?;
    Ok(accepted(state, request_id))
}

/// Wakes the daemon to take the request's link action; `202` with its id.
fn accepted(state: &Shared, request_id: String) -> Response {
    state.link_due.notify_one();
    (
        StatusCode::ACCEPTED,
        Json(CommandAccepted {
            request_id,
            status: "sent",
        }),
    )
        .into_response()
}

/// A command endpoint's body: checked JSON that becomes a [`CommandRequest`].
pub(crate) trait CommandBody: DeserializeOwned + Send {
    fn into_request(self) -> CommandRequest;
}

/// Every command endpoint but parameters and cutdown: operator only, body checked, sent.
pub(crate) async fn command<B: CommandBody>(
    State(state): State<AppState>,
    caller: Caller,
    body: Result<Json<B>, JsonRejection>,
) -> Result<Response, HttpError> {
    caller.operator()?;
    let request = json_body(body)?.into_request();
    submit(&state, &caller, request)
}

impl CommandBody for ModeBody {
    fn into_request(self) -> CommandRequest {
        CommandRequest::Mode(self.mode)
    }
}

impl CommandBody for HeadingBody {
    fn into_request(self) -> CommandRequest {
        CommandRequest::Heading {
            heading_deg: self.heading_deg,
        }
    }
}

impl CommandBody for CourseBody {
    fn into_request(self) -> CommandRequest {
        CommandRequest::Course {
            course_deg: self.course_deg,
        }
    }
}

impl CommandBody for LocalizerBody {
    fn into_request(self) -> CommandRequest {
        CommandRequest::Localizer {
            lat_deg: self.lat_deg,
            lon_deg: self.lon_deg,
            course_deg: self.course_deg,
            glide_slope: self.glide_slope,
        }
    }
}

impl CommandBody for TargetBody {
    fn into_request(self) -> CommandRequest {
        CommandRequest::Target {
            lat_deg: self.lat_deg,
            lon_deg: self.lon_deg,
            alt_msl_m: self.alt_msl_m,
            approach_course_deg: self.approach_course_deg,
        }
    }
}

impl CommandBody for PlanBody {
    fn into_request(self) -> CommandRequest {
        let items = self
            .items
            .into_iter()
            .map(|item| match item {
                PlanItemBody::Waypoint {
                    lat_deg,
                    lon_deg,
                    alt_msl_m,
                } => PlanItem::Waypoint {
                    lat_deg,
                    lon_deg,
                    alt_msl_m,
                },
                PlanItemBody::Land {
                    lat_deg,
                    lon_deg,
                    alt_msl_m,
                    approach_course_deg,
                } => PlanItem::Land {
                    lat_deg,
                    lon_deg,
                    alt_msl_m,
                    approach_heading_deg: approach_course_deg,
                },
            })
            .collect();
        CommandRequest::Plan(items)
    }
}

pub(crate) async fn set_param(
    State(state): State<AppState>,
    caller: Caller,
    Path(name): Path<String>,
    body: Result<Json<ParamBody>, JsonRejection>,
) -> Result<Response, HttpError> {
    caller.operator()?;
    let b = json_body(body)?;
    submit(
        &state,
        &caller,
        CommandRequest::ParamSet {
            name,
            value: b.value,
        },
    )
}

pub(crate) async fn arm_cutdown(
    State(state): State<AppState>,
    caller: Caller,
) -> Result<Response, HttpError> {
    caller.operator()?;
    let now = state.now_s();
    let arm = state.core().arm_cutdown(now, &caller.name);
    Ok(Json(arm).into_response())
}

pub(crate) async fn confirm_cutdown(
    State(state): State<AppState>,
    caller: Caller,
    body: Result<Json<ConfirmBody>, JsonRejection>,
) -> Result<Response, HttpError> {
    caller.operator()?;
    let b = json_body(body)?;
    let now = state.now_s();
    let request_id = state.core().confirm_cutdown(now, &caller.name, &b.arm_id)?;
    Ok(accepted(&state, request_id))
}
