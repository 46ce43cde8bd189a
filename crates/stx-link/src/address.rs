//! Where a link's bytes go: the address strings of the command line and the station's
//! config (`udpin:HOST:PORT`, `udpout:HOST:PORT`, `tcp:HOST:PORT` (client), `tcpin:HOST:PORT`
//! (server), `serial:PATH:BAUD`), parsed into an [`Address`] or an [`AddressError`] that says
//! what is wrong. Opening one is the I/O adapter's job (`stx-link-tokio`).

use std::fmt;
use std::net::SocketAddr;
use std::str::FromStr;

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
