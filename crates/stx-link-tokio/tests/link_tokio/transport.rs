//! Loopback-only tests of the tokio adapters: a ground and a vehicle endpoint driven over real
//! UDP and TCP sockets on 127.0.0.1 and over a pseudo-terminal pair.

use std::time::Duration;

use stx_link::command::{Command, CommandOutcome, CommandResult, RequestId};
use stx_link::endpoint::{
    GroundConfig, GroundEndpoint, GroundEvent, LinkConfig, VehicleConfig, VehicleEndpoint,
    VehicleEvent,
};
use stx_link::param::{ParamEvent, ParamSpec};
use stx_link::sansio::IoEvent;
use stx_link_tokio::{
    Action, DriveOptions, DriverEvent, IO_ERROR_REPORT_INTERVAL, Transport, TransportError, drive,
};
use tokio::sync::mpsc;
use tokio::task::JoinHandle;

fn fast(mut link: LinkConfig) -> LinkConfig {
    link.heartbeat_period = Duration::from_millis(100);
    link.link_timeout = Duration::from_millis(500);
    link
}

struct Driven<E: stx_link::sansio::SansIo> {
    actions: mpsc::Sender<Action<E>>,
    events: mpsc::Receiver<DriverEvent<E::Event>>,
    task: JoinHandle<(E, stx_link::sansio::IoStats)>,
}

