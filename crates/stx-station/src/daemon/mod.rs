//! The daemon's tokio wiring: the link driver (`stx_link_tokio::drive_paths` running the
//! station's [`StationLink`] over every configured radio), the `station_loop` (messages
//! between the driver, the core and the pages), and the HTTP server (HTTPS with `[tls]`, see
//! `tls`), all stopped together by one shutdown signal; `pages` sends the pages their states
//! and messages. A replay station's core is fed by the recording's feeder thread instead of
//! the link (`replay_feed`); the live station opens them (`replay_sessions`). What is shared
//! beyond the pages runs beside: `forward`, `chase`, and `sondehub` with its queue's files
//! (`sondehub_store`). Nothing here decides anything: the core does.

mod anemometer;
mod chase;
mod forward;
mod pages;
mod replay_feed;
mod replay_sessions;
mod sondehub;
mod sondehub_store;
mod station_loop;
mod tls;

use std::future::Future;
use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use axum::extract::ws::Utf8Bytes;
use axum_server::tls_rustls::RustlsConfig;
use stx_link::endpoint::{GroundConfig, GroundEndpoint};
use stx_link::signing::SigningConfig;
use stx_link_tokio::{Action, DriveOptions, Transport, drive_paths};
use thiserror::Error;
use tokio::sync::{Notify, broadcast, mpsc, watch};

use crate::config::StationConfig;
use crate::core::StationCore;
use crate::http::{Shared, StateFrame, router};
use crate::link::StationLink;
use crate::recorder::Recording;
use crate::replay::ReplayControl;
use crate::tile_pack::LoadedPack;

pub use replay_feed::spawn_replay_feeder;
pub use replay_sessions::{IDLE, MAX_SESSIONS, PreparedReplay, ReplayOpenError, serve_replay};
pub use station_loop::STATE_PERIOD;
pub use tls::tls_config;

/// Events, command results and parameter tables kept for each page that has not read them
/// yet; a page further behind is told how many it missed (`lagged`).
pub const RELIABLE_BACKLOG: usize = 4096;

