//! Thin tokio adapters that move bytes between a socket (or serial port) and a sans-io
//! endpoint, so the protocol logic of `stx-link` stays free of I/O and clocks.
//!
//! [`Transport`] is an open socket for an [`Address`]. UDP-in answers the address that last
//! sent a datagram carrying a frame accepted from the expected system (the driver hands each
//! datagram to the endpoint and its verdict to [`Transport::datagram_verdict`]; see
//! `udp_peer.rs`), so garbage cannot divert the uplink; other datagrams are counted in
//! [`IoStats::ignored_datagrams`] and reported rate-limited. Frames sent before any peer was
//! heard are queued (up to [`MAX_QUEUED_WITHOUT_PEER`]) and flushed when one is, with an
//! [`IoEvent`] for the queueing and for any overflow. TCP server accepts one client at a time and accepts the next when it
//! leaves; TCP client and serial reopen after [`REOPEN_DELAY`]. No I/O error is swallowed:
//! each is counted in [`IoStats`]; they are reported (a `tracing` warning and an [`IoEvent`])
//! rate-limited, because a link without a peer fails every frame — the first failure at once,
//! then one report with the count per [`IO_ERROR_REPORT_INTERVAL`] while failures go on.

use std::collections::VecDeque;
use std::fmt;
use std::io;
use std::net::SocketAddr;
use std::time::Duration;

use stx_link::address::{Address, AddressError};
use stx_link::sansio::{IoEvent, IoStats};
use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};
use tokio::net::{TcpListener, TcpStream, UdpSocket};
use tokio::time::Instant;

use crate::udp_peer::{UdpPeer, Verdict};

mod reports;

use reports::{Dir, ErrorReports};

/// Frames kept for a UDP-in peer not yet heard from.
pub const MAX_QUEUED_WITHOUT_PEER: usize = 256;

/// Wait before re-opening a TCP client connection or a serial port.
pub const REOPEN_DELAY: Duration = Duration::from_secs(1);

/// Shortest time between two reports of failing reads (or writes) of one transport.
pub const IO_ERROR_REPORT_INTERVAL: Duration = Duration::from_secs(5);

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

trait ByteStream: AsyncRead + AsyncWrite + Unpin + Send {}
impl<T: AsyncRead + AsyncWrite + Unpin + Send> ByteStream for T {}

enum Kind {
    Udp {
        socket: UdpSocket,
        peer: UdpPeer,
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

/// An open transport.
pub struct Transport {
    address: Address,
    kind: Kind,
    stats: IoStats,
    pub(crate) events: VecDeque<IoEvent>,
    recv_reports: ErrorReports,
    send_reports: ErrorReports,
    /// Datagrams ignored as peer candidates (not failures, but reported the same way).
    ignored_reports: ErrorReports,
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
                peer: UdpPeer::learned(),
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
                    peer: UdpPeer::fixed(*a),
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
            ignored_reports: ErrorReports::default(),
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

    /// Whether bytes arrive as datagrams (UDP): each [`recv`](Self::recv) then returns one
    /// whole datagram, to be fed with `SansIo::handle_datagram_on` and answered with
    /// [`datagram_verdict`](Self::datagram_verdict).
    pub fn is_datagram(&self) -> bool {
        matches!(self.kind, Kind::Udp { .. })
    }

    /// The endpoint's verdict on the datagram [`recv`](Self::recv) last returned:
    /// `from_expected` when it carried a frame accepted from the expected peer system. On
    /// UDP-in, such a datagram from a new address makes that address the peer (logged once, and
    /// an [`IoEvent::PeerChanged`]); any other datagram from an address that is not the peer
    /// is ignored as a peer candidate, counted in [`IoStats::ignored_datagrams`] and reported
    /// at most once per [`IO_ERROR_REPORT_INTERVAL`]. Nothing on other transports.
    pub fn datagram_verdict(&mut self, from_expected: bool) {
        let Kind::Udp { peer, .. } = &mut self.kind else {
            return;
        };
        let previous = peer.get();
        match peer.verdict(from_expected) {
            Verdict::Kept => {}
            Verdict::Adopted(from) => {
                match previous {
                    Some(previous) => tracing::info!(%from, %previous, "udp peer moved"),
                    None => tracing::info!(%from, "udp peer"),
                }
                self.events.push_back(IoEvent::PeerChanged { peer: from });
            }
            Verdict::Ignored(from) => {
                self.stats.ignored_datagrams += 1;
                if let Some(since_last_report) = self.ignored_reports.failed(Instant::now()) {
                    let peer = previous.map_or_else(|| "none yet".to_string(), |p| p.to_string());
                    tracing::warn!(
                        address = %self.address,
                        %from,
                        %peer,
                        since_last_report,
                        total = self.stats.ignored_datagrams,
                        "udp datagrams ignored: no frame accepted from the expected system, the \
                         peer stays (reported at most every {} s)",
                        IO_ERROR_REPORT_INTERVAL.as_secs()
                    );
                }
            }
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
            Kind::Udp { socket, peer, .. } => match socket.recv_from(buf).await {
                Ok((n, from)) => {
                    peer.received_from(from);
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
                peer,
                queue,
            } => match peer.get() {
                Some(peer) => {
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
                None => {
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
            },
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