fn spawn<E: stx_link::sansio::SansIo>(transport: Transport, endpoint: E) -> Driven<E> {
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
        matches!(
            e,
            DriverEvent::Io {
                event: IoEvent::QueuedWithoutPeer { .. },
                ..
            }
        )
    })
    .await;

    let v = Transport::open_str(&format!("udpout:127.0.0.1:{port}"))
        .await
        .expect("udpout");
    let (v_actions, v_app) = vehicle_app(spawn(v, vehicle()));

    wait_for(&mut g.events, |e| {
        matches!(
            e,
            DriverEvent::Io {
                event: IoEvent::PeerChanged { .. },
                ..
            }
        )
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
        matches!(
            e,
            DriverEvent::Io {
                event: IoEvent::Connected { .. },
                ..
            }
        )
    })
    .await;
    drop(client);
    wait_for(&mut vd.events, |e| {
        matches!(
            e,
            DriverEvent::Io {
                event: IoEvent::Disconnected { .. },
                ..
            }
        )
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
        if matches!(
            e,
            DriverEvent::Io {
                event: IoEvent::QueuedWithoutPeer { .. },
                ..
            }
        ) {
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
        stx_link::signing::persist::load_signing_timestamp(&path).expect("read"),
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
    let stored = stx_link::signing::persist::load_signing_timestamp(&path)
        .expect("read")
        .expect("written");
    // 2026-01-01 is 347 155 200 s = 34 715 520 000 000 units of 10 µs after 2015-01-01; the
    // mark reserves 10 s (1 000 000 units) ahead of the first timestamp.
    assert_eq!(stored, 34_715_520_000_000 - 1 + 1_000_000);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Regression: every frame sent with no TCP peer (a `tcpin:` link before the station connects)
/// logged a warning and raised an event — 66,761 lines in 1.2 s from `stx drone`. Every failure
/// is still counted; reports come first at once, then one per interval with the total.
#[tokio::test(start_paused = true)]
async fn send_errors_without_a_peer_are_all_counted_but_reported_rate_limited() {
    let mut t = Transport::open_str("tcpin:127.0.0.1:0")
        .await
        .expect("bind");
    let frame = [0xFD_u8; 20];
    let reports = |t: &mut Transport| {
        let mut counts = Vec::new();
        while let Some(e) = t.poll_event() {
            if let IoEvent::SendError { count, .. } = e {
                counts.push(count);
            }
        }
        counts
    };
    for _ in 0..10_000 {
        t.send(&frame).await;
    }
    assert_eq!(t.stats().send_errors, 10_000);
    assert_eq!(reports(&mut t), [1], "the first failure, reported at once");
    tokio::time::advance(IO_ERROR_REPORT_INTERVAL / 2).await;
    t.send(&frame).await;
    assert!(reports(&mut t).is_empty(), "not before the interval");
    tokio::time::advance(IO_ERROR_REPORT_INTERVAL / 2).await;
    t.send(&frame).await;
    assert_eq!(reports(&mut t), [10_002], "one report with the total");
    assert_eq!(t.stats().send_errors, 10_002);
}

#[tokio::test]
async fn the_bound_port_of_a_server_address_with_port_0_is_known() {
    for address in ["udpin:127.0.0.1:0", "tcpin:127.0.0.1:0"] {
        let t = Transport::open_str(address).await.expect("bind");
        let bound = t.listening_address().expect("a server");
        let text = bound.to_string();
        assert!(text.starts_with(&address[..address.len() - 1]), "{text}");
        assert!(!text.ends_with(":0"), "{text}");
        assert_eq!(
            t.local_addr().map(|a| a.port()),
            text.rsplit(':').next().and_then(|p| p.parse().ok())
        );
    }
    let t = Transport::open_str("udpout:127.0.0.1:9")
        .await
        .expect("bind");
    assert_eq!(t.listening_address(), None);
}

/// Regression: a TCP connection that dropped mid-frame left the partial frame uncounted.
#[tokio::test]
async fn a_frame_cut_off_by_a_dropped_tcp_connection_is_counted_as_truncated() {
    use tokio::io::AsyncWriteExt;
    let t = Transport::open_str("tcpin:127.0.0.1:0")
        .await
        .expect("bind");
    let port = t.local_addr().expect("bound").port();
    let mut v = spawn(t, vehicle());
    let mut client = tokio::net::TcpStream::connect(("127.0.0.1", port))
        .await
        .expect("connect");
    wait_for(&mut v.events, |e| {
        matches!(
            e,
            DriverEvent::Io {
                event: IoEvent::Connected { .. },
                ..
            }
        )
    })
    .await;
    // A whole frame and half of a second one, then the connection drops.
    let mut ground = ground();
    let heartbeat = stx_link::MavMessage::HEARTBEAT(Default::default());
    ground.send_message(Duration::ZERO, &heartbeat);
    ground.send_message(Duration::ZERO, &heartbeat);
    let mut bytes = ground.poll_transmit(Duration::ZERO).expect("a frame");
    let whole = bytes.len();
    let second = ground.poll_transmit(Duration::ZERO).expect("a frame");
    bytes.extend(&second[..second.len() / 2]);
    client.write_all(&bytes).await.expect("write");
    drop(client);
    wait_for(&mut v.events, |e| {
        matches!(
            e,
            DriverEvent::Io {
                event: IoEvent::Disconnected { .. },
                ..
            }
        )
    })
    .await;
    drop(v.actions);
    let (endpoint, _) = v.task.await.expect("driver");
    let mut endpoint = endpoint;
    let stats = endpoint.link_stats(Duration::from_secs(1));
    assert!(whole > 0 && stats.frames_in >= 1, "{stats:?}");
    assert_eq!(stats.decoder.truncated, 1, "{:?}", stats.decoder);
    assert_eq!(
        stats.decoder.bytes_in,
        stats.decoder.bytes_discarded + (whole as u64),
        "every byte accounted for"
    );
}

/// Each write to a [`WatchingStream`]: the signing mark on disk at that moment, the bytes.
type Writes = std::sync::Arc<std::sync::Mutex<Vec<(Option<u64>, Vec<u8>)>>>;

/// A byte stream standing for a radio: it never delivers anything, and for each write it
/// notes the bytes and the signing mark on disk at that moment.
struct WatchingStream {
    file: Option<std::path::PathBuf>,
    writes: Writes,
}

impl tokio::io::AsyncRead for WatchingStream {
    fn poll_read(
        self: std::pin::Pin<&mut Self>,
        _: &mut std::task::Context<'_>,
        _: &mut tokio::io::ReadBuf<'_>,
    ) -> std::task::Poll<std::io::Result<()>> {
        std::task::Poll::Pending
    }
}

impl tokio::io::AsyncWrite for WatchingStream {
    fn poll_write(
        self: std::pin::Pin<&mut Self>,
        _: &mut std::task::Context<'_>,
        buf: &[u8],
    ) -> std::task::Poll<std::io::Result<usize>> {
        let mark = self
            .file
            .as_deref()
            .and_then(|f| stx_link::signing::persist::load_signing_timestamp(f).expect("readable"));
        self.writes.lock().expect("lock").push((mark, buf.to_vec()));
        std::task::Poll::Ready(Ok(buf.len()))
    }

    fn poll_flush(
        self: std::pin::Pin<&mut Self>,
        _: &mut std::task::Context<'_>,
    ) -> std::task::Poll<std::io::Result<()>> {
        std::task::Poll::Ready(Ok(()))
    }

    fn poll_shutdown(
        self: std::pin::Pin<&mut Self>,
        _: &mut std::task::Context<'_>,
    ) -> std::task::Poll<std::io::Result<()>> {
        std::task::Poll::Ready(Ok(()))
    }
}

/// The signing timestamp across a restart with the wall clock set back an hour, through the
/// real driver and file. Regression: the driver sent frames before writing the high-water mark
/// that covered them, so a crash could leave timestamps on the air above the mark on disk.
/// Now every frame leaves with a mark above its timestamp already on disk, and the restarted
/// endpoint signs above every timestamp the first run used. Without the file (the control
/// case) the restart's timestamps fall back with the clock.
#[tokio::test(start_paused = true)]
async fn signed_timestamps_stay_monotonic_across_a_restart_with_the_clock_set_back() {
    use stx_link::frame::FrameDecoder;
    use stx_link::signing::{SigningConfig, SigningKey};
    let dir = std::env::temp_dir().join(format!("stx-link-restart-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("tmp dir");
    let jan_2026 = Duration::from_secs(1_767_225_600);

    // Runs a signed vehicle for 30 s; returns each frame's timestamp with the mark on disk
    // when it was written to the stream.
    let run = |unix: Duration, file: Option<std::path::PathBuf>| async move {
        let persisted = file
            .as_deref()
            .and_then(|f| stx_link::signing::persist::load_signing_timestamp(f).expect("readable"));
        let signing = SigningConfig::new(SigningKey::from_bytes([5; 32]), 0, unix)
            .with_persisted_timestamp(persisted);
        let ep = VehicleEndpoint::new(
            VehicleConfig {
                link: fast(LinkConfig::vehicle()).with_signing(Some(signing)),
                ..Default::default()
            },
            Duration::ZERO,
        )
        .expect("vehicle");
        let writes = Writes::default();
        let stream = WatchingStream {
            file: file.clone(),
            writes: std::sync::Arc::clone(&writes),
        };
        let (atx, arx) = mpsc::channel::<Action<VehicleEndpoint>>(1);
        let (etx, mut erx) = mpsc::channel(1024);
        let task = tokio::spawn(drive(
            Transport::from_stream("radio", stream),
            ep,
            arx,
            etx,
            DriveOptions {
                signing_timestamp_file: file,
            },
        ));
        let drain = tokio::spawn(async move { while erx.recv().await.is_some() {} });
        tokio::time::sleep(Duration::from_secs(30)).await;
        drop(atx);
        let _ = task.await;
        let _ = drain.await;
        let writes = std::mem::take(&mut *writes.lock().expect("lock"));
        writes
            .into_iter()
            .flat_map(|(mark, bytes)| {
                let mut dec = FrameDecoder::default();
                dec.push(&bytes);
                let mut stamps = Vec::new();
                while let Some(Ok(f)) = dec.poll(Duration::ZERO) {
                    stamps.push((f.header.signature.expect("signed").timestamp_10us, mark));
                }
                stamps
            })
            .collect::<Vec<_>>()
    };

    for with_file in [true, false] {
        let file = with_file.then(|| dir.join(format!("ts-{with_file}")));
        let first = run(jan_2026, file.clone()).await;
        assert!(first.len() > 200, "{} frames", first.len());
        assert!(first.windows(2).all(|w| w[0].0 < w[1].0));
        if with_file {
            for (ts, mark) in &first {
                assert!(
                    mark.is_some_and(|m| m > *ts),
                    "frame {ts} left with mark {mark:?} on disk"
                );
            }
        }
        let last = first.last().expect("frames").0;
        let second = run(jan_2026 - Duration::from_secs(3600), file).await;
        let restart = second.first().expect("frames after the restart").0;
        if with_file {
            assert!(
                restart > last,
                "after the restart {restart} <= before {last}"
            );
        } else {
            assert!(
                restart < last,
                "control: the clock set back takes the timestamps back"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
