//! The relay's tokio adapter: an axum server for the viewers with the public page, its
//! WebSocket, the KML feed and the relay's status, fed by the upstream's socket
//! ([`super::upstream`]). There is no token and no command route: a relay has nothing to
//! command with (its upstream token is a viewer's, and all it sends up is its audience).
//!
//! Each viewer gets the newest state through a `watch` channel (a slow one skips to the newest,
//! it never queues), serialised once per state for all of them, so a thousand viewers cost the
//! relay a thousand small tasks and the station one page. Every answer carries the station's
//! security headers (`crate::http::headers`).

use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use axum::Router;
use axum::extract::State;
use axum::extract::ws::{Message, Utf8Bytes, WebSocket, WebSocketUpgrade};
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};
use axum::routing::{any, get};
use tokio::net::TcpListener;
use tokio::sync::watch;
use tower_http::services::{ServeDir, ServeFile};

use super::feed::{Feed, RelaySettings};
use super::public::RelayStatusBody;
use super::upstream::{Follower, Upstream};
use crate::http::headers::SecurityHeaders;

/// How often held states are looked at for being due, s.
const RELEASE_EVERY: Duration = Duration::from_millis(100);
/// A viewer socket's read buffer, bytes.
const VIEWER_BUFFER: usize = 4096;
/// The largest message a viewer may send, bytes.
const VIEWER_MESSAGE_MAX: usize = 16 * 1024;

/// What `stx relay` runs.
#[derive(Debug, Clone)]
pub struct RelayOptions {
    /// The upstream, `http(s)://HOST:PORT/?token=VIEWER-TOKEN` for a station or
    /// `http(s)://HOST:PORT/` for a relay (`ws://` and `wss://` work as well).
    pub upstream: String,
    /// A PEM file of certificates trusted for an `https://` upstream besides Mozilla's roots
    /// (a field station's self-signed certificate).
    pub upstream_ca: Option<PathBuf>,
    /// The built dashboard (`web/dist`): the public page and its assets.
    pub web_dir: PathBuf,
    /// Delay and grid.
    pub settings: RelaySettings,
    /// Most viewers at once.
    pub max_viewers: usize,
}

pub use super::upstream::RelayError;

struct Relay {
    feed: Mutex<Feed>,
    /// The newest public state as sent, shared by every viewer's socket (a reference count,
    /// not a copy each).
    latest: watch::Sender<Option<Utf8Bytes>>,
    /// Viewer sockets open.
    viewers: AtomicUsize,
    /// Pages served through this relay: a viewer socket counts one, a relay below counts what
    /// it last reported.
    audience: AtomicUsize,
    connected: AtomicBool,
    shown_upstream: String,
    max_viewers: usize,
    started: Instant,
}

impl Relay {
    fn feed(&self) -> MutexGuard<'_, Feed> {
        self.feed.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn now_s(&self) -> f64 {
        self.started.elapsed().as_secs_f64()
    }

    /// A viewer socket that counted `old` pages now counts `new`.
    fn recount(&self, old: usize, new: usize) {
        self.audience.fetch_add(new, Ordering::Relaxed);
        self.audience.fetch_sub(old, Ordering::Relaxed);
    }

    /// Sends the viewers the newest state come due.
    fn release(&self) {
        let due = self.feed().due(self.now_s());
        if let Some(text) = due.and_then(|s| serde_json::to_string(&s).ok()) {
            self.latest.send_replace(Some(text.into()));
        }
    }
}

impl Follower for Relay {
    fn set_connected(&self, up: bool) {
        self.connected.store(up, Ordering::Relaxed);
    }

    fn on_upstream(&self, news: super::public::UpstreamNews) {
        self.feed().on_upstream(self.now_s(), news);
        self.release();
    }

    fn audience(&self) -> usize {
        self.audience.load(Ordering::Relaxed)
    }
}

/// Serves viewers on `listener` from the upstream until `shutdown` resolves.
pub async fn run(
    options: RelayOptions,
    listener: TcpListener,
    shutdown: impl std::future::Future<Output = ()> + Send + 'static,
) -> Result<(), RelayError> {
    let upstream = Upstream::parse(&options.upstream)?;
    let connector = if upstream.tls {
        Some(super::upstream::tls_connector(
            options.upstream_ca.as_deref(),
        )?)
    } else {
        None
    };
    let relay = Arc::new(Relay {
        feed: Mutex::new(Feed::new(options.settings)),
        latest: watch::channel(None).0,
        viewers: AtomicUsize::new(0),
        audience: AtomicUsize::new(0),
        connected: AtomicBool::new(false),
        shown_upstream: upstream.shown.clone(),
        max_viewers: options.max_viewers,
        started: Instant::now(),
    });
    let upstream = tokio::spawn(super::upstream::follow(relay.clone(), upstream, connector));
    let ticker = tokio::spawn({
        let relay = relay.clone();
        async move {
            let mut every = tokio::time::interval(RELEASE_EVERY);
            loop {
                every.tick().await;
                relay.release();
            }
        }
    });
    let index = options.web_dir.join("public.html");
    let app = Router::new()
        .route("/api/ws", get(viewer_socket))
        .route("/api/relay", get(status))
        .route("/api/public/state", get(public_state))
        .route("/api", any(not_here))
        .route("/api/{*rest}", any(not_here))
        .route("/kml", get(kml_link))
        .route("/kml/live", get(kml_live))
        .route_service("/", ServeFile::new(index.clone()))
        .fallback_service(ServeDir::new(&options.web_dir).fallback(ServeFile::new(index)))
        .with_state(relay)
        .layer(axum::middleware::from_fn_with_state(
            Arc::new(SecurityHeaders::plain()),
            crate::http::headers::add,
        ));
    let served = axum::serve(listener, app)
        .with_graceful_shutdown(shutdown)
        .await;
    upstream.abort();
    ticker.abort();
    served.map_err(RelayError::Serve)
}

