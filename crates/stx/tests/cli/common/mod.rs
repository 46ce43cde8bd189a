//! Helpers the `stx` command-line tests share: run the real binary, a fresh scratch
//! directory per test, and a running `stx serve` to ask over HTTP.

pub mod mavproxy;
pub mod station;

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};

/// Kills the process when the test ends, passed or not.
pub struct Killed(pub Child);

impl Drop for Killed {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// The HTTP address (host:port) and operator token a starting `stx serve` prints on its first
/// line of stdout (`… http://HOST:PORT/?token=TOKEN`).
#[allow(dead_code)]
pub fn read_started(child: &mut Child) -> (String, String) {
    use std::io::{BufRead, BufReader};
    let mut line = String::new();
    BufReader::new(child.stdout.take().expect("stdout piped"))
        .read_line(&mut line)
        .expect("the station says where it listens");
    let url = line.trim().rsplit(' ').next().expect("a URL");
    let rest = url.strip_prefix("http://").expect("an http URL");
    let (http, token) = rest.split_once("/?token=").expect("address and token");
    (http.to_string(), token.to_string())
}

/// Runs the `stx` binary under test with `args`.
pub fn stx(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_stx"))
        .args(args)
        .output()
        .expect("stx runs")
}

/// An empty directory `stx-cli-{suite}-{name}-{pid}` under the system's temporary directory.
pub fn temp_dir(suite: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("stx-cli-{suite}-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// The shipped vehicle file with `from` replaced by `to` (which must be there), written as
/// `dir/name`; its path. Only the tests that fly a vehicle file use it.
#[allow(dead_code)]
pub fn vehicle_file(dir: &Path, name: &str, from: &str, to: &str) -> PathBuf {
    let shipped = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config/vehicle/straplex.toml"),
    )
    .expect("shipped vehicle file");
    assert!(shipped.contains(from), "{from} in the shipped vehicle file");
    let path = dir.join(name);
    std::fs::write(&path, shipped.replacen(from, to, 1)).expect("write");
    path
}

/// `GET path` of the station at `http` (host:port) with `token`; the body as JSON, `None` if
/// there is none yet (not answering, not JSON).
#[allow(dead_code)]
pub fn get_json(http: &str, token: &str, path: &str) -> Option<serde_json::Value> {
    request_json(http, token, "GET", path, "")
}

/// `method path` with the JSON `body` (may be empty) to the station at `http` with `token`;
/// the answer's body as JSON. Plain HTTP/1.1 over a socket: the tests need no client library.
#[allow(dead_code)]
pub fn request_json(
    http: &str,
    token: &str,
    method: &str,
    path: &str,
    body: &str,
) -> Option<serde_json::Value> {
    let mut s = TcpStream::connect(http).ok()?;
    s.set_read_timeout(Some(std::time::Duration::from_secs(5)))
        .ok()?;
    let req = format!(
        "{method} {path} HTTP/1.1\r\nHost: {http}\r\nAuthorization: Bearer {token}\r\n\
         Content-Type: application/json\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}",
        body.len()
    );
    s.write_all(req.as_bytes()).ok()?;
    let mut answer = Vec::new();
    s.read_to_end(&mut answer).ok()?;
    let text = String::from_utf8_lossy(&answer);
    serde_json::from_str(text.split_once("\r\n\r\n")?.1).ok()
}

/// `method path` with `body` as `content_type` to the station at `http` with `token` (`None`:
/// no `Authorization`): the status and the body as JSON (`null` if it is none).
#[allow(dead_code)]
pub fn exchange(
    http: &str,
    token: Option<&str>,
    method: &str,
    path: &str,
    content_type: &str,
    body: &[u8],
) -> (u16, serde_json::Value) {
    let mut s = TcpStream::connect(http).expect("connect");
    s.set_read_timeout(Some(std::time::Duration::from_secs(60)))
        .expect("timeout");
    let auth = token.map_or(String::new(), |t| format!("Authorization: Bearer {t}\r\n"));
    let head = format!(
        "{method} {path} HTTP/1.1\r\nHost: {http}\r\n{auth}Content-Type: {content_type}\r\n\
         Content-Length: {}\r\nConnection: close\r\n\r\n",
        body.len()
    );
    s.write_all(head.as_bytes()).expect("write");
    s.write_all(body).expect("write");
    let mut answer = Vec::new();
    s.read_to_end(&mut answer).expect("read");
    let text = String::from_utf8_lossy(&answer);
    let status = text
        .split(' ')
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or(0);
    let json = text
        .split_once("\r\n\r\n")
        .and_then(|(_, b)| serde_json::from_str(b).ok())
        .unwrap_or(serde_json::Value::Null);
    (status, json)
}

/// `GET path` from the station at `address` with `token`: the whole HTTP response.
pub fn get(address: &str, path: &str, token: &str) -> String {
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

/// The first line `child` prints: the start banner with the dashboard's URL.
pub fn banner(child: &mut std::process::Child) -> String {
    let mut line = String::new();
    BufReader::new(child.stdout.take().expect("stdout"))
        .read_line(&mut line)
        .expect("a line");
    line
}

/// Asks `child` to stop as systemd does.
pub fn sigterm(child: &std::process::Child) {
    let killed = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(killed.success());
}

/// Starts `stx serve` with `args`, its stdout piped.
pub fn spawn_serve(args: &[&str]) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_stx"))
        .arg("serve")
        .arg("--no-record")
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("stx serve starts")
}

/// Starts `stx serve` with `args` and returns the child and the address and token it printed.
pub fn serve(args: &[&str]) -> (std::process::Child, String, String) {
    let mut child = spawn_serve(args);
    let (address, token) = read_started(&mut child);
    (child, address, token)
}

/// `GET path` as JSON, `null` when there is none (see [`get_json`]).
pub fn get_value(address: &str, path: &str, token: &str) -> serde_json::Value {
    get_json(address, token, path).unwrap_or(serde_json::Value::Null)
}
