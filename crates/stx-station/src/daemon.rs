//! The daemon's tokio wiring: the link task (stx-link's driver over the configured transport),
//! the station loop (events in, state out at 4 Hz), the joystick watchdog, and the HTTP server
//! (HTTPS with `[tls]`: rustls through axum-server), all stopped together by one shutdown
//! signal.

use std::future::Future;
use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use axum::extract::ws::Utf8Bytes;
use stx_link::endpoint::{GroundConfig, GroundEndpoint, GroundEvent, LinkEvent};
use stx_link::signing::SigningConfig;
use stx_link_tokio::{Action, DriveOptions, DriverEvent, Transport, drive_paths};
use thiserror::Error;
use tokio::sync::{broadcast, mpsc, watch};

use crate::config::{StationConfig, TlsSettings};
use crate::core::{LinkAction, Outbound, StationCore};
use crate::http::{LinkRequest, ManualState, Shared, StateFrame, router};
use axum_server::tls_rustls::RustlsConfig;

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

/// The rustls server configuration of `[tls]`, read and checked before anything starts.
pub fn tls_config(tls: &TlsSettings) -> Result<RustlsConfig, DaemonError> {
    use rustls_pki_types::pem::PemObject;
    use rustls_pki_types::{CertificateDer, PrivateKeyDer};
    let cert_err = |reason: String| DaemonError::Tls {
        field: "tls.cert_path",
        path: tls.cert_path.display().to_string(),
        reason,
    };
    let certs = CertificateDer::pem_file_iter(&tls.cert_path)
        .map_err(|e| cert_err(e.to_string()))?
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| cert_err(e.to_string()))?;
    if certs.is_empty() {
        return Err(cert_err("no PEM certificate in the file".into()));
    }
    let key = PrivateKeyDer::from_pem_file(&tls.key_path).map_err(|e| DaemonError::Tls {
        field: "tls.key_path",
        path: tls.key_path.display().to_string(),
        reason: e.to_string(),
    })?;
    let provider = Arc::new(rustls::crypto::ring::default_provider());
    let mut server = rustls::ServerConfig::builder_with_provider(provider)
        .with_safe_default_protocol_versions()
        .map_err(|e| cert_err(e.to_string()))?
        .with_no_client_auth()
        .with_single_cert(certs, key)
        .map_err(|e| DaemonError::Tls {
            field: "tls.key_path",
            path: tls.key_path.display().to_string(),
            reason: format!("does not fit the certificate: {e}"),
        })?;
    // HTTP/1.1 only: the dashboard's WebSocket upgrades over it.
    server.alpn_protocols = vec![b"http/1.1".to_vec()];
    Ok(RustlsConfig::from_config(Arc::new(server)))
}

/// The state message period: 4 Hz, the drone's rate.
pub const STATE_PERIOD: Duration = Duration::from_millis(250);
/// Link statistics are sampled this often.
const STATS_PERIOD: Duration = Duration::from_millis(500);
/// Telemetry frames arriving within this window of the first one are answered with one
/// `state` message: the drone sends its sensors in bursts, and one message per burst keeps
/// pages current without flooding them.
const COALESCE: Duration = Duration::from_millis(1);
/// Landing predictions run this often, off the station loop.
const PREDICTION_PERIOD: Duration = Duration::from_secs(1);
/// Sticks silent this long stop the uplink of MANUAL_CONTROL.
pub const MANUAL_SILENCE_S: f64 = 0.5;
/// Events, command results and parameter tables kept for each page that has not read them
/// yet; a page further behind is told how many it missed (`lagged`).
pub const RELIABLE_BACKLOG: usize = 4096;

/// An operator's plan upload that meets the station's own plan download on the link is tried
/// again this often, s …
const UPLOAD_RETRY: Duration = Duration::from_millis(250);
/// … this many times (a download is over within a few round trips) before it is refused.
const UPLOAD_TRIES: u32 = 40;

/// A link request the endpoint could not start, for the core.
#[derive(Debug)]
enum Refusal {
    /// An operator's request.
    Request { request_id: String, reason: String },
    /// An operator's plan upload found another plan transfer running: try it again.
    UploadBusy {
        request_id: String,
        items: Vec<stx_link::plan::PlanItem>,
        tries: u32,
        reason: String,
    },
    /// The station's own plan download.
    PlanDownload { reason: String },
}

/// The closure that applies a [`LinkAction`] on the endpoint; a refusal goes back to the
/// core.
fn apply_action(
    request_id: Option<String>,
    action: LinkAction,
    refusals: mpsc::Sender<Refusal>,
) -> Action<GroundEndpoint> {
    apply_action_try(request_id, action, refusals, 1)
}