/// Why the daemon could not start or stopped.
#[derive(Debug, Error)]
pub enum DaemonError {
    /// The HTTP address could not be bound.
    #[error("cannot listen on {address}: {source}")]
    Listen {
        address: SocketAddr,
        #[source]
        source: std::io::Error,
    },
    /// The drone link could not be opened.
    #[error("cannot open the drone link {address}: {source}")]
    Link {
        address: String,
        #[source]
        source: stx_link_tokio::TransportError,
    },
    /// The signing key or its timestamp file is unusable.
    #[error("signing: {0}")]
    Signing(String),
    /// The HTTP server failed.
    #[error("HTTP server: {0}")]
    Serve(#[source] std::io::Error),
    /// The TLS certificate or key cannot be used.
    #[error("TLS: `{field}` ({path}): {reason}")]
    Tls {
        /// The configuration field.
        field: &'static str,
        /// The file.
        path: String,
        /// What is wrong.
        reason: String,
    },
}
/// What a running daemon exposes to its starter (tests and `stx serve --sim`).
#[derive(Clone)]
pub struct Running {
    /// Where the dashboard and API listen.
    pub http: SocketAddr,
    /// `https` with `[tls]`, else `http`.
    pub scheme: &'static str,
    /// The drone link's local socket address, for UDP and TCP servers (the port the drone
    /// must send to when the config asked for port 0). With several radios, the primary's.
    pub link_local: Option<SocketAddr>,
    /// Each radio's local socket address, the primary first.
    pub link_locals: Vec<Option<SocketAddr>>,
    /// The shared state.
    pub shared: Arc<Shared>,
}

fn signing(config: &StationConfig) -> Result<Option<SigningConfig>, DaemonError> {
    let Some(key) = config
        .link
        .signing_key()
        .map_err(|e| DaemonError::Signing(e.to_string()))?
    else {
        return Ok(None);
    };
    let unix_s = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_err(|e| DaemonError::Signing(e.to_string()))?;
    stx_link::signing::persist::start_signing(
        key,
        unix_s,
        config.link.signing_timestamp_file.as_deref(),
    )
    .map(Some)
    .map_err(|e| DaemonError::Signing(e.to_string()))
}

/// The drone link's radios, opened: the transports, their local addresses, and how to name
/// them in the log (for `udpin:…:0` / `tcpin:…:0`, the port the drone must be pointed at).
async fn open_radios(
    config: &StationConfig,
) -> Result<(Vec<Transport>, Vec<Option<SocketAddr>>, String), DaemonError> {
    let mut transports = Vec::new();
    for address in config.link.addresses() {
        let transport = Transport::open_str(address)
            .await
            .map_err(|source| DaemonError::Link {
                address: address.clone(),
                source,
            })?;
        transports.push(transport);
    }
    let locals = transports.iter().map(Transport::local_addr).collect();
    let shown = transports
        .iter()
        .zip(config.link.addresses())
        .map(|(t, a)| {
            t.listening_address()
                .map_or_else(|| a.clone(), |l| l.to_string())
        })
        .collect::<Vec<_>>()
        .join(" + ");
    Ok((transports, locals, shown))
}

/// The ground endpoint for `paths` radios, its signing high-water mark on disk before anything
/// is signed (or the station does not start).
fn ground_link(config: &StationConfig, paths: usize) -> Result<StationLink, DaemonError> {
    let mut ground = GroundConfig::default();
    ground.link = ground.link.with_signing(signing(config)?).with_paths(paths);
    let endpoint = GroundEndpoint::new(ground, Duration::ZERO);
    stx_link::signing::persist::persist_signing_mark(
        &endpoint,
        config.link.signing_timestamp_file.as_deref(),
    )
    .map_err(|e| DaemonError::Signing(e.to_string()))?;
    Ok(StationLink::new(endpoint))
}

/// Starts the station; `started(running)` is called once it listens; returns when `shutdown`
/// resolves (or a task fails).
pub async fn run(
    config: StationConfig,
    shutdown: impl Future<Output = ()> + Send + 'static,
    started: impl FnOnce(Running) + Send,
) -> Result<(), DaemonError> {
    run_with(config, None, shutdown, started).await
}

/// Starts a station that replays a recording under `replay` (its link hears the feeder,
/// `stx_station::replay::feeder`, started by the caller in `started`; nothing is recorded
/// and nothing can be commanded); returns when `shutdown` resolves.
pub async fn run_replay(
    mut config: StationConfig,
    replay: Arc<ReplayControl>,
    shutdown: impl Future<Output = ()> + Send + 'static,
    started: impl FnOnce(Running) + Send,
) -> Result<(), DaemonError> {
    config.recording.enabled = false;
    // A replay is not the flight: chase cars and watchers must not take it for the drone.
    config.chase = None;
    config.forward.clear();
    // Nor SondeHub: a replay's points would go on the public map as a second flight.
    config.sondehub = None;
    run_with(config, Some(replay), shutdown, started).await
}

async fn run_with(
    config: StationConfig,
    replay: Option<Arc<ReplayControl>>,
    shutdown: impl Future<Output = ()> + Send + 'static,
    started: impl FnOnce(Running) + Send,
) -> Result<(), DaemonError> {
    let tls = config.tls.as_ref().map(tls_config).transpose()?;
    let listen_error = |source| DaemonError::Listen {
        address: config.listen,
        source,
    };
    let listener = tokio::net::TcpListener::bind(config.listen)
        .await
        .map_err(listen_error)?;
    let http_address = listener.local_addr().map_err(listen_error)?;
    let (transports, link_locals, link_shown) = open_radios(&config).await?;
    let start = Instant::now();
    let wall_origin_ms = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_millis() as u64)
        .unwrap_or(0);
    let recording = Recording::start(&config, start, wall_origin_ms);
    let mut link = ground_link(&config, transports.len())?;
    if let Some(tap) = recording.frame_tap() {
        link = link.with_tap(tap);
    }
    let (actions_tx, actions_rx) = mpsc::channel::<Action<StationLink>>(1024);
    let (stop_tx, stop_rx) = watch::channel(false);
    let (forward_sink, forwards) =
        forward::start(&config.forward, actions_tx.clone(), stop_rx.clone());
    if let Some(sink) = forward_sink {
        link = link.with_forward(sink);
    }
    let (events_tx, events_rx) = mpsc::channel(4096);
    let options = DriveOptions {
        signing_timestamp_file: config.link.signing_timestamp_file.clone(),
    };
    let link_task = tokio::spawn(drive_paths(
        transports, link, actions_rx, events_tx, options,
    ));

