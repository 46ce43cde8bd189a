//! Loopback-only tests of the tokio adapters: a ground and a vehicle endpoint driven over real
//! UDP and TCP sockets on 127.0.0.1 and over a pseudo-terminal pair.

use std::time::Duration;

use stx_link::command::{Command, CommandOutcome, CommandResult, RequestId};
use stx_link::endpoint::{
    GroundConfig, GroundEndpoint, GroundEvent, LinkConfig, VehicleConfig, VehicleEndpoint,
    VehicleEvent,
};
use stx_link::param::{ParamEvent, ParamSpec};
use stx_link::transport::{
    Action, DriveOptions, DriverEvent, IoEvent, Transport, TransportError, drive,
};
use tokio::sync::mpsc;
use tokio::task::JoinHandle;

fn fast(mut link: LinkConfig) -> LinkConfig {
    link.heartbeat_period = Duration::from_millis(100);
    link.link_timeout = Duration::from_millis(500);
    link
}

struct Driven<E: stx_link::transport::SansIo> {
    actions: mpsc::Sender<Action<E>>,
    events: mpsc::Receiver<DriverEvent<E::Event>>,
    task: JoinHandle<(E, stx_link::transport::IoStats)>,
}

fn spawn<E: stx_link::transport::SansIo>(transport: Transport, endpoint: E) -> Driven<E> {
    let (atx, arx) = mpsc::channel(16);
    let (etx, erx) = mpsc::channel(1024);
    let task = tokio::spawn(drive(
        transport,
        endpoint,
        arx,
        etx,
        DriveOptions::default(),
    ));
    Driven {
        actions: atx,
        events: erx,
        task,
    }
}

fn ground() -> GroundEndpoint {
    GroundEndpoint::new(
        GroundConfig {
            link: fast(LinkConfig::ground()),
            ..Default::default()
        },
        Duration::ZERO,
    )
}

fn vehicle() -> VehicleEndpoint {
    let params = vec![ParamSpec::new(
        "FLARE_ALT_M",
        8.0,
        0.0,
        50.0,
        "flare height, m",
    )];
    VehicleEndpoint::new(
        VehicleConfig {
            link: fast(LinkConfig::vehicle()),
            params,
            ..Default::default()
        },
        Duration::ZERO,
    )
    .expect("vehicle")
}

/// Runs the vehicle's application side: accepts every command.
fn vehicle_app(
    mut v: Driven<VehicleEndpoint>,
) -> (
    mpsc::Sender<Action<VehicleEndpoint>>,
    JoinHandle<Vec<DriverEvent<VehicleEvent>>>,
) {
    let actions = v.actions.clone();
    let handle = tokio::spawn(async move {
        let mut seen = Vec::new();
        while let Some(e) = v.events.recv().await {
            if let DriverEvent::Endpoint(VehicleEvent::Command(c)) = &e {
                let id = c.id;
                let _ = v
                    .actions
                    .send(Box::new(move |ep: &mut VehicleEndpoint, _| {
                        ep.respond_command(id, CommandResult::Accepted);
                    }))
                    .await;
            }
            seen.push(e);
        }
        seen
    });
    (actions, handle)
}

async fn wait_for<E: std::fmt::Debug>(
    events: &mut mpsc::Receiver<DriverEvent<E>>,
    pred: impl Fn(&DriverEvent<E>) -> bool,
) -> Vec<DriverEvent<E>> {
    let mut seen = Vec::new();
    let r = tokio::time::timeout(Duration::from_secs(5), async {
        while let Some(e) = events.recv().await {
            let hit = pred(&e);
            seen.push(e);
            if hit {
                return;
            }
        }
    })
    .await;
    assert!(r.is_ok(), "timed out; saw {seen:?}");
    seen
}

