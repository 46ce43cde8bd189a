//! `stx bench station --lab-montecarlo N`: Lab Monte Carlo batches of N runs started over the
//! API (as the Lab page starts them), one after another for the whole telemetry window — a new
//! batch as soon as the last one ends — and the last cancelled after it, so the figure shows
//! whether a long Lab job stalls telemetry on its way to the pages. A batch of the Lab's
//! largest size (500 runs) ends well inside the 60 s window on a fast machine, so a single
//! batch would leave part of the window measured with the Lab idle; the report says how much
//! of the window the Lab was busy, counted from the batches' start and end as seen.

use std::net::SocketAddr;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use http_body_util::Full;
use hyper::body::Bytes;
use serde::Serialize;
use stx_station::daemon::Running;
use stx_station::lab::{LabResult, LabService};
use tokio::sync::watch;
use tokio::task::JoinHandle;

/// How often the Lab's state is read to start the next batch: the idle gap between two
/// batches is at most this plus one HTTP request.
const POLL: Duration = Duration::from_millis(5);

/// What the Lab jobs did during the telemetry window.
#[derive(Debug, Serialize)]
pub struct LabLoadReport {
    /// Runs asked of each batch.
    pub runs_per_batch: u32,
    /// Batches started (the last one cancelled at the window's end if still running).
    pub batches: u32,
    /// Batches that ended on their own (done or stopped by the time cap) before the end.
    pub batches_finished: u32,
    /// Runs flown by all the batches until the window ended.
    pub runs_flown: u64,
    /// Share of the telemetry window during which a batch ran (0 … 1): from the answer to
    /// its start to the last moment it was seen running, so a gap is never counted as busy.
    pub busy_fraction: f64,
    /// The longest gap between two batches inside the window, ms.
    pub longest_idle_ms: f64,
}

/// The share of `window` (`from`, `to`, s) that `spans` (`start`, `end`, s; in any order,
/// overlaps counted once) cover, and the longest stretch of it they leave uncovered, s.
pub fn coverage(spans: &[(f64, f64)], window: (f64, f64)) -> (f64, f64) {
    let (from, to) = window;
    if to <= from {
        return (0.0, 0.0);
    }
    let mut clipped: Vec<(f64, f64)> = spans
        .iter()
        .map(|&(a, b)| (a.max(from), b.min(to)))
        .filter(|(a, b)| b > a)
        .collect();
    clipped.sort_by(|x, y| x.0.total_cmp(&y.0));
    let (mut covered, mut longest_gap, mut reached) = (0.0, 0.0_f64, from);
    for (a, b) in clipped {
        if a > reached {
            longest_gap = longest_gap.max(a - reached);
        }
        if b > reached {
            covered += b - a.max(reached);
            reached = b;
        }
    }
    longest_gap = longest_gap.max(to - reached);
    (covered / (to - from), longest_gap)
}

/// What the batch-starting task saw.
#[derive(Default)]
struct Batches {
    started: u32,
    finished: u32,
    /// Runs of the batches that ended.
    runs_flown: u64,
    /// Each batch's (answered, last seen running).
    spans: Vec<(Instant, Instant)>,
}

/// Lab batches running beside the measurement.
pub struct LabLoad {
    runs: u32,
    stop: watch::Sender<bool>,
    task: JoinHandle<anyhow::Result<Batches>>,
    http: SocketAddr,
    token: String,
}

impl LabLoad {
    /// Gives the station its Lab and keeps `runs`-run batches going as an operator until
    /// [`LabLoad::stop`]; returns once the first batch runs.
    pub async fn start(running: &Running, token: &str, runs: u32) -> anyhow::Result<Self> {
        let dir = std::env::temp_dir().join("stx-bench-lab");
        let _ = running.shared.lab.set(stx_lab::service(dir));
        let lab = running.shared.lab.get().context("the Lab")?.clone();
        let mut sender = connect(running.http).await?;
        let mut batches = Batches::default();
        let first = start_batch(&mut sender, running.http, token, runs, 1).await?;
        batches.started = 1;
        let (stop, stop_rx) = watch::channel(false);
        let task = tokio::spawn(keep_busy(
            lab,
            running.shared.clone(),
            sender,
            (running.http, token.to_string()),
            runs,
            first,
            batches,
            stop_rx,
        ));
        Ok(Self {
            runs,
            stop,
            task,
            http: running.http,
            token: token.to_string(),
        })
    }

