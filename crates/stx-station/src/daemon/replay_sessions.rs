//! Replay stations: `stx replay FILE` runs one ([`serve_replay`]), and the live station opens
//! them for its pages (`POST /api/recordings/{name}/replay`, [`replay_sessions`]). Each is a
//! whole station of its own in this process — its own core fed by the recording's feeder
//! thread, its own HTTP port on the live station's address — so the live station's core, link
//! and recording are untouched by it.
//!
//! The live station keeps at most [`MAX_SESSIONS`] at once; one that has had no page for
//! [`IDLE`] ends, and all end with the live station.

use std::future::Future;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use axum::http::StatusCode;
use stx_record::{ReadError, Recording};
use thiserror::Error;
use tokio::sync::{Notify, mpsc, watch};
use tokio::task::JoinHandle;

use super::{DaemonError, Running, run_replay, spawn_replay_feeder};
use crate::config::StationConfig;
use crate::http::{ReplayRefusal, ReplayRequest};
use crate::replay::{ReplayControl, ReplayError, ReplayMode};
use crate::replies::ReplayOpened;

/// Replay stations a live station runs at once.
pub const MAX_SESSIONS: usize = 2;
/// A replay station with no page for this long ends.
pub const IDLE: Duration = Duration::from_secs(600);
/// How often a replay station looks for pages.
const IDLE_CHECK: Duration = Duration::from_secs(5);