#[tokio::test]
async fn udp_in_and_out_carry_a_command_and_its_ack() {
    let g = Transport::open_str("udpin:127.0.0.1:0")
        .await
        .expect("bind");
    let port = g.local_addr().expect("addr").port();
    let mut g = spawn(g, ground());
    // The ground heartbeats before anyone was heard: queued, not silently dropped.
    wait_for(&mut g.events, |e| {
        matches!(e, DriverEvent::Io(IoEvent::QueuedWithoutPeer { .. }))
    })
    .await;

    let v = Transport::open_str(&format!("udpout:127.0.0.1:{port}"))
        .await
        .expect("udpout");
    let (v_actions, v_app) = vehicle_app(spawn(v, vehicle()));

    wait_for(&mut g.events, |e| {
        matches!(e, DriverEvent::Io(IoEvent::PeerChanged { .. }))
    })
    .await;
    g.actions
        .send(Box::new(|ep: &mut GroundEndpoint, now| {
            ep.send_command(now, RequestId(77), Command::Cutdown)
                .expect("sent");
        }))
        .await
        .expect("driver alive");
    let seen = wait_for(&mut g.events, |e| matches!(e, DriverEvent::Endpoint(GroundEvent::Command(c)) if c.request_id == RequestId(77))).await;
    let Some(DriverEvent::Endpoint(GroundEvent::Command(c))) = seen.last() else {
        panic!()
    };
    assert_eq!(c.outcome, CommandOutcome::Accepted);

    drop(g.actions);
    let (g_ep, g_io) = g.task.await.expect("ground task");
    assert!(g_io.queued_without_peer >= 1);
    assert!(g_io.rx_bytes > 0 && g_io.tx_bytes > 0);
    assert_eq!(g_io.recv_errors, 0);
    drop(g_ep);
    drop(v_actions);
    v_app.abort();
}

#[tokio::test]
async fn tcp_client_and_server_carry_a_param_read() {
    let v = Transport::open_str("tcpin:127.0.0.1:0")
        .await
        .expect("listen");
    let port = v.local_addr().expect("addr").port();
    let (_v_actions, v_app) = vehicle_app(spawn(v, vehicle()));
    let g = Transport::open_str(&format!("tcp:127.0.0.1:{port}"))
        .await
        .expect("connect");
    let mut g = spawn(g, ground());
    g.actions
        .send(Box::new(|ep: &mut GroundEndpoint, now| {
            ep.param_read(now, "FLARE_ALT_M").expect("read")
        }))
        .await
        .expect("driver alive");
    let seen = wait_for(&mut g.events, |e| {
        matches!(e, DriverEvent::Endpoint(GroundEvent::Param(_)))
    })
    .await;
    let Some(DriverEvent::Endpoint(GroundEvent::Param(ParamEvent::ReadDone { param }))) =
        seen.last()
    else {
        panic!("{seen:?}")
    };
    assert_eq!(param.value, 8.0);
    wait_for(&mut g.events, |e| {
        matches!(
            e,
            DriverEvent::Endpoint(GroundEvent::Link(
                stx_link::endpoint::LinkEvent::Connected { .. }
            ))
        )
    })
    .await;

    // The station goes away: the vehicle's server reports it, then loses the link.
    drop(g.actions);
    let _ = g.task.await;
    v_app.abort();
}

#[tokio::test]
async fn tcp_server_reports_client_leaving() {
    let v = Transport::open_str("tcpin:127.0.0.1:0")
        .await
        .expect("listen");
    let port = v.local_addr().expect("addr").port();
    let mut vd = spawn(v, vehicle());
    let client = tokio::net::TcpStream::connect(("127.0.0.1", port))
        .await
        .expect("connect");
    wait_for(&mut vd.events, |e| {
        matches!(e, DriverEvent::Io(IoEvent::Connected { .. }))
    })
    .await;
    drop(client);
    wait_for(&mut vd.events, |e| {
        matches!(e, DriverEvent::Io(IoEvent::Disconnected { .. }))
    })
    .await;
    drop(vd.actions);
    let (_, io) = vd.task.await.expect("task");
    assert_eq!(io.connects, 1);
}

#[tokio::test(start_paused = true)]
async fn udpin_without_peer_queues_every_send_and_counts_it() {
    let g = Transport::open_str("udpin:127.0.0.1:0")
        .await
        .expect("bind");
    let mut g = spawn(g, ground());
    // Paused clock: 1 s of heartbeats at 10 Hz, all queued.
    tokio::time::sleep(Duration::from_millis(1050)).await;
    drop(g.actions);
    let (_, io) = g.task.await.expect("task");
    assert_eq!(io.queued_without_peer, 11);
    assert_eq!(io.tx_bytes, 0);
    let mut queued = 0;
    while let Ok(e) = g.events.try_recv() {
        if matches!(e, DriverEvent::Io(IoEvent::QueuedWithoutPeer { .. })) {
            queued += 1;
        }
    }
    assert_eq!(queued, 11);
}

