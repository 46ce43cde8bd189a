//! `stx bench memory`: the station daemon's memory after a whole mission of three hours, flown
//! faster than real time.
//!
//! It runs the real thing as an operator would: the daemon `stx serve` in one child process
//! (the `stx` executable of [`MemoryBenchOptions::stx`]) and the simulated drone `stx drone` in
//! another, on the daemon's UDP link — the same bytes as `stx serve --sim`, but with the
//! drone's physics and memory outside the figure. The drone flies the built-in `mission` held
//! on the pad long enough that launch day lasts three hours of mission time (a station is up
//! well before the balloon goes), and dashboard pages are connected over WebSocket the whole
//! time, reading everything. Once the station sees the drone landed, the daemon's resident set
//! (`VmRSS`) and its peak (`VmHWM`) are read from `/proc` (sampled every second along the way
//! too); the drone's peak is reported beside it. The daemon records the run (into a directory
//! of its own, removed after: the recording's size is reported), 20 more pages come and go
//! every five seconds, and the daemon's open file descriptors are counted a minute in and at
//! the end, so a leak of either shows.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::Stdio;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use futures_util::StreamExt;
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use tokio::io::{AsyncBufReadExt, AsyncReadExt, AsyncWriteExt, BufReader};
use tokio::process::Command;

/// What [`run`] measures and how.
pub struct MemoryBenchOptions {
    /// The `stx` executable, run as the daemon and as the drone (the command line passes
    /// itself): the figure is of the program an operator runs.
    pub stx: PathBuf,
    /// Mission time of the whole launch day, s.
    pub mission_s: f64,
    /// Mission time per real time.
    pub speed: f64,
    /// Dashboard pages connected throughout.
    pub clients: usize,
}

/// The measured figures.
#[derive(Debug, Serialize)]
pub struct MemoryReport {
    /// Mission time the station saw, s (from the drone's clock at landing).
    pub mission_time_s: f64,
    /// Real time the run took, s.
    pub wall_time_s: f64,
    /// Mission time per real time asked of the drone.
    pub speed: f64,
    /// Dashboard pages connected.
    pub clients: usize,
    /// Whether the drone landed (the station saw stage `landed`).
    pub landed: bool,
    /// The daemon's resident memory after the landing, MB (10⁶ bytes).
    pub rss_after_mb: f64,
    /// The highest resident memory of the daemon during the run (`VmHWM`), MB.
    pub rss_peak_mb: f64,
    /// The simulated drone's own peak resident memory (its process, not in the figures
    /// above), MB.
    pub drone_rss_peak_mb: f64,
    /// Resident memory one minute of real time into the run, MB, to see growth against.
    pub rss_early_mb: f64,
    /// Messages the pages received over the run.
    pub page_messages: u64,
    /// Bytes the pages received over the run.
    pub page_bytes: u64,
    /// Pages that connected for a few seconds and left, over the run (beside the `clients`
    /// that stay).
    pub pages_come_and_gone: u64,
    /// The daemon's open file descriptors one minute into the run.
    pub fds_early: usize,
    /// … and after the landing.
    pub fds_after: usize,
    /// The run's recording on disk after the landing, MB (10⁶ bytes).
    pub recording_mb: f64,
    /// Messages the recording could not write.
    pub recording_lost: u64,
}

/// The report as `stx bench memory` prints it without `--json`.
impl std::fmt::Display for MemoryReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "station daemon alone after {:.0} s of mission ({}, {:.0} s wall at {}x, {} pages): RSS {:.1} MB, peak {:.1} MB (after 1 min: {:.1} MB; the drone's process peaked at {:.1} MB); pages received {} messages, {:.1} MB",
            self.mission_time_s,
            if self.landed { "landed" } else { "NOT landed" },
            self.wall_time_s,
            self.speed,
            self.clients,
            self.rss_after_mb,
            self.rss_peak_mb,
            self.rss_early_mb,
            self.drone_rss_peak_mb,
            self.page_messages,
            self.page_bytes as f64 / 1e6
        )?;
        writeln!(
            f,
            "{} pages came and went; open file descriptors {} after 1 min, {} at the end; recording {:.1} MB on disk, {} messages lost",
            self.pages_come_and_gone,
            self.fds_early,
            self.fds_after,
            self.recording_mb,
            self.recording_lost
        )
    }
}