fn apply_action_try(
    request_id: Option<String>,
    action: LinkAction,
    refusals: mpsc::Sender<Refusal>,
    tries: u32,
) -> Action<GroundEndpoint> {
    Box::new(move |ep, now| {
        if let (Some(id), LinkAction::PlanUpload(items)) = (&request_id, &action)
            && let Err(e @ stx_link::plan::PlanRequestError::Busy) =
                ep.plan_upload(now, items.clone())
        {
            let _ = refusals.try_send(Refusal::UploadBusy {
                request_id: id.clone(),
                items: items.clone(),
                tries,
                reason: e.to_string(),
            });
            return;
        }
        let outcome = match action {
            LinkAction::Command {
                request_id: link_id,
                command,
            } => ep
                .send_command(now, link_id, command)
                .map_err(|e| e.to_string()),
            LinkAction::ParamSet { name, value } => {
                ep.param_set(now, &name, value).map_err(|e| e.to_string())
            }
            // Sent above (or refused as busy).
            LinkAction::PlanUpload(_) if request_id.is_some() => Ok(()),
            LinkAction::PlanUpload(items) => ep.plan_upload(now, items).map_err(|e| e.to_string()),
            LinkAction::PlanDownload => ep.plan_download(now).map_err(|e| e.to_string()),
        };
        if let Err(reason) = outcome {
            let refusal = match request_id {
                Some(request_id) => Refusal::Request { request_id, reason },
                None => Refusal::PlanDownload { reason },
            };
            let _ = refusals.try_send(refusal);
        }
    })
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

/// Starts the station; `started(running)` is called once it listens; returns when `shutdown`
/// resolves (or a task fails).
pub async fn run(
    config: StationConfig,
    shutdown: impl Future<Output = ()> + Send + 'static,
    started: impl FnOnce(Running) + Send,
) -> Result<(), DaemonError> {
    let tls = config.tls.as_ref().map(tls_config).transpose()?;
    let listener = tokio::net::TcpListener::bind(config.listen)
        .await
        .map_err(|source| DaemonError::Listen {
            address: config.listen,
            source,
        })?;
    let http_address = listener
        .local_addr()
        .map_err(|source| DaemonError::Listen {
            address: config.listen,
            source,
        })?;
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
    let link_locals: Vec<_> = transports.iter().map(Transport::local_addr).collect();
    // For `udpin:…:0` / `tcpin:…:0`: the port the drone must be pointed at.
    let link_shown = transports
        .iter()
        .zip(config.link.addresses())
        .map(|(t, a)| {
            t.listening_address()
                .map_or_else(|| a.clone(), |l| l.to_string())
        })
        .collect::<Vec<_>>()
        .join(" + ");
    let start = Instant::now();
    let mut ground = GroundConfig::default();
    ground.link = ground
        .link
        .with_signing(signing(&config)?)
        .with_paths(transports.len());
    let endpoint = GroundEndpoint::new(ground, Duration::ZERO);
    // The first high-water mark is on disk before anything is signed, or the station does not
    // start.
    stx_link::signing::persist::persist_signing_mark(
        &endpoint,
        config.link.signing_timestamp_file.as_deref(),
    )
    .map_err(|e| DaemonError::Signing(e.to_string()))?;
    let (actions_tx, actions_rx) = mpsc::channel::<Action<GroundEndpoint>>(1024);
    let (events_tx, events_rx) = mpsc::channel(4096);
    let options = DriveOptions {
        signing_timestamp_file: config.link.signing_timestamp_file.clone(),
    };
    let (stop_tx, stop_rx) = watch::channel(false);
    let link_task = tokio::spawn(drive_paths(
        transports, endpoint, actions_rx, events_tx, options,
    ));

    let wall_origin_ms = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_millis() as u64)
        .unwrap_or(0);
    let (requests_tx, mut requests_rx) = mpsc::channel::<LinkRequest>(1024);
    let (broadcast_tx, _) = broadcast::channel::<Utf8Bytes>(RELIABLE_BACKLOG);
    let shared = Arc::new(Shared {
        core: Mutex::new(StationCore::new(config.clone(), wall_origin_ms)),
        config: config.clone(),
        started: start,
        link: requests_tx,
        broadcast: broadcast_tx.clone(),
        states: watch::channel(StateFrame::default()).0,
        manual: Mutex::new(ManualState::default()),
        clients: Mutex::new(Default::default()),
        next_client: Default::default(),
        broadcast_total: Default::default(),
    });

    // Operators' requests → closures on the endpoint; refusals come back to the core.
    let (refusals_tx, refusals_rx) = mpsc::channel::<Refusal>(256);
    let request_actions = actions_tx.clone();
    let request_refusals = refusals_tx.clone();
    let mut stop = stop_rx.clone();
    let requests_task = tokio::spawn(async move {
        loop {
            let request = tokio::select! {
                r = requests_rx.recv() => match r { Some(r) => r, None => break },
                _ = stop.changed() => break,
            };
            let refusals = request_refusals.clone();
            let action: Action<GroundEndpoint> = match request {
                LinkRequest::Action { request_id, action } => {
                    apply_action(Some(request_id), action, refusals)
                }
                LinkRequest::Manual(sticks) => Box::new(move |ep, now| ep.manual_hold(now, sticks)),
                LinkRequest::ManualRelease => Box::new(|ep, _| ep.manual_release()),
            };
            if request_actions.send(action).await.is_err() {
                break;
            }
        }
    });

    // The station loop.
    let (stats_tx, stats_rx) = mpsc::channel(8);
    let station_task = tokio::spawn(station_loop(StationLoop {
        shared: shared.clone(),
        actions: actions_tx.clone(),
        events: events_rx,
        refusals: refusals_rx,
        refusals_tx: refusals_tx.clone(),
        stats_tx,
        stats_rx,
        stop: stop_rx.clone(),
    }));

    started(Running {
        http: http_address,
        scheme: if tls.is_some() { "https" } else { "http" },
        link_local: link_locals.first().copied().flatten(),
        link_locals,
        shared: shared.clone(),
    });
    tracing::info!(address = %http_address, link = %link_shown, "station listening");
    let stop_http = async move {
        shutdown.await;
        let _ = stop_tx.send(true);
    };
    let served = match tls {
        None => {
            axum::serve(listener, router(shared))
                .with_graceful_shutdown(stop_http)
                .await
        }
        Some(tls) => {
            let handle = axum_server::Handle::new();
            let stopper = handle.clone();
            tokio::spawn(async move {
                stop_http.await;
                stopper.graceful_shutdown(Some(Duration::from_secs(1)));
            });
            match listener
                .into_std()
                .and_then(|l| axum_server::from_tcp_rustls(l, tls))
            {
                Ok(server) => {
                    server
                        .handle(handle)
                        .serve(router(shared).into_make_service())
                        .await
                }
                Err(e) => Err(e),
            }
        }
    };
    drop(actions_tx);
    station_task.abort();
    requests_task.abort();
    link_task.abort();
    served.map_err(DaemonError::Serve)
}

