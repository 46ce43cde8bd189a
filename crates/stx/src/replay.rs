//! `stx replay FILE`: a recording played back through a station into the same dashboard
//! (`stx_station::replay`): REPLAY on the page, commands refused, pause, seek and speed from
//! the page (`POST /api/replay`).

use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, ValueEnum};
use stx_station::daemon::{PreparedReplay, serve_replay};
use stx_station::replay::{MAX_SPEED, MIN_SPEED, ReplayMode};

use crate::BadInput;
use crate::serve::{announce, check_exposure, load_config, shutdown_signal};

#[derive(Clone, Copy, ValueEnum)]
enum Mode {
    /// The recorded link bytes through this station's estimator, guidance and predictor
    /// (with `--config`, e.g. other guidance gains).
    Rerun,
    /// The station's `state` and events as they were recorded.
    Recorded,
}

#[derive(Args)]
pub struct ReplayArgs {
    /// The recording (MCAP) to play.
    file: PathBuf,
    /// × real time, 0.25–64 (the page can change it).
    #[arg(long, default_value_t = 1.0)]
    speed: f64,
    /// Where the dashboard listens (default: the configuration's). Beyond loopback the
    /// shipped rehearsal tokens are refused, and plain HTTP needs --insecure-http.
    #[arg(long)]
    listen: Option<std::net::SocketAddr>,
    /// Serve plain HTTP beyond loopback without `[tls]`: tokens cross the network in clear.
    #[arg(long)]
    insecure_http: bool,
    /// Re-run the station on the recorded link bytes, or show what was recorded.
    #[arg(long, value_enum, default_value = "rerun")]
    mode: Mode,
    /// Station configuration (tokens, map, guidance settings; default: the shipped one).
    #[arg(long)]
    config: Option<PathBuf>,
}

pub fn run(args: ReplayArgs) -> anyhow::Result<()> {
    if !(MIN_SPEED..=MAX_SPEED).contains(&args.speed) {
        return Err(BadInput(anyhow::anyhow!(
            "--speed {} is not within {MIN_SPEED}–{MAX_SPEED}",
            args.speed
        ))
        .into());
    }
    let mode = match args.mode {
        Mode::Rerun => ReplayMode::Rerun,
        Mode::Recorded => ReplayMode::Recorded,
    };
    let prepared =
        PreparedReplay::open(&args.file, mode, args.speed).map_err(|e| BadInput(e.into()))?;
    let mut config = load_config(args.config.as_deref())?;
    if let Some(listen) = args.listen {
        config.listen = listen;
    }
    check_exposure(&config, args.insecure_http)?;
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .context("starting the async runtime")?;
    runtime.block_on(async {
        let operator = config.operator_token().unwrap_or_default().to_owned();
        serve_replay(config, prepared, shutdown_signal(), |running| {
            announce(&format!(
                "stx replay: open {}://{}/?token={operator}\n",
                running.scheme, running.http
            ));
        })
        .await
        .context("replay station")
    })
}
