//! `stx drone`, the real binary, end to end over loopback UDP.
//!
//! - A station built from stx-link's [`GroundEndpoint`] (driven over a tokio UDP socket by
//!   stx-link's own driver) receives the drone's telemetry, lists and sets a parameter, changes
//!   the mode and back, is refused a cutdown under the parafoil, and watches the short mission
//!   land near its target.
//! - The whole mission, launch to landing, flies at `--speed max` with no operator; the
//!   drone's summary gives the figures the project reports (mission and wall time, miss).
//! - Bad names, files and flags exit with code 2 and say what is wrong.

use std::net::UdpSocket;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;
use stx_gnc::mission::{FlightMode, FlightStage};
use stx_link::command::{Command as LinkCommand, CommandOutcome, CommandResult, RequestId};
use stx_link::endpoint::{GroundConfig, GroundEndpoint, GroundEvent};
use stx_link::param::ParamEvent;
use stx_link::telemetry::Telemetry;
use stx_link_tokio::{Action, DriveOptions, DriverEvent, Transport, drive};
use tokio::sync::mpsc;

fn stx() -> Command {
    Command::new(env!("CARGO_BIN_EXE_stx"))
}

fn spawn_drone(port: u16, args: &[&str]) -> Child {
    stx()
        .arg("drone")
        .args(["--connect", &format!("udpout:127.0.0.1:{port}")])
        .args(args)
        .arg("--summary-json")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("stx runs")
}

/// Waits for the drone to exit and returns its JSON summary (last stdout line).
fn summary(child: Child) -> Value {
    let out = child.wait_with_output().expect("stx drone finishes");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "stx drone failed ({}): {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(stdout.lines().last().unwrap_or_default())
        .unwrap_or_else(|e| panic!("summary is not JSON ({e}): {stdout}"))
}

/// A station: stx-link's ground endpoint driven over a UDP socket listening for the drone.
struct Station {
    actions: mpsc::Sender<Action<GroundEndpoint>>,
    events: mpsc::Receiver<DriverEvent<GroundEvent>>,
    port: u16,
    /// Every STATUSTEXT seen, for failure messages.
    texts: Vec<String>,
}

impl Station {
    async fn listen() -> Self {
        let transport = Transport::open_str("udpin:127.0.0.1:0")
            .await
            .expect("udp socket");
        let port = transport.local_addr().expect("bound").port();
        let (atx, arx) = mpsc::channel(16);
        let (etx, erx) = mpsc::channel(4096);
        tokio::spawn(drive(
            transport,
            GroundEndpoint::new(GroundConfig::default(), Duration::ZERO),
            arx,
            etx,
            DriveOptions::default(),
        ));
        Self {
            actions: atx,
            events: erx,
            port,
            texts: Vec::new(),
        }
    }

    async fn act(&self, f: impl FnOnce(&mut GroundEndpoint, Duration) + Send + 'static) {
        self.actions.send(Box::new(f)).await.expect("driver runs");
    }

    /// The first ground event `pick` accepts, within `timeout`; every heartbeat seen on the
    /// way goes to `seen`.
    async fn until<T>(
        &mut self,
        what: &str,
        timeout: Duration,
        seen: &mut Vec<(FlightMode, FlightStage)>,
        mut pick: impl FnMut(&GroundEvent) -> Option<T>,
    ) -> T {
        let deadline = tokio::time::Instant::now() + timeout;
        loop {
            let event = tokio::time::timeout_at(deadline, self.events.recv())
                .await
                .unwrap_or_else(|_| panic!("no {what} within {timeout:?}; texts: {:?}", self.texts))
                .expect("driver runs");
            if let DriverEvent::Endpoint(GroundEvent::StatusText { text, .. }) = &event {
                self.texts.push(text.clone());
            }
            if let DriverEvent::Endpoint(e) = event {
                if let GroundEvent::Telemetry {
                    telemetry: Telemetry::Status(s),
                    ..
                } = &e
                {
                    seen.push((s.mode, s.stage));
                }
                if let Some(t) = pick(&e) {
                    return t;
                }
            }
        }
    }
}

impl Station {
    /// The drone's whole parameter table, within `timeout`.
    async fn param_list(
        &mut self,
        timeout: Duration,
        seen: &mut Vec<(FlightMode, FlightStage)>,
    ) -> Vec<stx_link::param::ParamValue> {
        self.act(|g, now| g.param_list(now).expect("list starts"))
            .await;
        self.until("parameter list", timeout, seen, |e| match e {
            GroundEvent::Param(ParamEvent::ListComplete { params }) => Some(params.clone()),
            _ => None,
        })
        .await
    }

