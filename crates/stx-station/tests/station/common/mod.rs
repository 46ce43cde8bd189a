//! Test fixtures: a station on loopback, a scripted drone or the simulated one (the runner of
//! `stx drone`) on the other end of the real MAVLink link, a small HTTP client and WebSocket
//! helpers.

#![allow(dead_code)] // each test file uses a different part

use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use futures_util::{SinkExt, StreamExt};
use serde_json::Value;
use stx_gnc::mission::{FlightMode, FlightStage, GuidancePhase};
use stx_link::command::{Command, CommandResult};
use stx_link::endpoint::{LinkConfig, VehicleConfig, VehicleEndpoint, VehicleEvent};
use stx_link::manual::ManualEvent;
use stx_link::param::ParamSpec;
use stx_link::telemetry::{Attitude, SystemState, Telemetry, VehicleStatus};
use stx_link_tokio::{Action, DriveOptions, DriverEvent, Transport, drive};
use stx_station::config::{DEFAULT_STATION_TOML, StationConfig};
use stx_station::daemon::{Running, run};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio::sync::{mpsc, oneshot};
use tokio_tungstenite::tungstenite::Message;

pub const OPERATOR: &str = "operator-token";
pub const VIEWER: &str = "viewer-token";

/// A running station; dropping it shuts it down.
pub struct Station {
    pub running: Running,
    stop: Option<oneshot::Sender<()>>,
}

impl Drop for Station {
    fn drop(&mut self) {
        if let Some(stop) = self.stop.take() {
            let _ = stop.send(());
        }
    }
}

impl Station {
    pub fn http(&self) -> SocketAddr {
        self.running.http
    }
}

/// The shipped config on ephemeral loopback ports, changed by `edit`.
pub fn config(edit: impl FnOnce(&mut StationConfig)) -> StationConfig {
    let mut c = StationConfig::from_toml_str(DEFAULT_STATION_TOML).expect("shipped config");
    c.listen = "127.0.0.1:0".parse().expect("address");
    c.link.address = "udpin:127.0.0.1:0".into();
    c.web_dir = std::env::temp_dir().join("stx-station-test-no-web");
    // Tests that record say where.
    c.recording.enabled = false;
    // The shipped zones, wherever the test runs (read only: no test here edits them).
    c.keep_out = Some(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../config/keep-out/sample.geojson"),
    );
    edit(&mut c);
    c.validate().expect("valid test config");
    c
}

pub async fn start_station(config: StationConfig) -> Station {
    let (stop_tx, stop_rx) = oneshot::channel::<()>();
    let (started_tx, started_rx) = oneshot::channel();
    tokio::spawn(async move {
        let shutdown = async move {
            let _ = stop_rx.await;
        };
        if let Err(e) = run(config, shutdown, move |r| {
            let _ = started_tx.send(r);
        })
        .await
        {
            panic!("station failed: {e}");
        }
    });
    let running = tokio::time::timeout(Duration::from_secs(10), started_rx)
        .await
        .expect("station started in time")
        .expect("station started");
    Station {
        running,
        stop: Some(stop_tx),
    }
}

/// What the scripted drone has seen from the station.
#[derive(Debug, Default)]
pub struct Seen {
    pub commands: Vec<Command>,
    pub sticks: Vec<stx_link::manual::Sticks>,
    pub param_changes: Vec<(String, f32)>,
    pub plans: usize,
}

/// A drone that accepts every command (a mode command becomes its reported mode), holds the
/// parameter `HK1`, records what it receives and sends an attitude and a heartbeat when told.
pub struct FakeDrone {
    pub seen: Arc<Mutex<Seen>>,
    pub actions: mpsc::Sender<Action<VehicleEndpoint>>,
}

pub fn fast_link(mut link: LinkConfig) -> LinkConfig {
    link.heartbeat_period = Duration::from_millis(200);
    link
}

