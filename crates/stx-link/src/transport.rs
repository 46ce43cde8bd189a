//! Thin tokio adapters that move bytes between a socket (or serial port) and a sans-io
//! endpoint, so the protocol logic above stays free of I/O and clocks.
//!
//! - [`Address`] parses `udpin:HOST:PORT`, `udpout:HOST:PORT`, `tcp:HOST:PORT` (client),
//!   `tcpin:HOST:PORT` (server) and `serial:PATH:BAUD`, with an [`AddressError`] that says what
//!   is wrong.
//! - [`Transport`] is an open socket. UDP-in answers whoever sent the last datagram; frames sent
//!   before any peer was heard are queued (up to [`MAX_QUEUED_WITHOUT_PEER`]) and flushed when
//!   one is, with an [`IoEvent`] for the queueing and for any overflow. TCP server accepts one
//!   client at a time and accepts the next when it leaves; TCP client and serial reopen after
//!   [`REOPEN_DELAY`].
//! - [`drive`] runs an endpoint over a transport: it reads, feeds bytes and timeouts to the
//!   endpoint, writes what it transmits, runs the application's closures on it (the only way
//!   to touch the endpoint while it is driven) and forwards its events. No I/O error is
//!   swallowed: each is counted in [`IoStats`]; they are reported (a `tracing` warning and an
//!   [`IoEvent`]) rate-limited, because a link without a peer fails every frame — the first
//!   failure at once, then one report with the count per [`IO_ERROR_REPORT_INTERVAL`] while
//!   failures go on.
//! - [`drive_paths`] does the same over several radios to one peer (see [`crate::paths`]).
//! - With signing on, [`drive`] writes the signing timestamp's high-water mark to the
//!   [`DriveOptions::signing_timestamp_file`] whenever it moves, before the frames signed under
//!   it are sent, so a restart (even with the wall clock set back) continues above every
//!   timestamp that ever left. [`default_state_dir`] is where stx keeps such files by default.
//!
//! Time: `now` given to the endpoint is `tokio::time::Instant` elapsed since the driver
//! started, so `tokio::time::pause` makes tests deterministic.

use std::collections::VecDeque;
use std::fmt;
use std::io;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::Duration;

use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};
use tokio::net::{TcpListener, TcpStream, UdpSocket};
use tokio::sync::mpsc;
use tokio::time::Instant;

use crate::endpoint::{GroundEndpoint, GroundEvent, VehicleEndpoint, VehicleEvent};

/// Frames kept for a UDP-in peer not yet heard from.
pub const MAX_QUEUED_WITHOUT_PEER: usize = 256;

/// Wait before re-opening a TCP client connection or a serial port.
pub const REOPEN_DELAY: Duration = Duration::from_secs(1);

/// Shortest time between two reports of failing reads (or writes) of one transport.
pub const IO_ERROR_REPORT_INTERVAL: Duration = Duration::from_secs(5);

/// Where to connect.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Address {
    /// Bind here; reply to the address last heard from.
    UdpIn(SocketAddr),
    /// Send to this fixed address (bound to an ephemeral local port), receive replies.
    UdpOut(SocketAddr),
    /// TCP client to `host:port`.
    TcpClient(String),
    /// TCP server bound here.
    TcpServer(SocketAddr),
    /// Serial port.
    Serial { path: String, baud: u32 },
}

/// A malformed transport address.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum AddressError {
    /// Nothing before the first `:` we know.
    #[error(
        "unknown transport {scheme:?} in {address:?}: use udpin:, udpout:, tcp:, tcpin: or serial:"
    )]
    UnknownScheme { address: String, scheme: String },
    /// No `:` at all.
    #[error("{address:?} has no transport prefix: expected e.g. udpin:127.0.0.1:14550")]
    MissingScheme { address: String },
    /// The socket address does not parse.
    #[error("{address:?}: {rest:?} is not IP:PORT ({reason})")]
    BadSocketAddr {
        address: String,
        rest: String,
        reason: String,
    },
    /// TCP client without a port.
    #[error("{address:?}: expected HOST:PORT")]
    BadHostPort { address: String },
    /// Serial without path or baud.
    #[error("{address:?}: expected serial:PATH:BAUD, e.g. serial:/dev/ttyUSB0:57600")]
    BadSerial { address: String },
    /// Baud rate not a positive number.
    #[error("{address:?}: baud rate {baud:?} is not a positive integer")]
    BadBaud { address: String, baud: String },
}

