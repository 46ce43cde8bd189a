//! `stx bench station`: the station's latencies on loopback, measured from outside the way a
//! drone and the operators' pages see them.
//!
//! - telemetry: the simulated drone (`stx_sim::runner`, as `stx drone` flies it) flies the
//!   built-in `rehearsal` — under the parafoil, a spiral landing on a target it holds in its
//!   plan — on the station's link, one control period per burst at the frame rate asked (4 Hz
//!   is real time): every period GPS_RAW_INT, SCALED_PRESSURE, ATTITUDE, GLOBAL_POSITION_INT,
//!   VFR_HUD and SERVO_OUTPUT_RAW, every second WIND_COV, NAV_CONTROLLER_OUTPUT, SYS_STATUS and
//!   BATTERY_STATUS, every two seconds its predicted landing, heartbeats at 1 Hz from its link.
//!   So the station's whole per-frame pipeline runs (estimator, guidance replica, plan read
//!   back, landing prediction) and each `state` is as large as in flight. Each period's
//!   ATTITUDE carries its own `time_boot_ms` (the AHRS sample's mission time); N WebSocket
//!   pages each time the first `state` that carries it. The figure is the end of the drone's
//!   step (its frames queued for the socket, which the link's driver sends next) → page
//!   receive, so it bounds the station's frame-received → message-sent latency from above (it
//!   adds the loopback and the page's own reading). The rehearsal flies about five minutes of
//!   mission time: the telemetry window must end before it lands.
//! - commands: HTTP requests on a kept-alive connection, timed from the request's first byte
//!   to the drone's link reporting the COMMAND_LONG (executed and answered, microseconds after
//!   its bytes arrived), while telemetry keeps flowing and the pages stay connected.
//!
//! The station runs in this process on its own runtime; pages and drone run on another.

use std::collections::HashMap;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use futures_util::{SinkExt, StreamExt};
use serde::Serialize;
use stx_gnc::stats::percentile;
use stx_link_tokio::DriverEvent;
use stx_sim::drone::MissionConfig;
use stx_sim::drone::link::DroneEvent;
use stx_sim::guided::CONTROL_PERIOD_S;
use stx_sim::runner::{FlightObserver, FlyOptions, Speed, StepReport};
use stx_station::config::{DEFAULT_STATION_TOML, Role, StationConfig};
use tokio::sync::{mpsc, oneshot};
use tokio_tungstenite::tungstenite::Message;

/// What to measure.
pub struct StationBenchOptions {
    /// WebSocket pages connected during the telemetry measurement.
    pub clients: usize,
    /// Telemetry bursts timed (one per control period).
    pub frames: usize,
    /// Bursts per second (the drone's control rate, 4 Hz).
    pub frame_rate_hz: f64,
    /// Commands sent.
    pub commands: usize,
    /// Record the run into this directory (the station's recording on), else not.
    pub record_dir: Option<std::path::PathBuf>,
    /// Flood the station from other addresses while telemetry is timed ([`crate::abuse`]).
    pub abuse: bool,
    /// Keep Lab Monte Carlo batches of this many runs going while telemetry is timed
    /// ([`crate::lab_load`]).
    pub lab_montecarlo: Option<u32>,
}

/// Latency distribution, ms (nearest-rank percentiles, `stx_gnc::stats::percentile`).
#[derive(Debug, Serialize)]
pub struct Latency {
    pub samples: usize,
    pub p50_ms: f64,
    pub p99_ms: f64,
    pub max_ms: f64,
}

impl Latency {
    pub(crate) fn of(mut samples_ms: Vec<f64>) -> Self {
        samples_ms.sort_by(f64::total_cmp);
        let at = |q: f64| percentile(&samples_ms, q);
        Latency {
            samples: samples_ms.len(),
            p50_ms: at(0.5),
            p99_ms: at(0.99),
            max_ms: at(1.0),
        }
    }
}

#[derive(Debug, Serialize)]
pub struct TelemetryReport {
    pub clients: usize,
    pub frames_sent: usize,
    pub frame_rate_hz: f64,
    /// Size of the `state` message at the end, bytes.
    pub state_bytes: usize,
    /// Frames some page never saw in a `state` (each page, each frame).
    pub missed: usize,
    /// Drone socket send → page receive of the `state` carrying the frame.
    pub latency: Latency,
}

