//! Read-only forwarding (`[[forward]]`) against MAVProxy 1.8.75, a ground station nobody here
//! wrote: `stx serve --sim` forwards its link to MAVProxy, which sees the drone's telemetry and
//! its parameters (the value the drone answers when the station's operator sets one);
//! MAVProxy's `param set` and mode change never reach the drone (the drone would answer a set
//! with the new value, and report a new mode in its heartbeat: the station hears both), and
//! the station counts what it kept back. With an `in` allow list naming them, the same set
//! does reach the drone (tried by hand when this was written: the test then fails).

use std::time::{Duration, Instant};

use serde_json::Value;

use crate::common::mavproxy::Console;
use crate::common::station::{Station, free_udp_port};
use crate::common::{request_json, temp_dir};

fn param(params: &Value, name: &str) -> Option<f64> {
    params["params"]
        .as_array()?
        .iter()
        .find(|p| p["name"] == name)?["value"]
        .as_f64()
}

#[test]
fn mavproxy_on_a_forward_sees_the_drone_and_cannot_command_it() {
    let port = free_udp_port();
    let dir = temp_dir("forward", "mavproxy");
    // The watcher first, so it hears the station's parameter fetch when the drone connects.
    let mut c = Console::start(&format!("udpin:127.0.0.1:{port}"), &dir);
    let station = Station::start(
        &dir,
        &format!("[[forward]]\nname = \"mavproxy\"\naddress = \"udpout:127.0.0.1:{port}\"\n"),
    );
    let (http, token) = (station.http.as_str(), station.token.as_str());
    let get = |path: &str| station.get(path);

    // It watches: the drone comes online, its attitude streams, and a parameter the drone
    // reports reaches MAVProxy's table.
    c.wait_for(30, "the vehicle online", |l| l.contains("online system 1"));
    let until = Instant::now() + Duration::from_secs(60);
    let params = loop {
        if let Some(p) = get("/api/params")
            && p["complete"] == true
        {
            break p;
        }
        assert!(
            Instant::now() < until,
            "the station never had the parameters"
        );
        std::thread::sleep(Duration::from_millis(300));
    };
    let shipped_flare = param(&params, "SP_FLARE_H").expect("SP_FLARE_H on the station");
    // The station's operator sets it; the drone's answer reaches MAVProxy's table.
    let flare = shipped_flare + 1.0;
    let set = request_json(
        http,
        token,
        "POST",
        "/api/params/SP_FLARE_H",
        &format!("{{\"value\":{flare}}}"),
    );
    assert!(set.is_some(), "the station takes the set");
    let until = Instant::now() + Duration::from_secs(15);
    while get("/api/params").and_then(|p| param(&p, "SP_FLARE_H")) != Some(flare) {
        assert!(
            Instant::now() < until,
            "the drone never answered the station's set"
        );
        std::thread::sleep(Duration::from_millis(200));
    }
    // Asked again each second: MAVProxy reads its console and the network on two threads, so
    // on a loaded machine the first `param show` may run before the drone's answer is in.
    // (`shown_param` reads its table's lines, not the drone's STATUSTEXT "… SP_FLARE_H = 7".)
    for _ in 0..15 {
        c.send("param show SP_FLARE_H");
        c.drain(1);
        if c.shown_param("SP_FLARE_H") == Some(flare) {
            break;
        }
    }
    assert_eq!(
        c.shown_param("SP_FLARE_H"),
        Some(flare),
        "{}",
        c.seen.join("\n")
    );
    c.send("status ATTITUDE");
    c.wait_for(10, "the drone's attitude", |l| l.contains("ATTITUDE"));

    // It cannot command: a parameter set and a mode change go nowhere.
    let mode_before = get("/api/state").expect("state")["vehicle"]["mode"].clone();
    assert!(
        mode_before.is_string(),
        "the drone's mode is known: {mode_before}"
    );
    c.send(&format!("param set SP_FLARE_H {}", flare + 3.0));
    c.send("long DO_SET_MODE 1 1");
    c.send("mode 1");
    c.drain(4);
    let after = get("/api/params").expect("params");
    assert_eq!(
        param(&after, "SP_FLARE_H"),
        Some(flare),
        "the drone's value is unchanged"
    );
    let mode_after = get("/api/state").expect("state")["vehicle"]["mode"].clone();
    assert_eq!(mode_after, mode_before, "the drone's mode is unchanged");
    let forwards = get("/api/sharing").expect("forwards");
    let f = &forwards["forwards"][0];
    assert_eq!(f["name"], "mavproxy");
    assert_eq!(f["may_send_to_drone"], serde_json::json!([]));
    assert_eq!(f["in_passed"], 0, "{forwards}");
    assert!(
        f["in_refused"].as_u64() >= Some(3),
        "the set, the command and heartbeats kept back: {forwards}"
    );
    assert!(f["out_passed"].as_u64() >= Some(100), "{forwards}");
    let _ = std::fs::remove_dir_all(&dir);
}
