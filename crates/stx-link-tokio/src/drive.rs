//! [`drive`] runs a sans-io endpoint over a [`Transport`]: it reads, feeds bytes (each UDP
//! datagram whole, passing the endpoint's verdict on it back to the transport, which moves
//! its peer only on a datagram from the expected system) and timeouts to the endpoint, writes what it transmits, runs the application's closures on it (the only
//! way to touch the endpoint while it is driven) and forwards its events; [`drive_paths`] does
//! the same over several radios to one peer (see `stx_link::paths`).
//!
//! With signing on, the driver writes the signing timestamp's high-water mark to the
//! [`DriveOptions::signing_timestamp_file`] whenever it moves, before the frames signed under
//! it are sent, so a restart (even with the wall clock set back) continues above every
//! timestamp that ever left (`stx_link::signing::persist`).
//!
//! Time: `now` given to the endpoint is `tokio::time::Instant` elapsed since the driver
//! started, so `tokio::time::pause` makes tests deterministic.

use std::path::PathBuf;
use std::time::Duration;

use stx_link::sansio::{IoEvent, IoStats, SansIo};
use stx_link::signing::persist::store_signing_timestamp;
use tokio::sync::mpsc;
use tokio::time::Instant;

use crate::transport::{Transport, TransportError};

/// What the driver forwards to the application.
#[derive(Debug)]
pub enum DriverEvent<E> {
    /// An endpoint event.
    Endpoint(E),
    /// A transport event, on radio `path` (0 with one transport).
    Io { path: usize, event: IoEvent },
}

/// An action the application runs on the driven endpoint, given `now`.
pub type Action<E> = Box<dyn FnOnce(&mut E, Duration) + Send>;

/// Options of [`drive`].
#[derive(Debug, Clone, Default)]
pub struct DriveOptions {
    /// File where the signing timestamp high-water mark is written when it moves, before the
    /// frames signed under it are sent. With signing on, set it: without it the timestamps
    /// are monotonic across restarts only while the wall clock is.
    pub signing_timestamp_file: Option<PathBuf>,
}

/// Drives `endpoint` over `transport` until `actions` closes; returns the endpoint and the
/// transport's counters. Endpoint and I/O events go to `events` (if the receiver is gone they
/// are dropped, and the driver stops).
pub async fn drive<E: SansIo>(
    transport: Transport,
    endpoint: E,
    actions: mpsc::Receiver<Action<E>>,
    events: mpsc::Sender<DriverEvent<E::Event>>,
    options: DriveOptions,
) -> (E, IoStats) {
    let (endpoint, mut stats) =
        drive_paths(vec![transport], endpoint, actions, events, options).await;
    (endpoint, stats.pop().unwrap_or_default())
}

