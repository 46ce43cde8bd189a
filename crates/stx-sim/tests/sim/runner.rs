//! The runner (`stx_sim::runner`) over real loopback sockets: it stops when told and reports
//! the flight so far, signs above every timestamp of its last run after a restart with the
//! clock set back, tells each step's ATTITUDE stamp, answers queries between steps, refuses
//! a drone it cannot build before opening anything, and sends the simulated ground
//! anemometer's NMEA MWV sentences where asked.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use nalgebra::Vector3;
use stx_dynamics::wind::{MeanWindConfig, WindConfig};
use stx_link::signing::SigningKey;
use stx_sim::drone::MissionConfig;
use stx_sim::runner::{
    Flight, FlightObserver, FlyError, FlyOptions, Signing, Speed, StepReport, fly,
};
use stx_types::mwv::{MwvReference, parse_mwv};
use tokio::net::UdpSocket;
use tokio::time::timeout;

const KEY: &str = "c0ffee00c0ffee00c0ffee00c0ffee00c0ffee00c0ffee00c0ffee00c0ffee00";

fn rehearsal() -> MissionConfig {
    MissionConfig::builtin("rehearsal").expect("built-in mission")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("stx-runner-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// A socket standing for the station, and the address the drone sends to.
async fn station() -> (UdpSocket, String) {
    let socket = UdpSocket::bind("127.0.0.1:0")
        .await
        .expect("station socket");
    let port = socket.local_addr().expect("bound").port();
    (socket, format!("udpout:127.0.0.1:{port}"))
}

/// Every signing timestamp the drone sends until it has sent `frames`, then all it sends
/// while stopping (the flight of `options`, pointed at a fresh socket).
async fn signed_timestamps(mut options: FlyOptions, frames: usize) -> Vec<u64> {
    let (station, connect) = station().await;
    options.connect = connect;
    let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
    let flight = tokio::spawn(fly(
        options,
        async {
            let _ = stopped.await;
        },
        (),
    ));
    let mut stamps = Vec::new();
    let mut buf = [0_u8; 512];
    let decode = |bytes: &[u8], stamps: &mut Vec<u64>| {
        let mut dec = stx_link::frame::FrameDecoder::default();
        dec.push(bytes);
        while let Some(Ok(f)) = dec.poll(Duration::ZERO) {
            stamps.push(f.header.signature.expect("signed").timestamp_10us);
        }
    };
    while stamps.len() < frames {
        let n = timeout(Duration::from_secs(20), station.recv(&mut buf))
            .await
            .expect("the drone sends")
            .expect("recv");
        decode(&buf[..n], &mut stamps);
    }
    stop.send(()).expect("flight running");
    timeout(Duration::from_secs(20), flight)
        .await
        .expect("fly returns after the shutdown")
        .expect("task")
        .expect("flight");
    while let Ok(n) = station.try_recv(&mut buf) {
        decode(&buf[..n], &mut stamps);
    }
    stamps
}

/// Regression: `stx drone` signed with `SigningConfig::new(key, 0, now)` and no timestamp
/// file, so a restart with the clock set back signed below its last run (replays to the
/// station). Now the high-water mark is kept in a file, written before the first frame.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_restarted_drone_signs_above_its_last_run_with_the_clock_set_back() {
    let dir = temp_dir("restart");
    let file = dir.join("drone.signing.timestamp");
    let options = |unix: Duration| {
        let mut o = FlyOptions::new("udpout:127.0.0.1:9", rehearsal());
        o.speed = Speed::Times(10.0);
        o.linger = None;
        o.signing = Some(Signing {
            key: SigningKey::from_hex(KEY).expect("hex"),
            timestamp_file: file.clone(),
            clock_unix: Some(unix),
        });
        o
    };
    let jan_2026 = Duration::from_secs(1_767_225_600);
    let first = signed_timestamps(options(jan_2026), 20).await;
    let mark = stx_link::signing::persist::load_signing_timestamp(&file)
        .expect("readable")
        .expect("written");
    let last = *first.iter().max().expect("frames");
    assert!(
        mark > last,
        "mark {mark} on disk above every timestamp sent ({last})"
    );
    let second = signed_timestamps(options(jan_2026 - Duration::from_secs(3600)), 5).await;
    assert!(
        second[0] > last,
        "after the restart {} <= before {last}",
        second[0]
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn fly_stops_when_shutdown_resolves_and_reports_the_flight_so_far() {
    let (station, connect) = station().await;
    let mut options = FlyOptions::new(&connect, rehearsal());
    options.speed = Speed::Times(10.0);
    // Stay on the ground after landing: only the shutdown ends this flight.
    options.linger = None;
    let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
    let flight = tokio::spawn(fly(
        options,
        async {
            let _ = stopped.await;
        },
        (),
    ));
    // The drone is on the air once its first frame arrives.
    let mut buf = [0_u8; 512];
    let n = timeout(Duration::from_secs(20), station.recv(&mut buf))
        .await
        .expect("the drone sends")
        .expect("recv");
    assert!(n > 0 && buf[0] == 0xFD, "a MAVLink 2 frame");
    stop.send(()).expect("flight running");
    let report = timeout(Duration::from_secs(20), flight)
        .await
        .expect("fly returns after the shutdown")
        .expect("task")
        .expect("flight");
    assert!(report.interrupted);
    assert!(!report.landed, "stopped long before the landing");
    assert!(report.mission.mission_time_s < 100.0);
    assert!(report.io.tx_bytes > 0);
}

/// Records every step report.
#[derive(Clone, Default)]
struct Steps(Arc<Mutex<Vec<StepReport>>>);

impl FlightObserver for Steps {
    fn step(&mut self, report: &StepReport) {
        self.0.lock().expect("steps").push(*report);
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn each_step_reports_the_attitude_it_sent_and_queries_read_the_drone_between_steps() {
    let (_station, connect) = station().await;
    let mut options = FlyOptions::new(&connect, rehearsal());
    options.speed = Speed::Times(20.0);
    options.linger = None;
    let flight = Flight::start(options).await.expect("on the air");
    let handle = flight.handle();
    let steps = Steps::default();
    let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
    let run = tokio::spawn(flight.run(
        async {
            let _ = stopped.await;
        },
        steps.clone(),
    ));
    tokio::time::sleep(Duration::from_millis(500)).await;
    let time_s = handle
        .query(|d| d.drone().time_s())
        .await
        .expect("the drone answers while it flies");
    assert!(time_s > 0.0, "{time_s}");
    stop.send(()).expect("flight running");
    let report = timeout(Duration::from_secs(20), run)
        .await
        .expect("run returns")
        .expect("task")
        .expect("flight");
    assert!(handle.query(|d| d.drone().time_s()).await.is_none());
    let steps = steps.0.lock().expect("steps").clone();
    assert!(steps.len() >= 20, "{} steps", steps.len());
    // The AHRS runs at the control rate: every step sends one ATTITUDE, stamped with the
    // mission time of its sample, each stamp once, in order.
    let stamps: Vec<u32> = steps
        .iter()
        .filter_map(|s| s.attitude_time_boot_ms)
        .collect();
    assert!(stamps.len() + 2 >= steps.len(), "{stamps:?}");
    assert!(stamps.windows(2).all(|w| w[0] < w[1]), "{stamps:?}");
    let last = steps.last().expect("steps");
    assert!(last.time_s <= report.mission.mission_time_s);
    assert!(
        steps
            .windows(2)
            .all(|w| w[0].finished_at <= w[1].finished_at)
    );
}

#[tokio::test]
async fn a_drone_that_cannot_be_built_is_refused_before_the_link_opens() {
    let mut mission = rehearsal();
    // The main-line limit beyond the vehicle's servo travel.
    mission.onboard.guidance.gains.main_line_limit_m = 1.0;
    let err = fly(
        FlyOptions::new("carrier-pigeon:1", mission),
        std::future::pending(),
        (),
    )
    .await
    .expect_err("refused");
    assert!(matches!(err, FlyError::Drone { .. }), "{err}");
    assert!(err.is_input());
    let err = fly(
        FlyOptions::new("carrier-pigeon:1", rehearsal()),
        std::future::pending(),
        (),
    )
    .await
    .expect_err("refused");
    assert!(matches!(err, FlyError::Open { .. }), "{err}");
    assert!(err.is_input());
}

/// `anemometer_to`: the ground anemometer by the target measures the mission's wind and sends
/// each report as one NMEA MWV datagram, counted in the flight's report.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_ground_anemometer_sends_the_mission_wind_as_mwv_datagrams() {
    let (_station, connect) = station().await;
    let receiver = UdpSocket::bind("127.0.0.1:0")
        .await
        .expect("anemometer's receiver");
    let mission = rehearsal();
    let mut options = FlyOptions::new(&connect, mission.clone());
    // The first report comes 10 to 15 s of mission time in: a fraction of a second at max.
    options.speed = Speed::Max;
    options.linger = None;
    options.anemometer_to = Some(receiver.local_addr().expect("bound"));
    let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
    let flight = tokio::spawn(fly(
        options,
        async {
            let _ = stopped.await;
        },
        (),
    ));
    let mut buf = [0_u8; 256];
    let n = timeout(Duration::from_secs(20), receiver.recv(&mut buf))
        .await
        .expect("the anemometer sends")
        .expect("recv");
    stop.send(()).expect("flight running");
    let report = timeout(Duration::from_secs(20), flight)
        .await
        .expect("fly returns after the shutdown")
        .expect("task")
        .expect("flight");
    let counters = report.anemometer.expect("the anemometer was on");
    assert!(
        counters.sent >= 1 && counters.send_errors == 0,
        "{counters:?}"
    );

    // One sentence a datagram, as an NMEA line ends.
    let line = std::str::from_utf8(&buf[..n]).expect("ASCII");
    assert!(line.starts_with("$WIMWV,"), "{line:?}");
    assert_eq!(line.matches("\r\n").count(), 1, "{line:?}");
    assert!(line.ends_with("\r\n"), "{line:?}");
    let reading = parse_mwv(line).expect(line);
    assert_eq!(reading.reference, MwvReference::True);

    // What the mission's mean wind (no gusts) is at the top of the 10-m mast by the target.
    let wind = mission.wind.as_ref().expect("the rehearsal has a wind");
    let MeanWindConfig::Profile { rows } = &wind.mean else {
        panic!("the rehearsal's wind is a profile");
    };
    let mean = WindConfig {
        mean: wind.mean.clone(),
        turbulence: None,
    }
    .build()
    .expect("the mission's wind builds");
    let target = mission.target_ned_m().expect("the rehearsal has a target");
    let w = mean.wind_ned_mps(0.0, &Vector3::new(target.x, target.y, -10.0));
    let mean_from_deg = (-w.y).atan2(-w.x).to_degrees().rem_euclid(360.0);
    assert!(w.x.hypot(w.y) > 1.0, "a wind with a direction to compare");

    // Speed: within the profile's speeds, widened by the instrument's calibration (clamped
    // at 3 σ = 15 %) and 0.7 m/s, 3 σ of its report noise (0.1 m/s) and the gusts (0.2 m/s)
    // together.
    let (slowest, fastest) = rows.iter().fold((f64::INFINITY, 0.0_f64), |(lo, hi), r| {
        (lo.min(r[1]), hi.max(r[1]))
    });
    let speed = reading.speed_mps;
    assert!(
        (0.85 * slowest - 0.7..=1.15 * fastest + 0.7).contains(&speed),
        "{speed} m/s outside {slowest}..{fastest} m/s and the instrument's errors: {line:?}"
    );
    // Direction: within 30° of the mean wind's: the vane's bias is at most 15° (clamped at
    // 3 σ of 5°) and gusts of 0.2 m/s across a 2 m/s wind swing a 10-s mean by a few degrees,
    // 15° being more than 2 σ of their swing before any averaging.
    let apart = (reading.from_deg - mean_from_deg).rem_euclid(360.0);
    let apart = apart.min(360.0 - apart);
    assert!(
        apart <= 30.0,
        "from {:.1}° vs the mean wind's {mean_from_deg:.1}°: {line:?}",
        reading.from_deg
    );
}
