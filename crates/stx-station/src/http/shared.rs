//! What every handler shares: the core behind its lock, the mission clock, the channels that
//! feed the pages, each page's counters, and the `{error, reason}` answer of every refusal.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use axum::Json;
use axum::extract::rejection::JsonRejection;
use axum::extract::ws::Utf8Bytes;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use tokio::sync::{Notify, broadcast, watch};

use crate::config::{Role, StationConfig};
use crate::core::{ApiError, StationCore};
use crate::limits::{Limits, RetryAfter};
use crate::messages::ErrorBody;
use crate::replies::ClientView;

/// State shared by every handler.
pub struct Shared {
    /// The station.
    pub core: Mutex<StationCore>,
    /// The `[[forward]]` outputs and their counts, kept by their tasks.
    pub forwards: Arc<Mutex<Vec<crate::forward::ForwardView>>>,
    /// The chase broadcast as its task last reported it; `None` when it is off.
    pub chase: Mutex<Option<crate::forward::ChaseView>>,
    /// The SondeHub upload; `None` when it is off.
    pub sondehub: Option<SondehubShare>,
    /// Configuration (immutable).
    pub config: StationConfig,
    /// Mission clock origin.
    pub started: Instant,
    /// Woken when a handler gave the core something for the link (a request, sticks): the
    /// daemon then takes the core's link actions at once instead of at its next tick.
    pub link_due: Notify,
    /// Events, command results and parameter tables for every WebSocket, pre-serialised
    /// (shared bytes: one copy for all pages); kept until every page has read them, up to
    /// the backlog.
    pub broadcast: broadcast::Sender<Utf8Bytes>,
    /// The newest `state` message, pre-serialised, with its sequence number.
    pub states: watch::Sender<StateFrame>,
    /// Connected pages and what each was sent or missed.
    pub clients: Mutex<BTreeMap<u64, Arc<ClientCounters>>>,
    /// The next page's id.
    pub next_client: AtomicU64,
    /// Messages put on [`Shared::broadcast`] so far (to tell how far behind a page is).
    pub broadcast_total: AtomicU64,
    /// Requests per token and wrong tokens per address ([`crate::limits`]).
    pub limits: Mutex<Limits>,
    /// The run's recording.
    pub recording: crate::recorder::Recording,
    /// The replay this station shows (`stx replay`); `None` when live.
    pub replay: Option<Arc<crate::replay::ReplayControl>>,
    /// Recordings' summaries already read, for `GET /api/recordings`.
    pub recording_summaries: SummaryCache,
    /// The offline map's tile pack, opened at start (or why not).
    pub tiles: crate::tile_pack::LoadedPack,
    /// Where `POST /api/recordings/{name}/replay` asks the daemon for a replay station;
    /// `None` in a replay station (replays are opened from the live one).
    pub replay_requests: Option<tokio::sync::mpsc::Sender<ReplayRequest>>,
    /// Held while an edit of the keep-out zones is written and applied.
    pub keep_out_edit: tokio::sync::Mutex<()>,
    /// Held while a pre-flight plan is computed (up to a second of a core): one at a time,
    /// so pages cannot take the cores the link and the telemetry need.
    pub planning: Arc<tokio::sync::Mutex<()>>,
    /// Forecast files the Plan page sent, for its launch windows.
    pub uploads: Mutex<crate::forecast_upload::Uploads>,
    /// The configured `[forecast_file] gfs` as a field, read at its first use (the launch
    /// windows and the Tawhiri API fly it; the rows at start are only its launch-site
    /// profile), or why it cannot be read.
    pub forecast_field: std::sync::OnceLock<Result<Arc<stx_weather::GfsField>, String>>,
    /// The Lab, set once with stx-lab's jobs by the binary (`stx serve`, and `stx bench
    /// station` for its Lab load); unset, the Lab's endpoints answer that there is none.
    pub lab: std::sync::OnceLock<Arc<crate::lab::LabService>>,
    /// The simulated drone's restarts, set once by a binary that flies one beside the station
    /// (`stx serve --sim`); unset, `POST /api/lab/rehearse` answers that there is none.
    pub rehearsal: std::sync::OnceLock<Rehearsals>,
}