    /// Stops starting batches, cancels the one running and says what ran in the window
    /// `from` … `to`.
    pub async fn stop(self, from: Instant, to: Instant) -> anyhow::Result<LabLoadReport> {
        let _ = self.stop.send(true);
        let mut batches = self.task.await.context("the Lab load's task")??;
        let mut sender = connect(self.http).await?;
        let cancel = crate::http::post(
            &mut sender,
            self.http,
            "/api/lab/cancel",
            &self.token,
            String::new(),
        )
        .await?;
        // 404: the last batch ended on its own meanwhile (its runs are already counted).
        if cancel != 200 && cancel != 404 {
            bail!("the station answered {cancel} to the Lab's cancel");
        }
        let at = |t: Instant| t.saturating_duration_since(from).as_secs_f64();
        let spans: Vec<(f64, f64)> = batches.spans.iter().map(|&(a, b)| (at(a), at(b))).collect();
        let (busy_fraction, longest_idle_s) = coverage(&spans, (0.0, at(to)));
        batches.spans.clear();
        Ok(LabLoadReport {
            runs_per_batch: self.runs,
            batches: batches.started,
            batches_finished: batches.finished,
            runs_flown: batches.runs_flown,
            busy_fraction,
            longest_idle_ms: longest_idle_s * 1e3,
        })
    }
}

async fn connect(
    http: SocketAddr,
) -> anyhow::Result<hyper::client::conn::http1::SendRequest<Full<Bytes>>> {
    let stream = tokio::net::TcpStream::connect(http).await?;
    let (sender, connection) =
        hyper::client::conn::http1::handshake(hyper_util::rt::TokioIo::new(stream)).await?;
    tokio::spawn(connection);
    Ok(sender)
}

/// Starts batch number `n` (its seed, so each batch flies other landings); when it answered.
async fn start_batch(
    sender: &mut hyper::client::conn::http1::SendRequest<Full<Bytes>>,
    http: SocketAddr,
    token: &str,
    runs: u32,
    n: u32,
) -> anyhow::Result<Instant> {
    let body = format!(
        r#"{{"kind":"monte_carlo","runs":{runs},"seed":{n},"wind_max_mps":4,"altitude_m":600}}"#
    );
    let status = crate::http::post(sender, http, "/api/lab/jobs", token, body)
        .await
        .context("starting a Lab batch")?;
    if status != 202 {
        bail!("the station answered {status} to Lab batch {n}");
    }
    Ok(Instant::now())
}

/// Watches the running batch and starts the next as soon as it ends, until told to stop;
/// the runs of the batch still running then are read as it is left.
#[allow(clippy::too_many_arguments)]
async fn keep_busy(
    lab: Arc<LabService>,
    shared: Arc<stx_station::http::Shared>,
    mut sender: hyper::client::conn::http1::SendRequest<Full<Bytes>>,
    (http, token): (SocketAddr, String),
    runs: u32,
    mut started: Instant,
    mut batches: Batches,
    stop: watch::Receiver<bool>,
) -> anyhow::Result<Batches> {
    let mut seen_running = started;
    loop {
        tokio::time::sleep(POLL).await;
        let status = lab.jobs().status(shared.now_s());
        if let Some(job) = &status.job {
            seen_running = Instant::now();
            if *stop.borrow() {
                batches.runs_flown += job.done;
                batches.spans.push((started, seen_running));
                return Ok(batches);
            }
            continue;
        }
        batches.spans.push((started, seen_running));
        batches.finished += 1;
        match status.last.as_ref().and_then(|l| l.result.as_ref()) {
            Some(LabResult::MonteCarlo(summary)) => batches.runs_flown += summary.runs_flown,
            _ => bail!(
                "a Lab batch ended without its runs: {}",
                status.last.map_or("no outcome".into(), |l| l.outcome)
            ),
        }
        if *stop.borrow() {
            return Ok(batches);
        }
        batches.started += 1;
        started = start_batch(&mut sender, http, &token, runs, batches.started).await?;
        seen_running = started;
    }
}

#[cfg(test)]
mod tests {
    use super::coverage;

    #[test]
    fn batches_back_to_back_cover_the_window_and_gaps_are_idle() {
        // Two batches leaving 0.5 s between them, the first started before the window.
        let (busy, gap) = coverage(&[(-1.0, 20.0), (20.5, 60.0)], (0.0, 60.0));
        assert!((busy - 59.5 / 60.0).abs() < 1e-12, "{busy}");
        assert!((gap - 0.5).abs() < 1e-12, "{gap}");
    }

    #[test]
    fn a_batch_ending_early_leaves_the_rest_idle() {
        let (busy, gap) = coverage(&[(0.0, 45.0)], (0.0, 60.0));
        assert_eq!((busy, gap), (0.75, 15.0));
        let (busy, gap) = coverage(&[], (0.0, 60.0));
        assert_eq!((busy, gap), (0.0, 60.0));
    }

    #[test]
    fn overlaps_count_once_and_spans_outside_count_nothing() {
        let (busy, gap) = coverage(
            &[(30.0, 40.0), (10.0, 35.0), (70.0, 90.0), (-5.0, -1.0)],
            (0.0, 60.0),
        );
        assert_eq!((busy, gap), (0.5, 20.0));
        assert_eq!(coverage(&[(0.0, 1.0)], (5.0, 5.0)), (0.0, 0.0));
    }
}