async fn viewer_socket(State(relay): State<Arc<Relay>>, upgrade: WebSocketUpgrade) -> Response {
    if relay.viewers.load(Ordering::Relaxed) >= relay.max_viewers {
        let body = format!("this relay serves {} viewers at once", relay.max_viewers);
        return (
            StatusCode::SERVICE_UNAVAILABLE,
            [(header::RETRY_AFTER, "10")],
            body,
        )
            .into_response();
    }
    // A viewer sends at most a relay's audience report: small buffers and a small limit keep a
    // thousand viewers within a relay's memory (the defaults, 128 KiB read buffer each, are
    // 130 MB at 1,000) and a hostile one from sending megabytes.
    upgrade
        .read_buffer_size(VIEWER_BUFFER)
        .write_buffer_size(0)
        .max_message_size(VIEWER_MESSAGE_MAX)
        .max_frame_size(VIEWER_MESSAGE_MAX)
        .on_upgrade(move |socket| serve_viewer(relay, socket))
}

async fn serve_viewer(relay: Arc<Relay>, mut socket: WebSocket) {
    relay.viewers.fetch_add(1, Ordering::Relaxed);
    // A page counts one; a relay below says how many it serves.
    let mut counts = 1;
    relay.recount(0, counts);
    let mut states = relay.latest.subscribe();
    let history = serde_json::to_string(&relay.feed().history());
    let mut first: Vec<Utf8Bytes> = history.ok().map(|h| vec![h.into()]).unwrap_or_default();
    if let Some(s) = states.borrow_and_update().clone() {
        first.push(s);
    }
    let mut open = true;
    for text in first {
        open &= socket.send(Message::Text(text)).await.is_ok();
    }
    while open {
        tokio::select! {
            changed = states.changed() => {
                let Ok(()) = changed else { break };
                let text = states.borrow_and_update().clone();
                if let Some(text) = text {
                    open = socket.send(Message::Text(text)).await.is_ok();
                }
            }
            incoming = socket.recv() => match incoming {
                Some(Ok(Message::Text(text))) => {
                    // Pages have nothing to say; a relay below reports its audience. Anything
                    // else is read and dropped.
                    if let Some(n) = audience_report(text.as_str()) {
                        relay.recount(counts, n);
                        counts = n;
                    }
                }
                Some(Ok(Message::Close(_))) | None | Some(Err(_)) => open = false,
                Some(Ok(_)) => {}
            },
        }
    }
    relay.recount(counts, 0);
    relay.viewers.fetch_sub(1, Ordering::Relaxed);
}

/// The pages a relay below serves, from its `relay_viewers` message.
fn audience_report(text: &str) -> Option<usize> {
    match serde_json::from_str::<crate::requests::ClientMessage>(text) {
        Ok(crate::requests::ClientMessage::RelayViewers { viewers }) => {
            usize::try_from(viewers).ok()
        }
        _ => None,
    }
}

async fn status(State(relay): State<Arc<Relay>>) -> Response {
    let settings = relay.feed().settings();
    axum::Json(RelayStatusBody {
        upstream: relay.shown_upstream.clone(),
        upstream_connected: relay.connected.load(Ordering::Relaxed),
        viewers: u32::try_from(relay.viewers.load(Ordering::Relaxed)).unwrap_or(u32::MAX),
        audience: u32::try_from(relay.audience()).unwrap_or(u32::MAX),
        max_viewers: u32::try_from(relay.max_viewers).unwrap_or(u32::MAX),
        delay_s: settings.delay_s,
        coarsen_m: settings.coarsen_m,
    })
    .into_response()
}

async fn public_state(State(relay): State<Arc<Relay>>) -> Response {
    match relay.feed().latest() {
        Some(s) => axum::Json(s.clone()).into_response(),
        None => not_yet(),
    }
}

fn not_yet() -> Response {
    let body = serde_json::json!({"error": "unavailable", "reason": "nothing heard from the upstream yet"});
    (StatusCode::SERVICE_UNAVAILABLE, axum::Json(body)).into_response()
}

async fn not_here() -> Response {
    let body = serde_json::json!({"error": "not_found", "reason": "a relay serves /api/ws, /api/relay and /api/public/state only"});
    (StatusCode::NOT_FOUND, axum::Json(body)).into_response()
}

async fn kml_link(headers: axum::http::HeaderMap) -> Response {
    let host = headers
        .get(header::HOST)
        .and_then(|h| h.to_str().ok())
        .unwrap_or("localhost");
    let body = crate::kml::network_link("stx relay", &format!("http://{host}/kml/live"), 5.0);
    kml(body)
}

async fn kml_live(State(relay): State<Arc<Relay>>) -> Response {
    let feed = relay.feed();
    kml(super::kml::public_live(
        "stx relay",
        feed.track(),
        feed.latest(),
    ))
}

fn kml(body: String) -> Response {
    (
        [(header::CONTENT_TYPE, "application/vnd.google-earth.kml+xml")],
        body,
    )
        .into_response()
}

/// Binds the viewers' socket (before the banner, so a test reads the port from it).
pub async fn bind(listen: SocketAddr) -> Result<TcpListener, RelayError> {
    Ok(TcpListener::bind(listen).await?)
}
