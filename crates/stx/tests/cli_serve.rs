//! `stx serve` from the outside: it starts, prints where to look, answers, and stops cleanly on
//! SIGTERM; a bad configuration is refused with exit code 2.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn get(address: &str, path: &str, token: &str) -> String {
    let mut stream = TcpStream::connect(address).expect("connect");
    write!(
        stream,
        "GET {path} HTTP/1.1\r\nHost: {address}\r\nAuthorization: Bearer {token}\r\nConnection: close\r\n\r\n"
    )
    .expect("write");
    let mut response = String::new();
    stream.read_to_string(&mut response).expect("read");
    response
}

#[test]
fn serve_prints_its_url_answers_and_stops_on_sigterm() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_stx"))
        .args([
            "serve",
            "--listen",
            "127.0.0.1:0",
            "--link",
            "udpin:127.0.0.1:0",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("stx serve starts");
    let mut line = String::new();
    BufReader::new(child.stdout.take().expect("stdout"))
        .read_line(&mut line)
        .expect("a line");
    // "stx station: open http://127.0.0.1:PORT/?token=TOKEN"
    let url = line.trim().rsplit(' ').next().expect("a URL").to_string();
    let rest = url.strip_prefix("http://").expect("http URL");
    let (address, query) = rest.split_once("/?token=").expect("address and token");
    let session = get(address, "/api/session", query);
    assert!(session.starts_with("HTTP/1.1 200"), "{session}");
    assert!(session.contains(r#""role":"operator""#), "{session}");

    let pid = child.id().to_string();
    let killed = Command::new("kill")
        .args(["-TERM", &pid])
        .status()
        .expect("kill");
    assert!(killed.success());
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