/// Why a recording cannot be replayed.
#[derive(Debug, Error)]
pub enum ReplayOpenError {
    /// The file is not a readable recording.
    #[error("cannot read the recording {file}: {source}")]
    Read {
        /// The file.
        file: String,
        /// Why.
        #[source]
        source: ReadError,
    },
    /// It holds no messages.
    #[error("{file} holds no messages")]
    Empty {
        /// The file.
        file: String,
    },
    /// The speed is out of range.
    #[error(transparent)]
    Control(#[from] ReplayError),
}

/// A recording opened and ready to replay.
pub struct PreparedReplay {
    recording: Recording<std::fs::File>,
    file: PathBuf,
    control: Arc<ReplayControl>,
}

impl PreparedReplay {
    /// Opens `file` to replay in `mode` at `speed` × real time.
    pub fn open(file: &Path, mode: ReplayMode, speed: f64) -> Result<Self, ReplayOpenError> {
        let shown = || file.display().to_string();
        let recording = Recording::open(file).map_err(|source| ReplayOpenError::Read {
            file: shown(),
            source,
        })?;
        let (start, end) = recording
            .time_range()
            .ok_or_else(|| ReplayOpenError::Empty { file: shown() })?;
        let control = ReplayControl::new(shown(), mode, start, end, speed)?;
        Ok(Self {
            recording,
            file: file.to_owned(),
            control: Arc::new(control),
        })
    }
}

/// Runs a station replaying `prepared` until `shutdown` (`config`'s link is replaced by a
/// loopback port that hears nothing: the feeder runs the recording through the core itself;
/// nothing is recorded). `started` is called once it listens, before the feeder starts.
pub async fn serve_replay(
    mut config: StationConfig,
    prepared: PreparedReplay,
    shutdown: impl Future<Output = ()> + Send + 'static,
    started: impl FnOnce(&Running) + Send,
) -> Result<(), DaemonError> {
    config.link.address = "udpin:127.0.0.1:0".into();
    config.link.more_addresses.clear();
    let PreparedReplay {
        recording,
        file,
        control,
    } = prepared;
    let stop = Arc::new(AtomicBool::new(false));
    let feeder_stop = stop.clone();
    let feeder_control = control.clone();
    let result = run_replay(config, control, shutdown, move |running| {
        started(&running);
        if let Err(e) = spawn_replay_feeder(
            recording,
            file,
            feeder_control,
            running.shared.clone(),
            feeder_stop,
        ) {
            tracing::error!(error = %e, "the replay could not start");
        }
    })
    .await;
    stop.store(true, Ordering::Relaxed);
    result
}

/// [`serve_replay`] behind a box: the live station's future spawns the sessions, which run
/// this, which is a station's future again; the named, boxed type ends that cycle for the
/// compiler's `Send` check.
type ReplayStation = std::pin::Pin<Box<dyn Future<Output = Result<(), DaemonError>> + Send>>;

fn replay_station(
    config: StationConfig,
    prepared: PreparedReplay,
    shutdown: impl Future<Output = ()> + Send + 'static,
    started: impl FnOnce(&Running) + Send + 'static,
) -> ReplayStation {
    Box::pin(serve_replay(config, prepared, shutdown, started))
}

/// Resolves once `shared`'s station has had no page for [`IDLE`].
async fn idle(running: Running) {
    let mut quiet = Duration::ZERO;
    while quiet < IDLE {
        tokio::time::sleep(IDLE_CHECK).await;
        let pages = running
            .shared
            .clients
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .len();
        quiet = if pages == 0 {
            quiet + IDLE_CHECK
        } else {
            Duration::ZERO
        };
    }
}

fn refusal(status: StatusCode, kind: &'static str, reason: impl Into<String>) -> ReplayRefusal {
    (status, kind, reason.into())
}

/// The live station's replay stations: serves `requests` until `stop` turns true, then ends
/// every replay it started.
pub(crate) async fn replay_sessions(
    config: StationConfig,
    http: SocketAddr,
    mut requests: mpsc::Receiver<ReplayRequest>,
    mut stop: watch::Receiver<bool>,
) {
    let mut sessions: Vec<JoinHandle<()>> = Vec::new();
    loop {
        let request = tokio::select! {
            r = requests.recv() => r,
            _ = stop.wait_for(|s| *s) => None,
        };
        let Some(ReplayRequest { file, answer }) = request else {
            break;
        };
        sessions.retain(|s| !s.is_finished());
        if sessions.len() >= MAX_SESSIONS {
            let _ = answer.send(Err(refusal(
                StatusCode::CONFLICT,
                "busy",
                format!(
                    "{MAX_SESSIONS} replays are open already; one ends {} min after its last page closes",
                    IDLE.as_secs() / 60
                ),
            )));
            continue;
        }
        let opening = file.clone();
        let prepared = tokio::task::spawn_blocking(move || {
            PreparedReplay::open(&opening, ReplayMode::Rerun, 1.0)
        })
        .await;
        let prepared = match prepared {
            Ok(Ok(p)) => p,
            Ok(Err(e)) => {
                let _ = answer.send(Err(refusal(
                    StatusCode::UNPROCESSABLE_ENTITY,
                    "unreadable",
                    e.to_string(),
                )));
                continue;
            }
            Err(e) => {
                let _ = answer.send(Err(refusal(
                    StatusCode::INTERNAL_SERVER_ERROR,
                    "internal",
                    e.to_string(),
                )));
                continue;
            }
        };
        let mut replay_config = config.clone();
        replay_config.listen = SocketAddr::new(http.ip(), 0);
        let ended = Arc::new(Notify::new());
        let mut live_stop = stop.clone();
        let ending = ended.clone();
        let shutdown = async move {
            tokio::select! {
                _ = live_stop.wait_for(|s| *s) => {}
                _ = ending.notified() => {}
            }
        };
        // The answer goes out from `started`, or with the error if the station never starts.
        let answer = Arc::new(Mutex::new(Some(answer)));
        let on_start = answer.clone();
        let name = file
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        sessions.push(tokio::spawn(async move {
            let result = replay_station(replay_config, prepared, shutdown, move |running| {
                tracing::info!(recording = %name, address = %running.http, "replay station listening");
                let opened = ReplayOpened {
                    name,
                    port: running.http.port(),
                    scheme: running.scheme,
                };
                let running = running.clone();
                tokio::spawn(async move {
                    idle(running).await;
                    ended.notify_one();
                });
                if let Some(a) = on_start.lock().unwrap_or_else(|e| e.into_inner()).take() {
                    let _ = a.send(Ok(opened));
                }
            })
            .await;
            if let Err(e) = result {
                tracing::error!(error = %e, "replay station failed");
                if let Some(a) = answer.lock().unwrap_or_else(|e| e.into_inner()).take() {
                    let _ = a.send(Err(refusal(
                        StatusCode::INTERNAL_SERVER_ERROR,
                        "replay_failed",
                        e.to_string(),
                    )));
                }
            }
        }));
    }
    // The live station stops: every replay sees the same stop and closes; wait for them.
    for s in sessions {
        let _ = s.await;
    }
}