impl FromStr for Address {
    type Err = AddressError;

    fn from_str(address: &str) -> Result<Self, AddressError> {
        let owned = || address.to_string();
        let (scheme, rest) = address
            .split_once(':')
            .ok_or_else(|| AddressError::MissingScheme { address: owned() })?;
        let sock = |rest: &str| {
            rest.parse::<SocketAddr>()
                .map_err(|e| AddressError::BadSocketAddr {
                    address: owned(),
                    rest: rest.to_string(),
                    reason: e.to_string(),
                })
        };
        match scheme {
            "udpin" => Ok(Self::UdpIn(sock(rest)?)),
            "udpout" | "udp" => Ok(Self::UdpOut(sock(rest)?)),
            "tcpin" => Ok(Self::TcpServer(sock(rest)?)),
            "tcp" | "tcpout" => match rest.rsplit_once(':') {
                Some((host, port)) if !host.is_empty() && port.parse::<u16>().is_ok() => {
                    Ok(Self::TcpClient(rest.to_string()))
                }
                _ => Err(AddressError::BadHostPort { address: owned() }),
            },
            "serial" => {
                let (path, baud) = rest
                    .rsplit_once(':')
                    .ok_or_else(|| AddressError::BadSerial { address: owned() })?;
                if path.is_empty() {
                    return Err(AddressError::BadSerial { address: owned() });
                }
                let b = baud.parse::<u32>().ok().filter(|&b| b > 0).ok_or_else(|| {
                    AddressError::BadBaud {
                        address: owned(),
                        baud: baud.to_string(),
                    }
                })?;
                Ok(Self::Serial {
                    path: path.to_string(),
                    baud: b,
                })
            }
            other => Err(AddressError::UnknownScheme {
                address: owned(),
                scheme: other.to_string(),
            }),
        }
    }
}

impl fmt::Display for Address {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::UdpIn(a) => write!(f, "udpin:{a}"),
            Self::UdpOut(a) => write!(f, "udpout:{a}"),
            Self::TcpClient(a) => write!(f, "tcp:{a}"),
            Self::TcpServer(a) => write!(f, "tcpin:{a}"),
            Self::Serial { path, baud } => write!(f, "serial:{path}:{baud}"),
        }
    }
}

/// Failure to open or run a transport.
#[derive(Debug, thiserror::Error)]
pub enum TransportError {
    /// Bad address.
    #[error(transparent)]
    Address(#[from] AddressError),
    /// Opening failed.
    #[error("cannot open {address}: {source}")]
    Open {
        address: String,
        #[source]
        source: io::Error,
    },
    /// Serial support not compiled in.
    #[error("serial transport not built: enable the `serial` feature")]
    SerialDisabled,
}

/// Something that happened on the socket; none of it is hidden from the application.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum IoEvent {
    /// Reads failed: the first failure, then at most one report per
    /// [`IO_ERROR_REPORT_INTERVAL`] while they go on. `error` is the latest failure, `count`
    /// the total so far (`recv_errors`).
    RecvError { error: String, count: u64 },
    /// Writes failed, reported like [`IoEvent::RecvError`]; `count` is `send_errors`.
    SendError { error: String, count: u64 },
    /// UDP-in: a frame was queued because no peer has been heard yet.
    QueuedWithoutPeer { queued: usize },
    /// UDP-in: the queue was full and its oldest frame was dropped.
    DroppedWithoutPeer { dropped_total: u64 },
    /// UDP-in: replies now go to this address.
    PeerChanged { peer: SocketAddr },
    /// TCP / serial: connected (peer address, or the port path).
    Connected { peer: String },
    /// TCP / serial: the connection ended.
    Disconnected { reason: String },
    /// Writing the signing timestamp file failed.
    PersistFailed { path: PathBuf, error: String },
}