    /// The first STATUSTEXT containing `needle`, already seen or within `timeout`.
    async fn text(
        &mut self,
        what: &str,
        timeout: Duration,
        seen: &mut Vec<(FlightMode, FlightStage)>,
        needle: &str,
    ) -> String {
        if let Some(t) = self.texts.iter().find(|t| t.contains(needle)) {
            return t.clone();
        }
        self.until(what, timeout, seen, |e| match e {
            GroundEvent::StatusText { text, .. } if text.contains(needle) => Some(text.clone()),
            _ => None,
        })
        .await
    }
}

fn command_outcome(request: u64) -> impl FnMut(&GroundEvent) -> Option<CommandOutcome> {
    move |e| match e {
        GroundEvent::Command(c) if c.request_id == RequestId(request) => Some(c.outcome),
        _ => None,
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_station_reads_sets_commands_and_watches_the_rehearsal_land() {
    let mut station = Station::listen().await;
    // 20× real time: the five minutes of the rehearsal (the parafoil deployed 900 m up near
    // the target) in about fifteen seconds, slow enough to talk to the drone on the way down.
    let drone = spawn_drone(station.port, &["--scenario", "rehearsal", "--speed", "20"]);
    let mut seen = Vec::new();
    let long = Duration::from_secs(30);

    // Telemetry: the drone's sensors arrive.
    station
        .until("GPS telemetry", long, &mut seen, |e| match e {
            GroundEvent::Telemetry {
                telemetry: Telemetry::GpsRaw(g),
                ..
            } if g.lat_deg != 0.0 => Some(()),
            _ => None,
        })
        .await;

    // Parameters: the whole list, then a gain set and echoed.
    let params = station.param_list(long, &mut seen).await;
    assert!(params.len() >= 10, "{params:?}");
    let gain = params
        .iter()
        .find(|p| p.name.ends_with("HK2"))
        .expect("the heading-rate gain is a parameter")
        .clone();
    let new = gain.value * 1.25;
    let name = gain.name.clone();
    station
        .act(move |g, now| g.param_set(now, &name, new).expect("set starts"))
        .await;
    let (accepted, actual) = station
        .until("parameter echo", long, &mut seen, |e| match e {
            GroundEvent::Param(ParamEvent::SetDone {
                accepted, actual, ..
            }) => Some((*accepted, *actual)),
            _ => None,
        })
        .await;
    assert!(
        accepted && (actual - new).abs() < 1e-9,
        "{actual} for {new}"
    );

    // Modes: heading, then back to the spiral landing, each acknowledged and in the heartbeat.
    for (request, mode) in [(1, FlightMode::Heading), (2, FlightMode::SpiralLanding)] {
        station
            .act(move |g, now| {
                g.send_command(now, RequestId(request), LinkCommand::SetMode(mode))
                    .expect("command sent")
            })
            .await;
        let outcome = station
            .until("command outcome", long, &mut seen, command_outcome(request))
            .await;
        assert_eq!(outcome, CommandOutcome::Accepted, "{mode:?}");
        station
            .until("heartbeat in the new mode", long, &mut seen, |e| match e {
                GroundEvent::Telemetry {
                    telemetry: Telemetry::Status(s),
                    ..
                } if s.mode == mode => Some(()),
                _ => None,
            })
            .await;
    }

    // No balloon to cut under the parafoil: refused, with a reason in the log.
    station
        .act(|g, now| {
            g.send_command(now, RequestId(3), LinkCommand::Cutdown)
                .expect("command sent")
        })
        .await;
    let outcome = station
        .until("cutdown outcome", long, &mut seen, command_outcome(3))
        .await;
    assert_eq!(
        outcome,
        CommandOutcome::Rejected {
            result: CommandResult::Denied
        }
    );
    station
        .text("cutdown refusal text", long, &mut seen, "cutdown refused")
        .await;

    // It flies the rest of its plan to the ground and says so.
    let landed = station
        .text("landing text", Duration::from_secs(60), &mut seen, "landed")
        .await;
    let s = tokio::task::spawn_blocking(move || summary(drone))
        .await
        .expect("joined");
    println!("{landed}\nsummary: {s}");
    assert_eq!(s["landed"], true);
    let miss = s["landing"]["miss_m"].as_f64().expect("a target");
    assert!(miss < 40.0, "missed by {miss} m");
    assert!(seen.iter().any(|(_, st)| *st == FlightStage::Parafoil));
    assert!(seen.iter().any(|(m, _)| *m == FlightMode::Heading));
}

#[test]
fn the_whole_mission_flies_from_launch_to_landing_at_max_speed_with_no_operator() {
    // A bare socket stands for the station: it only counts what arrives.
    let socket = UdpSocket::bind("127.0.0.1:0").expect("udp socket");
    socket
        .set_read_timeout(Some(Duration::from_millis(200)))
        .expect("timeout");
    let port = socket.local_addr().expect("bound").port();
    let started = Instant::now();
    let mut drone = spawn_drone(port, &["--scenario", "mission", "--speed", "max"]);
    let mut datagrams = 0u64;
    let mut buf = [0_u8; 2048];
    loop {
        if let Ok(n) = socket.recv(&mut buf)
            && n > 0
        {
            datagrams += 1;
        }
        if drone.try_wait().expect("waitable").is_some() {
            break;
        }
        assert!(
            started.elapsed() < Duration::from_secs(600),
            "mission still flying"
        );
    }
    let s = summary(drone);
    println!("whole mission: {s}\ndatagrams received: {datagrams}");
    assert_eq!(s["landed"], true);
    let stages: Vec<&str> = s["stages"]
        .as_array()
        .expect("stages")
        .iter()
        .filter_map(|st| st["stage"].as_str())
        .collect();
    assert_eq!(
        stages,
        [
            "pre_launch",
            "ascent",
            "round_chute",
            "parafoil_deploy",
            "parafoil",
            "landed"
        ]
    );
    // The timeline: the balloon climbs at 5 m/s on average from the pad (245 m) to its burst.
    let start = |stage: &str| {
        s["stages"]
            .as_array()
            .and_then(|a| a.iter().find(|st| st["stage"] == stage))
            .and_then(|st| st["start_s"].as_f64())
            .unwrap_or(f64::NAN)
    };
    let burst_msl_m = s["balloon_end"][2].as_f64().unwrap_or(f64::NAN);
    let mean_ascent_mps = (burst_msl_m - 245.0) / (start("round_chute") - start("ascent"));
    println!(
        "timeline: launch {:.0} s, burst {:.0} s at {burst_msl_m:.0} m ({mean_ascent_mps:.3} m/s \
         on average), deploy {:.0} s, landed {:.0} s",
        start("ascent"),
        start("round_chute"),
        start("parafoil_deploy"),
        start("landed")
    );
    assert!((mean_ascent_mps - 5.0).abs() < 0.05, "{s}");
    let miss = s["landing"]["miss_m"].as_f64().expect("a target");
    assert!(miss < 50.0, "missed by {miss} m");
    // Hours of mission in (much) less time.
    let mission_s = s["mission_time_s"].as_f64().unwrap_or(0.0);
    let wall_s = s["wall_time_s"].as_f64().unwrap_or(f64::INFINITY);
    assert!(mission_s > 5000.0 && wall_s < mission_s / 20.0, "{s}");
    assert!(datagrams > 10_000, "{datagrams} datagrams");
}

#[test]
fn the_failure_flags_are_flown_and_counted() {
    let socket = UdpSocket::bind("127.0.0.1:0").expect("udp socket");
    let port = socket.local_addr().expect("bound").port();
    let drone = spawn_drone(
        port,
        &[
            "--scenario",
            "rehearsal",
            "--speed",
            "max",
            "--link-drop",
            "20:40",
            "--gps-loss",
            "60:80",
            "--stuck-servo",
            "right@100",
            "--packet-loss",
            "10",
        ],
    );
    let s = summary(drone);
    println!("with failures: {s}");
    assert_eq!(s["landed"], true);
    let link = &s["link"];
    assert!(
        link["dropped_link_down"].as_u64().unwrap_or(0) > 100,
        "{link}"
    );
    assert!(link["dropped_random"].as_u64().unwrap_or(0) > 100, "{link}");
}

/// `stx drone --gains FILE`: the onboard guidance starts with the file's gains, and they are
/// its parameters — what a station lists over PARAM_* is what the file says.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_gains_file_is_what_the_drone_reports_over_param() {
    let gains = stx_gnc::control::ControlGains {
        hk1_m_per_rad: 0.0123,
        hk2_m_s_per_rad: 0.0211,
        hk3_m_per_m: 0.000345,
        convergence_distance_m: 55.0,
        vk1: 2.25,
        vk2_per_m: 0.375,
        brake_trim: 0.35,
        main_line_limit_m: 0.0175,
    };
    let dir = std::env::temp_dir().join(format!("stx-drone-gains-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let path = dir.join("gains.toml");
    std::fs::write(&path, gains.to_toml_string()).expect("write");
    assert_eq!(
        stx_gnc::control::ControlGains::from_toml_str(&gains.to_toml_string()).expect("valid"),
        gains
    );
    let mut station = Station::listen().await;
    let mut drone = spawn_drone(
        station.port,
        &[
            "--scenario",
            "rehearsal",
            "--gains",
            path.to_str().expect("utf-8"),
        ],
    );
    let mut seen = Vec::new();
    let long = Duration::from_secs(30);
    station
        .until("a heartbeat", long, &mut seen, |e| match e {
            GroundEvent::Telemetry {
                telemetry: Telemetry::Status(_),
                ..
            } => Some(()),
            _ => None,
        })
        .await;
    let params = station.param_list(long, &mut seen).await;
    let _ = drone.kill();
    let _ = drone.wait();
    let value = |name: &str| {
        params
            .iter()
            .find(|p| p.name == name)
            .map(|p| p.value)
            .unwrap_or_else(|| panic!("no {name} in {params:?}"))
    };
    for (name, expected) in [
        ("GN_HK1", gains.hk1_m_per_rad),
        ("GN_HK2", gains.hk2_m_s_per_rad),
        ("GN_HK3", gains.hk3_m_per_m),
        ("GN_CONV_DIST", gains.convergence_distance_m),
        ("GN_VK1", gains.vk1),
        ("GN_VK2", gains.vk2_per_m),
        ("GN_BRAKE_TRIM", gains.brake_trim),
        ("GN_LINE_MAX", gains.main_line_limit_m),
    ] {
        assert_eq!(value(name), expected as f32, "{name}");
    }
    // Not the built-in gains.
    assert_ne!(
        value("GN_HK1"),
        stx_gnc::control::ControlGains::default().hk1_m_per_rad as f32
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Regression: with `tcpin:` and no station connected, every frame failed and was logged
/// twice — 66,761 stderr lines in 1.2 s. Now every failure is counted (the summary's
/// `io.send_errors`) and reported a few times; and the port chosen for `:0` is logged, so a
/// station can connect to it.
#[test]
fn a_drone_waiting_for_a_station_logs_its_port_and_not_every_failed_frame() {
    use std::io::{BufRead, BufReader, Read};
    let mut child = stx()
        .args([
            "drone",
            "--connect",
            "tcpin:127.0.0.1:0",
            "--scenario",
            "rehearsal",
        ])
        .args(["--speed", "max", "--summary-json"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("stx runs");
    let stderr = child.stderr.take().expect("stderr");
    let (lines_tx, lines_rx) = std::sync::mpsc::channel();
    let reader = std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            let _ = lines_tx.send(line);
        }
    });
    let mut lines = Vec::new();
    let mut got_frames = false;
    for line in lines_rx.iter() {
        let port = line
            .split("tcpin:127.0.0.1:")
            .nth(1)
            .map(|rest| {
                rest.chars()
                    .take_while(char::is_ascii_digit)
                    .collect::<String>()
            })
            .and_then(|p| p.parse::<u16>().ok())
            .filter(|&p| p != 0 && line.contains("listening"));
        lines.push(line);
        if let Some(port) = port {
            // The logged address is the real one: a station connecting there gets frames.
            let mut client =
                std::net::TcpStream::connect(("127.0.0.1", port)).expect("the logged port");
            client
                .set_read_timeout(Some(Duration::from_secs(10)))
                .expect("timeout");
            let mut buf = [0_u8; 64];
            got_frames = client
                .read(&mut buf)
                .is_ok_and(|n| n > 0 && buf.contains(&0xFD));
            break;
        }
    }
    lines.extend(lines_rx.iter());
    reader.join().expect("reader");
    let s = summary(child);
    assert!(got_frames, "no frames on the logged port: {lines:#?}");
    let send_errors = s["io"]["send_errors"].as_u64().unwrap_or(0);
    let error_lines = lines.iter().filter(|l| l.contains("send failed")).count();
    println!(
        "{} stderr lines, {error_lines} about failed sends, {send_errors} sends failed",
        lines.len()
    );
    assert!(send_errors > 1000, "every failure counted: {s}");
    assert!(
        (1..=10).contains(&error_lines),
        "{error_lines} lines about failed sends"
    );
    assert!(lines.len() < 300, "{} stderr lines", lines.len());
}

#[test]
fn bad_names_files_and_flags_exit_with_code_2() {
    let dir = std::env::temp_dir().join(format!("stx-drone-badkey-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let bad_key = dir.join("key");
    std::fs::write(&bad_key, "not-hex-secret\n").expect("write");
    let bad_key = bad_key.to_str().expect("utf-8").to_string();
    for args in [
        vec!["--scenario", "no-such-mission"],
        vec!["--scenario", "/no/such/file.toml"],
        vec!["--link-drop", "50:10"],
        vec!["--gps-loss", "soon"],
        vec!["--stuck-servo", "rudder@10"],
        vec!["--packet-loss", "150"],
        vec!["--speed", "0"],
        vec!["--sign-key-file", bad_key.as_str()],
        vec!["--sign-key-file", "/nonexistent/key"],
        vec!["--gains", "/nonexistent/gains.toml"],
        vec!["--connect", "carrier-pigeon:1"],
    ] {
        let out = stx().arg("drone").args(&args).output().expect("stx runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(
            stderr.contains("error"),
            "{args:?} says what is wrong: {stderr}"
        );
        assert!(!stderr.contains("not-hex"), "the key is never echoed");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
