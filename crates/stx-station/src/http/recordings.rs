//! The recordings directory over HTTP: `GET /api/recordings` lists the station's recordings
//! (`recording::summary`), `GET /api/recordings/{name}` downloads one, and
//! `POST /api/recordings/{name}/replay` (operators) opens one in a replay station of its own,
//! started by the daemon ([`ReplayRequest`]), whose port the page opens in a new tab.
//!
//! A name is only ever a plain file name of the directory (letters, digits, `._-`, ending in
//! `.mcap`): nothing outside the directory can be named, listed or served.

use std::path::{Path, PathBuf};
use std::time::SystemTime;

use axum::Json;
use axum::body::Body;
use axum::extract::{Path as UrlPath, Request, State};
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use tokio::sync::oneshot;
use tower_http::services::ServeFile;

use super::auth::Caller;
use super::shared::{AppState, HttpError, ReplayRequest, SummaryCache, error};
use crate::recording::summary::summarize;
use crate::replies::{RecordingsBody, UnreadableRecording};

/// A plain recording file name (see the module documentation).
pub(crate) fn valid_name(name: &str) -> bool {
    name.len() <= 200
        && name.ends_with(".mcap")
        && !name.starts_with('.')
        && name
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b"._-".contains(&b))
}

fn directory(state: &AppState) -> Result<PathBuf, HttpError> {
    state.config.recording.dir.clone().ok_or_else(|| {
        error(
            StatusCode::NOT_FOUND,
            "not_found",
            "this station has no recordings directory",
        )
    })
}

/// The path of the recording `name`, which must exist.
pub(crate) fn recording_path(state: &AppState, name: &str) -> Result<PathBuf, HttpError> {
    let not_found = || {
        error(
            StatusCode::NOT_FOUND,
            "not_found",
            format!("no recording named {name:?}"),
        )
    };
    if !valid_name(name) {
        return Err(not_found());
    }
    let path = directory(state)?.join(name);
    match std::fs::metadata(&path) {
        Ok(m) if m.is_file() => Ok(path),
        _ => Err(not_found()),
    }
}

fn list(dir: &Path, current: Option<&str>, cache: &SummaryCache) -> RecordingsBody {
    let mut recordings = Vec::new();
    let mut unreadable = Vec::new();
    let entries = std::fs::read_dir(dir).into_iter().flatten().flatten();
    for entry in entries {
        let name = entry.file_name().to_string_lossy().into_owned();
        let Ok(meta) = entry.metadata() else { continue };
        if !meta.is_file() || !valid_name(&name) {
            continue;
        }
        let size = meta.len();
        let modified = meta.modified().unwrap_or(SystemTime::UNIX_EPOCH);
        let cached = cache
            .0
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .get(&name)
            .filter(|(s, m, _)| (*s, *m) == (size, modified))
            .map(|(_, _, summary)| summary.clone());
        let summary = match cached {
            Some(s) => Ok(s),
            None => stx_record::Recording::open(&entry.path())
                .map_err(|e| e.to_string())
                .and_then(|mut r| summarize(&name, size, &mut r).map_err(|e| e.to_string())),
        };
        match summary {
            Ok(mut summary) => {
                cache
                    .0
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .insert(name.clone(), (size, modified, summary.clone()));
                summary.recording_now = current == Some(name.as_str());
                recordings.push(summary);
            }
            Err(reason) => unreadable.push(UnreadableRecording { name, reason }),
        }
    }
    // Files gone from the directory leave the cache too.
    cache
        .0
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .retain(|name, _| recordings.iter().any(|r| &r.name == name));
    recordings.sort_by(|a, b| (b.start_ms, &b.name).cmp(&(a.start_ms, &a.name)));
    unreadable.sort_by(|a, b| a.name.cmp(&b.name));
    RecordingsBody {
        directory: Some(dir.display().to_string()),
        recordings,
        unreadable,
    }
}

pub(crate) async fn recordings(
    State(state): State<AppState>,
    _caller: Caller,
) -> Result<Response, HttpError> {
    let Some(dir) = state.config.recording.dir.clone() else {
        return Ok(Json(RecordingsBody {
            directory: None,
            recordings: Vec::new(),
            unreadable: Vec::new(),
        })
        .into_response());
    };
    let current = state.recording.view().file.and_then(|f| {
        Path::new(&f)
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
    });
    let shared = state.clone();
    // Reading indexes is file I/O: off the async workers.
    let body = tokio::task::spawn_blocking(move || {
        list(&dir, current.as_deref(), &shared.recording_summaries)
    })
    .await
    .map_err(|e| error(StatusCode::INTERNAL_SERVER_ERROR, "internal", e.to_string()))?;
    Ok(Json(body).into_response())
}

pub(crate) async fn download(
    State(state): State<AppState>,
    _caller: Caller,
    UrlPath(name): UrlPath<String>,
    request: Request,
) -> Result<Response, HttpError> {
    let path = recording_path(&state, &name)?;
    // `.mcap` has no registered media type: served as `application/octet-stream`.
    let mut response = ServeFile::new(&path)
        .try_call(request)
        .await
        .map_err(|e| error(StatusCode::INTERNAL_SERVER_ERROR, "io", e.to_string()))?
        .map(Body::new);
    if let Ok(v) = HeaderValue::from_str(&format!("attachment; filename=\"{name}\"")) {
        response
            .headers_mut()
            .insert(header::CONTENT_DISPOSITION, v);
    }
    Ok(response)
}

pub(crate) async fn open_replay(
    State(state): State<AppState>,
    caller: Caller,
    UrlPath(name): UrlPath<String>,
) -> Result<Response, HttpError> {
    if caller.role != crate::config::Role::Operator {
        return Err(error(
            StatusCode::FORBIDDEN,
            "forbidden",
            "operator role required to open a replay (viewers can download recordings)",
        ));
    }
    let file = recording_path(&state, &name)?;
    let Some(requests) = state.replay_requests.as_ref() else {
        return Err(error(
            StatusCode::CONFLICT,
            "replay",
            "this station is itself a replay: open recordings from the live station",
        ));
    };
    let (answer, answered) = oneshot::channel();
    let gone = || {
        error(
            StatusCode::SERVICE_UNAVAILABLE,
            "unavailable",
            "the station is stopping",
        )
    };
    requests
        .send(ReplayRequest { file, answer })
        .await
        .map_err(|_| gone())?;
    match answered.await.map_err(|_| gone())? {
        Ok(opened) => {
            tracing::info!(
                by = caller.name,
                recording = name,
                port = opened.port,
                "replay opened"
            );
            Ok((StatusCode::CREATED, Json(opened)).into_response())
        }
        Err((status, kind, reason)) => Err(error(status, kind, reason)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_plain_recording_names_are_names() {
        for ok in [
            "stx-2026-11-25T10-00-00Z-1.mcap",
            "a.mcap",
            "flight_2.recovered.mcap",
        ] {
            assert!(valid_name(ok), "{ok}");
        }
        for bad in [
            "../secret.mcap",
            "a/b.mcap",
            ".hidden.mcap",
            "flight.txt",
            "flight.mcap/",
            "fl ight.mcap",
            "flight%2e.mcap",
            "",
            "..mcap",
        ] {
            assert!(!valid_name(bad), "{bad}");
        }
    }
}
