//! Two radios to one drone: a relay stands for the pair (every datagram the drone sends goes
//! out on both, each radio's uplink reaches the drone) and can silence either radio.

use crate::common;

use std::net::SocketAddr;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use common::*;
use stx_gnc::mission::FlightMode;
use stx_link::command::Command;
use tokio::net::UdpSocket;

/// One radio of the relay: its socket towards the station, whether it works, and how many
/// datagrams it carried up to the drone.
struct Radio {
    up: AtomicBool,
    uplinked: AtomicU64,
}

struct Relay {
    /// Where the drone sends.
    drone_side: SocketAddr,
    radios: [Arc<Radio>; 2],
}

async fn relay(station_radios: [SocketAddr; 2]) -> Relay {
    let drone_socket = Arc::new(UdpSocket::bind("127.0.0.1:0").await.expect("bind"));
    let drone_side = drone_socket.local_addr().expect("address");
    let drone_peer = Arc::new(tokio::sync::Mutex::new(None::<SocketAddr>));
    let radios = [0, 1].map(|_| {
        Arc::new(Radio {
            up: AtomicBool::new(true),
            uplinked: AtomicU64::new(0),
        })
    });
    let mut sockets = Vec::new();
    for (radio, station) in radios.iter().zip(station_radios) {
        let socket = Arc::new(UdpSocket::bind("127.0.0.1:0").await.expect("bind"));
        socket.connect(station).await.expect("connect");
        sockets.push(socket.clone());
        // Station → drone over this radio.
        let (radio, drone_socket, drone_peer) =
            (radio.clone(), drone_socket.clone(), drone_peer.clone());
        tokio::spawn(async move {
            let mut buf = vec![0_u8; 2048];
            while let Ok(n) = socket.recv(&mut buf).await {
                let peer = *drone_peer.lock().await;
                if let (true, Some(peer)) = (radio.up.load(Ordering::SeqCst), peer) {
                    radio.uplinked.fetch_add(1, Ordering::SeqCst);
                    let _ = drone_socket.send_to(&buf[..n], peer).await;
                }
            }
        });
    }
    // Drone → station over every radio that works.
    let downlink_radios = radios.clone();
    tokio::spawn(async move {
        let mut buf = vec![0_u8; 2048];
        while let Ok((n, from)) = drone_socket.recv_from(&mut buf).await {
            *drone_peer.lock().await = Some(from);
            for (radio, socket) in downlink_radios.iter().zip(&sockets) {
                if radio.up.load(Ordering::SeqCst) {
                    let _ = socket.send(&buf[..n]).await;
                }
            }
        }
    });
    Relay { drone_side, radios }
}

fn link_stats(station: &Station) -> stx_link::endpoint::LinkStats {
    station
        .running
        .shared
        .core
        .lock()
        .unwrap()
        .link_stats()
        .clone()
}

async fn set_mode(station: &Station, mode: &str) -> String {
    let (status, reply) = http(
        station.http(),
        "POST",
        "/api/commands/mode",
        Some(OPERATOR),
        Some(&format!(r#"{{"mode":"{mode}"}}"#)),
    )
    .await;
    assert_eq!(status, 202, "{reply}");
    reply["request_id"]
        .as_str()
        .expect("request id")
        .to_string()
}

#[tokio::test]
async fn with_two_radios_each_frame_is_taken_once_and_commands_go_round_a_silent_one() {
    let station = start_station(config(|c| {
        c.link.more_addresses = vec!["udpin:127.0.0.1:0".into()];
    }))
    .await;
    let locals = &station.running.link_locals;
    assert_eq!(locals.len(), 2, "one socket per radio");
    let relay = relay([locals[0].expect("radio 1"), locals[1].expect("radio 2")]).await;
    let drone = fake_drone(relay.drone_side).await;
    let mut ws = ws_connect(station.http(), OPERATOR).await;

    // Both radios carry the drone's heartbeats (5 Hz): every frame is heard twice and taken
    // once.
    let both = ws_until(&mut ws, 10.0, |m| {
        m["type"] == "state"
            && m["link"]["connected"] == true
            && m["link"]["radios"]
                .as_array()
                .is_some_and(|r| r.len() == 2 && r.iter().all(|r| r["stale"] == false))
    })
    .await
    .expect("both radios heard");
    assert_eq!(both["link"]["radios"][0]["transmitting"], true, "{both}");
    assert_eq!(both["link"]["radios"][1]["transmitting"], false, "{both}");
    for i in 0..20 {
        drone.send_attitude(i * 50, 0.1).await;
    }
    assert!(
        eventually(3.0, || link_stats(&station).duplicates_dropped >= 20).await,
        "{:?}",
        link_stats(&station)
    );
    let stats = link_stats(&station);
    let drone_stats = stats
        .senders
        .iter()
        .find(|s| s.system_id == 1)
        .expect("the drone's frames");
    assert_eq!(
        drone_stats.duplicates, 0,
        "no copy reached the merged stream: {stats:?}"
    );
    assert_eq!(drone_stats.lost, 0, "{stats:?}");
    let heard: u64 = stats.paths.iter().map(|p| p.frames_in).sum();
    assert_eq!(
        stats.frames_in + stats.duplicates_dropped,
        heard,
        "every frame heard is either taken or a dropped copy: {stats:?}"
    );
    assert!(
        stats.frames_in < heard * 6 / 10,
        "about half the frames heard were copies: {stats:?}"
    );

    // Commands go out on the primary while it is heard.
    let id = set_mode(&station, "heading").await;
    let result = command_result(&mut ws, &id).await;
    assert_eq!(result["outcome"], "accepted", "{result}");
    assert!(relay.radios[0].uplinked.load(Ordering::SeqCst) > 0);
    let uplinked_on_backup = relay.radios[1].uplinked.load(Ordering::SeqCst);
    assert_eq!(uplinked_on_backup, 0, "nothing went out on the backup");

    // The primary falls silent: the link stays up on the backup, which now carries the
    // commands, and the operators are told.
    relay.radios[0].up.store(false, Ordering::SeqCst);
    let switched = ws_until(&mut ws, 10.0, |m| {
        m["type"] == "state"
            && m["link"]["radios"][0]["stale"] == true
            && m["link"]["radios"][1]["transmitting"] == true
    })
    .await
    .expect("the backup takes over");
    assert_eq!(switched["link"]["connected"], true, "{switched}");
    assert_eq!(switched["link"]["stale"], false, "{switched}");
    let id = set_mode(&station, "spiral_landing").await;
    let result = command_result(&mut ws, &id).await;
    assert_eq!(result["outcome"], "accepted", "{result}");
    assert!(drone.seen(|s| {
        s.commands
            .contains(&Command::SetMode(FlightMode::SpiralLanding))
    }));
    assert!(relay.radios[1].uplinked.load(Ordering::SeqCst) > 0);
    let texts = event_texts(station.http()).await;
    assert!(
        texts
            .iter()
            .any(|t| t.starts_with("commands now go out on radio 2")),
        "the switch is in the event log: {texts:?}"
    );
    assert!(
        !texts.iter().any(|t| t.contains("link to the drone lost")),
        "the link never dropped: {texts:?}"
    );

    // The primary comes back and is preferred again.
    relay.radios[0].up.store(true, Ordering::SeqCst);
    let back = ws_until(&mut ws, 10.0, |m| {
        m["type"] == "state" && m["link"]["radios"][0]["transmitting"] == true
    })
    .await;
    assert!(back.is_some(), "the primary carries the commands again");
}