/// The station loop's inputs and outputs.
struct StationLoop {
    shared: Arc<Shared>,
    actions: mpsc::Sender<Action<GroundEndpoint>>,
    events: mpsc::Receiver<DriverEvent<GroundEvent>>,
    refusals: mpsc::Receiver<Refusal>,
    refusals_tx: mpsc::Sender<Refusal>,
    stats_tx: mpsc::Sender<stx_link::endpoint::LinkStats>,
    stats_rx: mpsc::Receiver<stx_link::endpoint::LinkStats>,
    stop: watch::Receiver<bool>,
}

/// Events in, `state` out: a `state` follows each burst of telemetry within [`COALESCE`],
/// and the 4 Hz timer fills the gaps so pages see the link go stale when nothing arrives.
async fn station_loop(mut io: StationLoop) {
    let shared = io.shared.clone();
    let mut state_timer = tokio::time::interval(STATE_PERIOD);
    let mut stats_timer = tokio::time::interval(STATS_PERIOD);
    let mut manual_timer = tokio::time::interval(Duration::from_millis(100));
    let mut prediction_timer = tokio::time::interval(PREDICTION_PERIOD);
    let (prediction_tx, mut prediction_rx) = mpsc::channel(1);
    let mut predicting = false;
    let mut manual_active = false;
    let mut burst_deadline: Option<tokio::time::Instant> = None;
    let mut last_state = tokio::time::Instant::now();
    loop {
        let burst_due = async {
            match burst_deadline {
                Some(deadline) => tokio::time::sleep_until(deadline).await,
                None => std::future::pending().await,
            }
        };
        tokio::select! {
            event = io.events.recv() => {
                let Some(event) = event else { break };
                if handle_driver_event(&shared, &io.actions, event).await && burst_deadline.is_none() {
                    burst_deadline = Some(tokio::time::Instant::now() + COALESCE);
                }
            }
            () = burst_due => {
                burst_deadline = None;
                last_state = tokio::time::Instant::now();
                publish(&shared, true);
            }
            Some(refusal) = io.refusals.recv() => {
                let now = shared.now_s();
                match refusal {
                    Refusal::Request { request_id, reason } => {
                        lock(&shared).refuse(now, &request_id, reason);
                        publish(&shared, false);
                    }
                    Refusal::UploadBusy { request_id, items, tries, reason } => {
                        if tries >= UPLOAD_TRIES {
                            lock(&shared).refuse(now, &request_id, reason);
                            publish(&shared, false);
                        } else {
                            let actions = io.actions.clone();
                            let refusals = io.refusals_tx.clone();
                            tokio::spawn(async move {
                                tokio::time::sleep(UPLOAD_RETRY).await;
                                let retry = apply_action_try(
                                    Some(request_id),
                                    LinkAction::PlanUpload(items),
                                    refusals,
                                    tries + 1,
                                );
                                let _ = actions.send(retry).await;
                            });
                        }
                    }
                    Refusal::PlanDownload { reason } => {
                        lock(&shared).plan_download_refused(now, &reason);
                    }
                }
            }
            Some(stats) = io.stats_rx.recv() => {
                let now = shared.now_s();
                lock(&shared).set_link_stats(now, stats);
            }
            Some(prediction) = prediction_rx.recv() => {
                predicting = false;
                lock(&shared).set_prediction(prediction);
            }
            _ = prediction_timer.tick() => {
                let job = if predicting { None } else { lock(&shared).prediction_job() };
                if let Some(job) = job {
                    predicting = true;
                    let tx = prediction_tx.clone();
                    tokio::task::spawn_blocking(move || {
                        let _ = tx.blocking_send(job.run());
                    });
                }
            }
            _ = stats_timer.tick() => {
                let tx = io.stats_tx.clone();
                let _ = io.actions.send(Box::new(move |ep: &mut GroundEndpoint, now| {
                    let _ = tx.try_send(ep.link_stats(now));
                })).await;
            }
            _ = manual_timer.tick() => {
                let now = shared.now_s();
                let last = shared.manual.lock().unwrap_or_else(|e| e.into_inner()).last_s;
                let fresh = last.is_some_and(|t| now - t <= MANUAL_SILENCE_S);
                if manual_active && !fresh {
                    let _ = io.actions.send(Box::new(|ep: &mut GroundEndpoint, _| ep.manual_release())).await;
                }
                manual_active = fresh;
            }
            _ = state_timer.tick() => {
                if last_state.elapsed() >= STATE_PERIOD {
                    last_state = tokio::time::Instant::now();
                    publish(&shared, true);
                }
            }
            _ = io.stop.changed() => break,
        }
        // What the core decided to do on the link on its own (read the drone's plan).
        let now = shared.now_s();
        let own = lock(&shared).take_link_actions(now);
        for action in own {
            let _ = io
                .actions
                .send(apply_action(None, action, io.refusals_tx.clone()))
                .await;
        }
    }
}

