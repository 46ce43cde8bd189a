//! `stx bench relay`: what a public relay's audience costs the station. The station (`stx
//! serve`) and the relay (`stx relay`, on a viewer's token) run as child processes, as in the
//! field; the simulated drone flies the built-in `rehearsal` on the station's link from this
//! process, one control period per burst, and operator pages on the station time each burst
//! to the first `state` that carries it (as `stx bench station` does).
//!
//! The telemetry → page delay is timed twice over windows of the same length: first with no
//! relay, then with the relay serving its viewers (WebSockets from this process reading every
//! `public_state`). Between and after, the station's and the relay's resident memory are read
//! from `/proc`, and the station's `GET /api/sharing` must count every viewer the relay serves.
//! The viewers and the drone share this machine's cores with the station, as they would not in
//! the field: the difference is an upper bound of what the audience costs.

use std::collections::HashMap;
use std::path::PathBuf;
use std::process::Stdio;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use futures_util::StreamExt;
use serde::Serialize;
use stx_sim::drone::MissionConfig;
use stx_sim::guided::CONTROL_PERIOD_S;
use stx_sim::runner::{FlyOptions, Speed};
use stx_station::config::{DEFAULT_STATION_TOML, Role, StationConfig};
use tokio::io::{AsyncBufReadExt, BufReader};
use tokio::process::Command;
use tokio::sync::{mpsc, oneshot};
use tokio_tungstenite::tungstenite::protocol::WebSocketConfig;

use crate::memory::{ServeChild, get_json, memory_mb};
use crate::station::{Clocks, Latency, page, page_latencies};

/// The goals of issue 30: the delay's p99 within this of the figure without viewers, ms.
pub const P99_GOAL_MS: f64 = 1.0;
/// The relay's resident memory at its audience, MB.
pub const RELAY_RSS_GOAL_MB: f64 = 150.0;
/// "The station's memory flat": its growth over the window with the relay's audience, beyond
/// its growth over the window without (the flight's own history grows either way), MB.
pub const STATION_GROWTH_GOAL_MB: f64 = 1.0;

/// What to measure.
pub struct RelayBenchOptions {
    /// The `stx` executable, run as the station and the relay.
    pub stx: PathBuf,
    /// Viewers on the relay.
    pub viewers: usize,
    /// Operator pages on the station, timing telemetry.
    pub pages: usize,
    /// Telemetry bursts timed in each window.
    pub frames: usize,
    /// Bursts per second (the drone's control rate, 4 Hz).
    pub frame_rate_hz: f64,
}

/// The measured figures.
#[derive(Debug, Serialize)]
pub struct RelayReport {
    pub viewers: usize,
    pub pages: usize,
    /// Telemetry → station page with no relay.
    pub without_relay: Latency,
    /// The same with the relay serving its viewers.
    pub with_relay: Latency,
    /// Bursts some page never saw, in both windows.
    pub missed: usize,
    /// Viewers connected when the second window ended.
    pub viewers_connected: usize,
    /// The fewest `public_state` messages a viewer read in the second window.
    pub fewest_states_per_viewer: u64,
    /// The pages the station's `GET /api/sharing` counted through the relay.
    pub station_counted: u64,
    /// The station's resident memory at the start and the end of the window without the
    /// relay, and of the window with it, MB.
    pub station_rss_without_mb: [f64; 2],
    pub station_rss_with_mb: [f64; 2],
    /// The relay's resident memory after the second window and its peak, MB.
    pub relay_rss_mb: f64,
    pub relay_rss_peak_mb: f64,
}

impl RelayReport {
    /// The station's growth over the window with the audience less that over the window
    /// without, MB.
    pub fn audience_growth_mb(&self) -> f64 {
        let [a0, a1] = self.station_rss_without_mb;
        let [b0, b1] = self.station_rss_with_mb;
        (b1 - b0) - (a1 - a0)
    }

    /// The goals not met, in words.
    pub fn unmet(&self) -> Vec<String> {
        let mut unmet = Vec::new();
        let cost = self.with_relay.p99_ms - self.without_relay.p99_ms;
        if cost > P99_GOAL_MS {
            unmet.push(format!(
                "p99 {cost:.2} ms slower with the relay (goal ≤ {P99_GOAL_MS} ms)"
            ));
        }
        let growth = self.audience_growth_mb();
        if growth > STATION_GROWTH_GOAL_MB {
            unmet.push(format!(
                "the station grew {growth:.1} MB more with the relay than without (goal ≤ {STATION_GROWTH_GOAL_MB} MB)"
            ));
        }
        if self.relay_rss_peak_mb > RELAY_RSS_GOAL_MB {
            unmet.push(format!(
                "the relay peaked at {:.1} MB (goal ≤ {RELAY_RSS_GOAL_MB} MB)",
                self.relay_rss_peak_mb
            ));
        }
        if self.viewers_connected < self.viewers || self.fewest_states_per_viewer == 0 {
            unmet.push(format!(
                "{} of {} viewers connected, the fewest read {} states",
                self.viewers_connected, self.viewers, self.fewest_states_per_viewer
            ));
        }
        if self.station_counted != self.viewers as u64 {
            unmet.push(format!(
                "the station counted {} public pages of {}",
                self.station_counted, self.viewers
            ));
        }
        unmet
    }
}

