//! `stx drone` against MAVProxy 1.8.75 (from PyPI), a ground station nobody here wrote, driven
//! through its command line as an operator would: it sees the vehicle, fetches the parameters,
//! sets one and reads it back, has a fraction refused with the reason where only whole numbers
//! go, changes the mode, and reads the health of what the drone
//! reports — with no false alarm on the way.
//!
//! Regression (issue 17 item 2): connecting MAVProxy announced "fence breach" at once, because
//! SYS_STATUS left the health bit of a geofence the drone does not have clear.
//!
//! Python: `$STX_PYTHON` or `.venv/bin/python` at the workspace root, with MAVProxy installed
//! (`tests/run-all` does both).

use std::net::UdpSocket;
use std::process::{Command, Stdio};

use crate::common::mavproxy::{Console, Killed};

#[test]
fn mavproxy_fetches_sets_parameters_changes_mode_and_raises_no_false_alarm() {
    let port = UdpSocket::bind("127.0.0.1:0")
        .and_then(|s| s.local_addr())
        .expect("a free port")
        .port();
    let work = std::env::temp_dir().join(format!("stx-mavproxy-{}", std::process::id()));
    std::fs::create_dir_all(&work).expect("work dir");
    let mut c = Console::start(&format!("udpin:127.0.0.1:{port}"), &work);
    let _drone = Killed(
        Command::new(env!("CARGO_BIN_EXE_stx"))
            .args(["drone", "--scenario", "rehearsal", "--speed", "1"])
            .arg("--connect")
            .arg(format!("udpout:127.0.0.1:{port}"))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("stx drone starts"),
    );
    c.wait_for(30, "the vehicle online", |l| l.contains("online system 1"));
    c.send("param fetch");
    let received = c.wait_for(60, "the parameters received", |l| {
        l.contains("Received") && l.contains("parameters")
    });
    let count: usize = received
        .split_whitespace()
        .find_map(|w| w.parse().ok())
        .unwrap_or(0);
    assert!(count >= 20, "{received}");

    c.send("param set SP_FLARE_H 7");
    c.drain(2);
    c.send("param show SP_FLARE_H");
    c.wait_for(10, "SP_FLARE_H read back as 7", |l| {
        let mut words = l
            .split_whitespace()
            .skip_while(|w| !w.ends_with("SP_FLARE_H"));
        words.nth(1).and_then(|v| v.parse::<f64>().ok()) == Some(7.0)
    });

    // A choice takes whole numbers: a fraction is refused, and the drone says why.
    c.send("param set FS_GPS_ACTION 1.05");
    c.wait_for(10, "the refusal of 1.05 explained", |l| {
        l.contains("FS_GPS_ACTION") && l.contains("whole numbers")
    });

    // Heading mode (custom mode 2) through COMMAND_LONG DO_SET_MODE: MAVProxy has no names for
    // a parafoil's modes, so the operator gives the number.
    c.send("long DO_SET_MODE 1 2");
    c.wait_for(10, "the mode change accepted", |l| {
        l.contains("DO_SET_MODE") && l.contains("ACCEPTED")
    });

    c.send("status SYS_STATUS");
    let status = c.wait_for(10, "SYS_STATUS", |l| {
        l.contains("onboard_control_sensors_health")
    });
    c.drain(3);
    let alarms: Vec<&String> = c
        .seen
        .iter()
        .filter(|l| {
            let l = l.to_lowercase();
            l.contains("breach") || l.contains("unhealthy") || l.contains("failsafe")
        })
        .collect();
    assert!(
        alarms.is_empty(),
        "false alarms: {alarms:?}\nSYS_STATUS: {status}\nall:\n{}",
        c.seen.join("\n")
    );
    let _ = std::fs::remove_dir_all(&work);
}