/// The SondeHub upload's side of [`Shared`]: what its task last reported, and where a
/// recovery phone's position goes (the newest wins: an older one is worth nothing).
pub struct SondehubShare {
    /// The upload as its task last reported it.
    pub view: Mutex<crate::sondehub::SondehubView>,
    /// The chase car's position, `[lat °, lon °, alt m]`.
    pub chase_car: watch::Sender<Option<[f64; 3]>>,
}

/// Where the Lab asks for the simulated drone to fly its mission again with another vehicle.
pub struct Rehearsals {
    /// The binary's side: it stops the drone flying and starts one with the vehicle.
    pub requests: tokio::sync::mpsc::Sender<RehearsalRequest>,
    /// The rehearsal the Lab last started.
    pub last: Mutex<Option<crate::lab::bodies::LabRehearsalBody>>,
}

/// A request to fly the simulated drone's mission again, from its start, with `vehicle` as
/// the truth.
pub struct RehearsalRequest {
    /// The vehicle, validated.
    pub vehicle: stx_dynamics::vehicle::Vehicle,
    /// The mission's name once the new drone flies, or why it does not.
    pub answer: tokio::sync::oneshot::Sender<Result<String, String>>,
}

/// Why a replay could not be opened: `(status, error, reason)` of the answer.
pub type ReplayRefusal = (StatusCode, &'static str, String);

/// A page's request to replay a recording, for the daemon's replay sessions.
pub struct ReplayRequest {
    /// The recording's path.
    pub file: std::path::PathBuf,
    /// Where the answer goes.
    pub answer: tokio::sync::oneshot::Sender<Result<crate::replies::ReplayOpened, ReplayRefusal>>,
}

/// Summaries already read, by name, with the size and modification time they were read at:
/// a closed recording is read once, the one being written each time it grew.
#[derive(Default)]
pub struct SummaryCache(pub(crate) Mutex<SummaryEntries>);

type SummaryEntries = std::collections::HashMap<
    String,
    (
        u64,
        std::time::SystemTime,
        crate::recording::summary::RecordingSummary,
    ),
>;

/// The newest `state`, numbered so a page can count the ones it skipped.
#[derive(Debug, Clone, Default)]
pub struct StateFrame {
    /// 1 for the first state published, then +1 each.
    pub seq: u64,
    /// The message.
    pub text: Utf8Bytes,
}

/// One page's WebSocket, as `GET /api/clients` shows it.
#[derive(Debug, Default)]
pub struct ClientCounters {
    /// Token name.
    pub name: String,
    /// Role.
    pub role: Option<Role>,
    /// Mission time it connected, s.
    pub connected_s: f64,
    /// [`Shared::broadcast_total`] when it subscribed.
    pub base: u64,
    /// `state` messages sent.
    pub states_sent: AtomicU64,
    /// `state` messages skipped because the page was behind (a newer one was sent instead).
    pub states_coalesced: AtomicU64,
    /// Events, command results and parameter tables sent.
    pub messages_sent: AtomicU64,
    /// Events, command results and parameter tables it missed by falling more than the
    /// backlog behind (each time announced to it with `lagged`).
    pub messages_missed: AtomicU64,
    /// Times it fell that far behind.
    pub lag_episodes: AtomicU64,
    /// A public relay's last `relay_viewers` figure; `None` for a page.
    pub relay_viewers: Mutex<Option<u32>>,
}

impl ClientCounters {
    pub(crate) fn view(&self, id: u64, total: u64) -> ClientView {
        let n = |c: &AtomicU64| c.load(Ordering::Relaxed);
        let done = self.base + n(&self.messages_sent) + n(&self.messages_missed);
        ClientView {
            id,
            name: self.name.clone(),
            role: self.role,
            connected_s: self.connected_s,
            states_sent: n(&self.states_sent),
            states_coalesced: n(&self.states_coalesced),
            messages_sent: n(&self.messages_sent),
            messages_missed: n(&self.messages_missed),
            messages_behind: total.saturating_sub(done),
            lag_episodes: n(&self.lag_episodes),
            relay_viewers: *self.relay_viewers.lock().unwrap_or_else(|e| e.into_inner()),
        }
    }
}

impl Shared {
    /// Seconds on the mission clock: since the station started, or in a replay station the
    /// replay's position in its recording (its core runs on the recording's clock: a pause
    /// stops it, a seek moves it).
    pub fn now_s(&self) -> f64 {
        match &self.replay {
            Some(replay) => replay.mission_s(),
            None => self.elapsed_s(),
        }
    }

    /// Seconds since the station started, on the wall clock (request limits run on it, also
    /// in a replay).
    pub fn elapsed_s(&self) -> f64 {
        self.started.elapsed().as_secs_f64()
    }

    /// The request limits, for a moment.
    pub fn limits(&self) -> std::sync::MutexGuard<'_, Limits> {
        self.limits.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The uploads, for a moment.
    pub fn uploads(&self) -> std::sync::MutexGuard<'_, crate::forecast_upload::Uploads> {
        self.uploads.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The configured GFS field (reads the files the first time: call it off the async
    /// workers); `None` without `[forecast_file] gfs`.
    pub fn configured_field(&self) -> Option<Result<Arc<stx_weather::GfsField>, String>> {
        let files = &self.config.forecast_file.as_ref()?.gfs;
        if files.is_empty() {
            return None;
        }
        Some(
            self.forecast_field
                .get_or_init(|| crate::forecast_file::read_gfs(files).map(Arc::new))
                .clone(),
        )
    }

    /// The core, for a moment.
    pub fn core(&self) -> std::sync::MutexGuard<'_, StationCore> {
        // A panic while holding the lock would be a bug in the core; keep serving.
        self.core.lock().unwrap_or_else(|e| e.into_inner())
    }
}

pub(crate) type AppState = Arc<Shared>;

/// An error answered as `{error, reason}`.
pub struct HttpError(StatusCode, ErrorBody, Option<RetryAfter>);

impl IntoResponse for HttpError {
    fn into_response(self) -> Response {
        let mut response = (self.0, Json(self.1)).into_response();
        if let Some(RetryAfter(s)) = self.2 {
            response
                .headers_mut()
                .insert(axum::http::header::RETRY_AFTER, s.into());
        }
        response
    }
}

impl HttpError {
    /// 409: a replay commands nothing.
    pub(crate) fn replaying() -> Self {
        error(
            StatusCode::CONFLICT,
            "replay",
            "this station is replaying a recording: there is no drone to command",
        )
    }

    /// 429 Too Many Requests, with `Retry-After`: what is done one at a time is being done
    /// for another caller.
    pub(crate) fn busy(reason: impl Into<String>, retry: RetryAfter) -> Self {
        let mut e = error(StatusCode::TOO_MANY_REQUESTS, "busy", reason);
        e.2 = Some(retry);
        e
    }

    /// 429 Too Many Requests, with `Retry-After`.
    pub(crate) fn too_many(reason: impl Into<String>, retry: RetryAfter) -> Self {
        let mut e = error(StatusCode::TOO_MANY_REQUESTS, "too_many_requests", reason);
        e.2 = Some(retry);
        e
    }
}

impl From<ApiError> for HttpError {
    fn from(e: ApiError) -> Self {
        HttpError(
            StatusCode::from_u16(e.status).unwrap_or(StatusCode::BAD_REQUEST),
            ErrorBody {
                error: e.error,
                reason: e.reason,
            },
            None,
        )
    }
}

pub(crate) fn error(
    status: StatusCode,
    kind: &'static str,
    reason: impl Into<String>,
) -> HttpError {
    HttpError(
        status,
        ErrorBody {
            error: kind,
            reason: reason.into(),
        },
        None,
    )
}

pub(crate) fn json_body<T>(body: Result<Json<T>, JsonRejection>) -> Result<T, HttpError> {
    body.map(|Json(v)| v).map_err(|e| {
        error(
            StatusCode::BAD_REQUEST,
            "bad_request",
            format!("malformed request body: {}", e.body_text()),
        )
    })
}