#[cfg(feature = "serial")]
#[tokio::test]
async fn serial_pty_pair_links_ground_and_vehicle() {
    let (master, slave) = match tokio_serial::SerialStream::pair() {
        Ok(p) => p,
        Err(e) => panic!("cannot create a pseudo-terminal pair here: {e}"),
    };
    let (_v_actions, v_app) =
        vehicle_app(spawn(Transport::from_stream("pty-slave", slave), vehicle()));
    let mut g = spawn(Transport::from_stream("pty-master", master), ground());
    g.actions
        .send(Box::new(|ep: &mut GroundEndpoint, now| {
            ep.send_command(now, RequestId(5), Command::Cutdown)
                .expect("sent")
        }))
        .await
        .expect("driver alive");
    let seen = wait_for(&mut g.events, |e| {
        matches!(e, DriverEvent::Endpoint(GroundEvent::Command(_)))
    })
    .await;
    assert!(
        matches!(seen.last(), Some(DriverEvent::Endpoint(GroundEvent::Command(c))) if c.outcome == CommandOutcome::Accepted)
    );
    drop(g.actions);
    let _ = g.task.await;
    v_app.abort();
}

/// `serial:PATH:BAUD` opened by path: the vehicle end of a pseudo-terminal pair.
#[cfg(feature = "serial")]
#[tokio::test]
async fn serial_address_opens_a_tty_by_path() {
    use tokio_serial::SerialPort;
    let (master, slave) = tokio_serial::SerialStream::pair().expect("pseudo-terminal pair");
    let path = slave.name().expect("pty has a path");
    let v = Transport::open_str(&format!("serial:{path}:57600"))
        .await
        .expect("open by path");
    let (_v_actions, v_app) = vehicle_app(spawn(v, vehicle()));
    let mut g = spawn(Transport::from_stream("pty-master", master), ground());
    let seen = wait_for(&mut g.events, |e| {
        matches!(
            e,
            DriverEvent::Endpoint(GroundEvent::Link(
                stx_link::endpoint::LinkEvent::Connected { system_id: 1, .. }
            ))
        )
    })
    .await;
    assert!(!seen.is_empty());
    drop(g.actions);
    let _ = g.task.await;
    drop(slave);
    v_app.abort();
}

#[tokio::test]
async fn opening_bad_addresses_fails_clearly() {
    let e = Transport::open_str("udpin:not-an-ip:1")
        .await
        .expect_err("must fail");
    assert!(matches!(e, TransportError::Address(_)), "{e}");
    let e = Transport::open_str("serial:/nonexistent/tty-stx:57600")
        .await
        .expect_err("must fail");
    assert!(e.to_string().contains("/nonexistent/tty-stx"), "{e}");
}

#[tokio::test]
async fn signing_timestamp_file_is_written_and_read_back() {
    let dir = std::env::temp_dir().join(format!("stx-link-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("tmp dir");
    let path = dir.join("signing_ts");
    let _ = std::fs::remove_file(&path);
    assert_eq!(
        stx_link::transport::load_signing_timestamp(&path).expect("read"),
        None
    );
    let key = stx_link::signing::SigningKey::from_bytes([3; 32]);
    let signing = stx_link::signing::SigningConfig::new(key, 0, Duration::from_secs(1_767_225_600));
    let ep = GroundEndpoint::new(
        GroundConfig {
            link: fast(LinkConfig::ground()).with_signing(Some(signing)),
            ..Default::default()
        },
        Duration::ZERO,
    );
    let t = Transport::open_str("udpin:127.0.0.1:0")
        .await
        .expect("bind");
    let (atx, arx) = mpsc::channel::<Action<GroundEndpoint>>(1);
    let (etx, mut erx) = mpsc::channel(1024);
    let task = tokio::spawn(drive(
        t,
        ep,
        arx,
        etx,
        DriveOptions {
            signing_timestamp_file: Some(path.clone()),
        },
    ));
    wait_for(&mut erx, |e| {
        matches!(
            e,
            DriverEvent::Endpoint(GroundEvent::Link(
                stx_link::endpoint::LinkEvent::PersistSigningTimestamp(_)
            ))
        )
    })
    .await;
    drop(atx);
    let _ = task.await;
    let stored = stx_link::transport::load_signing_timestamp(&path)
        .expect("read")
        .expect("written");
    // 2026-01-01 is 347 155 200 s = 34 715 520 000 000 units of 10 µs after 2015-01-01; the
    // mark reserves 10 s (1 000 000 units) ahead of the first timestamp.
    assert_eq!(stored, 34_715_520_000_000 - 1 + 1_000_000);
    let _ = std::fs::remove_dir_all(&dir);
}