impl std::fmt::Display for RelayReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let line = |l: &Latency| {
            format!(
                "p50 {:.2} ms, p99 {:.2} ms, max {:.2} ms ({} samples)",
                l.p50_ms, l.p99_ms, l.max_ms, l.samples
            )
        };
        writeln!(
            f,
            "telemetry → station page, {} pages, no relay:            {}",
            self.pages,
            line(&self.without_relay)
        )?;
        writeln!(
            f,
            "telemetry → station page, relay with {} viewers: {}",
            self.viewers,
            line(&self.with_relay)
        )?;
        writeln!(
            f,
            "p99 cost of the audience {:+.2} ms (goal ≤ {P99_GOAL_MS} ms); {} bursts missed by a page",
            self.with_relay.p99_ms - self.without_relay.p99_ms,
            self.missed
        )?;
        writeln!(
            f,
            "viewers: {} connected, the fewest read {} public states; the station counts {} public pages",
            self.viewers_connected, self.fewest_states_per_viewer, self.station_counted
        )?;
        let [a0, a1] = self.station_rss_without_mb;
        let [b0, b1] = self.station_rss_with_mb;
        writeln!(
            f,
            "station RSS without the relay {a0:.1} → {a1:.1} MB, with it {b0:.1} → {b1:.1} MB: {:+.1} MB more with the audience (goal ≤ {STATION_GROWTH_GOAL_MB} MB)",
            self.audience_growth_mb()
        )?;
        writeln!(
            f,
            "relay RSS {:.1} MB, peak {:.1} MB (goal ≤ {RELAY_RSS_GOAL_MB} MB)",
            self.relay_rss_mb, self.relay_rss_peak_mb
        )
    }
}