/// Open file descriptors of a process (`/proc/PID/fd`).
fn open_fds(pid: u32) -> anyhow::Result<usize> {
    Ok(std::fs::read_dir(format!("/proc/{pid}/fd"))
        .with_context(|| format!("reading /proc/{pid}/fd (Linux only)"))?
        .count())
}

/// Bytes of the files in `dir`.
fn dir_bytes(dir: &std::path::Path) -> u64 {
    std::fs::read_dir(dir)
        .map(|d| {
            d.filter_map(Result::ok)
                .filter_map(|e| e.metadata().ok())
                .map(|m| m.len())
                .sum()
        })
        .unwrap_or(0)
}

/// Pages that come and go: 20 at a time connect, read for a few seconds and leave, again and
/// again, as people open and close the dashboard over a day.
async fn churn(url: String, gone: Arc<AtomicU64>) {
    loop {
        let mut pages = Vec::new();
        for _ in 0..20 {
            if let Ok((ws, _)) = tokio_tungstenite::connect_async(url.clone()).await {
                pages.push(ws);
            }
        }
        let read = async {
            for ws in &mut pages {
                let _ = tokio::time::timeout(Duration::from_millis(100), ws.next()).await;
            }
        };
        read.await;
        tokio::time::sleep(Duration::from_secs(3)).await;
        gone.fetch_add(pages.len() as u64, Ordering::Relaxed);
        drop(pages);
        tokio::time::sleep(Duration::from_secs(2)).await;
    }
}

/// The built-in `mission`, held on the pad so that launch to landing and the wait before it
/// last `mission_s` of mission time; written to a file the child can read.
fn three_hour_mission(mission_s: f64) -> anyhow::Result<tempfile_path::TempFile> {
    let (_, text) = stx_sim::drone::config::BUILTIN
        .iter()
        .find(|(name, _)| *name == "mission")
        .context("the built-in mission")?;
    // The built-in mission flies from release to landing in about 7,500 s.
    const FLIGHT_S: f64 = 7_500.0;
    let delay_s = (mission_s - FLIGHT_S).max(10.0);
    let patched = text
        .replacen("name = \"mission\"", "name = \"mission-bench-memory\"", 1)
        .replacen(
            "launch_delay_s = 10.0",
            &format!("launch_delay_s = {delay_s:.1}"),
            1,
        )
        .replacen(
            "max_duration_s = 21600.0",
            &format!("max_duration_s = {:.1}", mission_s * 2.0),
            1,
        );
    if !patched.contains("mission-bench-memory") || !patched.contains("launch_delay_s = ") {
        bail!("the built-in mission no longer has the fields the benchmark adjusts");
    }
    tempfile_path::TempFile::write("stx-bench-memory-mission.toml", &patched)
}

/// A file in the temporary directory, removed when dropped.
mod tempfile_path {
    use std::path::{Path, PathBuf};

    pub struct TempFile(PathBuf);

    impl TempFile {
        pub fn write(name: &str, text: &str) -> anyhow::Result<Self> {
            let path = std::env::temp_dir().join(format!("{}-{name}", std::process::id()));
            std::fs::write(&path, text)?;
            Ok(Self(path))
        }

        pub fn path(&self) -> &Path {
            &self.0
        }
    }

    impl Drop for TempFile {
        fn drop(&mut self) {
            let _ = std::fs::remove_file(&self.0);
        }
    }
}

/// `VmRSS` and `VmHWM` of a process, MB.
pub(crate) fn memory_mb(pid: u32) -> anyhow::Result<(f64, f64)> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status"))
        .with_context(|| format!("reading /proc/{pid}/status (Linux only)"))?;
    let field = |name: &str| -> anyhow::Result<f64> {
        let line = status
            .lines()
            .find(|l| l.starts_with(name))
            .with_context(|| format!("{name} in /proc/{pid}/status"))?;
        let kb: f64 = line
            .split_whitespace()
            .nth(1)
            .and_then(|v| v.parse().ok())
            .with_context(|| format!("{line:?}"))?;
        Ok(kb * 1024.0 / 1e6)
    };
    Ok((field("VmRSS:")?, field("VmHWM:")?))
}