/// I/O counters of one transport.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct IoStats {
    /// Bytes read.
    pub rx_bytes: u64,
    /// Bytes written.
    pub tx_bytes: u64,
    /// Failed reads.
    pub recv_errors: u64,
    /// Failed writes.
    pub send_errors: u64,
    /// Frames queued while no UDP-in peer was known.
    pub queued_without_peer: u64,
    /// Frames dropped from that queue when it overflowed.
    pub dropped_without_peer: u64,
    /// Connections (re)established.
    pub connects: u64,
}

trait ByteStream: AsyncRead + AsyncWrite + Unpin + Send {}
impl<T: AsyncRead + AsyncWrite + Unpin + Send> ByteStream for T {}

enum Kind {
    Udp {
        socket: UdpSocket,
        peer: Option<SocketAddr>,
        fixed: bool,
        queue: VecDeque<Vec<u8>>,
    },
    TcpServer {
        listener: TcpListener,
        conn: Option<TcpStream>,
    },
    Reopening {
        address: Address,
        conn: Option<Box<dyn ByteStream>>,
        retry_at: Option<Instant>,
    },
}

/// Rate limit of the reports of one kind of I/O failure (every failure is counted
/// elsewhere): the first at once, then at most one per [`IO_ERROR_REPORT_INTERVAL`] carrying
/// how many failed since the previous report.
#[derive(Debug, Default)]
struct ErrorReports {
    last_report: Option<Instant>,
    unreported: u64,
    last_error: String,
}

/// Which way an I/O operation went.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Dir {
    Recv,
    Send,
}

impl ErrorReports {
    /// A failure at `now`: `Some(failures since the last report)` when it is to be reported.
    fn failed(&mut self, now: Instant) -> Option<u64> {
        self.unreported += 1;
        self.due(now)
    }

    /// A success at `now`: reports the failures not yet reported, once the interval allows.
    fn succeeded(&mut self, now: Instant) -> Option<u64> {
        if self.unreported == 0 {
            return None;
        }
        self.due(now)
    }

    fn due(&mut self, now: Instant) -> Option<u64> {
        let due = self
            .last_report
            .is_none_or(|t| now.duration_since(t) >= IO_ERROR_REPORT_INTERVAL);
        due.then(|| {
            self.last_report = Some(now);
            std::mem::take(&mut self.unreported)
        })
    }
}

/// An open transport.
pub struct Transport {
    address: Address,
    kind: Kind,
    stats: IoStats,
    events: VecDeque<IoEvent>,
    recv_reports: ErrorReports,
    send_reports: ErrorReports,
    /// A stream connection ended since the driver last asked.
    stream_ended: bool,
}

impl fmt::Debug for Transport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Transport")
            .field("address", &self.address)
            .field("stats", &self.stats)
            .finish()
    }
}

async fn open_stream(address: &Address) -> io::Result<(Box<dyn ByteStream>, String)> {
    match address {
        Address::TcpClient(a) => {
            let s = TcpStream::connect(a.as_str()).await?;
            s.set_nodelay(true)?;
            let peer = s
                .peer_addr()
                .map(|p| p.to_string())
                .unwrap_or_else(|_| a.clone());
            Ok((Box::new(s), peer))
        }
        #[cfg(feature = "serial")]
        Address::Serial { path, baud } => {
            use tokio_serial::SerialPortBuilderExt;
            let s = tokio_serial::new(path.as_str(), *baud)
                .open_native_async()
                .map_err(io::Error::other)?;
            Ok((Box::new(s), path.clone()))
        }
        #[cfg(not(feature = "serial"))]
        Address::Serial { .. } => Err(io::Error::new(
            io::ErrorKind::Unsupported,
            "serial feature disabled",
        )),
        _ => Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "not a stream address",
        )),
    }
}

