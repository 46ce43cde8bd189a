//! `stx bench station`: the station's latencies on loopback, measured from outside the way a
//! drone and the operators' pages see them.
//!
//! - telemetry: a scripted drone sends what the drone sends, at its rates ([`burst`]): every
//!   4 Hz control period GPS_RAW_INT, SCALED_PRESSURE, GLOBAL_POSITION_INT, VFR_HUD,
//!   SERVO_OUTPUT_RAW and ATTITUDE; every second WIND_COV, NAV_CONTROLLER_OUTPUT, SYS_STATUS,
//!   BATTERY_STATUS; every two seconds the predicted landing; heartbeats at 1 Hz from its link.
//!   It glides under the parafoil in spiral-landing mode towards a target it holds in its plan,
//!   so the station's whole per-frame pipeline runs (estimator, guidance replica, plan read
//!   back, landing prediction) and each `state` is as large as in flight. Each burst ends with
//!   an ATTITUDE carrying its own `time_boot_ms`; N WebSocket pages each time the first `state`
//!   that carries it. The figure is drone socket send → page receive, so it bounds the
//!   station's frame-received → message-sent latency from above (it adds the loopback and the
//!   page's own reading).
//! - commands: HTTP requests on a kept-alive connection, timed from the request's first byte
//!   to the COMMAND_LONG arriving at the drone's socket, while telemetry keeps flowing and the
//!   pages stay connected.
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
use nalgebra::Vector3;
use serde::Serialize;
use stx_dynamics::atmosphere::{Atmosphere, StandardAtmosphere};
use stx_gnc::geo::LocalFrame;
use stx_gnc::mission::{FlightMode, FlightStage, GuidancePhase};
use stx_link::command::CommandResult;
use stx_link::endpoint::{LinkConfig, VehicleConfig, VehicleEndpoint, VehicleEvent};
use stx_link::plan::PlanItem;
use stx_link::telemetry::{
    Actuators, AirData, Attitude, BatteryStatus, GlobalPosition, GpsFix, GpsRaw, GuidanceStatus,
    Hud, PredictedLanding, SystemState, SystemStatus, Telemetry, VehicleStatus, Wind,
};
use stx_station::config::{DEFAULT_STATION_TOML, Role, StationConfig};
use tokio::net::UdpSocket;
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

/// The scripted flight: from 1,200 m above the site, 2 km south-west of the target (the
/// site), gliding towards it at 6 m/s through the air, sinking 3 m/s, in a 2 m/s westerly.
struct Glide {
    frame: LocalFrame,
    target_ned_m: Vector3<f64>,
}

impl Glide {
    const START_NED_M: [f64; 3] = [-1400.0, -1400.0, -1200.0];
    const AIRSPEED_MPS: f64 = 6.0;
    const SINK_MPS: f64 = 3.0;
    const WIND_NE_MPS: [f64; 2] = [0.0, 2.0];

    fn new(frame: LocalFrame) -> Self {
        Self {
            frame,
            target_ned_m: Vector3::zeros(),
        }
    }

    /// The drone's plan: land on the target.
    fn plan(&self) -> Vec<PlanItem> {
        let (lat_deg, lon_deg, alt_msl_m) = self.frame.to_geodetic(&self.target_ned_m);
        vec![PlanItem::Land {
            lat_deg,
            lon_deg,
            alt_msl_m,
            approach_heading_deg: None,
        }]
    }

    fn heading_rad(&self) -> f64 {
        let to = self.target_ned_m - Vector3::from(Self::START_NED_M);
        to.y.atan2(to.x)
    }

    fn position_ned_m(&self, t: f64) -> Vector3<f64> {
        Vector3::from(Self::START_NED_M) + self.ground_velocity_ned_mps() * t
    }

    fn ground_velocity_ned_mps(&self) -> Vector3<f64> {
        let h = self.heading_rad();
        Vector3::new(
            Self::AIRSPEED_MPS * h.cos() + Self::WIND_NE_MPS[0],
            Self::AIRSPEED_MPS * h.sin() + Self::WIND_NE_MPS[1],
            Self::SINK_MPS,
        )
    }
}

