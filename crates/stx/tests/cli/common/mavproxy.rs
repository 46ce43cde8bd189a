//! MAVProxy (from PyPI, in the workspace's `.venv`) as a peer nobody here wrote, driven through
//! its console as an operator would.

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{ChildStdin, Command, Stdio};

pub use super::Killed;
use std::sync::mpsc::{self, Receiver};
use std::time::{Duration, Instant};

/// `$STX_PYTHON`, else `.venv/bin/python` at the workspace root (`tests/run-all` installs
/// MAVProxy there).
pub fn python() -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let p = std::env::var_os("STX_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join(".venv/bin/python"));
    assert!(
        p.exists(),
        "MAVProxy peer: no Python at {} (set STX_PYTHON or run tests/run-all once)",
        p.display()
    );
    p
}

/// Runs the peer script `tests/peers/NAME` with `args` under [`python`] and gives its stdout;
/// a script that fails fails the test with what it printed on stderr.
#[allow(dead_code)]
pub fn run_peer(name: &str, args: &[&str]) -> Vec<u8> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/peers")
        .join(name);
    let out = Command::new(python())
        .arg(&script)
        .args(args)
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

/// MAVProxy's console: lines in, everything it printed kept.
pub struct Console {
    stdin: ChildStdin,
    lines: Receiver<String>,
    /// Every line it printed so far.
    pub seen: Vec<String>,
    _process: Killed,
}

impl Console {
    /// Starts MAVProxy on `master` (e.g. `udpin:127.0.0.1:14550`) in `work`.
    pub fn start(master: &str, work: &Path) -> Self {
        let mut mavproxy = Command::new(python())
            .args(["-m", "MAVProxy.mavproxy"])
            .arg(format!("--master={master}"))
            .args(["--nowait", "--show-errors"])
            .current_dir(work)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("MAVProxy starts (is it installed in the venv?)");
        let stdin = mavproxy.stdin.take().expect("stdin");
        let stdout = mavproxy.stdout.take().expect("stdout");
        let (tx, lines) = mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines() {
                let Ok(line) = line else { break };
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        Self {
            stdin,
            lines,
            seen: Vec::new(),
            _process: Killed(mavproxy),
        }
    }

    /// Types `command` into the console.
    pub fn send(&mut self, command: &str) {
        writeln!(self.stdin, "{command}").expect("MAVProxy reads its console");
        self.stdin.flush().expect("flush");
    }

    /// Waits up to `secs` for a line that `pred` accepts; returns it.
    pub fn wait_for(&mut self, secs: u64, what: &str, pred: impl Fn(&str) -> bool) -> String {
        let deadline = Instant::now() + Duration::from_secs(secs);
        while Instant::now() < deadline {
            if let Ok(line) = self.lines.recv_timeout(Duration::from_millis(100)) {
                self.seen.push(line.clone());
                if pred(&line) {
                    return line;
                }
            }
        }
        panic!(
            "MAVProxy did not show {what} in {secs} s; it printed:\n{}",
            self.seen.join("\n")
        );
    }

    /// Reads what it prints for `secs` seconds.
    pub fn drain(&mut self, secs: u64) {
        let deadline = Instant::now() + Duration::from_secs(secs);
        while Instant::now() < deadline {
            if let Ok(line) = self.lines.recv_timeout(Duration::from_millis(100)) {
                self.seen.push(line);
            }
        }
    }

    /// The value `param show NAME` printed last in what was seen, if any.
    pub fn shown_param(&self, name: &str) -> Option<f64> {
        self.seen.iter().rev().find_map(|l| {
            let mut words = l.split_whitespace().skip_while(|w| !w.ends_with(name));
            words.next()?;
            words.next()?.parse().ok()
        })
    }
}