impl Transport {
    /// Opens `address` (a string like `udpin:127.0.0.1:14550`).
    pub async fn open_str(address: &str) -> Result<Self, TransportError> {
        Self::open(address.parse()?).await
    }

    /// Opens `address`.
    pub async fn open(address: Address) -> Result<Self, TransportError> {
        let err = |source| TransportError::Open {
            address: address.to_string(),
            source,
        };
        let kind = match &address {
            Address::UdpIn(a) => Kind::Udp {
                socket: UdpSocket::bind(a).await.map_err(err)?,
                peer: None,
                fixed: false,
                queue: VecDeque::new(),
            },
            Address::UdpOut(a) => {
                let local: SocketAddr = if a.is_ipv4() {
                    ([0, 0, 0, 0], 0).into()
                } else {
                    (std::net::Ipv6Addr::UNSPECIFIED, 0).into()
                };
                Kind::Udp {
                    socket: UdpSocket::bind(local).await.map_err(err)?,
                    peer: Some(*a),
                    fixed: true,
                    queue: VecDeque::new(),
                }
            }
            Address::TcpServer(a) => Kind::TcpServer {
                listener: TcpListener::bind(a).await.map_err(err)?,
                conn: None,
            },
            Address::TcpClient(_) | Address::Serial { .. } => {
                #[cfg(not(feature = "serial"))]
                if matches!(address, Address::Serial { .. }) {
                    return Err(TransportError::SerialDisabled);
                }
                let (conn, _) = open_stream(&address).await.map_err(err)?;
                Kind::Reopening {
                    address: address.clone(),
                    conn: Some(conn),
                    retry_at: None,
                }
            }
        };
        let mut t = Self::new(address, kind);
        if matches!(t.kind, Kind::Reopening { .. }) {
            t.stats.connects += 1;
            t.events.push_back(IoEvent::Connected {
                peer: t.address.to_string(),
            });
        }
        Ok(t)
    }

