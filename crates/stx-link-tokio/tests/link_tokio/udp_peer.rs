//! A `udpin:` station under a hostile sender on loopback: garbage, frames from another system
//! and (with signing on) unsigned, badly signed and replayed frames from a second socket must
//! not move the station's peer — its heartbeats and commands keep going to the drone — while
//! the drone's valid frame from a new port must.
//!
//! Regression: the transport answered whoever sent the last datagram, so random bytes from
//! another port flipped the peer many times a second and the uplink went to their sender.

use std::net::SocketAddr;
use std::time::Duration;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use stx_link::MavMessage;
use stx_link::command::{Command, RequestId};
use stx_link::endpoint::{GroundConfig, GroundEndpoint, LinkConfig, VehicleConfig};
use stx_link::frame::FrameEncoder;
use stx_link::sansio::{IoEvent, IoStats};
use stx_link::signing::{SigningConfig, SigningKey};
use stx_link::telemetry::Telemetry;
use stx_link_tokio::{Action, DriveOptions, DriverEvent, Transport, drive};
use tokio::net::UdpSocket;
use tokio::sync::{mpsc, oneshot};
use tokio::task::JoinHandle;
use tokio::time::timeout;

const COMMAND_LONG: u32 = 76;
const WAIT: Duration = Duration::from_secs(5);
const JAN_2026: Duration = Duration::from_secs(1_767_225_600);

/// A station's ground endpoint driven over `udpin:127.0.0.1:0`.
struct Station {
    address: SocketAddr,
    actions: mpsc::Sender<Action<GroundEndpoint>>,
    /// Every peer change, in order; all other events are drained.
    peers: mpsc::UnboundedReceiver<SocketAddr>,
    task: JoinHandle<(GroundEndpoint, IoStats)>,
}

impl Station {
    async fn start(signing: Option<SigningConfig>) -> Self {
        let mut link = LinkConfig::ground().with_signing(signing);
        link.heartbeat_period = Duration::from_millis(50);
        let endpoint = GroundEndpoint::new(
            GroundConfig {
                link,
                ..Default::default()
            },
            Duration::ZERO,
        );
        let transport = Transport::open_str("udpin:127.0.0.1:0")
            .await
            .expect("bind");
        let address = transport.local_addr().expect("bound");
        let (actions, actions_rx) = mpsc::channel(16);
        let (events_tx, mut events) = mpsc::channel(1024);
        let (peers_tx, peers) = mpsc::unbounded_channel();
        tokio::spawn(async move {
            while let Some(e) = events.recv().await {
                if let DriverEvent::Io {
                    event: IoEvent::PeerChanged { peer },
                    ..
                } = e
                {
                    let _ = peers_tx.send(peer);
                }
            }
        });
        let task = tokio::spawn(drive(
            transport,
            endpoint,
            actions_rx,
            events_tx,
            DriveOptions::default(),
        ));
        Self {
            address,
            actions,
            peers,
            task,
        }
    }

    async fn next_peer(&mut self) -> SocketAddr {
        timeout(WAIT, self.peers.recv())
            .await
            .expect("a peer change in time")
            .expect("driver alive")
    }

    /// Frames the station decoded so far (every datagram before them was handled, verdict
    /// included: the driver judges a datagram before it runs the next action).
    async fn frames_in(&self) -> u64 {
        let (tx, rx) = oneshot::channel();
        self.actions
            .send(Box::new(move |ep: &mut GroundEndpoint, now| {
                let _ = tx.send(ep.link_stats(now).frames_in);
            }))
            .await
            .expect("driver alive");
        rx.await.expect("answered")
    }