/// The telemetry of control period `k` (at `rate_hz`), in the drone's order: the period's
/// other messages, then its ATTITUDE (stamped `stamp_ms`), so that a `state` carrying the
/// stamp has seen the whole burst.
fn burst(glide: &Glide, k: u64, rate_hz: f64, stamp_ms: u32) -> Vec<Telemetry> {
    let t = k as f64 / rate_hz;
    let p = glide.position_ned_m(t);
    let v = glide.ground_velocity_ned_mps();
    let (lat_deg, lon_deg, alt_msl_m) = glide.frame.to_geodetic(&p);
    let air = StandardAtmosphere.air_at(alt_msl_m);
    let airspeed = Glide::AIRSPEED_MPS.hypot(Glide::SINK_MPS);
    let heading = glide.heading_rad();
    let heading_deg = heading.to_degrees().rem_euclid(360.0);
    let ground_speed = v.x.hypot(v.y);
    let per_second = (rate_hz.round() as u64).max(1);
    let mut out = vec![
        Telemetry::GpsRaw(GpsRaw {
            time_usec: u64::from(stamp_ms) * 1000,
            fix: GpsFix::Fix3d,
            lat_deg,
            lon_deg,
            alt_msl_m,
            ground_speed_mps: Some(ground_speed),
            course_deg: Some(v.y.atan2(v.x).to_degrees().rem_euclid(360.0)),
            satellites: Some(11),
            h_acc_m: Some(1.5),
            v_acc_m: Some(3.0),
        }),
        Telemetry::AirData(AirData {
            time_boot_ms: stamp_ms,
            abs_pressure_pa: air.pressure_pa,
            diff_pressure_pa: 0.5 * air.density_kg_per_m3 * airspeed * airspeed,
            temperature_c: air.temperature_k - 273.15,
            diff_temperature_c: None,
        }),
        Telemetry::Position(GlobalPosition {
            time_boot_ms: stamp_ms,
            lat_deg,
            lon_deg,
            alt_msl_m,
            alt_rel_m: -p.z,
            v_north_mps: v.x,
            v_east_mps: v.y,
            v_down_mps: v.z,
            heading_deg: Some(heading_deg),
        }),
        Telemetry::Hud(Hud {
            airspeed_mps: airspeed,
            groundspeed_mps: ground_speed,
            heading_deg: heading_deg.round(),
            climb_mps: -v.z,
            alt_msl_m,
        }),
        Telemetry::Actuators(Actuators {
            time_usec: stamp_ms.wrapping_mul(1000),
            main_line: 0.05,
            brake_right: 0.0,
            brake_left: 0.0,
        }),
    ];
    if k.is_multiple_of(per_second) {
        let to = glide.target_ned_m - p;
        let bearing_deg = to.y.atan2(to.x).to_degrees().rem_euclid(360.0).round();
        out.extend([
            Telemetry::Wind(Wind {
                time_usec: u64::from(stamp_ms) * 1000,
                wind_north_mps: Some(Glide::WIND_NE_MPS[0]),
                wind_east_mps: Some(Glide::WIND_NE_MPS[1]),
                wind_down_mps: Some(0.0),
                var_horiz_mps: Some(0.3),
                var_vert_mps: Some(0.1),
                alt_msl_m: Some(alt_msl_m),
                horiz_accuracy_mps: 0.3,
                vert_accuracy_mps: 0.2,
            }),
            Telemetry::Guidance(GuidanceStatus {
                desired_roll_deg: 0.0,
                desired_heading_deg: bearing_deg,
                bearing_to_target_deg: bearing_deg,
                distance_to_target_m: to.xy().norm().round().min(65_535.0),
                alt_error_m: 0.0,
                xtrack_error_m: 0.0,
            }),
            Telemetry::System(SystemStatus {
                battery_voltage_v: Some(11.9),
                battery_current_a: Some(0.8),
                battery_remaining_pct: Some(78),
                load_pct: 12.0,
                comm_drop_rate_pct: 0.0,
                comm_errors: 0,
                sensors_present: 0xFF,
                sensors_enabled: 0xFF,
                sensors_health: 0xFF,
            }),
            Telemetry::Battery(BatteryStatus {
                id: 0,
                voltage_v: Some(11.9),
                current_a: Some(0.8),
                consumed_mah: Some(400),
                remaining_pct: Some(78),
                temperature_c: Some(15.0),
            }),
        ]);
    }
    if k.is_multiple_of(2 * per_second) {
        let (lat_deg, lon_deg, alt_msl_m) = glide.frame.to_geodetic(&glide.target_ned_m);
        out.push(Telemetry::PredictedLanding(PredictedLanding {
            time_boot_ms: stamp_ms,
            lat_deg,
            lon_deg,
            alt_msl_m,
        }));
    }
    out.push(Telemetry::Attitude(Attitude {
        time_boot_ms: stamp_ms,
        roll_rad: 0.0,
        pitch_rad: -(Glide::SINK_MPS / Glide::AIRSPEED_MPS).atan(),
        yaw_rad: heading,
        roll_rate_radps: 0.0,
        pitch_rate_radps: 0.0,
        yaw_rate_radps: 0.0,
    }));
    out
}