    /// Wraps an already open byte stream (e.g. one end of a pseudo-terminal pair in tests).
    pub fn from_stream<S: AsyncRead + AsyncWrite + Unpin + Send + 'static>(
        label: &str,
        stream: S,
    ) -> Self {
        let address = Address::Serial {
            path: label.to_string(),
            baud: 1,
        };
        let kind = Kind::Reopening {
            address: address.clone(),
            conn: Some(Box::new(stream)),
            retry_at: None,
        };
        Self::new(address, kind)
    }

    fn new(address: Address, kind: Kind) -> Self {
        Self {
            address,
            kind,
            stats: IoStats::default(),
            events: VecDeque::new(),
            recv_reports: ErrorReports::default(),
            send_reports: ErrorReports::default(),
            stream_ended: false,
        }
    }

    /// The address a server transport actually listens on — `udpin:` and `tcpin:` with the
    /// port the system chose for port 0 — for the operator to connect to; `None` for clients.
    pub fn listening_address(&self) -> Option<Address> {
        match (&self.address, self.local_addr()?) {
            (Address::UdpIn(_), local) => Some(Address::UdpIn(local)),
            (Address::TcpServer(_), local) => Some(Address::TcpServer(local)),
            _ => None,
        }
    }

    /// Whether a stream connection (TCP, serial) ended since the last call.
    pub fn take_stream_ended(&mut self) -> bool {
        std::mem::take(&mut self.stream_ended)
    }

    /// Local socket address (UDP and TCP server).
    pub fn local_addr(&self) -> Option<SocketAddr> {
        match &self.kind {
            Kind::Udp { socket, .. } => socket.local_addr().ok(),
            Kind::TcpServer { listener, .. } => listener.local_addr().ok(),
            Kind::Reopening { .. } => None,
        }
    }

    /// The address opened.
    pub fn address(&self) -> &Address {
        &self.address
    }

    /// I/O counters.
    pub fn stats(&self) -> IoStats {
        self.stats
    }

    /// Next I/O event.
    pub fn poll_event(&mut self) -> Option<IoEvent> {
        self.events.pop_front()
    }

    fn recv_error(&mut self, e: &io::Error) {
        self.stats.recv_errors += 1;
        self.failed(Dir::Recv, e);
    }

    fn send_error(&mut self, e: &io::Error) {
        self.stats.send_errors += 1;
        self.failed(Dir::Send, e);
    }

    fn reports(&mut self, dir: Dir) -> &mut ErrorReports {
        match dir {
            Dir::Recv => &mut self.recv_reports,
            Dir::Send => &mut self.send_reports,
        }
    }

    fn failed(&mut self, dir: Dir, e: &io::Error) {
        let reports = self.reports(dir);
        reports.last_error = e.to_string();
        if let Some(n) = reports.failed(Instant::now()) {
            self.report(dir, n);
        }
    }

    fn succeeded(&mut self, dir: Dir) {
        if let Some(n) = self.reports(dir).succeeded(Instant::now()) {
            self.report(dir, n);
        }
    }

    /// One report of `since_last` failures of `dir` (log line and event).
    fn report(&mut self, dir: Dir, since_last: u64) {
        let error = self.reports(dir).last_error.clone();
        let (what, total) = match dir {
            Dir::Recv => ("receive", self.stats.recv_errors),
            Dir::Send => ("send", self.stats.send_errors),
        };
        tracing::warn!(
            address = %self.address,
            %error,
            since_last_report = since_last,
            total,
            "{what} failed (reported at most every {} s)",
            IO_ERROR_REPORT_INTERVAL.as_secs()
        );
        self.events.push_back(match dir {
            Dir::Recv => IoEvent::RecvError {
                error,
                count: total,
            },
            Dir::Send => IoEvent::SendError {
                error,
                count: total,
            },
        });
    }

    /// Waits for bytes; returns how many were put in `buf` (0 when an event, such as an error
    /// or a connection change, happened instead). Cancel-safe.
    pub async fn recv(&mut self, buf: &mut [u8]) -> usize {
        let n = self.recv_inner(buf).await;
        if n > 0 {
            self.succeeded(Dir::Recv);
        }
        n
    }

    async fn recv_inner(&mut self, buf: &mut [u8]) -> usize {
        match &mut self.kind {
            Kind::Udp {
                socket,
                peer,
                fixed,
                ..
            } => match socket.recv_from(buf).await {
                Ok((n, from)) => {
                    if !*fixed && *peer != Some(from) {
                        *peer = Some(from);
                        tracing::info!(%from, "udp peer");
                        self.events.push_back(IoEvent::PeerChanged { peer: from });
                    }
                    self.stats.rx_bytes += n as u64;
                    n
                }
                Err(e) => {
                    self.recv_error(&e);
                    0
                }
            },
            Kind::TcpServer { listener, conn } => match conn {
                Some(stream) => match stream.read(buf).await {
                    Ok(0) => {
                        *conn = None;
                        self.stream_ended = true;
                        self.events.push_back(IoEvent::Disconnected {
                            reason: "peer closed".into(),
                        });
                        0
                    }
                    Ok(n) => {
                        self.stats.rx_bytes += n as u64;
                        n
                    }
                    Err(e) => {
                        *conn = None;
                        self.stream_ended = true;
                        self.recv_error(&e);
                        self.events.push_back(IoEvent::Disconnected {
                            reason: e.to_string(),
                        });
                        0
                    }
                },
                None => match listener.accept().await {
                    Ok((stream, peer)) => {
                        let _ = stream
                            .set_nodelay(true)
                            .inspect_err(|e| tracing::debug!(error = %e, "set_nodelay"));
                        *conn = Some(stream);
                        self.stats.connects += 1;
                        self.events.push_back(IoEvent::Connected {
                            peer: peer.to_string(),
                        });
                        0
                    }
                    Err(e) => {
                        self.recv_error(&e);
                        0
                    }
                },
            },
            Kind::Reopening {
                address,
                conn,
                retry_at,
            } => match conn {
                Some(stream) => match stream.read(buf).await {
                    Ok(0) => {
                        *conn = None;
                        *retry_at = Some(Instant::now() + REOPEN_DELAY);
                        self.stream_ended = true;
                        self.events.push_back(IoEvent::Disconnected {
                            reason: "closed".into(),
                        });
                        0
                    }
                    Ok(n) => {
                        self.stats.rx_bytes += n as u64;
                        n
                    }
                    Err(e) => {
                        *conn = None;
                        *retry_at = Some(Instant::now() + REOPEN_DELAY);
                        self.stream_ended = true;
                        self.recv_error(&e);
                        self.events.push_back(IoEvent::Disconnected {
                            reason: e.to_string(),
                        });
                        0
                    }
                },
                None => {
                    tokio::time::sleep_until(retry_at.unwrap_or_else(Instant::now)).await;
                    let address = address.clone();
                    match open_stream(&address).await {
                        Ok((stream, peer)) => {
                            if let Kind::Reopening { conn, retry_at, .. } = &mut self.kind {
                                *conn = Some(stream);
                                *retry_at = None;
                            }
                            self.stats.connects += 1;
                            self.events.push_back(IoEvent::Connected { peer });
                        }
                        Err(e) => {
                            if let Kind::Reopening { retry_at, .. } = &mut self.kind {
                                *retry_at = Some(Instant::now() + REOPEN_DELAY);
                            }
                            self.recv_error(&e);
                        }
                    }
                    0
                }
            },
        }
    }

    /// Sends one frame (or queues it, for UDP-in without a peer).
    pub async fn send(&mut self, frame: &[u8]) {
        let result = match &mut self.kind {
            Kind::Udp {
                socket,
                peer: Some(peer),
                queue,
                ..
            } => {
                let peer = *peer;
                let mut r = Ok(());
                // Flush what was queued before the peer was known, in order.
                while let Some(q) = queue.pop_front() {
                    if let Err(e) = socket.send_to(&q, peer).await {
                        r = Err(e);
                        break;
                    }
                    self.stats.tx_bytes += q.len() as u64;
                }
                match r {
                    Ok(()) => socket
                        .send_to(frame, peer)
                        .await
                        .map(|n| self.stats.tx_bytes += n as u64),
                    Err(e) => Err(e),
                }
            }
            Kind::Udp {
                peer: None, queue, ..
            } => {
                if queue.len() >= MAX_QUEUED_WITHOUT_PEER {
                    queue.pop_front();
                    self.stats.dropped_without_peer += 1;
                    self.events.push_back(IoEvent::DroppedWithoutPeer {
                        dropped_total: self.stats.dropped_without_peer,
                    });
                }
                queue.push_back(frame.to_vec());
                self.stats.queued_without_peer += 1;
                let queued = queue.len();
                tracing::debug!(queued, "udpin: no peer yet, frame queued");
                self.events.push_back(IoEvent::QueuedWithoutPeer { queued });
                Ok(())
            }
            Kind::TcpServer {
                conn: Some(stream), ..
            } => stream
                .write_all(frame)
                .await
                .map(|()| self.stats.tx_bytes += frame.len() as u64),
            Kind::Reopening {
                conn: Some(stream), ..
            } => stream
                .write_all(frame)
                .await
                .map(|()| self.stats.tx_bytes += frame.len() as u64),
            Kind::TcpServer { conn: None, .. } | Kind::Reopening { conn: None, .. } => {
                Err(io::Error::new(io::ErrorKind::NotConnected, "no connection"))
            }
        };
        match result {
            Ok(()) => self.succeeded(Dir::Send),
            Err(e) => self.send_error(&e),
        }
    }
}