pub async fn fake_drone(station_link: SocketAddr) -> FakeDrone {
    let transport = Transport::open_str(&format!("udpout:{station_link}"))
        .await
        .expect("drone socket");
    let endpoint = VehicleEndpoint::new(
        VehicleConfig {
            link: fast_link(LinkConfig::vehicle()),
            params: vec![ParamSpec::new(
                "HK1",
                0.012,
                0.0,
                0.1,
                "heading gain, m/rad",
            )],
            initial_status: VehicleStatus {
                mode: FlightMode::Uncontrolled,
                stage: FlightStage::Parafoil,
                phase: GuidancePhase::Idle,
                state: SystemState::Active,
            },
            ..Default::default()
        },
        Duration::ZERO,
    )
    .expect("vehicle endpoint");
    let (actions_tx, actions_rx) = mpsc::channel::<Action<VehicleEndpoint>>(256);
    let (events_tx, mut events_rx) = mpsc::channel(1024);
    tokio::spawn(drive(
        transport,
        endpoint,
        actions_rx,
        events_tx,
        DriveOptions::default(),
    ));
    let seen = Arc::new(Mutex::new(Seen::default()));
    let app_seen = seen.clone();
    let app_actions = actions_tx.clone();
    tokio::spawn(async move {
        while let Some(event) = events_rx.recv().await {
            let DriverEvent::Endpoint(event) = event else {
                continue;
            };
            match event {
                VehicleEvent::Command(c) => {
                    let id = c.id;
                    let command = c.command;
                    app_seen.lock().unwrap().commands.push(c.command);
                    let _ = app_actions
                        .send(Box::new(move |ep: &mut VehicleEndpoint, _| {
                            if let Command::SetMode(mode) = command {
                                let mut status = ep.status();
                                status.mode = mode;
                                ep.set_status(status);
                            }
                            ep.respond_command(id, CommandResult::Accepted);
                        }))
                        .await;
                }
                VehicleEvent::Manual(ManualEvent::Sticks(s)) => {
                    app_seen.lock().unwrap().sticks.push(s);
                }
                VehicleEvent::ParamChanged(p) => {
                    app_seen.lock().unwrap().param_changes.push((p.name, p.new));
                }
                VehicleEvent::PlanReceived(_) => app_seen.lock().unwrap().plans += 1,
                _ => {}
            }
        }
    });
    FakeDrone {
        seen,
        actions: actions_tx,
    }
}

impl FakeDrone {
    /// Sends one ATTITUDE with this time stamp.
    pub async fn send_attitude(&self, time_boot_ms: u32, yaw_rad: f64) {
        let _ = self
            .actions
            .send(Box::new(move |ep: &mut VehicleEndpoint, now| {
                ep.send_telemetry(
                    now,
                    &Telemetry::Attitude(Attitude {
                        time_boot_ms,
                        roll_rad: 0.0,
                        pitch_rad: 0.0,
                        yaw_rad,
                        roll_rate_radps: 0.0,
                        pitch_rate_radps: 0.0,
                        yaw_rate_radps: 0.0,
                    }),
                );
            }))
            .await;
    }

    pub fn seen<T>(&self, f: impl FnOnce(&Seen) -> T) -> T {
        f(&self.seen.lock().unwrap())
    }
}

