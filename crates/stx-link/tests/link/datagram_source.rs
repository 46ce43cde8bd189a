//! A hostile sender's datagrams at the endpoints, without sockets (the transport's side is
//! tested in stx-link-tokio): which datagrams may move a UDP-in transport's peer (the verdicts
//! of `handle_datagram_on` on garbage, frames from other systems, split frames and, with
//! signing on, unsigned and badly signed frames), and that another system's frames are never
//! taken for the drone's.

use std::time::Duration;

use mavlink::dialects::common as mc;
use mavlink::dialects::common::MavMessage;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use stx_link::endpoint::{
    GroundConfig, GroundEndpoint, GroundEvent, LinkConfig, VehicleConfig, VehicleEndpoint,
};
use stx_link::frame::FrameEncoder;
use stx_link::signing::{SigningConfig, SigningKey};
use stx_link::telemetry::{Severity, Telemetry, split_status_text};

const T: Duration = Duration::ZERO;
const JAN_2026: Duration = Duration::from_secs(1_767_225_600);

fn heartbeat(mavtype: mc::MavType) -> MavMessage {
    MavMessage::HEARTBEAT(mc::HEARTBEAT_DATA {
        custom_mode: 0,
        mavtype,
        autopilot: mc::MavAutopilot::MAV_AUTOPILOT_GENERIC,
        base_mode: mc::MavModeFlag::empty(),
        system_status: mc::MavState::MAV_STATE_ACTIVE,
        mavlink_version: 3,
    })
}

/// The drone's status heartbeat, as stx drones send it.
fn drone_heartbeat() -> MavMessage {
    Telemetry::Status(VehicleConfig::default().initial_status).to_mavlink()
}

fn gcs_heartbeat() -> MavMessage {
    heartbeat(mc::MavType::MAV_TYPE_GCS)
}

fn frame(system_id: u8, message: &MavMessage) -> Vec<u8> {
    FrameEncoder::new(system_id, 1).encode(T, message)
}

fn garbage(rng: &mut ChaCha8Rng) -> Vec<u8> {
    let len = rng.random_range(1..300);
    (0..len).map(|_| rng.random::<u8>()).collect()
}

fn signing(key: u8) -> SigningConfig {
    SigningConfig::new(SigningKey::from_bytes([key; 32]), 0, JAN_2026)
}

fn ground(signing: Option<SigningConfig>) -> GroundEndpoint {
    GroundEndpoint::new(
        GroundConfig {
            link: LinkConfig::ground().with_signing(signing),
            ..Default::default()
        },
        T,
    )
}

#[test]
fn only_a_whole_frame_from_the_drone_s_system_vouches_for_a_datagram() {
    let mut g = ground(None);
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    for _ in 0..2_000 {
        assert!(!g.handle_datagram_on(0, T, &garbage(&mut rng)));
    }
    // Valid frames from another system, alone or after garbage.
    let other = frame(7, &drone_heartbeat());
    assert!(!g.handle_datagram_on(0, T, &other));
    let mut noisy = garbage(&mut rng);
    noisy.extend_from_slice(&other);
    assert!(!g.handle_datagram_on(0, T, &noisy));
    // The drone's own system with a corrupted checksum.
    let mut bad_crc = frame(1, &drone_heartbeat());
    let last = bad_crc.len() - 1;
    bad_crc[last] ^= 0x5a;
    assert!(!g.handle_datagram_on(0, T, &bad_crc));
    // The drone's frame, even among garbage and another system's frame.
    let good = frame(1, &drone_heartbeat());
    assert!(g.handle_datagram_on(0, T, &good));
    let mut mixed = garbage(&mut rng);
    mixed.extend_from_slice(&other);
    mixed.extend_from_slice(&good);
    assert!(g.handle_datagram_on(0, T, &mixed));
    assert!(g.is_connected(), "the drone's heartbeat was delivered");
}