/// A viewer of the relay: counts the public states it reads.
async fn viewer(url: String, states: Arc<AtomicU64>, open: Arc<AtomicU64>) {
    // Small buffers: a thousand viewers in this process should not take its memory.
    let config = WebSocketConfig::default()
        .read_buffer_size(4096)
        .write_buffer_size(0);
    let Ok((mut ws, _)) =
        tokio_tungstenite::connect_async_with_config(url, Some(config), false).await
    else {
        return;
    };
    open.fetch_add(1, Ordering::Relaxed);
    while let Some(Ok(message)) = ws.next().await {
        if let Ok(text) = message.to_text()
            && text.starts_with(r#"{"type":"public_state""#)
        {
            states.fetch_add(1, Ordering::Relaxed);
        }
    }
    open.fetch_sub(1, Ordering::Relaxed);
}

/// `stx relay` on a loopback port in a child process; its pid and address.
async fn start_relay(
    exe: &std::path::Path,
    upstream: &str,
    max_viewers: usize,
) -> anyhow::Result<(tokio::process::Child, u32, String)> {
    let web_dir = std::env::temp_dir().join("stx-bench-no-dashboard");
    let mut child = Command::new(exe)
        .args(["relay", "--upstream", upstream, "--listen", "127.0.0.1:0"])
        .args(["--max-viewers", &max_viewers.to_string(), "--web-dir"])
        .arg(web_dir)
        .env("RUST_LOG", "warn")
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .kill_on_drop(true)
        .spawn()
        .context("starting stx relay")?;
    let pid = child.id().context("the relay's pid")?;
    let mut out = BufReader::new(child.stdout.take().context("the relay's stdout")?);
    let mut line = String::new();
    while out.read_line(&mut line).await? > 0 {
        if let Some(at) = line.trim().strip_prefix("open http://") {
            return Ok((child, pid, at.trim_end_matches('/').to_string()));
        }
        line.clear();
    }
    bail!("stx relay did not print its address")
}

pub fn run(options: &RelayBenchOptions) -> anyhow::Result<RelayReport> {
    if options.viewers == 0
        || options.pages == 0
        || options.frames == 0
        || !(options.frame_rate_hz > 0.0 && options.frame_rate_hz <= 100.0)
    {
        bail!("viewers, pages, frames and frame rate must be positive");
    }
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .context("starting the benchmark's runtime")?;
    runtime.block_on(measure(options))
}

async fn measure(options: &RelayBenchOptions) -> anyhow::Result<RelayReport> {
    let viewer_token = StationConfig::from_toml_str(DEFAULT_STATION_TOML)
        .context("shipped station config")?
        .tokens
        .iter()
        .find(|t| t.role == Role::Viewer)
        .map(|t| t.token.clone())
        .context("the shipped station config has no viewer token")?;
    let station = ServeChild::start(&options.stx, &[]).await?;
    let http: std::net::SocketAddr = station.address.parse().context("the station's address")?;

    // Pages connect before the drone starts, so they see every burst.
    let mut pages = Vec::new();
    let mut seen_by_page = Vec::new();
    for _ in 0..options.pages {
        let seen = Arc::new(Mutex::new(HashMap::new()));
        let (ready_tx, ready_rx) = oneshot::channel();
        pages.push(tokio::spawn(page(
            http,
            station.token.clone(),
            seen.clone(),
            ready_tx,
        )));
        ready_rx.await.context("a page could not connect")?;
        seen_by_page.push(seen);
    }
    let sent_at = Arc::new(Mutex::new(HashMap::new()));
    let landed = Arc::new(AtomicBool::new(false));
    let mut drone = FlyOptions::new(
        &format!("udpout:{}", station.link),
        MissionConfig::builtin("rehearsal").context("the built-in rehearsal")?,
    );
    drone.speed = Speed::Times(options.frame_rate_hz * CONTROL_PERIOD_S);
    drone.linger = None;
    let clocks = Clocks {
        sent_at: sent_at.clone(),
        commands: mpsc::unbounded_channel().0,
        landed: landed.clone(),
    };
    let (stop_drone, stop_rx) = oneshot::channel::<()>();
    let drone_task = tokio::spawn(stx_sim::runner::fly(
        drone,
        async move {
            let _ = stop_rx.await;
        },
        clocks,
    ));
    let window = Duration::from_secs_f64(options.frames as f64 / options.frame_rate_hz);
    // Link up, plan read back, estimator converged: not timed.
    tokio::time::sleep(Duration::from_secs(5)).await;
    let rss = || memory_mb(station.pid).map(|(now, _)| now);
    let without_from = Instant::now();
    let rss_without_start = rss()?;
    tokio::time::sleep(window).await;
    let without_to = Instant::now();
    let station_rss_without_mb = [rss_without_start, rss()?];

    let upstream = format!("http://{}/?token={viewer_token}", station.address);
    let (mut relay, relay_pid, relay_at) =
        start_relay(&options.stx, &upstream, options.viewers).await?;
    let open = Arc::new(AtomicU64::new(0));
    let mut per_viewer = Vec::new();
    // The viewers stand for other people's machines: they run on a runtime of their own at
    // the lowest priority, so a thousand of them waking at each state neither queue ahead of
    // the timing pages' tasks nor take a core from the station.
    let viewer_runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .thread_name("viewers")
        .on_thread_start(|| stx_station::priority::lower_this_thread("the bench's viewers"))
        .enable_all()
        .build()
        .context("the viewers' runtime")?;
    let mut viewers = Vec::new();
    for _ in 0..options.viewers {
        let read = Arc::new(AtomicU64::new(0));
        viewers.push(viewer_runtime.spawn(viewer(
            format!("ws://{relay_at}/api/ws"),
            read.clone(),
            open.clone(),
        )));
        per_viewer.push(read);
    }
    // Every viewer connected and counted up to the station (the relay says so within seconds).
    let settle = Instant::now() + Duration::from_secs(30);
    let mut station_counted = 0;
    while Instant::now() < settle {
        tokio::time::sleep(Duration::from_millis(500)).await;
        let sharing = get_json(&station.address, "/api/sharing", &station.token).await?;
        station_counted = sharing["relays"]
            .as_array()
            .map_or(0, |r| r.iter().filter_map(|r| r["viewers"].as_u64()).sum());
        if open.load(Ordering::Relaxed) as usize >= options.viewers
            && station_counted == options.viewers as u64
        {
            break;
        }
    }
    let before_window: Vec<u64> = per_viewer
        .iter()
        .map(|r| r.load(Ordering::Relaxed))
        .collect();
    let with_from = Instant::now();
    let rss_with_start = rss()?;
    tokio::time::sleep(window).await;
    let with_to = Instant::now();
    let station_rss_with_mb = [rss_with_start, rss()?];
    if landed.load(Ordering::Relaxed) {
        bail!("the drone landed before the second window ended: time fewer frames");
    }
    tokio::time::sleep(Duration::from_millis(500)).await;
    let (relay_rss_mb, relay_rss_peak_mb) = memory_mb(relay_pid)?;
    let fewest_states_per_viewer = per_viewer
        .iter()
        .zip(&before_window)
        .map(|(r, before)| r.load(Ordering::Relaxed) - before)
        .min()
        .unwrap_or(0);
    let viewers_connected = open.load(Ordering::Relaxed) as usize;
    let (without, missed_a, _) = page_latencies(&sent_at, &seen_by_page, without_from..=without_to);
    let (with, missed_b, _) = page_latencies(&sent_at, &seen_by_page, with_from..=with_to);
    pages.iter().for_each(|p| p.abort());
    viewers.iter().for_each(|v| v.abort());
    viewer_runtime.shutdown_background();
    let _ = stop_drone.send(());
    drone_task
        .await
        .context("the drone's task")?
        .context("the simulated drone")?;
    relay.kill().await.ok();
    drop(station);
    Ok(RelayReport {
        viewers: options.viewers,
        pages: options.pages,
        without_relay: Latency::of(without),
        with_relay: Latency::of(with),
        missed: missed_a + missed_b,
        viewers_connected,
        fewest_states_per_viewer,
        station_counted,
        station_rss_without_mb,
        station_rss_with_mb,
        relay_rss_mb,
        relay_rss_peak_mb,
    })
}
