//! The HTTP side (axum): authentication and roles, the REST endpoints and the WebSocket of
//! `API.md`, the KML feed, offline tiles and the built dashboard.
//!
//! Handlers only lock the core for a moment, build their answer, and hand link work to the
//! daemon's link task through [`Shared::link`]; nothing here waits on the radio.
//!
//! Each WebSocket page is fed from two sources: `state` messages through a `watch` channel
//! (latest wins: a page that falls behind skips to the newest state, counted as coalesced),
//! and events, command results and parameter tables through a broadcast backlog of
//! [`crate::daemon::RELIABLE_BACKLOG`] messages, never skipped silently: a page that falls
//! further behind gets a `lagged` message with the number it missed, and re-reads the event
//! log. Every page's counts are in `GET /api/clients`.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use axum::Json;
use axum::Router;
use axum::extract::rejection::JsonRejection;
use axum::extract::ws::{Message, Utf8Bytes, WebSocket, WebSocketUpgrade};
use axum::extract::{FromRequestParts, Path, Query, State};
use axum::http::request::Parts;
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};
use axum::routing::{any, get, post};
use serde::Deserialize;
use serde::de::DeserializeOwned;
use stx_gnc::mission::FlightMode;
use stx_link::manual::Sticks;
use stx_link::plan::PlanItem;
use tokio::sync::{broadcast, mpsc, watch};
use tower_http::services::{ServeDir, ServeFile};

use crate::config::{Role, StationConfig};
use crate::core::{ApiError, CommandRequest, LinkAction, StationCore};
use crate::messages::{ErrorBody, EventMsg, Level, Session, StationInfo};
use crate::replies::{
    ClientView, ClientsBody, CommandAccepted, EventsBody, HelloMsg, HistoryMsg, LaggedMsg, PongMsg,
    TrackBody,
};
use crate::requests::{
    ClientMessage, ConfirmBody, CourseBody, HeadingBody, LocalizerBody, ModeBody, ParamBody,
    PlanBody, PlanItemBody, TargetBody,
};

/// What the daemon's link task is asked to do.
#[derive(Debug, Clone, PartialEq)]
pub enum LinkRequest {
    /// An operator's request with its id.
    Action {
        request_id: String,
        action: LinkAction,
    },
    /// Joystick sticks from an operator's page (streamed while held).
    Manual(Sticks),
    /// The sticks were released or went silent.
    ManualRelease,
}

/// The latest joystick message, to stop streaming when it goes silent.
#[derive(Debug, Clone, Copy, Default)]
pub struct ManualState {
    /// Mission time of the last `manual` message, s.
    pub last_s: Option<f64>,
}

/// State shared by every handler.
pub struct Shared {
    /// The station.
    pub core: Mutex<StationCore>,
    /// Configuration (immutable).
    pub config: StationConfig,
    /// Mission clock origin.
    pub started: Instant,
    /// To the link task.
    pub link: mpsc::Sender<LinkRequest>,
    /// Events, command results and parameter tables for every WebSocket, pre-serialised
    /// (shared bytes: one copy for all pages); kept until every page has read them, up to
    /// the backlog.
    pub broadcast: broadcast::Sender<Utf8Bytes>,
    /// The newest `state` message, pre-serialised, with its sequence number.
    pub states: watch::Sender<StateFrame>,
    /// Joystick liveness.
    pub manual: Mutex<ManualState>,
    /// Connected pages and what each was sent or missed.
    pub clients: Mutex<BTreeMap<u64, Arc<ClientCounters>>>,
    /// The next page's id.
    pub next_client: AtomicU64,
    /// Messages put on [`Shared::broadcast`] so far (to tell how far behind a page is).
    pub broadcast_total: AtomicU64,
}

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
}

impl ClientCounters {
    fn view(&self, id: u64, total: u64) -> ClientView {
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
        }
    }
}

impl Shared {
    /// Seconds on the mission clock.
    pub fn now_s(&self) -> f64 {
        self.started.elapsed().as_secs_f64()
    }

    fn core(&self) -> std::sync::MutexGuard<'_, StationCore> {
        // A panic while holding the lock would be a bug in the core; keep serving.
        self.core.lock().unwrap_or_else(|e| e.into_inner())
    }
}

type AppState = Arc<Shared>;

