//! `stx bench station`: the station's latencies on loopback, measured from outside the way a
//! drone and the operators' pages see them.
//!
//! - telemetry: a scripted drone sends ATTITUDE frames, each with its own `time_boot_ms`; N
//!   WebSocket pages each time the first `state` that carries it. The figure is drone socket
//!   send → page receive, so it bounds the station's frame-received → message-sent latency
//!   from above (it adds the loopback and the page's own reading).
//! - commands: HTTP requests on a kept-alive connection, timed from the request's first byte
//!   to the COMMAND_LONG arriving at the drone's socket.
//!
//! The station runs in this process on its own runtime; pages and drone run on another.

use std::collections::HashMap;
use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use futures_util::StreamExt;
use http_body_util::{BodyExt, Full};
use hyper::body::Bytes;
use serde::Serialize;
use stx_link::command::CommandResult;
use stx_link::endpoint::{LinkConfig, VehicleConfig, VehicleEndpoint, VehicleEvent};
use stx_link::telemetry::{Attitude, Telemetry};
use stx_station::config::{DEFAULT_STATION_TOML, Role, StationConfig};
use tokio::net::UdpSocket;
use tokio::sync::{mpsc, oneshot};
use tokio_tungstenite::tungstenite::Message;

/// What to measure.
pub struct StationBenchOptions {
    /// WebSocket pages connected during the telemetry measurement.
    pub clients: usize,
    /// ATTITUDE frames sent.
    pub frames: usize,
    /// Frames per second.
    pub frame_rate_hz: f64,
    /// Commands sent.
    pub commands: usize,
}

/// Latency distribution, ms.
#[derive(Debug, Serialize)]
pub struct Latency {
    pub samples: usize,
    pub p50_ms: f64,
    pub p99_ms: f64,
    pub max_ms: f64,
}