/// `stx serve` on loopback ports in a child process, killed when dropped.
pub(crate) struct ServeChild {
    pub child: tokio::process::Child,
    pub pid: u32,
    /// `127.0.0.1:PORT` of its HTTP side.
    pub address: String,
    /// The operator's token it printed.
    pub token: String,
    /// Its drone link's UDP address.
    pub link: String,
}

impl ServeChild {
    /// Starts `exe serve` with `extra` arguments and reads its address and link from the
    /// banner it prints.
    pub async fn start(exe: &std::path::Path, extra: &[&std::ffi::OsStr]) -> anyhow::Result<Self> {
        let mut child = Command::new(exe)
            .args([
                "serve",
                "--listen",
                "127.0.0.1:0",
                "--link",
                "udpin:127.0.0.1:0",
            ])
            .args(extra)
            .env("RUST_LOG", "warn")
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .kill_on_drop(true)
            .spawn()
            .context("starting stx serve")?;
        let pid = child.id().context("the daemon's pid")?;
        let mut out = BufReader::new(child.stdout.take().context("the daemon's stdout")?);
        let mut line = String::new();
        out.read_line(&mut line).await?;
        let mut link_line = String::new();
        out.read_line(&mut link_line).await?;
        // "stx station: drone link listening on 127.0.0.1:PORT"
        let Some(link) = link_line
            .trim()
            .strip_prefix("stx station: drone link listening on ")
        else {
            bail!("stx serve did not print its link: {link_line:?}");
        };
        // "stx station: open http://127.0.0.1:PORT/?token=TOKEN"
        let url = line.trim().rsplit(' ').next().unwrap_or_default();
        let Some((address, token)) = url
            .strip_prefix("http://")
            .and_then(|rest| rest.split_once("/?token="))
        else {
            bail!("stx serve did not print its URL: {line:?}");
        };
        Ok(Self {
            child,
            pid,
            address: address.to_string(),
            token: token.to_string(),
            link: link.to_string(),
        })
    }
}

/// GET `path` with a bearer token, the body as JSON.
pub(crate) async fn get_json(
    address: &str,
    path: &str,
    token: &str,
) -> anyhow::Result<serde_json::Value> {
    let mut stream = tokio::net::TcpStream::connect(address).await?;
    stream
        .write_all(
            format!(
                "GET {path} HTTP/1.1\r\nHost: {address}\r\nAuthorization: Bearer {token}\r\nConnection: close\r\n\r\n"
            )
            .as_bytes(),
        )
        .await?;
    let mut response = Vec::new();
    stream.read_to_end(&mut response).await?;
    let text = String::from_utf8_lossy(&response);
    let body = text.split_once("\r\n\r\n").map_or("", |(_, b)| b);
    serde_json::from_str(body).with_context(|| format!("GET {path}: not JSON"))
}

/// A dashboard page that reads every message.
async fn page(url: String, messages: Arc<AtomicU64>, bytes: Arc<AtomicU64>) -> anyhow::Result<()> {
    let (mut ws, _) = tokio_tungstenite::connect_async(url).await?;
    while let Some(message) = ws.next().await {
        let message = message?;
        messages.fetch_add(1, Ordering::Relaxed);
        bytes.fetch_add(message.len() as u64, Ordering::Relaxed);
    }
    Ok(())
}

pub fn run(options: &MemoryBenchOptions) -> anyhow::Result<MemoryReport> {
    if !(options.mission_s > 0.0 && options.speed > 0.0) {
        bail!("--mission-hours and --speed must be > 0");
    }
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .enable_all()
        .build()
        .context("starting the benchmark's runtime")?;
    runtime.block_on(measure(options))
}

