//! `stx serve --sim` with the shipped configuration plus some tables of the test's own.

use std::path::Path;
use std::process::{Command, Stdio};

use super::Killed;

/// A running station: killed when dropped.
pub struct Station {
    /// Its HTTP address, host:port.
    pub http: String,
    /// The operator token it printed.
    pub token: String,
    _process: Killed,
}

impl Station {
    /// Starts `stx serve --sim` (the `rehearsal` scenario in real time, no recording) on free
    /// loopback ports with the shipped `config/station.toml` followed by `extra` (TOML tables),
    /// written into `dir`.
    pub fn start(dir: &Path, extra: &str) -> Self {
        Self::start_with(dir, extra, Stdio::null())
    }

    /// As [`Station::start`], its log (stderr) written to `log`.
    #[allow(dead_code)]
    pub fn start_logged(dir: &Path, extra: &str, log: &Path) -> Self {
        let file = std::fs::File::create(log).expect("log file");
        Self::start_with(dir, extra, Stdio::from(file))
    }

    fn start_with(dir: &Path, extra: &str, stderr: Stdio) -> Self {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let shipped =
            std::fs::read_to_string(root.join("config/station.toml")).expect("shipped config");
        let config = dir.join("station.toml");
        std::fs::write(&config, format!("{shipped}\n{extra}")).expect("write config");
        let mut child = Command::new(env!("CARGO_BIN_EXE_stx"))
            .arg("serve")
            .arg("--config")
            .arg(&config)
            .args([
                "--sim",
                "--sim-scenario",
                "rehearsal",
                "--sim-speed",
                "1",
                "--no-record",
            ])
            .args(["--listen", "127.0.0.1:0", "--link", "udpin:127.0.0.1:0"])
            .current_dir(&root)
            .stdout(Stdio::piped())
            .stderr(stderr)
            .spawn()
            .expect("stx serve starts");
        let (http, token) = super::read_started(&mut child);
        Self {
            http,
            token,
            _process: Killed(child),
        }
    }

    /// `GET path` as JSON (see [`super::get_json`]).
    pub fn get(&self, path: &str) -> Option<serde_json::Value> {
        super::get_json(&self.http, &self.token, path)
    }
}

/// A free UDP port on loopback (free when asked).
pub fn free_udp_port() -> u16 {
    std::net::UdpSocket::bind("127.0.0.1:0")
        .and_then(|s| s.local_addr())
        .expect("a free port")
        .port()
}