impl Latency {
    fn of(mut samples_ms: Vec<f64>) -> Self {
        samples_ms.sort_by(f64::total_cmp);
        let at = |q: f64| {
            if samples_ms.is_empty() {
                f64::NAN
            } else {
                samples_ms[((samples_ms.len() - 1) as f64 * q).round() as usize]
            }
        };
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
}

/// Starts the station on its own runtime; returns its addresses and the stop switch.
fn start_station() -> anyhow::Result<(stx_station::daemon::Running, String, oneshot::Sender<()>)> {
    let mut config =
        StationConfig::from_toml_str(DEFAULT_STATION_TOML).context("shipped station config")?;
    config.listen = "127.0.0.1:0".parse()?;
    config.link.address = "udpin:127.0.0.1:0".into();
    config.web_dir = std::env::temp_dir().join("stx-bench-no-dashboard");
    let operator = config
        .tokens
        .iter()
        .find(|t| t.role == Role::Operator)
        .map(|t| t.token.clone())
        .context("the station config has no operator token")?;
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

/// What the scripted drone does: send numbered attitudes, report command arrivals.
enum DroneOrder {
    Attitude {
        stamp: u32,
        sent: oneshot::Sender<Instant>,
    },
}

/// The scripted drone: a VehicleEndpoint on a UDP socket, answering every command.
async fn drone(
    station_link: SocketAddr,
    mut orders: mpsc::Receiver<DroneOrder>,
    commands: mpsc::UnboundedSender<Instant>,
) -> anyhow::Result<()> {
    let socket = UdpSocket::bind("127.0.0.1:0").await?;
    socket.connect(station_link).await?;
    let start = Instant::now();
    let mut endpoint = VehicleEndpoint::new(
        VehicleConfig {
            link: LinkConfig::vehicle(),
            ..Default::default()
        },
        Duration::ZERO,
    )?;
    let mut buf = vec![0_u8; 2048];
    loop {
        let now = start.elapsed();
        while let Some(bytes) = endpoint.poll_transmit(now) {
            socket.send(&bytes).await?;
        }
        let timer = endpoint
            .poll_timeout()
            .map_or(Duration::from_millis(100), |t| t.saturating_sub(now));
        tokio::select! {
            received = socket.recv(&mut buf) => {
                let n = received?;
                let arrived = Instant::now();
                endpoint.handle_bytes(start.elapsed(), &buf[..n]);
                while let Some(event) = endpoint.poll_event() {
                    if let VehicleEvent::Command(c) = event {
                        let _ = commands.send(arrived);
                        endpoint.respond_command(c.id, CommandResult::Accepted);
                    }
                }
            }
            order = orders.recv() => match order {
                None => return Ok(()),
                Some(DroneOrder::Attitude { stamp, sent }) => {
                    endpoint.send_telemetry(start.elapsed(), &Telemetry::Attitude(Attitude {
                        time_boot_ms: stamp,
                        roll_rad: 0.0,
                        pitch_rad: 0.0,
                        yaw_rad: 0.0,
                        roll_rate_radps: 0.0,
                        pitch_rate_radps: 0.0,
                        yaw_rate_radps: 0.0,
                    }));
                    while let Some(bytes) = endpoint.poll_transmit(start.elapsed()) {
                        socket.send(&bytes).await?;
                    }
                    let _ = sent.send(Instant::now());
                }
            },
            () = tokio::time::sleep(timer) => endpoint.handle_timeout(start.elapsed()),
        }
    }
}

/// A page: records when each attitude stamp first arrives in a `state`.
async fn page(
    http: SocketAddr,
    token: String,
    seen: Arc<Mutex<HashMap<u32, Instant>>>,
    ready: oneshot::Sender<()>,
) -> anyhow::Result<()> {
    let (mut ws, _) = tokio_tungstenite::connect_async(format!("ws://{http}/api/ws?token={token}"))
        .await
        .context("WebSocket")?;
    let _ = ready.send(());
    while let Some(message) = ws.next().await {
        let Message::Text(text) = message? else {
            continue;
        };
        let arrived = Instant::now();
        if let Some(stamp) = attitude_stamp(text.as_str()) {
            let mut seen = seen.lock().unwrap_or_else(|e| e.into_inner());
            seen.entry(stamp).or_insert(arrived);
        }
    }
    Ok(())
}

/// The attitude stamp of a `state` message. A page of the benchmark reads only this, so that
/// fifty pages in one process do not spend more time parsing than the station spends sending.
fn attitude_stamp(text: &str) -> Option<u32> {
    if !text.starts_with(r#"{"type":"state""#) {
        return None;
    }
    let at = text.find(r#""time_boot_ms":"#)? + r#""time_boot_ms":"#.len();
    let digits: String = text[at..]
        .chars()
        .take_while(char::is_ascii_digit)
        .collect();
    digits.parse().ok()
}

/// One HTTP/1.1 POST on the kept-alive connection; the status.
async fn post(
    sender: &mut hyper::client::conn::http1::SendRequest<Full<Bytes>>,
    http: SocketAddr,
    path: &str,
    token: &str,
    body: String,
) -> anyhow::Result<u16> {
    let request = hyper::Request::post(format!("http://{http}{path}"))
        .header("authorization", format!("Bearer {token}"))
        .header("content-type", "application/json")
        .header("host", http.to_string())
        .body(Full::new(Bytes::from(body)))?;
    let response = sender.send_request(request).await?;
    let status = response.status().as_u16();
    response.into_body().collect().await?;
    Ok(status)
}

pub fn run(options: &StationBenchOptions) -> anyhow::Result<StationReport> {
    if options.clients == 0 || options.frames == 0 || options.frame_rate_hz <= 0.0 {
        bail!("clients, frames and frame rate must be positive");
    }
    let (running, token, stop_station) = start_station()?;
    let link = running
        .link_local
        .context("the station's link has no local address")?;
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()?;
    let report = runtime.block_on(async {
        let (orders_tx, orders_rx) = mpsc::channel(16);
        let (commands_tx, mut commands_rx) = mpsc::unbounded_channel();
        let drone_task = tokio::spawn(drone(link, orders_rx, commands_tx));
        // Pages connect, and the station hears the drone, before timing starts.
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
        tokio::time::sleep(Duration::from_millis(1500)).await;

        let period = Duration::from_secs_f64(1.0 / options.frame_rate_hz);
        let mut sent_at = HashMap::new();
        let mut ticker = tokio::time::interval(period);
        for k in 0..options.frames {
            ticker.tick().await;
            let stamp = 1_000_000 + k as u32 * 10;
            let (sent_tx, sent_rx) = oneshot::channel();
            orders_tx
                .send(DroneOrder::Attitude {
                    stamp,
                    sent: sent_tx,
                })
                .await
                .context("the drone stopped")?;
            sent_at.insert(stamp, sent_rx.await.context("the drone stopped")?);
        }
        tokio::time::sleep(Duration::from_millis(500)).await;
        let mut samples = Vec::new();
        let mut missed = 0;
        for seen in &seen_by_page {
            let seen = seen.lock().unwrap_or_else(|e| e.into_inner());
            for (stamp, sent) in &sent_at {
                match seen.get(stamp) {
                    Some(arrived) => {
                        samples.push(arrived.saturating_duration_since(*sent).as_secs_f64() * 1e3)
                    }
                    None => missed += 1,
                }
            }
        }
        let telemetry = TelemetryReport {
            clients: options.clients,
            frames_sent: options.frames,
            frame_rate_hz: options.frame_rate_hz,
            missed,
            latency: Latency::of(samples),
        };
        for p in &pages {
            p.abort();
        }

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
            let status = post(
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
        drop(orders_tx);
        let _ = drone_task.await;
        anyhow::Ok(StationReport {
            telemetry_to_websocket: telemetry,
            command_to_mavlink: CommandReport {
                commands_sent: options.commands,
                lost,
                latency: Latency::of(samples),
            },
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
        let state =
            r#"{"type":"state","vehicle":{"attitude":{"time_boot_ms":1000030,"roll_deg":0}}}"#;
        assert_eq!(attitude_stamp(state), Some(1_000_030));
        assert_eq!(attitude_stamp(r#"{"type":"event","time_boot_ms":5}"#), None);
        assert_eq!(attitude_stamp(r#"{"type":"state","vehicle":null}"#), None);
    }

    #[test]
    fn percentiles_come_from_the_sorted_samples() {
        let l = Latency::of((1..=100).rev().map(f64::from).collect());
        assert_eq!(
            (l.p50_ms, l.p99_ms, l.max_ms, l.samples),
            (51.0, 99.0, 100.0, 100)
        );
    }
}