#[derive(Debug, Serialize)]
pub struct CommandReport {
    pub commands_sent: usize,
    /// Commands whose bytes never reached the drone.
    pub lost: usize,
    /// HTTP request written → COMMAND_LONG received by the drone.
    pub latency: Latency,
}

#[derive(Debug, Serialize)]
pub struct StationReport {
    pub telemetry_to_websocket: TelemetryReport,
    pub command_to_mavlink: CommandReport,
    /// The station's recording at the end (`off` without `--record-dir`).
    pub recording: stx_station::messages::RecordingView,
    /// The flood during the telemetry window, with `--abuse`.
    pub abuse: Option<crate::abuse::AbuseReport>,
    /// The Lab batches during the telemetry window, with `--lab-montecarlo`.
    pub lab: Option<crate::lab_load::LabLoadReport>,
}

/// The report as `stx bench station` prints it without `--json`: a line a figure.
impl std::fmt::Display for StationReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let t = &self.telemetry_to_websocket;
        let c = &self.command_to_mavlink;
        writeln!(
            f,
            "telemetry → WebSocket, {} pages, {} bursts at {} Hz, state {} bytes: p50 {:.2} ms, p99 {:.2} ms, max {:.2} ms ({} samples, {} missed)",
            t.clients,
            t.frames_sent,
            t.frame_rate_hz,
            t.state_bytes,
            t.latency.p50_ms,
            t.latency.p99_ms,
            t.latency.max_ms,
            t.latency.samples,
            t.missed
        )?;
        writeln!(
            f,
            "command → MAVLink bytes, {} commands: p50 {:.2} ms, p99 {:.2} ms, max {:.2} ms ({} lost)",
            c.commands_sent, c.latency.p50_ms, c.latency.p99_ms, c.latency.max_ms, c.lost
        )?;
        if let Some(a) = &self.abuse {
            writeln!(
                f,
                "flood during it: {} wrong-token requests ({} answered 429, {} 401, {} other), {} WebSockets tried ({} opened and closed); process RSS {:.1} MB before, {:.1} MB after",
                a.bad_token_requests,
                a.answered_429,
                a.answered_401,
                a.other,
                a.websockets_tried,
                a.websockets_opened,
                a.rss_before_mb,
                a.rss_after_mb
            )?;
        }
        if let Some(l) = &self.lab {
            writeln!(
                f,
                "Lab Monte Carlo during it: {} batch{} of {} runs started back to back ({} ended on their own), {} runs flown; the Lab busy {:.1} % of the window (longest gap {:.0} ms)",
                l.batches,
                if l.batches == 1 { "" } else { "es" },
                l.runs_per_batch,
                l.batches_finished,
                l.runs_flown,
                l.busy_fraction * 100.0,
                l.longest_idle_ms
            )?;
        }
        let r = &self.recording;
        writeln!(
            f,
            "recording: {:?}, {} messages ({:.2} MB) written, {} lost{}",
            r.state,
            r.messages_written,
            r.bytes_written as f64 / 1e6,
            r.messages_lost,
            r.problem
                .as_deref()
                .map(|p| format!(" (last problem: {p})"))
                .unwrap_or_default()
        )
    }
}

