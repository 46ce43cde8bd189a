//! `GET /api/keep-out` (anyone) and `PUT /api/keep-out` (operators): the keep-out zones. An
//! edit is checked by the core, written to the configured file (a whole new file renamed over
//! the old one, so a crash or a full disk never leaves half a file), and only then put in
//! force: what the pages show is what a restart reads back.

use std::io::Write;
use std::path::Path;

use axum::Json;
use axum::extract::State;
use axum::extract::rejection::JsonRejection;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};

use super::auth::Caller;
use super::shared::{AppState, HttpError, error, json_body};
use crate::keep_out::KeepOutBody;

pub(crate) async fn keep_out(State(state): State<AppState>, _caller: Caller) -> Response {
    let now = state.now_s();
    Json(state.core().keep_out_msg(now)).into_response()
}

pub(crate) async fn set_keep_out(
    State(state): State<AppState>,
    caller: Caller,
    body: Result<Json<KeepOutBody>, JsonRejection>,
) -> Result<Response, HttpError> {
    caller.operator()?;
    let KeepOutBody(geojson) = json_body(body)?;
    // One edit at a time, so the file and the core end with the same one.
    let _one = state.keep_out_edit.lock().await;
    let checked = state.core().check_keep_out(geojson)?;
    let file = state.config.keep_out.clone();
    if let Some(path) = file.clone() {
        let text = checked.file_text();
        let written = tokio::task::spawn_blocking(move || write_atomically(&path, &text))
            .await
            .map_err(std::io::Error::other)
            .and_then(|r| r);
        if let Err(e) = written {
            let shown = file.as_deref().map(Path::display);
            let reason = format!(
                "keep-out zones not saved to {}: {e}; the zones in force are unchanged",
                shown.map(|d| d.to_string()).unwrap_or_default()
            );
            tracing::error!("{reason}");
            return Err(error(
                StatusCode::INTERNAL_SERVER_ERROR,
                "not_saved",
                reason,
            ));
        }
    }
    let now = state.now_s();
    let shown = file.as_ref().map(|p| p.display().to_string());
    let msg = state
        .core()
        .set_keep_out(now, &caller.name, checked, shown.as_deref());
    Ok(Json(msg).into_response())
}

/// Writes `text` to a new file beside `path`, flushed to the disk, and renames it over `path`.
fn write_atomically(path: &Path, text: &str) -> std::io::Result<()> {
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let temporary = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&temporary)?;
        f.write_all(text.as_bytes())?;
        f.sync_all()?;
        std::fs::rename(&temporary, path)?;
        // The rename itself reaches the disk with the directory (where the system allows it).
        if let Ok(d) = std::fs::File::open(dir) {
            let _ = d.sync_all();
        }
        Ok(())
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&temporary);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_is_replaced_whole_and_a_failed_write_leaves_it_and_no_scrap() {
        let dir = std::env::temp_dir().join(format!("stx-keep-out-write-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join("zones.geojson");
        std::fs::write(&path, "old").expect("write");
        write_atomically(&path, "new").expect("written");
        assert_eq!(std::fs::read_to_string(&path).expect("read"), "new");
        // A directory in the way of the rename: the write fails, the old file stays.
        let blocked = dir.join("blocked");
        std::fs::create_dir_all(blocked.join("inside")).expect("dir");
        assert!(write_atomically(&blocked, "x").is_err());
        let left: Vec<_> = std::fs::read_dir(&dir)
            .expect("list")
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        assert!(!left.iter().any(|n| n.ends_with(".tmp")), "{left:?}");
        assert_eq!(std::fs::read_to_string(&path).expect("read"), "new");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