/// Hands one driver event to the core; true if it was telemetry (a `state` is due).
async fn handle_driver_event(
    shared: &Shared,
    actions: &mpsc::Sender<Action<GroundEndpoint>>,
    event: DriverEvent<GroundEvent>,
) -> bool {
    let now = shared.now_s();
    match event {
        DriverEvent::Endpoint(e) => {
            let telemetry = matches!(e, GroundEvent::Telemetry { .. });
            let connected = matches!(e, GroundEvent::Link(LinkEvent::Connected { .. }));
            lock(shared).on_link_event(now, e);
            if connected {
                // Fetch the drone's parameter table whenever it (re)appears.
                let fetch: Action<GroundEndpoint> = Box::new(|ep, now| {
                    if let Err(e) = ep.param_list(now) {
                        tracing::warn!(error = %e, "parameter list not requested");
                    }
                });
                let _ = actions.send(fetch).await;
            }
            if !telemetry {
                // Command results, parameters and events go out at once.
                let outbound = lock(shared).drain_outbound();
                send_outbound(shared, outbound);
            }
            telemetry
        }
        DriverEvent::Io { path, event } => {
            lock(shared).on_io_event(now, path, event);
            false
        }
    }
}

/// Sends what the core queued and, with `with_state`, a fresh `state`.
fn publish(shared: &Shared, with_state: bool) {
    let now = shared.now_s();
    let (state, outbound) = {
        let mut core = lock(shared);
        let state = with_state.then(|| core.tick(now));
        (state, core.drain_outbound())
    };
    send_outbound(shared, outbound);
    if let Some(state) = state
        && let Ok(text) = serde_json::to_string(&state)
    {
        // Latest wins: a page that is behind gets the newest state, never a queue of old ones.
        shared.states.send_modify(|frame| {
            frame.seq += 1;
            frame.text = text.into();
        });
    }
}

fn send_outbound(shared: &Shared, outbound: Vec<Outbound>) {
    for o in outbound {
        let text = match o {
            Outbound::Event(e) => serde_json::to_string(&e),
            Outbound::CommandResult(r) => serde_json::to_string(&r),
            Outbound::Params(p) => serde_json::to_string(&p),
        };
        if let Ok(text) = text {
            shared
                .broadcast_total
                .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            // No page connected is not an error.
            let _ = shared.broadcast.send(text.into());
        }
    }
}

fn lock(shared: &Shared) -> std::sync::MutexGuard<'_, StationCore> {
    shared.core.lock().unwrap_or_else(|e| e.into_inner())
}
