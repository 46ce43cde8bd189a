//! `[surface_wind] anemometer` on the network or a serial line: the ground anemometer's NMEA
//! 0183 bytes, split into lines ([`crate::surface_wind::SentenceLines`]: a UDP datagram is a
//! whole sentence or several, a serial line a stream) and handed to the core, which parses
//! and averages them. The transport is stx-link-tokio's, so a serial port that is unplugged
//! is reopened as the drone's would be. A failure is shown and logged by the core; the
//! anemometer is a help to the final, never a reason to stop.

use std::sync::Arc;

use stx_link::address::Address;
use stx_link::sansio::IoEvent;
use stx_link_tokio::transport::Transport;
use tokio::sync::watch;

use crate::http::Shared;
use crate::surface_wind::SentenceLines;

/// Reads the anemometer at `address` until `stop`.
pub(super) async fn run(address: Address, shared: Arc<Shared>, mut stop: watch::Receiver<bool>) {
    let datagrams = matches!(address, Address::UdpIn(_));
    let name = address.to_string();
    let mut transport = match Transport::open(address).await {
        Ok(t) => t,
        Err(e) => {
            let now = shared.now_s();
            shared
                .core()
                .on_anemometer_error(now, format!("anemometer {name} not opened: {e}"));
            return;
        }
    };
    tracing::info!(address = %name, "reading the ground anemometer");
    let mut lines = SentenceLines::default();
    let mut buf = vec![0u8; 2048];
    loop {
        let n = tokio::select! {
            n = transport.recv(&mut buf) => n,
            _ = stop.changed() => break,
        };
        let got = if datagrams {
            lines.push_datagram(&buf[..n])
        } else {
            lines.push(&buf[..n])
        };
        let events: Vec<IoEvent> = std::iter::from_fn(|| transport.poll_event()).collect();
        if got.is_empty() && events.is_empty() {
            continue;
        }
        let now = shared.now_s();
        let mut core = shared.core();
        for line in got {
            core.on_anemometer_line(now, &line);
        }
        for event in events {
            match event {
                IoEvent::RecvError { error, .. } | IoEvent::Disconnected { reason: error } => {
                    core.on_anemometer_error(now, format!("anemometer {name}: {error}"));
                }
                other => tracing::debug!(?other, "anemometer transport"),
            }
        }
    }
}
