//! The relay's tokio adapter: one WebSocket to the upstream (a station, through a viewer's
//! token, or another relay), reconnected with back-off while it is down, fed into the
//! [`Feed`]; an axum server for the viewers with the public page, its WebSocket, the KML feed
//! and the relay's status. There is no token and no command route: a relay has nothing to
//! command with (its upstream token is a viewer's, and it never sends on that socket).
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
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};
use axum::routing::{any, get};
use futures_util::StreamExt;
use thiserror::Error;
use tokio::net::TcpListener;
use tokio::sync::watch;
use tower_http::services::{ServeDir, ServeFile};

use super::feed::{Feed, RelaySettings};
use super::public::{RelayStatusBody, read_upstream};
use crate::http::headers::SecurityHeaders;

/// How often held states are looked at for being due, s.
const RELEASE_EVERY: Duration = Duration::from_millis(100);
/// Longest wait between attempts to reach the upstream.
const MAX_BACKOFF: Duration = Duration::from_secs(5);

/// What `stx relay` runs.
#[derive(Debug, Clone)]
pub struct RelayOptions {
    /// The upstream, `http://HOST:PORT/?token=VIEWER-TOKEN` for a station or
    /// `http://HOST:PORT/` for a relay (`ws://` works as well).
    pub upstream: String,
    /// The built dashboard (`web/dist`): the public page and its assets.
    pub web_dir: PathBuf,
    /// Delay and grid.
    pub settings: RelaySettings,
    /// Most viewers at once.
    pub max_viewers: usize,
}

/// Why the relay cannot run.
#[derive(Debug, Error)]
pub enum RelayError {
    /// The upstream address is not one the relay can reach.
    #[error("upstream {0}: {1}")]
    Upstream(String, &'static str),
    /// The listening socket.
    #[error("serving viewers: {0}")]
    Serve(#[from] std::io::Error),
}

/// The upstream's WebSocket address and how it is shown (without its token).
pub fn upstream_ws(upstream: &str) -> Result<(String, String), RelayError> {
    let bad = |why| RelayError::Upstream(upstream.to_string(), why);
    let rest = if let Some(r) = upstream.strip_prefix("http://") {
        r
    } else if let Some(r) = upstream.strip_prefix("ws://") {
        r
    } else if upstream.starts_with("https://") || upstream.starts_with("wss://") {
        return Err(bad(
            "TLS upstreams are not supported yet: relay from the station's plain-HTTP address",
        ));
    } else {
        return Err(bad("not an http:// or ws:// address"));
    };
    let (host, tail) = rest.split_at(rest.find(['/', '?']).unwrap_or(rest.len()));
    if host.is_empty() {
        return Err(bad("no host"));
    }
    let query = tail.split_once('?').map(|(_, q)| q).unwrap_or("");
    let token = form_urlencoded::parse(query.as_bytes())
        .find(|(k, _)| k == "token")
        .map(|(_, v)| v.into_owned());
    let url = match &token {
        Some(t) => format!(
            "ws://{host}/api/ws?token={}",
            form_urlencoded::byte_serialize(t.as_bytes()).collect::<String>()
        ),
        None => format!("ws://{host}/api/ws"),
    };
    Ok((url, format!("http://{host}/")))
}

struct Relay {
    feed: Mutex<Feed>,
    latest: watch::Sender<Option<Arc<str>>>,
    viewers: AtomicUsize,
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

    /// Sends the viewers the newest state come due.
    fn release(&self) {
        let due = self.feed().due(self.now_s());
        if let Some(text) = due.and_then(|s| serde_json::to_string(&s).ok()) {
            self.latest.send_replace(Some(text.into()));
        }
    }
}

/// Serves viewers on `listener` from the upstream until `shutdown` resolves.
pub async fn run(
    options: RelayOptions,
    listener: TcpListener,
    shutdown: impl std::future::Future<Output = ()> + Send + 'static,
) -> Result<(), RelayError> {
    let (ws_url, shown_upstream) = upstream_ws(&options.upstream)?;
    let relay = Arc::new(Relay {
        feed: Mutex::new(Feed::new(options.settings)),
        latest: watch::channel(None).0,
        viewers: AtomicUsize::new(0),
        connected: AtomicBool::new(false),
        shown_upstream,
        max_viewers: options.max_viewers,
        started: Instant::now(),
    });
    let upstream = tokio::spawn(follow_upstream(relay.clone(), ws_url));
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

/// Keeps the upstream's WebSocket open, reconnecting with back-off, and feeds what it says.
async fn follow_upstream(relay: Arc<Relay>, url: String) {
    let mut backoff = Duration::from_millis(250);
    loop {
        match tokio_tungstenite::connect_async(url.as_str()).await {
            Ok((mut socket, _)) => {
                tracing::info!(upstream = %relay.shown_upstream, "relay: upstream connected");
                relay.connected.store(true, Ordering::Relaxed);
                backoff = Duration::from_millis(250);
                while let Some(message) = socket.next().await {
                    let text = match message {
                        Ok(tokio_tungstenite::tungstenite::Message::Text(t)) => t,
                        Ok(_) => continue,
                        Err(e) => {
                            tracing::warn!(error = %e, "relay: upstream socket failed");
                            break;
                        }
                    };
                    match read_upstream(&text) {
                        Ok(news) => {
                            relay.feed().on_upstream(relay.now_s(), news);
                            relay.release();
                        }
                        Err(e) => {
                            tracing::warn!(error = %e, "relay: an upstream message did not parse")
                        }
                    }
                }
                relay.connected.store(false, Ordering::Relaxed);
                tracing::warn!(upstream = %relay.shown_upstream, "relay: upstream lost; reconnecting");
            }
            Err(e) => {
                tracing::warn!(upstream = %relay.shown_upstream, error = %e, "relay: upstream unreachable");
            }
        }
        tokio::time::sleep(backoff).await;
        backoff = (backoff * 2).min(MAX_BACKOFF);
    }
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
    upgrade.on_upgrade(move |socket| serve_viewer(relay, socket))
}

async fn serve_viewer(relay: Arc<Relay>, mut socket: WebSocket) {
    relay.viewers.fetch_add(1, Ordering::Relaxed);
    let mut states = relay.latest.subscribe();
    let history = serde_json::to_string(&relay.feed().history());
    let mut first = history.ok().map(|h| vec![h]).unwrap_or_default();
    if let Some(s) = states.borrow_and_update().clone() {
        first.push(s.to_string());
    }
    let mut open = true;
    for text in first {
        open &= socket.send(Message::Text(text.into())).await.is_ok();
    }
    while open {
        tokio::select! {
            changed = states.changed() => {
                let Ok(()) = changed else { break };
                let text = states.borrow_and_update().clone();
                if let Some(text) = text {
                    open = socket.send(Message::Text(text.to_string().into())).await.is_ok();
                }
            }
            incoming = socket.recv() => {
                // Viewers have nothing to say: anything but a close is read and dropped.
                open = matches!(incoming, Some(Ok(m)) if !matches!(m, Message::Close(_)));
            }
        }
    }
    relay.viewers.fetch_sub(1, Ordering::Relaxed);
}

async fn status(State(relay): State<Arc<Relay>>) -> Response {
    let settings = relay.feed().settings();
    axum::Json(RelayStatusBody {
        upstream: relay.shown_upstream.clone(),
        upstream_connected: relay.connected.load(Ordering::Relaxed),
        viewers: u32::try_from(relay.viewers.load(Ordering::Relaxed)).unwrap_or(u32::MAX),
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