/// Polls `cond` every 20 ms for up to `secs`.
pub async fn eventually(secs: f64, mut cond: impl FnMut() -> bool) -> bool {
    let deadline = tokio::time::Instant::now() + Duration::from_secs_f64(secs);
    while tokio::time::Instant::now() < deadline {
        if cond() {
            return true;
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    cond()
}

/// One HTTP/1.1 request; the status and the JSON body (Null if the body is not JSON).
pub async fn http(
    addr: SocketAddr,
    method: &str,
    path: &str,
    token: Option<&str>,
    body: Option<&str>,
) -> (u16, Value) {
    let (status, text) = http_text(addr, method, path, token, body).await;
    (status, serde_json::from_str(&text).unwrap_or(Value::Null))
}

pub async fn http_text(
    addr: SocketAddr,
    method: &str,
    path: &str,
    token: Option<&str>,
    body: Option<&str>,
) -> (u16, String) {
    let stream = TcpStream::connect(addr).await.expect("connect");
    let (status, _, body) = http_on(stream, method, path, token, body).await;
    (status, body)
}

/// `GET path` with `token` from the local address `from` (another loopback address stands for
/// another machine): the status, the head (lower-case) and the body.
pub async fn get_from(
    from: std::net::IpAddr,
    addr: SocketAddr,
    path: &str,
    token: Option<&str>,
) -> (u16, String, String) {
    let socket = tokio::net::TcpSocket::new_v4().expect("socket");
    socket.bind(SocketAddr::new(from, 0)).expect("bind");
    let stream = socket.connect(addr).await.expect("connect");
    let (status, head, body) = http_on(stream, "GET", path, token, None).await;
    (status, head.to_ascii_lowercase(), body)
}

/// One HTTP/1.1 request on `stream`: the status, the head and the body.
async fn http_on(
    mut stream: TcpStream,
    method: &str,
    path: &str,
    token: Option<&str>,
    body: Option<&str>,
) -> (u16, String, String) {
    let addr = stream.peer_addr().expect("peer");
    let body = body.unwrap_or("");
    let auth = token.map_or(String::new(), |t| format!("Authorization: Bearer {t}\r\n"));
    let request = format!(
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\n{auth}Content-Type: application/json\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}",
        body.len()
    );
    stream.write_all(request.as_bytes()).await.expect("write");
    let mut response = Vec::new();
    stream.read_to_end(&mut response).await.expect("read");
    let text = String::from_utf8_lossy(&response).into_owned();
    let (head, body) = text.split_once("\r\n\r\n").expect("a response head");
    let status = head
        .split_whitespace()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .expect("a status code");
    (status, head.to_string(), body.to_string())
}

pub type Ws =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

pub async fn ws_connect(addr: SocketAddr, token: &str) -> Ws {
    let (ws, _) = tokio_tungstenite::connect_async(format!("ws://{addr}/api/ws?token={token}"))
        .await
        .expect("websocket");
    ws
}

/// The next JSON message of the socket, within `secs`.
pub async fn ws_next(ws: &mut Ws, secs: f64) -> Option<Value> {
    let deadline = tokio::time::Instant::now() + Duration::from_secs_f64(secs);
    loop {
        let next = tokio::time::timeout_at(deadline, ws.next()).await.ok()??;
        match next.ok()? {
            Message::Text(t) => return serde_json::from_str(t.as_str()).ok(),
            Message::Close(_) => return None,
            _ => continue,
        }
    }
}

/// Reads messages until one satisfies `pred`, within `secs`.
pub async fn ws_until(ws: &mut Ws, secs: f64, pred: impl Fn(&Value) -> bool) -> Option<Value> {
    let deadline = tokio::time::Instant::now() + Duration::from_secs_f64(secs);
    loop {
        let left = deadline.saturating_duration_since(tokio::time::Instant::now());
        let msg = ws_next(ws, left.as_secs_f64()).await?;
        if pred(&msg) {
            return Some(msg);
        }
    }
}

/// The texts of the station's whole event log, as a viewer reads it.
pub async fn event_texts(addr: SocketAddr) -> Vec<String> {
    let (status, events) = http(addr, "GET", "/api/events?since_s=0", Some(VIEWER), None).await;
    assert_eq!(status, 200, "{events}");
    events["events"]
        .as_array()
        .expect("events")
        .iter()
        .filter_map(|e| e["text"].as_str().map(str::to_string))
        .collect()
}

/// The `command_result` of request `id`, within 5 s.
pub async fn command_result(ws: &mut Ws, id: &str) -> Value {
    ws_until(ws, 5.0, |m| {
        m["type"] == "command_result" && m["request_id"] == id
    })
    .await
    .expect("command_result on the WebSocket")
}

pub async fn ws_send(ws: &mut Ws, value: Value) {
    ws.send(Message::Text(value.to_string().into()))
        .await
        .expect("send");
}

/// The real simulated drone (`stx_sim`'s onboard software, physics and link) flying `config`
/// over loopback UDP to the station, `speed` times faster than real time: the runner of
/// `stx drone` (`stx_sim::runner`), with heartbeats every 200 ms.
pub struct SimDrone {
    handle: stx_sim::runner::FlightHandle,
}

pub async fn sim_drone(
    station_link: SocketAddr,
    config: &stx_sim::drone::config::MissionConfig,
    speed: f64,
) -> SimDrone {
    sim_drone_with(station_link, config, speed, |_| {}).await
}

/// [`sim_drone`] with its options changed by `edit`.
pub async fn sim_drone_with(
    station_link: SocketAddr,
    config: &stx_sim::drone::config::MissionConfig,
    speed: f64,
    edit: impl FnOnce(&mut stx_sim::runner::FlyOptions),
) -> SimDrone {
    use stx_sim::runner::{Flight, FlyOptions, Speed};
    let mut options = FlyOptions::new(&format!("udpout:{station_link}"), config.clone());
    options.link = fast_link(LinkConfig::vehicle());
    options.speed = Speed::Times(speed);
    // On the ground it keeps answering until the test ends.
    options.linger = None;
    edit(&mut options);
    let flight = Flight::start(options).await.expect("drone on the air");
    let handle = flight.handle();
    tokio::spawn(flight.run(std::future::pending(), ()));
    SimDrone { handle }
}

impl SimDrone {
    /// Reads something of the drone between two of its steps.
    pub async fn query<T: Send + 'static>(
        &self,
        f: impl FnOnce(&stx_sim::drone::link::LinkedDrone) -> T + Send + 'static,
    ) -> T {
        self.handle.query(f).await.expect("the drone answers")
    }
}

/// The bytes of the recording `core` wrote, closed.
pub fn finished_recording(mut core: stx_record::RecorderCore) -> Vec<u8> {
    core.finish().expect("recording closed");
    let mut bytes = Vec::new();
    while let Some(out) = core.poll_output() {
        if let stx_record::Output::Bytes { data, .. } = out {
            bytes.extend(data);
        }
    }
    bytes
}
