//! `stx bench station --lab-montecarlo N`: a Lab Monte Carlo batch started over the API (as
//! the Lab page starts it) just before telemetry is timed and cancelled after, so the figure
//! shows whether a long Lab job stalls telemetry on its way to the pages.

use std::net::SocketAddr;

use anyhow::{Context, bail};
use http_body_util::Full;
use hyper::body::Bytes;
use serde::Serialize;
use stx_station::daemon::Running;
use stx_station::lab::LabResult;

/// What the Lab job did during the telemetry window.
#[derive(Debug, Serialize)]
pub struct LabLoadReport {
    /// Runs asked of the batch.
    pub runs_asked: u32,
    /// Runs flown when the window ended.
    pub runs_done_in_window: u64,
    /// The batch was still running when the window ended (it loaded the whole window).
    pub running_at_window_end: bool,
}

/// A Lab batch running beside the measurement.
pub struct LabLoad {
    runs: u32,
    sender: hyper::client::conn::http1::SendRequest<Full<Bytes>>,
    http: SocketAddr,
    token: String,
}

impl LabLoad {
    /// Gives the station its Lab and starts a `runs`-run batch as an operator.
    pub async fn start(running: &Running, token: &str, runs: u32) -> anyhow::Result<Self> {
        let dir = std::env::temp_dir().join("stx-bench-lab");
        let _ = running.shared.lab.set(crate::lab::service(dir));
        let stream = tokio::net::TcpStream::connect(running.http).await?;
        let (mut sender, connection) =
            hyper::client::conn::http1::handshake(hyper_util::rt::TokioIo::new(stream)).await?;
        tokio::spawn(connection);
        let body = format!(
            r#"{{"kind":"monte_carlo","runs":{runs},"seed":1,"wind_max_mps":4,"altitude_m":600}}"#
        );
        let status =
            crate::bench_http::post(&mut sender, running.http, "/api/lab/jobs", token, body)
                .await
                .context("starting the Lab batch")?;
        if status != 202 {
            bail!("the station answered {status} to the Lab batch");
        }
        Ok(Self {
            runs,
            sender,
            http: running.http,
            token: token.to_string(),
        })
    }

    /// The batch's state at the window's end; then cancels it.
    pub async fn stop(mut self, running: &Running) -> anyhow::Result<LabLoadReport> {
        let status = running
            .shared
            .lab
            .get()
            .context("the Lab")?
            .jobs()
            .status(running.shared.now_s());
        // A batch that ended within the window (done, failed or stopped by the time cap) flew
        // the runs its outcome counts, not necessarily all those asked.
        let runs_done_in_window = match (&status.job, &status.last) {
            (Some(job), _) => job.done,
            (None, Some(last)) => match &last.result {
                Some(LabResult::MonteCarlo(summary)) => summary.runs_flown,
                _ => bail!("the Lab batch ended without its runs: {}", last.outcome),
            },
            (None, None) => bail!("the Lab has neither the batch nor its outcome"),
        };
        let report = LabLoadReport {
            runs_asked: self.runs,
            runs_done_in_window,
            running_at_window_end: status.job.is_some(),
        };
        if report.running_at_window_end {
            crate::bench_http::post(
                &mut self.sender,
                self.http,
                "/api/lab/cancel",
                &self.token,
                String::new(),
            )
            .await?;
        }
        Ok(report)
    }
}
