//! The `[[forward]]` outputs on the network: one task per forward, fed by the link driver
//! through a broadcast channel (it never waits: a forward that falls behind loses frames and
//! counts them, the link does not slow down). What a watcher sends is filtered by
//! [`stx_link::forward::Forward`] and only what its `in` filter allows is queued to the link
//! as it is; by default that is nothing.

use std::sync::{Arc, Mutex};

use stx_link::forward::Forward;
use stx_link_tokio::{Action, Transport};
use tokio::sync::{broadcast, mpsc, watch};
use tokio::time::Instant;

use crate::forward::{ForwardConfig, ForwardView};
use crate::link::{ForwardSink, StationLink};

/// Frames the link accepted and the slowest forward has not sent yet; beyond, it loses some.
const BACKLOG: usize = 4096;

/// The link's side: each accepted frame onto the channel, at once.
struct Broadcast(broadcast::Sender<Arc<Vec<u8>>>);

impl ForwardSink for Broadcast {
    fn accepted(&mut self, frame: Vec<u8>) {
        // No forward running (all failed to open) is not the link's concern.
        let _ = self.0.send(Arc::new(frame));
    }
}

/// The forwards' views, each kept up to date by its task.
pub(super) type ForwardViews = Arc<Mutex<Vec<ForwardView>>>;

/// Opens the forwards of `configs` (each reporting into its slot of the returned views);
/// returns the sink for the link, or `None` without forwards.
pub(super) fn start(
    configs: &[ForwardConfig],
    actions: mpsc::Sender<Action<StationLink>>,
    stop: watch::Receiver<bool>,
) -> (Option<Box<dyn ForwardSink>>, ForwardViews) {
    let views = Arc::new(Mutex::new(
        configs
            .iter()
            .map(|c| ForwardView::new(c, Default::default(), 0))
            .collect::<Vec<_>>(),
    ));
    if configs.is_empty() {
        return (None, views);
    }
    let (tx, _) = broadcast::channel(BACKLOG);
    for (i, config) in configs.iter().enumerate() {
        tokio::spawn(run(
            i,
            config.clone(),
            tx.subscribe(),
            actions.clone(),
            views.clone(),
            stop.clone(),
        ));
    }
    (Some(Box::new(Broadcast(tx))), views)
}

async fn run(
    index: usize,
    config: ForwardConfig,
    mut frames: broadcast::Receiver<Arc<Vec<u8>>>,
    actions: mpsc::Sender<Action<StationLink>>,
    views: ForwardViews,
    mut stop: watch::Receiver<bool>,
) {
    let mut transport = match Transport::open_str(&config.address).await {
        Ok(t) => t,
        Err(e) => {
            tracing::error!(forward = %config.name, error = %e, "forward not opened");
            return;
        }
    };
    tracing::info!(forward = %config.name, address = %config.address, read_only = config.into_link.allow_msg_id.is_none(), "forwarding the link");
    let mut forward = Forward::new(config.out.clone(), config.into_link.clone());
    let start = Instant::now();
    let mut buf = vec![0_u8; 65_536];
    let mut dropped = 0_u64;
    loop {
        tokio::select! {
            frame = frames.recv() => match frame {
                Ok(frame) => {
                    if forward.to_watcher(&frame) {
                        transport.send(&frame).await;
                    }
                }
                Err(broadcast::error::RecvError::Lagged(n)) => dropped += n,
                Err(broadcast::error::RecvError::Closed) => break,
            },
            n = transport.recv(&mut buf) => {
                let bytes = buf.get(..n).unwrap_or(&[]);
                let heard = forward.counts().in_passed + forward.counts().in_refused;
                for frame in forward.from_watcher(start.elapsed(), bytes) {
                    let send: Action<StationLink> = Box::new(move |link, _| link.send_raw_frame(frame));
                    if actions.try_send(send).is_err() {
                        tracing::warn!(forward = %config.name, "link busy: a watcher's frame dropped");
                    }
                }
                let counts = forward.counts();
                if transport.is_datagram() {
                    // A `udpin:` forward answers whoever last sent it a frame.
                    transport.datagram_verdict(counts.in_passed + counts.in_refused > heard);
                }
                let _ = transport.take_stream_ended();
            }
            _ = stop.changed() => break,
        }
        if let Ok(mut views) = views.lock()
            && let Some(view) = views.get_mut(index)
        {
            *view = ForwardView::new(&config, forward.counts(), dropped);
        }
    }
}