/// A datagram cannot complete a frame another one began: otherwise a sender could push the
/// first half of a frame from the drone's system and claim the drone's address with a second
/// datagram (or hold back the drone's next datagram as the tail of its own fake header).
#[test]
fn a_frame_split_across_datagrams_is_truncated_not_joined() {
    let mut g = ground(None);
    let good = frame(1, &drone_heartbeat());
    let (head, tail) = good.split_at(good.len() / 2);
    assert!(!g.handle_datagram_on(0, T, head));
    assert!(!g.handle_datagram_on(0, T, tail));
    let stats = g.link_stats(T);
    assert_eq!(stats.frames_in, 0);
    assert!(stats.decoder.truncated >= 1, "{:?}", stats.decoder);
    // A header claiming 255 bytes of payload does not swallow the drone's next datagram.
    let mut fake_header = frame(1, &drone_heartbeat());
    fake_header.truncate(10);
    fake_header[1] = 255;
    assert!(!g.handle_datagram_on(0, T, &fake_header));
    assert!(g.handle_datagram_on(0, T, &good));
    assert_eq!(g.link_stats(T).frames_in, 1);
}

#[test]
fn with_signing_on_only_a_correctly_signed_frame_vouches_for_a_datagram() {
    let mut g = ground(Some(signing(3)));
    assert!(
        !g.handle_datagram_on(0, T, &frame(1, &drone_heartbeat())),
        "unsigned"
    );
    let mut forger = FrameEncoder::new(1, 1);
    forger.set_signer(Some(signing(4).build(T).0));
    assert!(
        !g.handle_datagram_on(0, T, &forger.encode(T, &drone_heartbeat())),
        "signed with another key"
    );
    let mut drone = FrameEncoder::new(1, 1);
    drone.set_signer(Some(signing(3).build(T).0));
    let signed = drone.encode(T, &drone_heartbeat());
    assert!(g.handle_datagram_on(0, T, &signed));
    assert!(
        !g.handle_datagram_on(0, T, &signed),
        "the same frame replayed"
    );
    assert!(g.handle_datagram_on(0, T, &drone.encode(T, &drone_heartbeat())));
}

#[test]
fn a_vehicle_follows_the_ground_station_it_serves() {
    let mut v = VehicleEndpoint::new(VehicleConfig::default(), T).expect("vehicle");
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    assert!(!v.handle_datagram_on(0, T, &garbage(&mut rng)));
    assert!(
        !v.handle_datagram_on(0, T, &frame(1, &drone_heartbeat())),
        "its own system id echoed back"
    );
    // Before any ground station announced itself, a tool's first command is answered.
    let ping = MavMessage::PARAM_REQUEST_LIST(mc::PARAM_REQUEST_LIST_DATA {
        target_system: 1,
        target_component: 1,
    });
    assert!(v.handle_datagram_on(0, T, &frame(200, &ping)));
    // Station 255 announces itself: from now on it is the one served.
    assert!(v.handle_datagram_on(0, T, &frame(255, &gcs_heartbeat())));
    assert!(v.handle_datagram_on(0, T, &frame(255, &ping)));
    assert!(!v.handle_datagram_on(0, T, &frame(200, &ping)));
    assert!(!v.handle_datagram_on(0, T, &frame(7, &drone_heartbeat())));
    assert!(!v.handle_datagram_on(0, T, &garbage(&mut rng)));
    // Another ground station announcing itself is served in turn.
    assert!(v.handle_datagram_on(0, T, &frame(254, &gcs_heartbeat())));
    assert!(v.handle_datagram_on(0, T, &frame(254, &ping)));
    assert!(!v.handle_datagram_on(0, T, &frame(255, &ping)));
}

/// Regression: the station read any system's HEARTBEAT and STATUSTEXT as the drone's, so a
/// sender of another system's frames changed the mode and texts the operators saw.
#[test]
fn another_system_s_frames_are_never_the_drone_s_telemetry() {
    let mut g = ground(None);
    let text = split_status_text(Severity::Critical, "cutdown fired", 1)
        .into_iter()
        .map(|chunk| Telemetry::StatusText(chunk).to_mavlink())
        .next()
        .expect("one chunk");
    for message in [drone_heartbeat(), text] {
        g.handle_datagram_on(0, T, &frame(7, &message));
        let mut events = Vec::new();
        while let Some(e) = g.poll_event() {
            events.push(e);
        }
        assert!(
            matches!(&events[..], [GroundEvent::Other(f)] if f.header.system_id == 7),
            "{events:?}"
        );
    }
    assert!(
        !g.is_connected(),
        "another system's heartbeat is not the drone's"
    );
    g.handle_datagram_on(0, T, &frame(1, &drone_heartbeat()));
    let mut telemetry = 0;
    while let Some(e) = g.poll_event() {
        telemetry += usize::from(matches!(e, GroundEvent::Telemetry { from: (1, 1), .. }));
    }
    assert_eq!(telemetry, 1);
    assert!(g.is_connected());
}
