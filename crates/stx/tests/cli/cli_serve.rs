//! `stx serve` from the outside: it starts, prints where to look, answers, and stops cleanly on
//! SIGTERM; a bad configuration is refused with exit code 2.

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::common::{banner, get, get_value, serve, sigterm, spawn_serve};

#[test]
fn serve_prints_its_url_answers_and_stops_on_sigterm() {
    let mut child = spawn_serve(&["--listen", "127.0.0.1:0", "--link", "udpin:127.0.0.1:0"]);
    let line = banner(&mut child);
    // "stx station: open http://127.0.0.1:PORT/?token=TOKEN"
    let url = line.trim().rsplit(' ').next().expect("a URL").to_string();
    let rest = url.strip_prefix("http://").expect("http URL");
    let (address, query) = rest.split_once("/?token=").expect("address and token");
    let session = get(address, "/api/session", query);
    assert!(session.starts_with("HTTP/1.1 200"), "{session}");
    assert!(session.contains(r#""role":"operator""#), "{session}");

    sigterm(&child);
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        if let Some(status) = child.try_wait().expect("wait") {
            assert!(status.success(), "exit after SIGTERM: {status}");
            break;
        }
        assert!(
            Instant::now() < deadline,
            "stx serve did not stop on SIGTERM"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn a_bad_station_config_exits_2_and_names_the_field() {
    let dir = std::env::temp_dir().join(format!("stx-cli-serve-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let path = dir.join("station.toml");
    let shipped = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../config/station.toml"
    ))
    .expect("shipped config");
    std::fs::write(
        &path,
        shipped.replace("cutdown_window_s = 5.0", "cutdown_window_s = -1.0"),
    )
    .expect("write");
    let out = Command::new(env!("CARGO_BIN_EXE_stx"))
        .args(["serve", "--config", path.to_str().expect("utf-8 path")])
        .output()
        .expect("stx runs");
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("cutdown_window_s"), "{stderr}");
    let missing = Command::new(env!("CARGO_BIN_EXE_stx"))
        .args(["serve", "--config", "/nonexistent/station.toml"])
        .output()
        .expect("stx runs");
    assert_eq!(missing.status.code(), Some(2));
}

/// Regression: `stx serve --listen 0.0.0.0:8140` with the shipped config started without a
/// word and printed `?token=operator-token`, which anyone on the field's Wi-Fi who had read the
/// README could use to cut the payload down, over plain HTTP. 127.0.0.2 stands for the field
/// network (the test switch `STX_TEST_NOT_LOOPBACK`).
#[test]
fn beyond_loopback_the_rehearsal_tokens_and_plain_http_are_refused_with_exit_2() {
    let serve_on_the_field = |config: Option<&std::path::Path>, more: &[&str]| {
        let mut command = Command::new(env!("CARGO_BIN_EXE_stx"));
        command
            .args(["serve", "--no-record", "--listen", "127.0.0.2:0"])
            .args(["--link", "udpin:127.0.0.1:0"])
            .args(more)
            .env(stx_station::exposure::NOT_LOOPBACK_ENV, "127.0.0.2");
        if let Some(config) = config {
            command.arg("--config").arg(config);
        }
        command
    };
    for more in [&[][..], &["--insecure-http"][..]] {
        let out = serve_on_the_field(None, more).output().expect("stx runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{more:?}: {stderr}");
        assert!(
            stderr.contains("stx token new") && stderr.contains("`tokens[0].token`"),
            "{stderr}"
        );
        assert!(out.stdout.is_empty(), "no URL with a token printed");
    }

    // With the station's own tokens, plain HTTP needs to be asked for by name.
    let dir = std::env::temp_dir().join(format!("stx-cli-serve-field-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let path = dir.join("station.toml");
    let shipped = stx_station::config::DEFAULT_STATION_TOML;
    let own = shipped
        .replace(
            r#""operator-token""#,
            r#""6d0c2a9f4b8e1735c6a2f0d9e4b7183a""#,
        )
        .replace(r#""viewer-token""#, r#""e5a1f7c3092b6d48a1e7c5f3b9d02468""#);
    assert_ne!(own, shipped);
    std::fs::write(&path, own).expect("write");
    let out = serve_on_the_field(Some(&path), &[])
        .output()
        .expect("stx runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("in clear")
            && stderr.contains("--insecure-http")
            && stderr.contains("[tls]"),
        "{stderr}"
    );
    let mut child = serve_on_the_field(Some(&path), &["--insecure-http"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("stx serve starts");
    let line = banner(&mut child);
    assert!(line.contains("http://127.0.0.2:"), "{line}");
    sigterm(&child);
    let out = child.wait_with_output().expect("exits");
    assert!(out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("cross the network in clear"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn serve_sim_flies_the_simulated_drone_to_a_landing_the_station_sees() {
    let (mut child, address, token) = serve(&[
        "--listen",
        "127.0.0.1:0",
        "--link",
        "udpin:127.0.0.1:0",
        "--sim",
        "--sim-scenario",
        "rehearsal",
        "--sim-speed",
        "max",
    ]);
    let deadline = Instant::now() + Duration::from_secs(90);
    let mut last = serde_json::Value::Null;
    let mut phases = std::collections::BTreeSet::new();
    while Instant::now() < deadline {
        last = get_value(&address, "/api/state", &token);
        if let Some(phase) = last["guidance"]["phase"].as_str() {
            phases.insert(phase.to_string());
        }
        if last["vehicle"]["stage"] == "landed" {
            break;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    assert_eq!(last["vehicle"]["stage"], "landed", "{last}");
    // Where the station saw it land, against the target guidance was given.
    let gps = &last["vehicle"]["gps"];
    let target = &last["guidance"]["target"];
    let (lat, lon) = (
        gps["lat_deg"].as_f64().unwrap(),
        gps["lon_deg"].as_f64().unwrap(),
    );
    let (target_lat, target_lon) = (
        target["lat_deg"].as_f64().unwrap(),
        target["lon_deg"].as_f64().unwrap(),
    );
    let north_m = (lat - target_lat).to_radians() * 6_371_000.0;
    let east_m = (lon - target_lon).to_radians() * 6_371_000.0 * target_lat.to_radians().cos();
    let miss_m = north_m.hypot(east_m);
    assert!(
        miss_m < 60.0,
        "landed {miss_m:.1} m from the target: {last}"
    );
    // At `max` the final approach and the flare last a fraction of a second of wall time, and
    // a 100 ms poll of the state can miss them both: the station's event log keeps the
    // replica's phase changes.
    let events = get_value(&address, "/api/events", &token);
    let said: Vec<&str> = events["events"]
        .as_array()
        .map(|es| es.iter().filter_map(|e| e["text"].as_str()).collect())
        .unwrap_or_default();
    assert!(
        phases.contains("final_approach")
            || phases.contains("flare")
            || said
                .iter()
                .any(|t| t.contains("→ FinalApproach") || t.contains("→ Flare")),
        "{phases:?}; events {said:?}"
    );
    // The drone's parameters arrive described from the shared catalogue.
    let params = get_value(&address, "/api/params", &token);
    let hk1 = params["params"]
        .as_array()
        .and_then(|p| p.iter().find(|p| p["name"] == "GN_HK1"))
        .unwrap_or_else(|| panic!("GN_HK1 listed: {params}"));
    assert_eq!(hk1["units"], "m/rad", "{hk1}");
    assert_eq!(hk1["group"], "gains", "{hk1}");
    child.kill().expect("kill");
    let _ = child.wait();
}

#[test]
fn serve_sim_refuses_a_link_it_cannot_fly_on_and_an_unknown_mission() {
    for args in [
        vec!["serve", "--sim", "--link", "serial:/dev/ttyUSB0:57600"],
        vec!["serve", "--sim", "--sim-scenario", "no-such-mission"],
        vec!["serve", "--sim-speed", "4"],
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_stx"))
            .args(&args)
            .output()
            .expect("stx runs");
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!stderr.is_empty(), "{args:?} says why");
    }
}

/// Regression: the start banner grew a second line, and a reader that closed stdout after the
/// first (as `serve` above does) made `println!` panic on the broken pipe and took the station
/// down with it, now and then, mid-request.
#[test]
fn serve_keeps_running_when_nobody_reads_its_stdout() {
    let mut child = spawn_serve(&["--listen", "127.0.0.1:0", "--link", "udpin:127.0.0.1:0"]);
    drop(child.stdout.take());
    std::thread::sleep(Duration::from_millis(1500));
    let early_exit = child.try_wait().expect("wait");
    let _ = child.kill();
    let _ = child.wait();
    assert!(
        early_exit.is_none(),
        "the station stopped with its stdout closed: {early_exit:?}"
    );
}