/// Starts the station on its own runtime; returns its addresses and the stop switch.
fn start_station(
    record_dir: Option<std::path::PathBuf>,
) -> anyhow::Result<(stx_station::daemon::Running, String, oneshot::Sender<()>)> {
    let mut config =
        StationConfig::from_toml_str(DEFAULT_STATION_TOML).context("shipped station config")?;
    config.recording.enabled = record_dir.is_some();
    config.recording.dir = record_dir;
    config.listen = "127.0.0.1:0".parse()?;
    config.link.address = "udpin:127.0.0.1:0".into();
    config.web_dir = std::env::temp_dir().join("stx-bench-no-dashboard");
    let operator = config
        .operator_token()
        .context("the station config has no operator token")?
        .to_owned();
    let (stop_tx, stop_rx) = oneshot::channel::<()>();
    let (started_tx, started_rx) = std::sync::mpsc::channel();
    std::thread::Builder::new()
        .name("station".into())
        .spawn(move || {
            let runtime = match tokio::runtime::Builder::new_multi_thread()
                .worker_threads(2)
                .enable_all()
                .build()
            {
                Ok(r) => r,
                Err(e) => {
                    tracing::error!(error = %e, "station runtime");
                    return;
                }
            };
            let shutdown = async move {
                let _ = stop_rx.await;
            };
            let result = runtime.block_on(stx_station::daemon::run(config, shutdown, move |r| {
                let _ = started_tx.send(r);
            }));
            if let Err(e) = result {
                tracing::error!(error = %e, "station stopped");
            }
        })
        .context("station thread")?;
    let running = started_rx
        .recv_timeout(Duration::from_secs(10))
        .context("the station did not start")?;
    Ok((running, operator, stop_tx))
}

/// What the benchmark reads of the drone's flight: when each ATTITUDE stamp left, when each
/// command arrived, whether it landed.
#[derive(Clone)]
pub(crate) struct Clocks {
    pub sent_at: Arc<Mutex<HashMap<u32, Instant>>>,
    pub commands: mpsc::UnboundedSender<Instant>,
    pub landed: Arc<AtomicBool>,
}

impl FlightObserver for Clocks {
    fn step(&mut self, report: &StepReport) {
        if let Some(stamp) = report.attitude_time_boot_ms {
            self.sent_at
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .entry(stamp)
                .or_insert(report.finished_at);
        }
        if report.landed {
            self.landed.store(true, Ordering::Relaxed);
        }
    }

    fn event(&mut self, event: &DriverEvent<DroneEvent>) {
        if let DriverEvent::Endpoint(DroneEvent::Command { .. }) = event {
            let _ = self.commands.send(Instant::now());
        }
    }
}

