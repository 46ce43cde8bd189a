//! `stx serve`: the ground station daemon — the drone link, the station's estimator, guidance
//! replica and predictor, and the dashboard on localhost.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use stx_station::config::{DEFAULT_STATION_TOML, StationConfig};

use crate::BadInput;

#[derive(Args)]
pub struct ServeArgs {
    /// Station configuration (default: the shipped config/station.toml).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Listen on this address instead of the configuration's (e.g. 127.0.0.1:8080).
    #[arg(long)]
    listen: Option<std::net::SocketAddr>,
    /// The drone link instead of the configuration's (e.g. udpin:0.0.0.0:14550,
    /// serial:/dev/ttyUSB0:57600, tcpout:192.168.1.20:5760).
    #[arg(long)]
    link: Option<String>,
}

/// Reads and validates the station configuration.
pub fn load_config(path: Option<&std::path::Path>) -> anyhow::Result<StationConfig> {
    let text = match path {
        None => DEFAULT_STATION_TOML.to_string(),
        Some(p) => std::fs::read_to_string(p)
            .with_context(|| format!("cannot read station config {}", p.display()))
            .map_err(BadInput)?,
    };
    StationConfig::from_toml_str(&text)
        .with_context(|| {
            format!(
                "station config {}",
                path.map_or("(shipped)".into(), |p| p.display().to_string())
            )
        })
        .map_err(|e| BadInput(e).into())
}

pub fn run(args: ServeArgs) -> anyhow::Result<()> {
    let mut config = load_config(args.config.as_deref())?;
    if let Some(listen) = args.listen {
        config.listen = listen;
    }
    if let Some(link) = args.link {
        config.link.address = link;
        config.validate().context("--link").map_err(BadInput)?;
    }
    if !config.web_dir.join("index.html").exists() {
        tracing::warn!(
            dir = %config.web_dir.display(),
            "the dashboard is not built here: run `cd web && npm ci && npm run build` (the API works without it)"
        );
    }
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .context("starting the async runtime")?;
    runtime.block_on(async move {
        let operator = config
            .tokens
            .iter()
            .find(|t| t.role == stx_station::config::Role::Operator)
            .map(|t| t.token.clone())
            .unwrap_or_default();
        stx_station::daemon::run(config, shutdown_signal(), move |running| {
            println!(
                "stx station: open http://{}/?token={operator}",
                running.http
            );
        })
        .await
        .context("station")
    })
}

/// Ctrl-C, or SIGTERM from systemd or a container runtime.
async fn shutdown_signal() {
    let interrupt = tokio::signal::ctrl_c();
    #[cfg(unix)]
    {
        let mut term =
            match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
                Ok(term) => term,
                Err(e) => {
                    tracing::warn!(error = %e, "SIGTERM will not stop the station gracefully");
                    let _ = interrupt.await;
                    return;
                }
            };
        tokio::select! {
            _ = interrupt => {}
            _ = term.recv() => {}
        }
    }
    #[cfg(not(unix))]
    let _ = interrupt.await;
    tracing::info!("shutting down");
}
