//! The relay's one WebSocket to its upstream: the address read from `--upstream` (plain or
//! TLS), the rustls client that checks a TLS upstream's certificate, and the loop that keeps
//! the socket open (reconnecting with back-off), feeds what the upstream says into the relay
//! and tells the upstream how many pages the relay serves.
//!
//! The audience travels up the tree: each relay sends its upstream `relay_viewers` with its
//! own pages plus what the relays below it reported, so the station's sharing panel counts
//! every public page however deep the tree. That is the only thing a relay ever sends.

use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

use futures_util::{SinkExt, StreamExt};
use tokio_tungstenite::Connector;
use tokio_tungstenite::tungstenite::Message;

use thiserror::Error;

use super::public::{UpstreamNews, read_upstream};

/// Longest wait between attempts to reach the upstream.
const MAX_BACKOFF: Duration = Duration::from_secs(5);
/// How often the audience is looked at for a change worth telling the upstream.
const AUDIENCE_CHECK: Duration = Duration::from_secs(1);
/// The audience is told again this often even when it did not change (a station restarted
/// or a new relay in between learns it without waiting for a change).
const AUDIENCE_REPEAT: Duration = Duration::from_secs(10);

/// Why the relay cannot run.
#[derive(Debug, Error)]
pub enum RelayError {
    /// The upstream address is not one the relay can reach.
    #[error("upstream {0}: {1}")]
    Upstream(String, &'static str),
    /// The certificates trusted for a TLS upstream.
    #[error("upstream certificates {0}: {1}")]
    UpstreamCa(String, String),
    /// The listening socket.
    #[error("serving viewers: {0}")]
    Serve(#[from] std::io::Error),
}

/// What the upstream's socket feeds: the relay's server.
pub(super) trait Follower: Send + Sync + 'static {
    /// The upstream's socket opened or closed.
    fn set_connected(&self, up: bool);
    /// The upstream said something the relay understands.
    fn on_upstream(&self, news: UpstreamNews);
    /// Pages served through the relay, to report up.
    fn audience(&self) -> usize;
}

/// Where the relay connects and how the address is shown (never with its token).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Upstream {
    /// `ws://…/api/ws?token=…` or `wss://…`.
    pub ws_url: String,
    /// `http://HOST:PORT/` or `https://…`, for logs and `/api/relay`.
    pub shown: String,
    /// Whether the upstream speaks TLS.
    pub tls: bool,
}

impl Upstream {
    /// Reads `http(s)://HOST:PORT/?token=VIEWER-TOKEN` (a station) or `http(s)://HOST:PORT/`
    /// (a relay); `ws://` and `wss://` are taken as well.
    pub fn parse(upstream: &str) -> Result<Self, RelayError> {
        let bad = |why| RelayError::Upstream(upstream.to_string(), why);
        let (tls, rest) = [
            ("http://", false),
            ("ws://", false),
            ("https://", true),
            ("wss://", true),
        ]
        .into_iter()
        .find_map(|(scheme, tls)| upstream.strip_prefix(scheme).map(|r| (tls, r)))
        .ok_or_else(|| bad("not an http://, https://, ws:// or wss:// address"))?;
        let (host, tail) = rest.split_at(rest.find(['/', '?']).unwrap_or(rest.len()));
        if host.is_empty() {
            return Err(bad("no host"));
        }
        let query = tail.split_once('?').map(|(_, q)| q).unwrap_or("");
        let token = form_urlencoded::parse(query.as_bytes())
            .find(|(k, _)| k == "token")
            .map(|(_, v)| v.into_owned());
        let (ws, http) = if tls {
            ("wss", "https")
        } else {
            ("ws", "http")
        };
        let ws_url = match &token {
            Some(t) => format!(
                "{ws}://{host}/api/ws?token={}",
                form_urlencoded::byte_serialize(t.as_bytes()).collect::<String>()
            ),
            None => format!("{ws}://{host}/api/ws"),
        };
        Ok(Self {
            ws_url,
            shown: format!("{http}://{host}/"),
            tls,
        })
    }
}

/// The TLS client for an `https://` upstream: Mozilla's roots, plus the certificates of
/// `extra_roots` (a PEM file: a field station's own self-signed certificate).
pub fn tls_connector(extra_roots: Option<&Path>) -> Result<Connector, RelayError> {
    use rustls_pki_types::CertificateDer;
    use rustls_pki_types::pem::PemObject;
    let mut roots = rustls::RootCertStore::empty();
    roots.extend(webpki_roots::TLS_SERVER_ROOTS.iter().cloned());
    if let Some(path) = extra_roots {
        let bad = |reason: String| RelayError::UpstreamCa(path.display().to_string(), reason);
        let certs = CertificateDer::pem_file_iter(path)
            .map_err(|e| bad(e.to_string()))?
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| bad(e.to_string()))?;
        if certs.is_empty() {
            return Err(bad("no PEM certificate in the file".into()));
        }
        for cert in certs {
            roots.add(cert).map_err(|e| bad(e.to_string()))?;
        }
    }
    let provider = Arc::new(rustls::crypto::ring::default_provider());
    let config = rustls::ClientConfig::builder_with_provider(provider)
        .with_safe_default_protocol_versions()
        .map_err(|e| RelayError::UpstreamCa("(built in)".into(), e.to_string()))?
        .with_root_certificates(roots)
        .with_no_client_auth();
    Ok(Connector::Rustls(Arc::new(config)))
}

/// Keeps the upstream's WebSocket open, reconnecting with back-off, feeds what it says into
/// the relay and reports the relay's audience up.
pub(super) async fn follow(
    relay: Arc<impl Follower>,
    upstream: Upstream,
    connector: Option<Connector>,
) {
    let mut backoff = Duration::from_millis(250);
    let shown = upstream.shown.as_str();
    loop {
        let connecting = tokio_tungstenite::connect_async_tls_with_config(
            upstream.ws_url.as_str(),
            None,
            false,
            connector.clone(),
        );
        match connecting.await {
            Ok((mut socket, _)) => {
                tracing::info!(upstream = %shown, "relay: upstream connected");
                relay.set_connected(true);
                backoff = Duration::from_millis(250);
                let mut check = tokio::time::interval(AUDIENCE_CHECK);
                let mut told: Option<(usize, Instant)> = None;
                loop {
                    tokio::select! {
                        message = socket.next() => {
                            let text = match message {
                                Some(Ok(Message::Text(t))) => t,
                                Some(Ok(_)) => continue,
                                Some(Err(e)) => {
                                    tracing::warn!(error = %e, "relay: upstream socket failed");
                                    break;
                                }
                                None => break,
                            };
                            match read_upstream(&text) {
                                Ok(news) => relay.on_upstream(news),
                                Err(e) => tracing::warn!(error = %e, "relay: an upstream message did not parse"),
                            }
                        }
                        _ = check.tick() => {
                            let audience = relay.audience();
                            let due = told.is_none_or(|(n, at)| n != audience || at.elapsed() >= AUDIENCE_REPEAT);
                            if due {
                                let report = serde_json::json!({"type": "relay_viewers", "viewers": audience});
                                if socket.send(Message::Text(report.to_string().into())).await.is_err() {
                                    break;
                                }
                                told = Some((audience, Instant::now()));
                            }
                        }
                    }
                }
                relay.set_connected(false);
                tracing::warn!(upstream = %shown, "relay: upstream lost; reconnecting");
            }
            Err(e) => {
                tracing::warn!(upstream = %shown, error = %e, "relay: upstream unreachable");
            }
        }
        tokio::time::sleep(backoff).await;
        backoff = (backoff * 2).min(MAX_BACKOFF);
    }
}