/// The sans-io surface [`drive`] needs; implemented by both endpoints.
pub trait SansIo: Send + 'static {
    /// The endpoint's event type.
    type Event: Send + 'static;
    /// Feeds bytes received on radio `path` (0 with one transport).
    fn handle_bytes_on(&mut self, path: usize, now: Duration, bytes: &[u8]);
    /// Runs timers.
    fn handle_timeout(&mut self, now: Duration);
    /// Next timer.
    fn poll_timeout(&self) -> Option<Duration>;
    /// Next frame to send.
    fn poll_transmit(&mut self, now: Duration) -> Option<Vec<u8>>;
    /// Next event.
    fn poll_event(&mut self) -> Option<Self::Event>;
    /// The stream connection of radio `path` ended (TCP, serial): flush what can no longer
    /// complete.
    fn handle_stream_end_on(&mut self, path: usize, now: Duration);
    /// The radio that frames from [`poll_transmit`](Self::poll_transmit) go out on now.
    fn transmit_path(&self, now: Duration) -> usize;
    /// The signing timestamp high-water mark in force (`None`: signing off); [`drive`]
    /// persists it whenever it moves, before sending frames signed under it.
    fn signing_timestamp_mark(&self) -> Option<u64>;
}

macro_rules! impl_sans_io {
    ($ty:ty, $ev:ty) => {
        impl SansIo for $ty {
            type Event = $ev;
            fn handle_bytes_on(&mut self, path: usize, now: Duration, bytes: &[u8]) {
                <$ty>::handle_bytes_on(self, path, now, bytes)
            }
            fn handle_timeout(&mut self, now: Duration) {
                <$ty>::handle_timeout(self, now)
            }
            fn poll_timeout(&self) -> Option<Duration> {
                <$ty>::poll_timeout(self)
            }
            fn poll_transmit(&mut self, now: Duration) -> Option<Vec<u8>> {
                <$ty>::poll_transmit(self, now)
            }
            fn poll_event(&mut self) -> Option<$ev> {
                <$ty>::poll_event(self)
            }
            fn handle_stream_end_on(&mut self, path: usize, now: Duration) {
                <$ty>::handle_stream_end_on(self, path, now)
            }
            fn transmit_path(&self, now: Duration) -> usize {
                <$ty>::transmit_path(self, now)
            }
            fn signing_timestamp_mark(&self) -> Option<u64> {
                <$ty>::signing_timestamp_mark(self)
            }
        }
    };
}