/// [`drive`] over several radios to the same peer: `transports[i]` is the endpoint's path
/// `i` (see [`stx_link::paths`]); bytes from each go to its path, and what the endpoint sends
/// goes out on its [`transmit_path`](SansIo::transmit_path). Returns each transport's
/// counters, in order.
pub async fn drive_paths<E: SansIo>(
    mut transports: Vec<Transport>,
    mut endpoint: E,
    mut actions: mpsc::Receiver<Action<E>>,
    events: mpsc::Sender<DriverEvent<E::Event>>,
    options: DriveOptions,
) -> (E, Vec<IoStats>) {
    let start = Instant::now();
    let mut bufs = vec![vec![0_u8; 65_536]; transports.len()];
    let mut open = true;
    // The last mark written, or the last one that failed (not retried: it is reported once,
    // and the mark moves on within seconds).
    let mut persisted = None;
    let mut frames = Vec::new();
    loop {
        let now = start.elapsed();
        endpoint.handle_timeout(now);
        while let Some(frame) = endpoint.poll_transmit(now) {
            frames.push(frame);
        }
        // The mark covering these frames' timestamps is on disk before they leave.
        let mark = endpoint.signing_timestamp_mark();
        if let (Some(path), Some(v)) = (options.signing_timestamp_file.as_deref(), mark)
            && persisted != Some(v)
        {
            persisted = Some(v);
            match store_signing_timestamp(path, v) {
                Ok(()) => {}
                // The link matters more than the guarantee: send anyway, and say so.
                Err(err) => {
                    tracing::error!(path = %path.display(), error = %err, "cannot persist signing timestamp");
                    if let Some(t) = transports.first_mut() {
                        t.events.push_back(IoEvent::PersistFailed {
                            path: path.to_path_buf(),
                            error: err.to_string(),
                        });
                    }
                }
            }
        }
        if !frames.is_empty() {
            let out = endpoint
                .transmit_path(now)
                .min(transports.len().saturating_sub(1));
            if let Some(transport) = transports.get_mut(out) {
                for frame in frames.drain(..) {
                    transport.send(&frame).await;
                }
            }
        }
        while let Some(e) = endpoint.poll_event() {
            if events.send(DriverEvent::Endpoint(e)).await.is_err() {
                open = false;
            }
        }
        for (path, transport) in transports.iter_mut().enumerate() {
            while let Some(event) = transport.poll_event() {
                if events.send(DriverEvent::Io { path, event }).await.is_err() {
                    open = false;
                }
            }
        }
        if !open {
            break;
        }
        let deadline = endpoint
            .poll_timeout()
            .map(|t| start + t)
            .unwrap_or_else(|| Instant::now() + Duration::from_secs(1));
        tokio::select! {
            (path, n) = recv_any(&mut transports, &mut bufs) => {
                if n > 0 {
                    let bytes = bufs.get(path).and_then(|b| b.get(..n)).unwrap_or(&[]);
                    match transports.get_mut(path) {
                        // Only the endpoint can tell a frame from its peer: its verdict decides
                        // whether the datagram's source becomes the transport's peer.
                        Some(t) if t.is_datagram() => {
                            let from_peer = endpoint.handle_datagram_on(path, start.elapsed(), bytes);
                            t.datagram_verdict(from_peer);
                        }
                        _ => endpoint.handle_bytes_on(path, start.elapsed(), bytes),
                    }
                }
                if transports.get_mut(path).is_some_and(Transport::take_stream_ended) {
                    endpoint.handle_stream_end_on(path, start.elapsed());
                }
            }
            action = actions.recv() => match action {
                Some(a) => a(&mut endpoint, start.elapsed()),
                None => break,
            },
            _ = tokio::time::sleep_until(deadline) => {}
        }
    }
    let stats = transports.iter().map(Transport::stats).collect();
    (endpoint, stats)
}

/// Waits for bytes on any transport: `(which, how many)` (see [`Transport::recv`]).
/// Cancel-safe, as each transport's `recv` is.
async fn recv_any(transports: &mut [Transport], bufs: &mut [Vec<u8>]) -> (usize, usize) {
    match (transports, bufs) {
        ([], _) | (_, []) => std::future::pending().await,
        ([only], [buf, ..]) => (0, only.recv(buf).await),
        (transports, bufs) => {
            let receivers = transports
                .iter_mut()
                .zip(bufs.iter_mut())
                .enumerate()
                .map(|(i, (t, buf))| Box::pin(async move { (i, t.recv(buf).await) }));
            futures_util::future::select_all(receivers).await.0
        }
    }
}

/// Opens `address` and drives `endpoint` over it (see [`drive`]).
pub async fn connect_and_drive<E: SansIo>(
    address: &str,
    endpoint: E,
    actions: mpsc::Receiver<Action<E>>,
    events: mpsc::Sender<DriverEvent<E::Event>>,
    options: DriveOptions,
) -> Result<(E, IoStats), TransportError> {
    let transport = Transport::open_str(address).await?;
    Ok(drive(transport, endpoint, actions, events, options).await)
}
