//! The Lab's endpoints (`/api/lab/…`): its status and last result for every page; starting and
//! cancelling a job, saving a vehicle or gains file and sending gains to the drone for
//! operators. A job's work runs on a thread of its own (named `stx-lab`), never on the runtime that
//! carries the telemetry, at the lowest priority (the idle scheduling class and
//! [`crate::priority::LOWEST_NICE`]), and reports to the pure runner ([`crate::lab::LabJobs`]). A comparison's
//! recording is checked before its job starts: a plain name of the recordings directory (as
//! `GET /api/recordings` lists them), a readable file, holding a flight, and one in the
//! window asked for, if any (the work reads it: [`crate::lab::LabWorker::check_window`]).

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;

use axum::Json;
use axum::extract::State;
use axum::extract::rejection::JsonRejection;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use stx_gnc::params::{CATALOG, OnboardSettings};

use super::auth::Caller;
use super::shared::{AppState, HttpError, Shared, error, json_body};
use crate::core::CommandRequest;
use crate::lab::bodies::{
    LabGain, LabGainsBody, LabGainsListBody, LabSavedBody, LabStartedBody, LabVehicleBody,
};
use crate::lab::compare::missing_flight;
use crate::lab::vehicle_fields::{FieldError, edited_config, edited_vehicle, fields};
use crate::lab::{JobControl, JobInputs, LabJobBody, LabJobs, LabService, VehicleEdits};

/// A refused field as every refusal is answered (`ErrorBody`): the reason starts with the
/// field's dotted name, so a page can mark it.
fn field_error(status: StatusCode, kind: &'static str, e: FieldError) -> Response {
    let reason = if e.field.is_empty() {
        e.reason
    } else {
        format!("{}: {}", e.field, e.reason)
    };
    error(status, kind, reason).into_response()
}

fn lab_of(state: &Shared) -> Result<Arc<LabService>, HttpError> {
    state.lab.get().cloned().ok_or_else(|| {
        error(
            StatusCode::SERVICE_UNAVAILABLE,
            "lab_unavailable",
            "this station runs no Lab (a replay, or started without one)",
        )
    })
}

pub(crate) async fn status(State(state): State<AppState>, _caller: Caller) -> Response {
    Json(status_body(&state)).into_response()
}

/// The Lab's status with what the station can rehearse.
fn status_body(state: &Shared) -> crate::lab::jobs::LabStatusBody {
    let now = state.now_s();
    let mut s = match state.lab.get() {
        Some(lab) => lab.jobs().status(now),
        None => {
            let mut s = LabJobs::new(0.0).status(now);
            s.available = false;
            s
        }
    };
    if let Some(rehearsals) = state.rehearsal.get() {
        s.rehearse = true;
        s.rehearsal = rehearsals
            .last
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .clone();
    }
    s
}

struct Control {
    shared: Arc<Shared>,
    lab: Arc<LabService>,
    id: u64,
}

impl JobControl for Control {
    fn progress(&self, done: usize, total: usize) {
        self.lab.jobs().progress(self.id, done, total);
    }
    fn should_stop(&self) -> bool {
        let now = self.shared.now_s();
        self.lab.jobs().stop_reason(self.id, now).is_some()
    }
}

pub(crate) async fn start(
    State(state): State<AppState>,
    caller: Caller,
    body: Result<Json<LabJobBody>, JsonRejection>,
) -> Result<Response, HttpError> {
    caller.operator()?;
    let lab = lab_of(&state)?;
    let job = json_body(body)?;
    if let Err((field, reason)) = job.check() {
        let e = FieldError { field, reason };
        return Ok(field_error(StatusCode::BAD_REQUEST, "invalid_job", e));
    }
    let vehicle = match edited_vehicle(job.vehicle_edits().unwrap_or(&VehicleEdits::new())) {
        Ok(v) => v,
        Err(e) => return Ok(field_error(StatusCode::BAD_REQUEST, "invalid_vehicle", e)),
    };
    let recording = match &job {
        LabJobBody::Compare { recording, .. } | LabJobBody::Identify { recording, .. } => {
            Some(flight_recording(&state, recording).await?)
        }
        _ => None,
    };
    let inputs = JobInputs { vehicle, recording };
    if job.has_window() {
        // Reading the recording as a flight log is file I/O and work: off the async workers.
        let (worker, job, inputs) = (lab.worker(), job.clone(), inputs.clone());
        let checked = tokio::task::spawn_blocking(move || worker.check_window(&job, &inputs))
            .await
            .map_err(|e| error(StatusCode::INTERNAL_SERVER_ERROR, "internal", e.to_string()))?;
        if let Err((field, reason)) = checked {
            let e = FieldError { field, reason };
            return Ok(field_error(StatusCode::BAD_REQUEST, "invalid_job", e));
        }
    }
    let kind = job.kind();
    let id = lab
        .jobs()
        .start(kind, &caller.name, state.now_s())
        .map_err(|busy| error(StatusCode::CONFLICT, "busy", busy.to_string()))?;
    let control = Control {
        shared: state.clone(),
        lab: lab.clone(),
        id,
    };
    let spawned = std::thread::Builder::new()
        .name("stx-lab".into())
        .spawn(move || {
            crate::priority::lower_this_thread("the Lab");
            let worker = control.lab.worker();
            let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                worker.run(&job, &inputs, &control)
            }))
            .unwrap_or_else(|_| Err("the job panicked (a bug: see the station's log)".into()));
            let now = control.shared.now_s();
            control.lab.jobs().finish(control.id, result, now);
        });
    if let Err(e) = spawned {
        lab.jobs().finish(
            id,
            Err(format!("no thread for the job: {e}")),
            state.now_s(),
        );
        return Err(error(
            StatusCode::SERVICE_UNAVAILABLE,
            "no_thread",
            format!("cannot start the job: {e}"),
        ));
    }
    tracing::info!(id, kind, by = %caller.name, "Lab job started");
    Ok((StatusCode::ACCEPTED, Json(LabStartedBody { id, kind })).into_response())
}