/// The scripted drone: a VehicleEndpoint on a UDP socket holding a plan, sending a burst of
/// telemetry every control period from the moment it starts (each burst's ATTITUDE send time
/// recorded by its stamp), answering every command (its arrival time reported).
async fn drone(
    station_link: SocketAddr,
    frame: LocalFrame,
    rate_hz: f64,
    sent_at: Arc<Mutex<HashMap<u32, Instant>>>,
    commands: mpsc::UnboundedSender<Instant>,
    mut stop: oneshot::Receiver<()>,
) -> anyhow::Result<()> {
    let socket = UdpSocket::bind("127.0.0.1:0").await?;
    socket.connect(station_link).await?;
    let start = Instant::now();
    let glide = Glide::new(frame);
    let mut endpoint = VehicleEndpoint::new(
        VehicleConfig {
            link: LinkConfig::vehicle(),
            initial_status: VehicleStatus {
                mode: FlightMode::SpiralLanding,
                stage: FlightStage::Parafoil,
                phase: GuidancePhase::Approximation,
                state: SystemState::Active,
            },
            ..Default::default()
        },
        Duration::ZERO,
    )?;
    endpoint.set_plan(glide.plan());
    let mut ticker = tokio::time::interval(Duration::from_secs_f64(1.0 / rate_hz));
    let mut k: u64 = 0;
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
            _ = ticker.tick() => {
                // The drone's clock: one control period per burst.
                let stamp = 1_000_000 + (k as f64 * 1000.0 / rate_hz).round() as u32;
                for telemetry in burst(&glide, k, rate_hz, stamp) {
                    endpoint.send_telemetry(start.elapsed(), &telemetry);
                }
                while let Some(bytes) = endpoint.poll_transmit(start.elapsed()) {
                    socket.send(&bytes).await?;
                }
                sent_at
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .insert(stamp, Instant::now());
                k += 1;
            }
            () = tokio::time::sleep(timer) => endpoint.handle_timeout(start.elapsed()),
            _ = &mut stop => return Ok(()),
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
    const KEY: &str = r#""attitude":{"time_boot_ms":"#;
    if !text.starts_with(r#"{"type":"state""#) {
        return None;
    }
    let at = text.find(KEY)? + KEY.len();
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
    let (running, token, stop_station) = start_station()?;
    let link = running
        .link_local
        .context("the station's link has no local address")?;
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()?;
    let frame = running.shared.config.origin;
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
        let (stop_drone, stop_rx) = oneshot::channel();
        let drone_task = tokio::spawn(drone(
            link,
            frame,
            options.frame_rate_hz,
            sent_at.clone(),
            commands_tx,
            stop_rx,
        ));
        // The first seconds (link up, plan read back, estimator converging) are not timed.
        tokio::time::sleep(Duration::from_secs(5)).await;
        let timed_from = Instant::now();
        let window = Duration::from_secs_f64(options.frames as f64 / options.frame_rate_hz);
        tokio::time::sleep(window).await;
        let timed: Vec<(u32, Instant)> = sent_at
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .iter()
            .filter(|(_, at)| **at >= timed_from)
            .map(|(s, at)| (*s, *at))
            .collect();
        tokio::time::sleep(Duration::from_millis(500)).await;
        let mut samples = Vec::new();
        let mut missed = 0;
        for seen in &seen_by_page {
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
        let (state_bytes, not_run) = station_view(&running);
        if !not_run.is_empty() {
            bail!("the station's pipeline did not run on the telemetry: no {not_run}");
        }
        let telemetry = TelemetryReport {
            clients: options.clients,
            frames_sent: timed.len(),
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
        for p in &pages {
            p.abort();
        }
        let _ = stop_drone.send(());
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
        let state = r#"{"type":"state","vehicle":{"predicted_landing":{"time_boot_ms":7},"attitude":{"time_boot_ms":1000030,"roll_deg":0}}}"#;
        assert_eq!(attitude_stamp(state), Some(1_000_030));
        assert_eq!(attitude_stamp(r#"{"type":"event","time_boot_ms":5}"#), None);
        assert_eq!(attitude_stamp(r#"{"type":"state","vehicle":null}"#), None);
    }

    #[test]
    fn bursts_carry_the_drones_set_at_its_rates_with_the_attitude_last() {
        let glide = Glide::new(LocalFrame {
            lat_deg: 38.5,
            lon_deg: -7.9,
            alt_msl_m: 245.0,
        });
        let mut counts: HashMap<&str, usize> = HashMap::new();
        for k in 0..8 {
            let stamp = 1_000_000 + k as u32 * 250;
            let b = burst(&glide, k, 4.0, stamp);
            assert!(
                matches!(b.last(), Some(Telemetry::Attitude(a)) if a.time_boot_ms == stamp),
                "the ATTITUDE with the burst's stamp comes last"
            );
            for t in &b {
                *counts.entry(t.message_name()).or_default() += 1;
            }
        }
        // Two seconds at 4 Hz.
        for name in [
            "GPS_RAW_INT",
            "SCALED_PRESSURE",
            "GLOBAL_POSITION_INT",
            "VFR_HUD",
            "SERVO_OUTPUT_RAW",
            "ATTITUDE",
        ] {
            assert_eq!(counts.get(name), Some(&8), "{name}");
        }
        for name in [
            "WIND_COV",
            "NAV_CONTROLLER_OUTPUT",
            "SYS_STATUS",
            "BATTERY_STATUS",
        ] {
            assert_eq!(counts.get(name), Some(&2), "{name}");
        }
        assert_eq!(counts.get("POSITION_TARGET_GLOBAL_INT"), Some(&1));
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