    let (broadcast_tx, _) = broadcast::channel::<Utf8Bytes>(RELIABLE_BACKLOG);
    // A live station opens replays of its recordings for its pages; a replay opens none.
    let (replay_requests, replay_requests_rx) = match replay {
        None => {
            let (tx, rx) = mpsc::channel(4);
            (Some(tx), Some(rx))
        }
        Some(_) => (None, None),
    };
    let mut core = StationCore::new(config.clone(), wall_origin_ms);
    if let Some(path) = &config.keep_out {
        // Missing or invalid, the station runs on with the reason on every page and in the
        // log: a station that does not start loses the drone's telemetry and commands, worse
        // than flying without the zones with everyone told so.
        let text = tokio::fs::read_to_string(path)
            .await
            .map_err(|e| e.to_string());
        core.load_keep_out(0.0, &path.display().to_string(), text);
    }
    // The go/no-go board's files: like the zones, a missing one leaves its checks open with
    // the reason rather than stopping the station.
    let read = |path: &std::path::Path| {
        let path = path.to_path_buf();
        async move {
            tokio::fs::read_to_string(&path)
                .await
                .map_err(|e| e.to_string())
        }
    };
    if let Some(path) = &config.readiness.checklist {
        core.load_checklist(0.0, &path.display().to_string(), read(path).await);
    }
    if let Some(path) = &config.readiness.params_file {
        core.load_saved_params(0.0, &path.display().to_string(), read(path).await);
    }
    let (sondehub_share, sondehub) = match config.sondehub.clone() {
        Some(c) => {
            let (share, prepared) = sondehub::prepare(c, 0.0).await;
            (Some(share), Some(prepared))
        }
        None => (None, None),
    };
    let shared = Arc::new(Shared {
        core: Mutex::new(core),
        config: config.clone(),
        started: start,
        link_due: Notify::new(),
        broadcast: broadcast_tx,
        states: watch::channel(StateFrame::default()).0,
        clients: Mutex::new(Default::default()),
        limits: Mutex::new(crate::limits::Limits::new(&config.limits)),
        next_client: Default::default(),
        broadcast_total: Default::default(),
        recording,
        replay,
        recording_summaries: Default::default(),
        tiles: LoadedPack::load(config.tile_pack.as_deref()).await,
        replay_requests,
        keep_out_edit: Default::default(),
        planning: Default::default(),
        uploads: Default::default(),
        forecast_field: Default::default(),
        lab: Default::default(),
        rehearsal: Default::default(),
        forwards,
        chase: Mutex::new(config.chase.as_ref().map(chase::view)),
        sondehub: sondehub_share,
    });
    let sessions_task = replay_requests_rx.map(|rx| {
        tokio::spawn(replay_sessions::replay_sessions(
            config.clone(),
            http_address,
            rx,
            stop_rx.clone(),
        ))
    });
    if let Ok(Some(address)) = config.surface_wind.anemometer_address() {
        tokio::spawn(anemometer::run(address, shared.clone(), stop_rx.clone()));
    }
    if let Some(chase_config) = config.chase.clone() {
        tokio::spawn(chase::run(chase_config, shared.clone(), stop_rx.clone()));
    }
    if let Some(prepared) = sondehub {
        tokio::spawn(sondehub::run(prepared, shared.clone(), stop_rx.clone()));
    }
    let station_task = tokio::spawn(station_loop::station_loop(station_loop::StationLoop {
        shared: shared.clone(),
        actions: actions_tx,
        events: events_rx,
        stop: stop_rx,
    }));

    started(Running {
        http: http_address,
        scheme: if tls.is_some() { "https" } else { "http" },
        link_local: link_locals.first().copied().flatten(),
        link_locals,
        shared: shared.clone(),
    });
    tracing::info!(address = %http_address, link = %link_shown, "station listening");
    let stop = async move {
        shutdown.await;
        let _ = stop_tx.send(true);
    };
    let served = serve(listener, tls, shared.clone(), stop).await;
    if let Some(sessions) = sessions_task {
        let _ = sessions.await;
    }
    station_task.abort();
    link_task.abort();
    // The loop and the driver hold recording handles; the writer drains its queue and closes
    // the file with its summary.
    let _ = station_task.await;
    let _ = link_task.await;
    let finishing = shared.clone();
    let _ = tokio::task::spawn_blocking(move || finishing.recording.finish()).await;
    served.map_err(DaemonError::Serve)
}

/// Serves the router on `listener` (over TLS with `tls`) until `stop` resolves.
async fn serve(
    listener: tokio::net::TcpListener,
    tls: Option<RustlsConfig>,
    shared: Arc<Shared>,
    stop: impl Future<Output = ()> + Send + 'static,
) -> std::io::Result<()> {
    let Some(tls) = tls else {
        return axum::serve(
            listener,
            router(shared).into_make_service_with_connect_info::<SocketAddr>(),
        )
        .with_graceful_shutdown(stop)
        .await;
    };
    let handle = axum_server::Handle::new();
    let stopper = handle.clone();
    tokio::spawn(async move {
        stop.await;
        stopper.graceful_shutdown(Some(Duration::from_secs(1)));
    });
    let server = axum_server::from_tcp_rustls(listener.into_std()?, tls)?;
    server
        .handle(handle)
        .serve(router(shared).into_make_service_with_connect_info::<SocketAddr>())
        .await
}