/// The path of the recording `name` for a comparison or an identification: a plain name of the recordings
/// directory, a file that opens as a recording and holds a flight.
async fn flight_recording(state: &AppState, name: &str) -> Result<PathBuf, HttpError> {
    let unknown = |why: &str| {
        error(
            StatusCode::NOT_FOUND,
            "unknown_recording",
            format!("no recording named {name:?} {why}"),
        )
    };
    if !super::recordings::valid_name(name) {
        return Err(unknown(
            "(a plain file name of the recordings directory, ending in .mcap)",
        ));
    }
    let Some(dir) = state.config.recording.dir.as_ref() else {
        return Err(unknown("(this station has no recordings directory)"));
    };
    let path = dir.join(name);
    if !std::fs::metadata(&path).is_ok_and(|m| m.is_file()) {
        return Err(unknown("in the recordings directory"));
    }
    // Reading the index is file I/O (a scan, for a file cut short): off the async workers.
    let opened = path.clone();
    let checked = tokio::task::spawn_blocking(move || {
        let recording = stx_record::Recording::open(&opened).map_err(|e| {
            (
                StatusCode::UNPROCESSABLE_ENTITY,
                "unreadable",
                format!("{}: {e}", opened.display()),
            )
        })?;
        match missing_flight(&recording) {
            Some(why) => Err((StatusCode::UNPROCESSABLE_ENTITY, "no_flight", why)),
            None => Ok(()),
        }
    })
    .await
    .map_err(|e| error(StatusCode::INTERNAL_SERVER_ERROR, "internal", e.to_string()))?;
    checked.map_err(|(status, kind, reason)| error(status, kind, reason))?;
    Ok(path)
}

pub(crate) async fn cancel(
    State(state): State<AppState>,
    caller: Caller,
) -> Result<Response, HttpError> {
    caller.operator()?;
    let lab = lab_of(&state)?;
    if !lab.jobs().cancel() {
        return Err(error(
            StatusCode::NOT_FOUND,
            "no_job",
            "no Lab job is running",
        ));
    }
    Ok(Json(status_body(&state)).into_response())
}

pub(crate) async fn vehicle_fields(_caller: Caller) -> Response {
    Json(fields()).into_response()
}

pub(crate) async fn vehicle_check(
    _caller: Caller,
    body: Result<Json<LabVehicleBody>, JsonRejection>,
) -> Result<Response, HttpError> {
    let b = json_body(body)?;
    Ok(match edited_vehicle(&b.vehicle) {
        Ok(_) => Json(fields()).into_response(),
        Err(e) => field_error(StatusCode::BAD_REQUEST, "invalid_vehicle", e),
    })
}

/// `dir/name.toml` for a name of letters, digits, `-` and `_`, refusing to replace a file
/// unless asked.
fn file_in(
    dir: &std::path::Path,
    name: Option<&str>,
    overwrite: bool,
) -> Result<PathBuf, HttpError> {
    let name = name.unwrap_or_default();
    let fine = !name.is_empty()
        && name.len() <= 64
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
    if !fine {
        return Err(error(
            StatusCode::BAD_REQUEST,
            "bad_name",
            "a file name of 1 to 64 letters, digits, `-` or `_` is required",
        ));
    }
    let path = dir.join(format!("{name}.toml"));
    if path.exists() && !overwrite {
        return Err(error(
            StatusCode::CONFLICT,
            "exists",
            format!("{} exists: ask to overwrite it", path.display()),
        ));
    }
    Ok(path)
}