async fn measure(options: &MemoryBenchOptions) -> anyhow::Result<MemoryReport> {
    let mission = three_hour_mission(options.mission_s)?;
    let exe = &options.stx;
    // The station records, as it does in the field; into a directory of its own.
    let record_dir = std::env::temp_dir().join(format!("stx-bench-memory-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&record_dir);
    let ServeChild {
        mut child,
        pid,
        address,
        token,
        link,
    } = ServeChild::start(exe, &["--record-dir".as_ref(), record_dir.as_os_str()]).await?;
    let mut drone = Command::new(exe)
        .args(["drone", "--connect", &format!("udpout:{link}")])
        .arg("--scenario")
        .arg(mission.path())
        .args(["--speed", &options.speed.to_string(), "--linger", "600"])
        .env("RUST_LOG", "warn")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .kill_on_drop(true)
        .spawn()
        .context("starting stx drone")?;
    let drone_pid = drone.id().context("the drone's pid")?;
    let messages = Arc::new(AtomicU64::new(0));
    let bytes = Arc::new(AtomicU64::new(0));
    for _ in 0..options.clients {
        let url = format!("ws://{address}/api/ws?token={token}");
        tokio::spawn(page(url, messages.clone(), bytes.clone()));
    }
    let gone = Arc::new(AtomicU64::new(0));
    let churning = tokio::spawn(churn(
        format!("ws://{address}/api/ws?token={token}"),
        gone.clone(),
    ));

    let progress = if std::io::stderr().is_terminal() {
        let bar = ProgressBar::new_spinner();
        bar.set_style(ProgressStyle::with_template("{spinner} {elapsed} {msg}")?);
        bar.enable_steady_tick(Duration::from_millis(200));
        bar
    } else {
        ProgressBar::hidden()
    };
    let start = Instant::now();
    let expected_wall_s = options.mission_s / options.speed;
    let deadline = start + Duration::from_secs_f64(expected_wall_s * 3.0 + 120.0);
    let mut rss_early_mb = None;
    let mut fds_early = None;
    let mut state = serde_json::Value::Null;
    let landed = loop {
        tokio::time::sleep(Duration::from_secs(1)).await;
        if let Some(status) = child.try_wait()? {
            bail!("stx serve exited during the mission: {status}");
        }
        if let Some(status) = drone.try_wait()? {
            bail!("stx drone exited during the mission: {status}");
        }
        let (rss, _) = memory_mb(pid)?;
        if rss_early_mb.is_none() && start.elapsed() >= Duration::from_secs(60) {
            rss_early_mb = Some(rss);
            fds_early = Some(open_fds(pid)?);
        }
        state = get_json(&address, "/api/state", &token)
            .await
            .unwrap_or(state);
        let stage = state["vehicle"]["stage"]
            .as_str()
            .unwrap_or("—")
            .to_string();
        let boot_ms = state["vehicle"]["attitude"]["time_boot_ms"].as_f64();
        progress.set_message(format!(
            "mission {:.0} s, stage {stage}, daemon {rss:.1} MB",
            boot_ms.unwrap_or(0.0) / 1e3
        ));
        if stage == "landed" {
            break true;
        }
        if Instant::now() > deadline {
            break false;
        }
    };
    progress.finish_and_clear();
    let wall_time_s = start.elapsed().as_secs_f64();
    churning.abort();
    // The pages that came and went have closed (the station notices within a second).
    tokio::time::sleep(Duration::from_secs(2)).await;
    let (rss_after_mb, rss_peak_mb) = memory_mb(pid)?;
    let fds_after = open_fds(pid)?;
    let recording_mb = dir_bytes(&record_dir) as f64 / 1e6;
    let recording_lost = state["recording"]["messages_lost"].as_u64().unwrap_or(0);
    let (_, drone_rss_peak_mb) = memory_mb(drone_pid)?;
    drone.kill().await.ok();
    child.kill().await.ok();
    let _ = std::fs::remove_dir_all(&record_dir);
    Ok(MemoryReport {
        mission_time_s: state["vehicle"]["attitude"]["time_boot_ms"]
            .as_f64()
            .map_or(0.0, |ms| ms / 1e3),
        wall_time_s,
        speed: options.speed,
        clients: options.clients,
        landed,
        rss_after_mb,
        rss_peak_mb,
        drone_rss_peak_mb,
        rss_early_mb: rss_early_mb.unwrap_or(rss_after_mb),
        page_messages: messages.load(Ordering::Relaxed),
        page_bytes: bytes.load(Ordering::Relaxed),
        pages_come_and_gone: gone.load(Ordering::Relaxed),
        fds_early: fds_early.unwrap_or(fds_after),
        fds_after,
        recording_mb,
        recording_lost,
    })
}