    async fn wait_frames_in(&self, expected: u64) {
        let deadline = tokio::time::Instant::now() + WAIT;
        loop {
            let n = self.frames_in().await;
            if n >= expected {
                assert_eq!(n, expected, "frames decoded");
                return;
            }
            assert!(
                tokio::time::Instant::now() < deadline,
                "only {n} of {expected} frames decoded"
            );
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
    }

    /// Sends `command` (nobody answers: each goes to a different MAV_CMD, so as not to be
    /// refused as busy).
    async fn send_command(&self, command: Command) {
        self.actions
            .send(Box::new(move |ep: &mut GroundEndpoint, now| {
                ep.send_command(now, RequestId(1), command).expect("sent");
            }))
            .await
            .expect("driver alive");
    }

    async fn stop(self) -> IoStats {
        drop(self.actions);
        self.task.await.expect("driver task").1
    }
}

async fn socket() -> UdpSocket {
    UdpSocket::bind("127.0.0.1:0").await.expect("bind")
}

/// The frames waiting on `socket` (one per datagram, as the station sends them).
fn received(socket: &UdpSocket) -> Vec<Vec<u8>> {
    let mut buf = [0_u8; 2048];
    let mut frames = Vec::new();
    while let Ok(n) = socket.try_recv(&mut buf) {
        frames.push(buf.get(..n).unwrap_or(&[]).to_vec());
    }
    frames
}

/// The first parameters of the COMMAND_LONGs among `frames` (retries included): the message
/// id of REQUEST_MESSAGE and SET_MESSAGE_INTERVAL, the heading of a heading hold.
fn commands(frames: &[Vec<u8>]) -> Vec<f32> {
    frames
        .iter()
        .filter(|f| f.get(7..10) == Some(&COMMAND_LONG.to_le_bytes()[..3]))
        .filter_map(|f| f.get(10..14))
        .map(|p| f32::from_le_bytes([p[0], p[1], p[2], p[3]]))
        .collect()
}

fn drone_heartbeat() -> MavMessage {
    Telemetry::Status(VehicleConfig::default().initial_status).to_mavlink()
}

fn garbage(rng: &mut ChaCha8Rng) -> Vec<u8> {
    let len = rng.random_range(1..280);
    (0..len).map(|_| rng.random::<u8>()).collect()
}

/// What the attacker sends: garbage, another system's valid frames and the drone's frame cut
/// in two datagrams. Returns (datagrams, valid frames among them).
async fn barrage(from: &UdpSocket, to: SocketAddr, rng: &mut ChaCha8Rng) -> (u64, u64) {
    let mut other = FrameEncoder::new(7, 1);
    let mut drone_copy = FrameEncoder::new(1, 1);
    let (mut datagrams, mut frames) = (0, 0);
    for i in 0..600 {
        let bytes = match i % 6 {
            0 => {
                frames += 1;
                other.encode(Duration::ZERO, &drone_heartbeat())
            }
            1 => {
                let whole = drone_copy.encode(Duration::ZERO, &drone_heartbeat());
                let (head, tail) = whole.split_at(whole.len() / 2);
                from.send_to(head, to).await.expect("send");
                datagrams += 1;
                tail.to_vec()
            }
            _ => garbage(rng),
        };
        from.send_to(&bytes, to).await.expect("send");
        datagrams += 1;
        if i % 50 == 0 {
            tokio::task::yield_now().await;
        }
    }
    (datagrams, frames)
}

#[tokio::test]
async fn garbage_and_other_systems_do_not_move_the_peer_but_the_drone_from_a_new_port_does() {
    let mut station = Station::start(None).await;
    let (drone, attacker, moved) = (socket().await, socket().await, socket().await);
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let mut encoder = FrameEncoder::new(1, 1);

    // First contact: the attacker is first, yet the peer is the drone.
    let (mut ignored, mut frames) = barrage(&attacker, station.address, &mut rng).await;
    drone
        .send_to(
            &encoder.encode(Duration::ZERO, &drone_heartbeat()),
            station.address,
        )
        .await
        .expect("send");
    frames += 1;
    assert_eq!(
        station.next_peer().await,
        drone.local_addr().expect("bound")
    );
    station.wait_frames_in(frames).await;

    // Under a second barrage, a command still reaches the drone.
    station
        .send_command(Command::RequestMessage { message_id: 33 })
        .await;
    let (d, f) = barrage(&attacker, station.address, &mut rng).await;
    station
        .send_command(Command::SetMessageInterval {
            message_id: 24,
            interval_us: 200_000,
        })
        .await;
    drone
        .send_to(
            &encoder.encode(Duration::ZERO, &drone_heartbeat()),
            station.address,
        )
        .await
        .expect("send");
    (ignored, frames) = (ignored + d, frames + f + 1);
    station.wait_frames_in(frames).await;
    tokio::time::sleep(Duration::from_millis(200)).await;
    assert!(
        station.peers.try_recv().is_err(),
        "the peer moved under the barrage"
    );
    let to_drone = commands(&received(&drone));
    assert!(
        to_drone.contains(&33.0) && to_drone.contains(&24.0),
        "both commands reached the drone: {to_drone:?}"
    );
    assert!(received(&attacker).is_empty(), "the attacker got frames");

    // The drone rebooted onto another port: its first frame moves the peer.
    moved
        .send_to(
            &encoder.encode(Duration::ZERO, &drone_heartbeat()),
            station.address,
        )
        .await
        .expect("send");
    assert_eq!(
        station.next_peer().await,
        moved.local_addr().expect("bound")
    );
    station
        .send_command(Command::HoldHeading { heading_deg: 30.0 })
        .await;
    let deadline = tokio::time::Instant::now() + WAIT;
    while !commands(&received(&moved)).contains(&30.0) {
        assert!(
            tokio::time::Instant::now() < deadline,
            "no command at the new port"
        );
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    assert!(received(&attacker).is_empty());

    let io = station.stop().await;
    assert_eq!(io.ignored_datagrams, ignored);
}

#[tokio::test]
async fn with_signing_on_unsigned_badly_signed_and_replayed_frames_do_not_move_the_peer() {
    let key = |k| SigningConfig::new(SigningKey::from_bytes([k; 32]), 0, JAN_2026);
    let mut station = Station::start(Some(key(3))).await;
    let (drone, attacker, moved) = (socket().await, socket().await, socket().await);
    let mut signed = FrameEncoder::new(1, 1);
    signed.set_signer(Some(key(3).build(Duration::ZERO).0));
    let mut unsigned = FrameEncoder::new(1, 1);
    let mut forger = FrameEncoder::new(1, 1);
    forger.set_signer(Some(key(4).build(Duration::ZERO).0));

    let first = signed.encode(Duration::ZERO, &drone_heartbeat());
    drone.send_to(&first, station.address).await.expect("send");
    assert_eq!(
        station.next_peer().await,
        drone.local_addr().expect("bound")
    );
    station.wait_frames_in(1).await;

    let mut ignored = 0;
    for _ in 0..100 {
        for bytes in [
            unsigned.encode(Duration::ZERO, &drone_heartbeat()),
            forger.encode(Duration::ZERO, &drone_heartbeat()),
            first.clone(),
        ] {
            attacker
                .send_to(&bytes, station.address)
                .await
                .expect("send");
            ignored += 1;
        }
    }
    station
        .send_command(Command::RequestMessage { message_id: 33 })
        .await;
    drone
        .send_to(
            &signed.encode(Duration::ZERO, &drone_heartbeat()),
            station.address,
        )
        .await
        .expect("send");
    station.wait_frames_in(2).await;
    tokio::time::sleep(Duration::from_millis(200)).await;
    assert!(station.peers.try_recv().is_err(), "the peer moved");
    assert!(commands(&received(&drone)).contains(&33.0));
    assert!(received(&attacker).is_empty(), "the attacker got frames");

    moved
        .send_to(
            &signed.encode(Duration::ZERO, &drone_heartbeat()),
            station.address,
        )
        .await
        .expect("send");
    assert_eq!(
        station.next_peer().await,
        moved.local_addr().expect("bound")
    );
    let io = station.stop().await;
    assert_eq!(io.ignored_datagrams, ignored);
}