fn write_file(path: &std::path::Path, text: &str) -> Result<Response, HttpError> {
    let written = path
        .parent()
        .map_or(Ok(()), std::fs::create_dir_all)
        .and_then(|()| std::fs::write(path, text));
    written.map_err(|e| {
        error(
            StatusCode::INTERNAL_SERVER_ERROR,
            "write_failed",
            format!("cannot write {}: {e}", path.display()),
        )
    })?;
    tracing::info!(path = %path.display(), "Lab file saved");
    Ok(Json(LabSavedBody {
        path: path.display().to_string(),
        request_ids: Vec::new(),
    })
    .into_response())
}

pub(crate) async fn vehicle_save(
    State(state): State<AppState>,
    caller: Caller,
    body: Result<Json<LabVehicleBody>, JsonRejection>,
) -> Result<Response, HttpError> {
    caller.operator()?;
    let lab = lab_of(&state)?;
    let b = json_body(body)?;
    let config = match edited_config(&b.vehicle) {
        Ok(c) => c,
        Err(e) => return Ok(field_error(StatusCode::BAD_REQUEST, "invalid_vehicle", e)),
    };
    let path = file_in(lab.dir(), b.name.as_deref(), b.overwrite)?;
    let text = toml::to_string(&config).map_err(|e| {
        error(
            StatusCode::INTERNAL_SERVER_ERROR,
            "write_failed",
            e.to_string(),
        )
    })?;
    write_file(
        &path,
        &format!(
            "# Vehicle saved from the stx Lab by {}.\n{text}",
            caller.name
        ),
    )
}

fn is_gain(name: &str) -> bool {
    name.starts_with("GN_")
}

/// What the Lab sends to the drone: gains, and the planning polar (`PL_…`, `stx polar --json`),
/// so that what a flight identified is what guidance plans the next with. Only gains are saved
/// as a gains file.
fn is_sendable(name: &str) -> bool {
    is_gain(name) || name.starts_with("PL_")
}

pub(crate) async fn gains(_caller: Caller) -> Response {
    let defaults = OnboardSettings::default();
    let gains = CATALOG
        .iter()
        .filter(|p| is_gain(p.name))
        .map(|p| LabGain {
            name: p.name.into(),
            units: p.units.into(),
            value: p.get(&defaults),
            min: p.min,
            max: p.max,
            description: p.description.into(),
        })
        .collect();
    Json(LabGainsListBody { gains }).into_response()
}

/// The built-in settings with `gains` applied, each checked as the drone checks it; a name
/// `allowed` refuses is refused as `not_allowed` says.
fn settings_with(
    gains: &BTreeMap<String, f64>,
    allowed: fn(&str) -> bool,
    not_allowed: &str,
) -> Result<OnboardSettings, FieldError> {
    let mut settings = OnboardSettings::default();
    for (name, value) in gains {
        let refused = |reason: String| FieldError {
            field: name.clone(),
            reason,
        };
        if !allowed(name) {
            return Err(refused(not_allowed.into()));
        }
        settings
            .apply(name, *value)
            .map_err(|e| refused(e.to_string()))?;
    }
    Ok(settings)
}

pub(crate) async fn gains_save(
    State(state): State<AppState>,
    caller: Caller,
    body: Result<Json<LabGainsBody>, JsonRejection>,
) -> Result<Response, HttpError> {
    caller.operator()?;
    let lab = lab_of(&state)?;
    let b = json_body(body)?;
    let settings = match settings_with(&b.gains, is_gain, "not a control gain (GN_…)") {
        Ok(s) => s,
        Err(e) => return Ok(field_error(StatusCode::BAD_REQUEST, "invalid_gains", e)),
    };
    let path = file_in(lab.dir(), b.name.as_deref(), b.overwrite)?;
    write_file(
        &path,
        &format!(
            "# Control gains saved from the stx Lab by {}.\n{}",
            caller.name,
            settings.guidance.gains.to_toml_string()
        ),
    )
}

pub(crate) async fn gains_send(
    State(state): State<AppState>,
    caller: Caller,
    body: Result<Json<LabGainsBody>, JsonRejection>,
) -> Result<Response, HttpError> {
    caller.operator()?;
    let b = json_body(body)?;
    if let Err(e) = settings_with(
        &b.gains,
        is_sendable,
        "neither a control gain (GN_…) nor the planning polar (PL_…)",
    ) {
        return Ok(field_error(StatusCode::BAD_REQUEST, "invalid_gains", e));
    }
    if !b.confirm {
        return Err(error(
            StatusCode::BAD_REQUEST,
            "confirmation_required",
            "sending gains changes the drone's guidance: resend with `confirm: true`",
        ));
    }
    let now = state.now_s();
    let mut request_ids = Vec::new();
    for (name, value) in &b.gains {
        let request = CommandRequest::ParamSet {
            name: name.clone(),
            value: *value,
        };
        request_ids.push(state.core().request(now, &caller.name, request)?);
    }
    state.link_due.notify_one();
    Ok((
        StatusCode::ACCEPTED,
        Json(LabSavedBody {
            path: String::new(),
            request_ids,
        }),
    )
        .into_response())
}
