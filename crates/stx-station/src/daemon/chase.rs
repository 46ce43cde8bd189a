//! `[chase]` on the network: every `period_s` the station's state becomes Horus UDP
//! `PAYLOAD_SUMMARY` datagrams ([`crate::chase`]) sent to the configured (broadcast) address.
//! A send that fails (no network on the field laptop) is logged once per run of failures and
//! retried at the next period: the chase map is a convenience, never a reason to stop.

use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;

use tokio::net::UdpSocket;
use tokio::sync::watch;

use crate::chase::{ChaseConfig, summaries};
use crate::forward::ChaseView;
use crate::http::Shared;

/// What the pages show of `config` before anything was sent.
pub(super) fn view(config: &ChaseConfig) -> ChaseView {
    ChaseView {
        callsign: config.callsign.clone(),
        landing_callsign: config.landing_callsign(),
        to: SocketAddr::new(config.address, config.port).to_string(),
        period_s: config.period_s,
        sent: 0,
        last_sent_wall_ms: None,
        error: None,
    }
}

/// Sends the summaries until `stop`.
pub(super) async fn run(config: ChaseConfig, shared: Arc<Shared>, mut stop: watch::Receiver<bool>) {
    let socket = match UdpSocket::bind(("0.0.0.0", 0)).await {
        Ok(s) => s,
        Err(e) => {
            tracing::error!(error = %e, "chase broadcast: no socket");
            return;
        }
    };
    if let Err(e) = socket.set_broadcast(true) {
        tracing::warn!(error = %e, "chase broadcast: broadcast not allowed, sending anyway");
    }
    let to = SocketAddr::new(config.address, config.port);
    tracing::info!(%to, callsign = %config.callsign, "chase broadcast on");
    let ground = shared.config.origin.alt_msl_m;
    let mut every = tokio::time::interval(Duration::from_secs_f64(config.period_s));
    let mut failing = false;
    loop {
        tokio::select! {
            _ = every.tick() => {}
            _ = stop.changed() => break,
        }
        let now = shared.now_s();
        let state = shared.core().state_msg_now(now);
        for summary in summaries(&config, ground, &state) {
            let Ok(bytes) = serde_json::to_vec(&summary) else {
                continue;
            };
            let sent = socket.send_to(&bytes, to).await;
            note(&shared, &sent, state.wall_ms);
            match sent {
                Ok(_) => failing = false,
                Err(e) if !failing => {
                    failing = true;
                    tracing::warn!(%to, error = %e, "chase broadcast: send failed (retried every period)");
                }
                Err(_) => {}
            }
        }
    }
}

/// What the pages are shown of a send at `wall_ms`.
fn note(shared: &Shared, sent: &std::io::Result<usize>, wall_ms: u64) {
    let Ok(mut guard) = shared.chase.lock() else {
        return;
    };
    let Some(view) = guard.as_mut() else { return };
    match sent {
        Ok(_) => {
            view.sent += 1;
            view.last_sent_wall_ms = Some(wall_ms);
            view.error = None;
        }
        Err(e) => view.error = Some(e.to_string()),
    }
}
