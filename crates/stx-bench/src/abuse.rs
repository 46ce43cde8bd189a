//! The field network leaning on the station while `stx bench station` times its telemetry
//! (`--abuse`): from 127.0.0.2, 1,000 requests a second with a wrong token, each on a new
//! connection (locked out after ten, answered 429); from 127.0.0.3, 200 WebSocket pages a
//! second opening and closing at once with a real viewer token (slowed by the token's request
//! limit). The operators' pages connect from 127.0.0.1, as before. What each side got is
//! counted, and the process's resident memory (the station runs in it) is read before and
//! after.

use std::net::SocketAddr;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use serde::Serialize;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::task::JoinHandle;

/// Wrong-token requests per second.
pub const BAD_TOKENS_PER_S: u64 = 1000;
/// WebSocket connects and disconnects per second.
pub const WEBSOCKETS_PER_S: u64 = 200;

/// What the flood did and got.
#[derive(Debug, Default, Serialize)]
pub struct AbuseReport {
    /// Wrong-token requests sent.
    pub bad_token_requests: u64,
    /// Of those, answered 429 (locked out).
    pub answered_429: u64,
    /// … answered 401 (before the lockout).
    pub answered_401: u64,
    /// … not answered (connection refused or reset, or some other status).
    pub other: u64,
    /// WebSocket handshakes tried.
    pub websockets_tried: u64,
    /// … that opened (then closed at once).
    pub websockets_opened: u64,
    /// Resident memory of the process holding the station before the flood, MB.
    pub rss_before_mb: f64,
    /// … after it, MB.
    pub rss_after_mb: f64,
}

#[derive(Default)]
struct Counters {
    sent: AtomicU64,
    s429: AtomicU64,
    s401: AtomicU64,
    other: AtomicU64,
    ws_tried: AtomicU64,
    ws_opened: AtomicU64,
}

/// A connection to `to` from the loopback address `from`.
async fn connect_from(from: [u8; 4], to: SocketAddr) -> std::io::Result<tokio::net::TcpStream> {
    let socket = tokio::net::TcpSocket::new_v4()?;
    socket.bind(SocketAddr::from((from, 0)))?;
    socket.connect(to).await
}

async fn bad_token(to: SocketAddr, c: Arc<Counters>) {
    c.sent.fetch_add(1, Ordering::Relaxed);
    let status = async {
        let mut s = connect_from([127, 0, 0, 2], to).await.ok()?;
        let req = format!(
            "GET /api/state HTTP/1.1\r\nHost: {to}\r\nAuthorization: Bearer not-a-token\r\nConnection: close\r\n\r\n"
        );
        s.write_all(req.as_bytes()).await.ok()?;
        let mut head = [0u8; 12];
        s.read_exact(&mut head).await.ok()?;
        std::str::from_utf8(&head[9..12]).ok()?.parse::<u16>().ok()
    };
    match tokio::time::timeout(Duration::from_secs(5), status).await {
        Ok(Some(429)) => c.s429.fetch_add(1, Ordering::Relaxed),
        Ok(Some(401)) => c.s401.fetch_add(1, Ordering::Relaxed),
        _ => c.other.fetch_add(1, Ordering::Relaxed),
    };
}

async fn page_in_and_out(to: SocketAddr, token: String, c: Arc<Counters>) {
    c.ws_tried.fetch_add(1, Ordering::Relaxed);
    let opened = async {
        let stream = connect_from([127, 0, 0, 3], to).await.ok()?;
        let url = format!("ws://{to}/api/ws?token={token}");
        let (mut ws, _) = tokio_tungstenite::client_async(url, stream).await.ok()?;
        let _ = ws.close(None).await;
        Some(())
    };
    if let Ok(Some(())) = tokio::time::timeout(Duration::from_secs(5), opened).await {
        c.ws_opened.fetch_add(1, Ordering::Relaxed);
    }
}

/// A running flood; [`Flood::stop`] ends it and reports.
pub struct Flood {
    counters: Arc<Counters>,
    tasks: Vec<JoinHandle<()>>,
    rss_before_mb: f64,
}

impl Flood {
    /// Starts the flood on the station at `http`; `viewer_token` opens the churned pages.
    pub fn start(http: SocketAddr, viewer_token: String) -> anyhow::Result<Self> {
        let (rss_before_mb, _) = crate::memory::memory_mb(std::process::id())?;
        let counters = Arc::new(Counters::default());
        let c = counters.clone();
        let requests = tokio::spawn(async move {
            let mut tick =
                tokio::time::interval(Duration::from_micros(1_000_000 / BAD_TOKENS_PER_S));
            tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Burst);
            loop {
                tick.tick().await;
                tokio::spawn(bad_token(http, c.clone()));
            }
        });
        let c = counters.clone();
        let pages = tokio::spawn(async move {
            let mut tick =
                tokio::time::interval(Duration::from_micros(1_000_000 / WEBSOCKETS_PER_S));
            tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Burst);
            loop {
                tick.tick().await;
                tokio::spawn(page_in_and_out(http, viewer_token.clone(), c.clone()));
            }
        });
        Ok(Self {
            counters,
            tasks: vec![requests, pages],
            rss_before_mb,
        })
    }

    /// Stops sending, lets the last answers come, and reports.
    pub async fn stop(self) -> anyhow::Result<AbuseReport> {
        for t in &self.tasks {
            t.abort();
        }
        tokio::time::sleep(Duration::from_secs(2)).await;
        let (rss_after_mb, _) = crate::memory::memory_mb(std::process::id())?;
        let c = &self.counters;
        Ok(AbuseReport {
            bad_token_requests: c.sent.load(Ordering::Relaxed),
            answered_429: c.s429.load(Ordering::Relaxed),
            answered_401: c.s401.load(Ordering::Relaxed),
            other: c.other.load(Ordering::Relaxed),
            websockets_tried: c.ws_tried.load(Ordering::Relaxed),
            websockets_opened: c.ws_opened.load(Ordering::Relaxed),
            rss_before_mb: self.rss_before_mb,
            rss_after_mb,
        })
    }
}