/// A page: records when each attitude stamp first arrives in a `state`, and acknowledges each
/// state as the dashboard does (`state_acks`), so the figure includes the station's holding a
/// state back until the page is ready for it.
pub(crate) async fn page(
    http: SocketAddr,
    token: String,
    seen: Arc<Mutex<HashMap<u32, Instant>>>,
    ready: oneshot::Sender<()>,
) -> anyhow::Result<()> {
    let (mut ws, _) = tokio_tungstenite::connect_async(format!(
        "ws://{http}/api/ws?token={token}&state_acks=true"
    ))
    .await
    .context("WebSocket")?;
    let _ = ready.send(());
    while let Some(message) = ws.next().await {
        let Message::Text(text) = message? else {
            continue;
        };
        let arrived = Instant::now();
        if !text.as_str().starts_with(STATE_PREFIX) {
            continue;
        }
        if let Some(stamp) = attitude_stamp(text.as_str()) {
            let mut seen = seen.lock().unwrap_or_else(|e| e.into_inner());
            seen.entry(stamp).or_insert(arrived);
        }
        ws.send(Message::Text(r#"{"type":"state_ack"}"#.into()))
            .await
            .context("acknowledging a state")?;
    }
    Ok(())
}

/// Each page's delay from a burst sent within `window` to the first `state` carrying it, ms;
/// the bursts some page never saw; and how many bursts were sent in the window.
pub(crate) fn page_latencies(
    sent_at: &Mutex<HashMap<u32, Instant>>,
    seen_by_page: &[Arc<Mutex<HashMap<u32, Instant>>>],
    window: std::ops::RangeInclusive<Instant>,
) -> (Vec<f64>, usize, usize) {
    let timed: Vec<(u32, Instant)> = sent_at
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .iter()
        .filter(|(_, at)| window.contains(*at))
        .map(|(s, at)| (*s, *at))
        .collect();
    let mut samples = Vec::new();
    let mut missed = 0;
    for seen in seen_by_page {
        let seen = seen.lock().unwrap_or_else(|e| e.into_inner());
        for (stamp, sent) in &timed {
            match seen.get(stamp) {
                Some(arrived) => {
                    samples.push(arrived.saturating_duration_since(*sent).as_secs_f64() * 1e3)
                }
                None => missed += 1,
            }
        }
    }
    (samples, missed, timed.len())
}

/// How a `state` message starts (the station writes `type` first).
const STATE_PREFIX: &str = r#"{"type":"state""#;

/// The attitude stamp of a `state` message. A page of the benchmark reads only this, so that
/// fifty pages in one process do not spend more time parsing than the station spends sending.
fn attitude_stamp(text: &str) -> Option<u32> {
    const KEY: &str = r#""attitude":{"time_boot_ms":"#;
    if !text.starts_with(STATE_PREFIX) {
        return None;
    }
    let at = text.find(KEY)? + KEY.len();
    let digits: String = text[at..]
        .chars()
        .take_while(char::is_ascii_digit)
        .collect();
    digits.parse().ok()
}

/// The size of the station's `state` now, and what of the pipeline did not run (empty when
/// the estimate, the guidance pattern, the station's and the drone's predictions are there).
fn station_view(running: &stx_station::daemon::Running) -> (usize, String) {
    let state = {
        let core = running
            .shared
            .core
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        core.state_msg_now(running.shared.now_s())
    };
    let bytes = serde_json::to_string(&state).map_or(0, |s| s.len());
    let mut missing = Vec::new();
    if state.estimate.is_none() {
        missing.push("estimate");
    }
    if state
        .guidance
        .as_ref()
        .and_then(|g| g.pattern.as_ref())
        .is_none()
    {
        missing.push("guidance pattern");
    }
    if state
        .prediction
        .as_ref()
        .and_then(|p| p.planned.as_ref())
        .is_none()
    {
        missing.push("planned prediction");
    }
    if state
        .vehicle
        .as_ref()
        .and_then(|v| v.predicted_landing.as_ref())
        .is_none()
    {
        missing.push("drone's prediction");
    }
    (bytes, missing.join(", "))
}

pub fn run(options: &StationBenchOptions) -> anyhow::Result<StationReport> {
    if options.clients == 0
        || options.frames == 0
        || !(options.frame_rate_hz > 0.0 && options.frame_rate_hz <= 100.0)
    {
        bail!("clients, frames and frame rate must be positive");
    }
    let (running, token, stop_station) = start_station(options.record_dir.clone())?;
    let shared = running.shared.clone();
    let link = running
        .link_local
        .context("the station's link has no local address")?;
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()?;
    let report = runtime.block_on(async {
        let (commands_tx, mut commands_rx) = mpsc::unbounded_channel();
        let sent_at = Arc::new(Mutex::new(HashMap::new()));
        // Pages connect before the drone starts, so they see every burst.
        let mut pages = Vec::new();
        let mut seen_by_page = Vec::new();
        for _ in 0..options.clients {
            let seen = Arc::new(Mutex::new(HashMap::new()));
            let (ready_tx, ready_rx) = oneshot::channel();
            pages.push(tokio::spawn(page(
                running.http,
                token.clone(),
                seen.clone(),
                ready_tx,
            )));
            ready_rx.await.context("a page could not connect")?;
            seen_by_page.push(seen);
        }
        let (stop_drone, stop_rx) = oneshot::channel::<()>();
        let mut drone = FlyOptions::new(
            &format!("udpout:{link}"),
            MissionConfig::builtin("rehearsal").context("the built-in rehearsal")?,
        );
        // One control period per burst.
        drone.speed = Speed::Times(options.frame_rate_hz * CONTROL_PERIOD_S);
        drone.linger = None;
        let landed = Arc::new(AtomicBool::new(false));
        let clocks = Clocks {
            sent_at: sent_at.clone(),
            commands: commands_tx,
            landed: landed.clone(),
        };
        let drone_task = tokio::spawn(stx_sim::runner::fly(
            drone,
            async move {
                let _ = stop_rx.await;
            },
            clocks,
        ));
        // The first seconds (link up, plan read back, estimator converging) are not timed.
        tokio::time::sleep(Duration::from_secs(5)).await;
        let flood = if options.abuse {
            let viewer = running
                .shared
                .config
                .tokens
                .iter()
                .find(|t| t.role == Role::Viewer)
                .map(|t| t.token.clone())
                .context("the station config has no viewer token")?;
            Some(crate::abuse::Flood::start(running.http, viewer)?)
        } else {
            None
        };
        let lab = match options.lab_montecarlo {
            Some(runs) => Some(crate::lab_load::LabLoad::start(&running, &token, runs).await?),
            None => None,
        };
        let timed_from = Instant::now();
        let window = Duration::from_secs_f64(options.frames as f64 / options.frame_rate_hz);
        tokio::time::sleep(window).await;
        let timed_to = Instant::now();
        let abuse = match flood {
            Some(f) => Some(f.stop().await?),
            None => None,
        };
        let lab = match lab {
            Some(l) => Some(l.stop(timed_from, timed_to).await?),
            None => None,
        };
        if landed.load(Ordering::Relaxed) {
            bail!("the drone landed before the telemetry window ended: time fewer frames");
        }
        tokio::time::sleep(Duration::from_millis(500)).await;
        let (samples, missed, frames_sent) =
            page_latencies(&sent_at, &seen_by_page, timed_from..=timed_to);
        let (state_bytes, not_run) = station_view(&running);
        if !not_run.is_empty() {
            bail!("the station's pipeline did not run on the telemetry: no {not_run}");
        }
        let telemetry = TelemetryReport {
            clients: options.clients,
            frames_sent,
            frame_rate_hz: options.frame_rate_hz,
            state_bytes,
            missed,
            latency: Latency::of(samples),
        };

        // Commands while telemetry flows and the pages read.
        let stream = tokio::net::TcpStream::connect(running.http).await?;
        let (mut sender, connection) =
            hyper::client::conn::http1::handshake(hyper_util::rt::TokioIo::new(stream)).await?;
        tokio::spawn(connection);
        let mut samples = Vec::new();
        let mut lost = 0;
        for k in 0..options.commands {
            while commands_rx.try_recv().is_ok() {}
            // A new heading each time, so the drone never takes it for a retry.
            let body = format!(r#"{{"heading_deg":{}}}"#, (k % 3600) as f64 * 0.1);
            let started = Instant::now();
            let status = crate::http::post(
                &mut sender,
                running.http,
                "/api/commands/heading",
                &token,
                body,
            )
            .await?;
            if status != 202 {
                bail!("the station answered {status} to a heading command");
            }
            match tokio::time::timeout(Duration::from_secs(2), commands_rx.recv()).await {
                Ok(Some(arrived)) => {
                    samples.push(arrived.saturating_duration_since(started).as_secs_f64() * 1e3)
                }
                _ => lost += 1,
            }
            // Let the ACK travel back so the next command is not queued behind this one.
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
        for p in &pages {
            p.abort();
        }
        let _ = stop_drone.send(());
        drone_task
            .await
            .context("the drone's task")?
            .context("the simulated drone")?;
        anyhow::Ok(StationReport {
            telemetry_to_websocket: telemetry,
            command_to_mavlink: CommandReport {
                commands_sent: options.commands,
                lost,
                latency: Latency::of(samples),
            },
            recording: shared.recording.view(),
            abuse,
            lab,
        })
    });
    let _ = stop_station.send(());
    report
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stamp_is_read_from_states_only() {
        let state = r#"{"type":"state","vehicle":{"predicted_landing":{"time_boot_ms":7},"attitude":{"time_boot_ms":1000030,"roll_deg":0}}}"#;
        assert_eq!(attitude_stamp(state), Some(1_000_030));
        assert_eq!(attitude_stamp(r#"{"type":"event","time_boot_ms":5}"#), None);
        assert_eq!(attitude_stamp(r#"{"type":"state","vehicle":null}"#), None);
    }

    #[test]
    fn percentiles_come_from_the_sorted_samples() {
        let l = Latency::of((1..=100).rev().map(f64::from).collect());
        assert_eq!(
            (l.p50_ms, l.p99_ms, l.max_ms, l.samples),
            (50.0, 99.0, 100.0, 100)
        );
    }
}