/// An error answered as `{error, reason}`.
pub struct HttpError(StatusCode, ErrorBody);

impl IntoResponse for HttpError {
    fn into_response(self) -> Response {
        (self.0, Json(self.1)).into_response()
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
        )
    }
}

fn error(status: StatusCode, kind: &'static str, reason: impl Into<String>) -> HttpError {
    HttpError(
        status,
        ErrorBody {
            error: kind,
            reason: reason.into(),
        },
    )
}

/// The authenticated caller.
pub struct Caller {
    /// Name from the station config.
    pub name: String,
    /// Role.
    pub role: Role,
}

impl Caller {
    fn operator(&self) -> Result<(), HttpError> {
        match self.role {
            Role::Operator => Ok(()),
            Role::Viewer => Err(error(
                StatusCode::FORBIDDEN,
                "forbidden",
                "viewers cannot command: operator role required",
            )),
        }
    }
}

fn token_from(parts: &Parts) -> Option<String> {
    if let Some(value) = parts.headers.get(header::AUTHORIZATION)
        && let Ok(text) = value.to_str()
        && let Some(token) = text.strip_prefix("Bearer ")
    {
        return Some(token.trim().to_string());
    }
    parts.uri.query().and_then(|q| {
        q.split('&').find_map(|pair| {
            let (k, v) = pair.split_once('=')?;
            (k == "token").then(|| percent_decode(v))
        })
    })
}