impl_sans_io!(GroundEndpoint, GroundEvent);
impl_sans_io!(VehicleEndpoint, VehicleEvent);

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

/// Where stx keeps state that must survive a restart (signing timestamps), looked up in the
/// environment `env` (e.g. `|k| std::env::var_os(k)`): `$STATE_DIRECTORY` (systemd's
/// `StateDirectory=`), else `$XDG_STATE_HOME/stx`, else `$HOME/.local/state/stx`; `None` when
/// none is set.
pub fn default_state_dir(env: impl Fn(&str) -> Option<std::ffi::OsString>) -> Option<PathBuf> {
    let set = |k: &str| env(k).filter(|v| !v.is_empty()).map(PathBuf::from);
    set("STATE_DIRECTORY")
        // systemd may list several directories, separated by ':'.
        .map(|p| {
            let text = p.to_string_lossy().into_owned();
            PathBuf::from(text.split(':').next().unwrap_or_default())
        })
        .or_else(|| set("XDG_STATE_HOME").map(|p| p.join("stx")))
        .or_else(|| set("HOME").map(|p| p.join(".local/state/stx")))
}

/// Writes `endpoint`'s signing timestamp high-water mark to `path` (when both signing and a
/// file are set): what an adapter does once before [`drive`], so that a file that cannot be
/// written stops the start instead of weakening the guarantee later.
pub fn persist_signing_mark<E: SansIo>(endpoint: &E, path: Option<&Path>) -> io::Result<()> {
    match (path, endpoint.signing_timestamp_mark()) {
        (Some(path), Some(mark)) => store_signing_timestamp(path, mark).map_err(|e| {
            io::Error::new(
                e.kind(),
                format!("signing timestamp file {}: {e}", path.display()),
            )
        }),
        _ => Ok(()),
    }
}

