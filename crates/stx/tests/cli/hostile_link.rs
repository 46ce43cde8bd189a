//! Fault injection through the real daemon: `stx serve --sim` (the station and its simulated
//! drone, over loopback UDP to the station's `udpin:` link) while someone on the network floods
//! the link port from other local ports with random datagrams, another system's valid frames
//! and the drone's frames with a broken checksum. The drone must keep hearing the station, an
//! operator's mode change must reach it, the station must show the drone's mode (not the
//! forger's) and the log must show no peer flip.
//!
//! Regression: the station answered whoever sent the last datagram, so random bytes flipped its
//! peer many times a second (`udp peer from=…` per datagram), the drone reported the station
//! lost, and commands went to the sender of the garbage.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream, UdpSocket};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::Value;
use stx_link::endpoint::VehicleConfig;
use stx_link::frame::FrameEncoder;
use stx_link::telemetry::Telemetry;

/// How long the flood lasts.
const FLOOD: Duration = Duration::from_secs(6);

/// `stx serve --sim`, its log going to a file.
struct Station {
    child: Child,
    http: String,
    token: String,
    link: SocketAddr,
    log: PathBuf,
}

impl Station {
    fn start() -> Self {
        let dir = std::env::temp_dir().join(format!("stx-hostile-link-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let log = dir.join("serve.log");
        let mut child = Command::new(env!("CARGO_BIN_EXE_stx"))
            .args([
                "serve",
                "--sim",
                "--listen",
                "127.0.0.1:0",
                "--link",
                "udpin:127.0.0.1:0",
                "--no-record",
            ])
            .env("RUST_LOG", "info")
            .stdout(Stdio::piped())
            .stderr(std::fs::File::create(&log).expect("log file"))
            .spawn()
            .expect("stx serve starts");
        let mut stdout = BufReader::new(child.stdout.take().expect("stdout"));
        let mut banner = String::new();
        for _ in 0..2 {
            stdout.read_line(&mut banner).expect("banner");
        }
        // "stx station: open http://127.0.0.1:PORT/?token=TOKEN"
        // "stx station: drone link listening on 127.0.0.1:PORT"
        let (url, link) = banner.trim().split_once('\n').expect("two lines");
        let url = url.rsplit(' ').next().expect("a URL");
        let (http, token) = url
            .strip_prefix("http://")
            .and_then(|u| u.split_once("/?token="))
            .expect("address and token");
        let link = link
            .rsplit(' ')
            .next()
            .and_then(|a| a.parse().ok())
            .expect("link address");
        Self {
            child,
            http: http.to_string(),
            token: token.to_string(),
            link,
            log,
        }
    }

    /// `(status, JSON body)` of one request.
    fn request(&self, method: &str, path: &str, body: Option<&str>) -> (u16, Value) {
        let mut stream = TcpStream::connect(&self.http).expect("connect");
        stream
            .set_read_timeout(Some(Duration::from_secs(10)))
            .expect("timeout");
        let body = body.unwrap_or("");
        write!(
            stream,
            "{method} {path} HTTP/1.1\r\nHost: {}\r\nAuthorization: Bearer {}\r\n\
             Content-Type: application/json\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}",
            self.http,
            self.token,
            body.len()
        )
        .expect("write");
        let mut response = String::new();
        stream.read_to_string(&mut response).expect("read");
        let status = response
            .split(' ')
            .nth(1)
            .and_then(|s| s.parse().ok())
            .unwrap_or(0);
        let body = response.split_once("\r\n\r\n").map_or("", |(_, b)| b);
        (status, serde_json::from_str(body).unwrap_or(Value::Null))
    }

    fn state(&self) -> Value {
        self.request("GET", "/api/state", None).1
    }

    /// Polls `what` every 100 ms until it holds; panics after `within` with the last value.
    fn wait_until(&self, within: Duration, what: &str, done: impl Fn(&Value) -> bool) -> Value {
        let deadline = Instant::now() + within;
        loop {
            let state = self.state();
            if done(&state) {
                return state;
            }
            assert!(Instant::now() < deadline, "{what}: {state}");
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// Stops it with SIGTERM and returns its log.
    fn stop(mut self) -> String {
        let pid = self.child.id().to_string();
        let _ = Command::new("kill").args(["-TERM", &pid]).status();
        let deadline = Instant::now() + Duration::from_secs(10);
        while self.child.try_wait().expect("wait").is_none() && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(50));
        }
        std::fs::read_to_string(&self.log).expect("log")
    }
}

/// A failed assertion does not leave the daemon running.
impl Drop for Station {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        if let Some(dir) = self.log.parent() {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
}

/// Floods `to` from two other local ports until `stop`; returns the datagrams sent.
fn flood(to: SocketAddr, stop: Arc<AtomicBool>) -> u64 {
    let garbage_socket = UdpSocket::bind("127.0.0.1:0").expect("bind");
    let frames_socket = UdpSocket::bind("127.0.0.1:0").expect("bind");
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    // Another system claiming to be a vehicle (its status says "uncontrolled"), and the
    // drone's own system id with a broken checksum.
    let status = Telemetry::Status(VehicleConfig::default().initial_status).to_mavlink();
    let mut other_system = FrameEncoder::new(7, 1);
    let mut drone_id = FrameEncoder::new(1, 1);
    let mut sent = 0;
    while !stop.load(Ordering::Relaxed) {
        for i in 0..20 {
            let (socket, bytes) = match i % 4 {
                0 => (&frames_socket, other_system.encode(Duration::ZERO, &status)),
                1 => {
                    let mut f = drone_id.encode(Duration::ZERO, &status);
                    if let Some(b) = f.last_mut() {
                        *b ^= 0xa5;
                    }
                    (&frames_socket, f)
                }
                _ => {
                    let len = rng.random_range(1..300);
                    let bytes = (0..len).map(|_| rng.random::<u8>()).collect();
                    (&garbage_socket, bytes)
                }
            };
            if socket.send_to(&bytes, to).is_ok() {
                sent += 1;
            }
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    sent
}

#[test]
fn a_flood_of_garbage_and_foreign_frames_neither_diverts_the_uplink_nor_loses_the_drone() {
    let station = Station::start();
    station.wait_until(Duration::from_secs(30), "the drone connects", |s| {
        s["link"]["connected"] == true && s["vehicle"]["mode"].is_string()
    });

    let stop = Arc::new(AtomicBool::new(false));
    let flooder = {
        let (to, stop) = (station.link, stop.clone());
        std::thread::spawn(move || flood(to, stop))
    };
    let started = Instant::now();
    std::thread::sleep(Duration::from_secs(1));

    // Under the flood, the operator changes the mode: the drone answers and flies it.
    let (status, reply) =
        station.request("POST", "/api/commands/mode", Some(r#"{"mode":"heading"}"#));
    assert_eq!(status, 202, "{reply}");
    let id = reply["request_id"]
        .as_str()
        .expect("request id")
        .to_string();
    let deadline = Instant::now() + Duration::from_secs(10);
    let outcome = loop {
        let (_, result) = station.request("GET", &format!("/api/commands/{id}"), None);
        if result["outcome"] != "in_progress" && !result["outcome"].is_null() {
            break result;
        }
        assert!(
            Instant::now() < deadline,
            "no answer from the drone: {result}"
        );
        std::thread::sleep(Duration::from_millis(100));
    };
    assert_eq!(outcome["outcome"], "accepted", "{outcome}");

    // The station shows the drone's mode, not the forger's, and never loses the drone.
    while started.elapsed() < FLOOD {
        let state = station.state();
        assert_eq!(state["link"]["connected"], true, "{state}");
        assert_eq!(state["vehicle"]["mode"], "heading", "{state}");
        std::thread::sleep(Duration::from_millis(250));
    }
    stop.store(true, Ordering::Relaxed);
    let sent = flooder.join().expect("flooder");
    assert!(sent >= 1_000, "only {sent} datagrams sent");
    let state = station.state();
    assert_eq!(state["link"]["connected"], true, "{state}");

    let log = station.stop();
    let lines = |pattern: &str| log.lines().filter(|l| l.contains(pattern)).count();
    assert_eq!(
        lines("udp peer"),
        1,
        "the peer is set once, by the drone's first frame, and never moves:\n{log}"
    );
    assert_eq!(lines("station lost"), 0, "{log}");
    assert_eq!(lines("connected=false"), 0, "{log}");
    assert!(
        lines("udp datagrams ignored") >= 1,
        "the flood reached the station and was reported:\n{log}"
    );
}