fn percent_encode(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for b in s.bytes() {
        if b.is_ascii_alphanumeric() || b"-._~".contains(&b) {
            out.push(char::from(b));
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

fn percent_decode(s: &str) -> String {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'%' if i + 2 < bytes.len() => {
                let hex = std::str::from_utf8(&bytes[i + 1..i + 3]).ok();
                match hex.and_then(|h| u8::from_str_radix(h, 16).ok()) {
                    Some(b) => {
                        out.push(b);
                        i += 3;
                    }
                    None => {
                        out.push(b'%');
                        i += 1;
                    }
                }
            }
            b'+' => {
                out.push(b' ');
                i += 1;
            }
            b => {
                out.push(b);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

impl FromRequestParts<AppState> for Caller {
    type Rejection = HttpError;

    async fn from_request_parts(parts: &mut Parts, state: &AppState) -> Result<Self, HttpError> {
        let Some(token) = token_from(parts) else {
            return Err(error(
                StatusCode::UNAUTHORIZED,
                "unauthorized",
                "a token is needed: Authorization: Bearer <token> or ?token=",
            ));
        };
        match state.config.authenticate(&token) {
            Some((name, role)) => Ok(Caller {
                name: name.to_string(),
                role,
            }),
            None => Err(error(
                StatusCode::UNAUTHORIZED,
                "unauthorized",
                "unknown token",
            )),
        }
    }
}

fn json_body<T>(body: Result<Json<T>, JsonRejection>) -> Result<T, HttpError> {
    body.map(|Json(v)| v).map_err(|e| {
        error(
            StatusCode::BAD_REQUEST,
            "bad_request",
            format!("malformed request body: {}", e.body_text()),
        )
    })
}

/// The router of the whole station.
pub fn router(state: AppState) -> Router {
    let web_dir = state.config.web_dir.clone();
    let index = web_dir.join("index.html");
    let mut app = Router::new()
        .route("/api/session", get(session))
        .route("/api/state", get(state_now))
        .route("/api/params", get(params))
        .route("/api/params/{name}", post(set_param))
        .route("/api/events", get(events))
        .route("/api/track", get(track))
        .route("/api/commands/{id}", get(command_result))
        .route("/api/commands/mode", post(command::<ModeBody>))
        .route("/api/commands/heading", post(command::<HeadingBody>))
        .route("/api/commands/course", post(command::<CourseBody>))
        .route("/api/commands/localizer", post(command::<LocalizerBody>))
        .route("/api/commands/target", post(command::<TargetBody>))
        .route("/api/commands/plan", post(command::<PlanBody>))
        .route("/api/cutdown/arm", post(arm_cutdown))
        .route("/api/cutdown/confirm", post(confirm_cutdown))
        .route("/api/clients", get(clients))
        .route("/api/ws", get(websocket))
        // An API path that does not exist is an API error, never the dashboard's page.
        .route("/api", any(api_not_found))
        .route("/api/", any(api_not_found))
        .route("/api/{*rest}", any(api_not_found))
        .route("/kml", get(kml_link))
        .route("/kml/live", get(kml_live));
    if let Some(tiles) = &state.config.tiles_dir {
        app = app.nest_service("/tiles", ServeDir::new(tiles));
    }
    app.fallback_service(ServeDir::new(web_dir).fallback(ServeFile::new(index)))
        .with_state(state)
}

fn session_of(state: &Shared, caller: &Caller) -> Session {
    let c = &state.config;
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
            tile_url: c.tile_url.clone(),
            tile_attribution: c.tile_attribution.clone(),
            offline_tiles: c.tiles_dir.is_some(),
            modes: FlightMode::ALL
                .iter()
                .map(|m| {
                    serde_json::to_value(m)
                        .ok()
                        .and_then(|v| v.as_str().map(String::from))
                        .unwrap_or_default()
                })
                .collect(),
        },
    }
}

async fn api_not_found(uri: axum::http::Uri) -> HttpError {
    error(
        StatusCode::NOT_FOUND,
        "not_found",
        format!("no API endpoint {} (see API.md)", uri.path()),
    )
}

async fn clients(State(state): State<AppState>, _caller: Caller) -> Response {
    let clients = state
        .clients
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .iter()
        .map(|(id, c)| c.view(*id, state.broadcast_total.load(Ordering::Relaxed)))
        .collect();
    Json(ClientsBody { clients }).into_response()
}

async fn session(State(state): State<AppState>, caller: Caller) -> Json<Session> {
    Json(session_of(&state, &caller))
}

async fn state_now(State(state): State<AppState>, _caller: Caller) -> Response {
    let now = state.now_s();
    let msg = state.core().state_msg_now(now);
    Json(msg).into_response()
}

async fn params(State(state): State<AppState>, _caller: Caller) -> Response {
    let now = state.now_s();
    Json(state.core().params_msg(now)).into_response()
}

#[derive(Deserialize)]
struct SinceQuery {
    since_s: Option<f64>,
}

async fn events(
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
struct EveryQuery {
    every_s: Option<f64>,
}

async fn track(
    State(state): State<AppState>,
    _caller: Caller,
    Query(q): Query<EveryQuery>,
) -> Response {
    let points = state.core().track(q.every_s.unwrap_or(0.0).max(0.0));
    Json(TrackBody { points }).into_response()
}

async fn command_result(
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

/// Records a request in the core and queues it for the link; answers 202 with its id.
async fn submit(
    state: &Shared,
    caller: &Caller,
    request: CommandRequest,
) -> Result<Response, HttpError> {
    caller.operator()?;
    let now = state.now_s();
    let (request_id, action) = state.core().request(now, &caller.name, request)?;
    queue(state, request_id, action).await
}

async fn queue(
    state: &Shared,
    request_id: String,
    action: LinkAction,
) -> Result<Response, HttpError> {
    state
        .link
        .send(LinkRequest::Action {
            request_id: request_id.clone(),
            action,
        })
        .await
        .map_err(|_| {
            error(
                StatusCode::SERVICE_UNAVAILABLE,
                "link_down",
                "the link task has stopped",
            )
        })?;
    Ok((
        StatusCode::ACCEPTED,
        Json(CommandAccepted {
            request_id,
            status: "sent",
        }),
    )
        .into_response())
}

/// A command endpoint's body: checked JSON that becomes a [`CommandRequest`].
trait CommandBody: DeserializeOwned + Send {
    fn into_request(self) -> CommandRequest;
}

/// Every command endpoint but parameters and cutdown: operator only, body checked, sent.
async fn command<B: CommandBody>(
    State(state): State<AppState>,
    caller: Caller,
    body: Result<Json<B>, JsonRejection>,
) -> Result<Response, HttpError> {
    caller.operator()?;
    let request = json_body(body)?.into_request();
    submit(&state, &caller, request).await
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

async fn set_param(
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
    .await
}

async fn arm_cutdown(State(state): State<AppState>, caller: Caller) -> Result<Response, HttpError> {
    caller.operator()?;
    let now = state.now_s();
    let arm = state.core().arm_cutdown(now, &caller.name);
    Ok(Json(arm).into_response())
}

async fn confirm_cutdown(
    State(state): State<AppState>,
    caller: Caller,
    body: Result<Json<ConfirmBody>, JsonRejection>,
) -> Result<Response, HttpError> {
    caller.operator()?;
    let b = json_body(body)?;
    let now = state.now_s();
    let (request_id, action) = state.core().confirm_cutdown(now, &caller.name, &b.arm_id)?;
    queue(&state, request_id, action).await
}

/// The address Google Earth used to reach the station (the `Host` header): the listen
/// address may be `0.0.0.0`, which names no machine. Without a usable header, the listen
/// address with `0.0.0.0` read as loopback.
fn public_host(headers: &axum::http::HeaderMap, listen: std::net::SocketAddr) -> String {
    let valid = |h: &str| {
        !h.is_empty()
            && h.len() <= 255
            && h.chars()
                .all(|c| c.is_ascii_alphanumeric() || "-.:[]_".contains(c))
    };
    match headers.get(header::HOST).and_then(|v| v.to_str().ok()) {
        Some(h) if valid(h) => h.to_string(),
        _ => {
            let ip = if listen.ip().is_unspecified() {
                std::net::IpAddr::from([127, 0, 0, 1])
            } else {
                listen.ip()
            };
            std::net::SocketAddr::new(ip, listen.port()).to_string()
        }
    }
}

async fn kml_link(
    State(state): State<AppState>,
    caller: Caller,
    headers: axum::http::HeaderMap,
) -> Response {
    let token = state
        .config
        .tokens
        .iter()
        .find(|t| t.name == caller.name)
        .map(|t| t.token.clone())
        .unwrap_or_default();
    let scheme = if state.config.tls.is_some() {
        "https"
    } else {
        "http"
    };
    let host = public_host(&headers, state.config.listen);
    let body = crate::kml::network_link(
        &state.config.name,
        &format!(
            "{scheme}://{host}/kml/live?token={}",
            percent_encode(&token)
        ),
        2.0,
    );
    (
        [(header::CONTENT_TYPE, "application/vnd.google-earth.kml+xml")],
        body,
    )
        .into_response()
}

async fn kml_live(State(state): State<AppState>, _caller: Caller) -> Response {
    let now = state.now_s();
    let core = state.core();
    let body = crate::kml::live(
        &state.config.name,
        &core.track(1.0),
        &core.state_msg_now(now),
    );
    drop(core);
    (
        [(header::CONTENT_TYPE, "application/vnd.google-earth.kml+xml")],
        body,
    )
        .into_response()
}

async fn websocket(
    State(state): State<AppState>,
    caller: Caller,
    upgrade: WebSocketUpgrade,
) -> Response {
    upgrade.on_upgrade(move |socket| serve_socket(state, caller, socket))
}

async fn serve_socket(state: AppState, caller: Caller, mut socket: WebSocket) {
    let mut updates = state.broadcast.subscribe();
    let base = state.broadcast_total.load(Ordering::Relaxed);
    let mut states = state.states.subscribe();
    let mut last_seq = states.borrow_and_update().seq;
    let id = state.next_client.fetch_add(1, Ordering::Relaxed) + 1;
    let counters = Arc::new(ClientCounters {
        name: caller.name.clone(),
        role: Some(caller.role),
        connected_s: state.now_s(),
        base,
        ..ClientCounters::default()
    });
    state
        .clients
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .insert(id, counters.clone());
    let greeting = {
        let now = state.now_s();
        let core = state.core();
        let hello = HelloMsg {
            kind: "hello",
            session: session_of(&state, &caller),
            role: caller.role,
            name: caller.name.clone(),
        };
        let mut events = core.events_since(f64::NEG_INFINITY);
        let history = HistoryMsg {
            kind: "history",
            track: core.track(1.0),
            events: events.split_off(events.len().saturating_sub(500)),
            states: core.history(),
        };
        let state_msg = core.state_msg_now(now);
        [
            serde_json::to_string(&hello).unwrap_or_default(),
            serde_json::to_string(&state_msg).unwrap_or_default(),
            serde_json::to_string(&history).unwrap_or_default(),
        ]
    };
    let mut open = true;
    for text in greeting {
        if socket.send(Message::Text(text.into())).await.is_err() {
            open = false;
            break;
        }
    }
    while open {
        tokio::select! {
            // Events and command results before states: they are what must not be lost.
            biased;
            update = updates.recv() => match update {
                Ok(text) => {
                    counters.messages_sent.fetch_add(1, Ordering::Relaxed);
                    open = socket.send(Message::Text(text)).await.is_ok();
                }
                Err(broadcast::error::RecvError::Lagged(missed)) => {
                    counters.messages_missed.fetch_add(missed, Ordering::Relaxed);
                    let episodes = counters.lag_episodes.fetch_add(1, Ordering::Relaxed) + 1;
                    tracing::warn!(client = id, name = %caller.name, missed, episodes,
                        "a page fell behind: it is told what it missed");
                    let notice = LaggedMsg {
                        kind: "lagged",
                        missed,
                        missed_total: counters.messages_missed.load(Ordering::Relaxed),
                        time_s: state.now_s(),
                        refetch: "/api/events",
                    };
                    let text = serde_json::to_string(&notice).unwrap_or_default();
                    open = socket.send(Message::Text(text.into())).await.is_ok();
                }
                Err(broadcast::error::RecvError::Closed) => break,
            },
            changed = states.changed() => {
                if changed.is_err() {
                    break;
                }
                let frame = states.borrow_and_update().clone();
                let skipped = frame.seq.saturating_sub(last_seq + 1);
                if skipped > 0 {
                    counters.states_coalesced.fetch_add(skipped, Ordering::Relaxed);
                }
                last_seq = frame.seq;
                counters.states_sent.fetch_add(1, Ordering::Relaxed);
                open = socket.send(Message::Text(frame.text)).await.is_ok();
            }
            incoming = socket.recv() => match incoming {
                Some(Ok(Message::Text(text))) => {
                    handle_client(&state, &caller, &mut socket, text.as_str()).await;
                }
                Some(Ok(Message::Close(_))) | None | Some(Err(_)) => break,
                Some(Ok(_)) => {}
            },
        }
    }
    state
        .clients
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .remove(&id);
}

/// The `event` a page gets back when its message is refused (to that page only, not logged).
fn refusal(state: &Shared, text: &str) -> Message {
    let now = state.now_s();
    let reply = EventMsg {
        kind: "event",
        time_s: now,
        wall_ms: state.core().wall_ms(now),
        level: Level::Error,
        source: "station",
        text: text.to_string(),
    };
    Message::Text(serde_json::to_string(&reply).unwrap_or_default().into())
}

async fn handle_client(state: &Shared, caller: &Caller, socket: &mut WebSocket, text: &str) {
    let message = serde_json::from_str::<ClientMessage>(text);
    if matches!(
        message,
        Ok(ClientMessage::Manual { .. } | ClientMessage::ManualRelease)
    ) && caller.role != Role::Operator
    {
        let reply = refusal(
            state,
            "viewers cannot fly the drone: operator role required",
        );
        let _ = socket.send(reply).await;
        return;
    }
    match message {
        Ok(ClientMessage::ManualRelease) => {
            state
                .manual
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .last_s = None;
            let _ = state.link.send(LinkRequest::ManualRelease).await;
        }
        Ok(ClientMessage::Ping) => {
            let pong = serde_json::to_string(&PongMsg { kind: "pong" }).unwrap_or_default();
            let _ = socket.send(Message::Text(pong.into())).await;
        }
        Ok(ClientMessage::Manual {
            x,
            y,
            z,
            r,
            buttons,
        }) => {
            let clamp = |v: f64| {
                if v.is_finite() {
                    v.clamp(-1.0, 1.0)
                } else {
                    0.0
                }
            };
            {
                let mut m = state.manual.lock().unwrap_or_else(|e| e.into_inner());
                m.last_s = Some(state.now_s());
            }
            let _ = state
                .link
                .send(LinkRequest::Manual(Sticks {
                    x: clamp(x),
                    y: clamp(y),
                    z: clamp(z),
                    r: clamp(r),
                    buttons,
                }))
                .await;
        }
        Err(e) => {
            let reply = refusal(state, &format!("malformed message refused: {e}"));
            let _ = socket.send(reply).await;
        }
    }
}