/// Reads a persisted signing timestamp; `Ok(None)` if the file does not exist.
pub fn load_signing_timestamp(path: &Path) -> io::Result<Option<u64>> {
    match std::fs::read_to_string(path) {
        Ok(s) => s
            .trim()
            .parse::<u64>()
            .map(Some)
            .map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e)),
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(e),
    }
}

/// Writes a signing timestamp atomically (temporary file, fsync, rename), creating the
/// directory if needed.
pub fn store_signing_timestamp(path: &Path, value: u64) -> io::Result<()> {
    use std::io::Write;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let tmp = path.with_extension("tmp");
    let mut f = std::fs::File::create(&tmp)?;
    writeln!(f, "{value}")?;
    f.sync_all()?;
    std::fs::rename(&tmp, path)
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
/// `i` (see [`crate::paths`]); bytes from each go to its path, and what the endpoint sends
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
                    endpoint.handle_bytes_on(path, start.elapsed(), bytes);
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn addresses_parse() {
        assert_eq!(
            "udpin:127.0.0.1:14550".parse(),
            Ok(Address::UdpIn(([127, 0, 0, 1], 14550).into()))
        );
        assert_eq!(
            "udpout:127.0.0.1:14550".parse(),
            Ok(Address::UdpOut(([127, 0, 0, 1], 14550).into()))
        );
        assert_eq!(
            "tcp:localhost:5760".parse(),
            Ok(Address::TcpClient("localhost:5760".into()))
        );
        assert_eq!(
            "tcpin:0.0.0.0:5760".parse(),
            Ok(Address::TcpServer(([0, 0, 0, 0], 5760).into()))
        );
        assert_eq!(
            "serial:/dev/ttyUSB0:57600".parse(),
            Ok(Address::Serial {
                path: "/dev/ttyUSB0".into(),
                baud: 57600
            })
        );
        for a in [
            "udpin:127.0.0.1:14550",
            "tcpin:0.0.0.0:5760",
            "serial:/dev/ttyUSB0:57600",
        ] {
            assert_eq!(
                a.parse::<Address>().map(|x| x.to_string()),
                Ok(a.to_string())
            );
        }
    }

    #[test]
    fn malformed_addresses_say_what_is_wrong() {
        assert!(matches!(
            "127.0.0.1:14550".parse::<Address>(),
            Err(AddressError::UnknownScheme { .. })
        ));
        assert!(matches!(
            "localhost".parse::<Address>(),
            Err(AddressError::MissingScheme { .. })
        ));
        assert!(matches!(
            "udpin:127.0.0.1".parse::<Address>(),
            Err(AddressError::BadSocketAddr { .. })
        ));
        assert!(matches!(
            "tcp:host".parse::<Address>(),
            Err(AddressError::BadHostPort { .. })
        ));
        assert!(matches!(
            "serial:/dev/ttyUSB0".parse::<Address>(),
            Err(AddressError::BadSerial { .. })
        ));
        assert!(matches!(
            "serial:/dev/ttyUSB0:fast".parse::<Address>(),
            Err(AddressError::BadBaud { .. })
        ));
        assert!(matches!(
            "serial::57600".parse::<Address>(),
            Err(AddressError::BadSerial { .. })
        ));
        let msg = "ftp:1.2.3.4:21"
            .parse::<Address>()
            .map_err(|e| e.to_string());
        assert!(msg.is_err_and(|m| m.contains("udpin:") && m.contains("ftp")));
    }
}
