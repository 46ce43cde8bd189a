//! Someone on the field network leaning on the station's API, against the real daemon
//! (`stx serve`): a flood of wrong tokens from one address is locked out with 429 and
//! `Retry-After` while an operator on another address is still served; a token asking too
//! fast is slowed with 429; WebSockets beyond the station's bound are refused.
//!
//! Regression (issue 17 item 6): wrong tokens were answered 401 as fast as they came, with no
//! limit, and any number of pages could connect.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::process::{Command, Stdio};

use crate::common::Killed;

fn serve() -> (Killed, SocketAddr, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_stx"))
        .args([
            "serve",
            "--listen",
            "127.0.0.1:0",
            "--link",
            "udpin:127.0.0.1:0",
            "--no-record",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("stx serve starts");
    let (address, token) = crate::common::read_started(&mut child);
    (Killed(child), address.parse().expect("address"), token)
}

/// GET `path` from the local address `from` (any of 127.0.0.0/8), `extra` headers added;
/// the status line and headers of the answer (a WebSocket stays open after them).
fn get_from(
    stream: &mut TcpStream,
    to: SocketAddr,
    path: &str,
    token: &str,
    extra: &str,
) -> String {
    write!(
        stream,
        "GET {path} HTTP/1.1\r\nHost: {to}\r\nAuthorization: Bearer {token}\r\n{extra}\r\n"
    )
    .expect("write");
    let mut head = Vec::new();
    let mut byte = [0_u8; 1];
    while !head.ends_with(b"\r\n\r\n") && stream.read(&mut byte).unwrap_or(0) == 1 {
        head.push(byte[0]);
    }
    String::from_utf8_lossy(&head).into_owned()
}

/// A one-request GET from `from`.
fn get(from: [u8; 4], to: SocketAddr, path: &str, token: &str) -> String {
    get_from(
        &mut connect_from(from, to),
        to,
        path,
        token,
        "Connection: close\r\n",
    )
}

/// A TCP connection from the loopback address `from` to `to` (std cannot bind before it
/// connects; tokio's socket can, on a small runtime).
fn connect_from(from: [u8; 4], to: SocketAddr) -> TcpStream {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_io()
        .build()
        .expect("runtime");
    let stream = rt.block_on(async {
        let socket = tokio::net::TcpSocket::new_v4().expect("socket");
        socket
            .bind(SocketAddr::from((from, 0)))
            .expect("bind a loopback address");
        let stream = socket.connect(to).await.expect("connect");
        stream.into_std().expect("std stream")
    });
    stream.set_nonblocking(false).expect("blocking");
    stream
}

fn status(head: &str) -> u16 {
    head.split_whitespace()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(0)
}

#[test]
fn wrong_tokens_are_locked_out_by_address_and_operators_are_still_served() {
    let (_daemon, at, token) = serve();
    const GUESSER: [u8; 4] = [127, 0, 0, 2];
    const OPERATOR: [u8; 4] = [127, 0, 0, 1];
    let mut statuses = Vec::new();
    for k in 0..30 {
        let head = get(GUESSER, at, "/api/state", &format!("guess-{k}"));
        statuses.push(status(&head));
        if status(&head) == 429 {
            let retry = head
                .lines()
                .find_map(|l| {
                    l.to_ascii_lowercase()
                        .strip_prefix("retry-after:")
                        .map(|v| v.trim().to_string())
                })
                .and_then(|v| v.parse::<u64>().ok());
            assert!(retry.is_some_and(|s| s >= 1), "429 says when: {head}");
        }
    }
    let unauthorized = statuses.iter().filter(|&&s| s == 401).count();
    let locked = statuses.iter().filter(|&&s| s == 429).count();
    assert_eq!((unauthorized, locked), (10, 20), "{statuses:?}");
    // Even the right token is not heard from the locked-out address...
    assert_eq!(status(&get(GUESSER, at, "/api/state", &token)), 429);
    // ...while the operator on another address is served as ever.
    assert_eq!(status(&get(OPERATOR, at, "/api/state", &token)), 200);
}

#[test]
fn a_token_asking_too_fast_is_slowed_and_pages_beyond_the_bound_are_refused() {
    let (_daemon, at, token) = serve();
    // Until the first 429 (2,000 requests at most): no more are served than the burst of
    // 300 and 100 a second since the first.
    let started = std::time::Instant::now();
    let mut served = 0;
    let mut slowed = false;
    for _ in 0..2000 {
        match status(&get([127, 0, 0, 1], at, "/api/state", &token)) {
            200 => served += 1,
            429 => {
                slowed = true;
                break;
            }
            other => panic!("answered {other}"),
        }
    }
    let allowed = 300.0 + 100.0 * started.elapsed().as_secs_f64() + 1.0;
    assert!(slowed, "{served} requests, none slowed");
    assert!(
        served >= 300 && f64::from(served) <= allowed,
        "{served} served before a 429 (at most {allowed:.0})"
    );

    // Pages: the station serves 64 at once (a fresh daemon, so the token's bucket is full).
    let (_daemon, at, token) = serve();
    let mut pages = Vec::new();
    let mut refused = None;
    for k in 0..70 {
        let from = [127, 0, 1, k as u8 + 1];
        let mut stream = connect_from(from, at);
        let head = get_from(
            &mut stream,
            at,
            "/api/ws",
            &token,
            "Upgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Version: 13\r\n\
             Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n",
        );
        let code = status(&head);
        if code == 101 {
            // The station greets a page once it has counted it: wait for the greeting, so
            // the next page asks with this one counted.
            let mut byte = [0_u8; 1];
            stream.read_exact(&mut byte).expect("the hello");
            pages.push(stream);
        } else {
            refused = Some((k, code));
            break;
        }
    }
    assert_eq!(refused, Some((64, 429)), "{} pages open", pages.len());
}
