//! The daemon's tokio wiring: the link task (stx-link's driver over the configured transport),
//! the station loop (events in, state out at 4 Hz), the joystick watchdog, and the HTTP server,
//! all stopped together by one shutdown signal.

use std::future::Future;
use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use axum::extract::ws::Utf8Bytes;
use stx_link::endpoint::{GroundConfig, GroundEndpoint, GroundEvent, LinkEvent};
use stx_link::signing::SigningConfig;
use stx_link::transport::{Action, DriveOptions, DriverEvent, Transport, drive};
use thiserror::Error;
use tokio::sync::{broadcast, mpsc, watch};

use crate::config::StationConfig;
use crate::core::{LinkAction, Outbound, StationCore};
use crate::http::{LinkRequest, ManualState, Shared, router};

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
        source: stx_link::transport::TransportError,
    },
    /// The signing key or its timestamp file is unusable.
    #[error("signing: {0}")]
    Signing(String),
    /// The HTTP server failed.
    #[error("HTTP server: {0}")]
    Serve(#[source] std::io::Error),
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

/// What a running daemon exposes to its starter (tests and `stx serve --sim`).
#[derive(Clone)]
pub struct Running {
    /// Where the dashboard and API listen.
    pub http: SocketAddr,
    /// The drone link's local socket address, for UDP and TCP servers (the port the drone
    /// must send to when the config asked for port 0).
    pub link_local: Option<SocketAddr>,
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
    let mut signing = SigningConfig::new(key, 0, unix_s);
    if let Some(path) = &config.link.signing_timestamp_file {
        let persisted = stx_link::transport::load_signing_timestamp(path)
            .map_err(|e| DaemonError::Signing(format!("{}: {e}", path.display())))?;
        signing = signing.with_persisted_timestamp(persisted);
    }
    Ok(Some(signing))
}

/// Starts the station; `started(running)` is called once it listens; returns when `shutdown`
/// resolves (or a task fails).
pub async fn run(
    config: StationConfig,
    shutdown: impl Future<Output = ()> + Send + 'static,
    started: impl FnOnce(Running) + Send,
) -> Result<(), DaemonError> {
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
    let transport = Transport::open_str(&config.link.address)
        .await
        .map_err(|source| DaemonError::Link {
            address: config.link.address.clone(),
            source,
        })?;
    let link_local = transport.local_addr();
    // For `udpin:…:0` / `tcpin:…:0`: the port the drone must be pointed at.
    let link_shown = transport
        .listening_address()
        .map_or_else(|| config.link.address.clone(), |a| a.to_string());
    let start = Instant::now();
    let mut ground = GroundConfig::default();
    ground.link = ground.link.with_signing(signing(&config)?);
    let endpoint = GroundEndpoint::new(ground, Duration::ZERO);
    // The first high-water mark is on disk before anything is signed, or the station does not
    // start.
    stx_link::transport::persist_signing_mark(
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
    let link_task = tokio::spawn(drive(transport, endpoint, actions_rx, events_tx, options));

    let wall_origin_ms = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_millis() as u64)
        .unwrap_or(0);
    let (requests_tx, mut requests_rx) = mpsc::channel::<LinkRequest>(1024);
    let (broadcast_tx, _) = broadcast::channel::<Utf8Bytes>(256);
    let shared = Arc::new(Shared {
        core: Mutex::new(StationCore::new(config.clone(), wall_origin_ms)),
        config: config.clone(),
        started: start,
        link: requests_tx,
        broadcast: broadcast_tx.clone(),
        manual: Mutex::new(ManualState::default()),
    });

    // Operators' requests → closures on the endpoint; refusals come back to the core.
    let (refusals_tx, refusals_rx) = mpsc::channel::<(String, String)>(256);
    let request_actions = actions_tx.clone();
    let mut stop = stop_rx.clone();
    let requests_task = tokio::spawn(async move {
        loop {
            let request = tokio::select! {
                r = requests_rx.recv() => match r { Some(r) => r, None => break },
                _ = stop.changed() => break,
            };
            let refusals = refusals_tx.clone();
            let action: Action<GroundEndpoint> = match request {
                LinkRequest::Action { request_id, action } => Box::new(move |ep, now| {
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
                        LinkAction::PlanUpload(items) => {
                            ep.plan_upload(now, items).map_err(|e| e.to_string())
                        }
                    };
                    if let Err(reason) = outcome {
                        let _ = refusals.try_send((request_id, reason));
                    }
                }),
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
        stats_tx,
        stats_rx,
        stop: stop_rx.clone(),
    }));

    started(Running {
        http: http_address,
        link_local,
        shared: shared.clone(),
    });
    tracing::info!(address = %http_address, link = %link_shown, "station listening");
    let stop_http = async move {
        shutdown.await;
        let _ = stop_tx.send(true);
    };
    let served = axum::serve(listener, router(shared))
        .with_graceful_shutdown(stop_http)
        .await;
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
    refusals: mpsc::Receiver<(String, String)>,
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
            Some((request_id, reason)) = io.refusals.recv() => {
                let now = shared.now_s();
                lock(&shared).refuse(now, &request_id, reason);
                publish(&shared, false);
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
        DriverEvent::Io(io) => {
            lock(shared).on_io_event(now, io);
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
        // No page connected is not an error.
        let _ = shared.broadcast.send(text.into());
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
            let _ = shared.broadcast.send(text.into());
        }
    }
}

fn lock(shared: &Shared) -> std::sync::MutexGuard<'_, StationCore> {
    shared.core.lock().unwrap_or_else(|e| e.into_inner())
}
