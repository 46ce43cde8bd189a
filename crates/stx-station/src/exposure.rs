//! What the station lets through beyond this machine.
//!
//! The shipped configuration's rehearsal tokens are printed in the README and in the start
//! banner, so anyone on the field's Wi-Fi who has read either knows them. They work on loopback
//! only, twice over: `stx serve` and `stx replay` refuse to listen beyond loopback while a
//! configured token is one of them ([`check_listen`], exit code 2), and the HTTP layer refuses
//! them from any peer that is not loopback ([`accepted_from`]), for a daemon started some other
//! way. Beyond loopback without `[tls]` every token crosses the network in clear, readable by
//! anyone on it: the commands refuse that too unless told `--insecure-http`.
//!
//! Loopback is `127.0.0.0/8` and `::1` (an IPv4-mapped `::ffff:127.x.y.z` too), less the
//! addresses a test names in [`NOT_LOOPBACK_ENV`] (read with the rest of the environment by
//! [`StationConfig::apply_environment`]): that lets one machine's tests show the refusals
//! without a network namespace. It can only make the station stricter.

use std::net::{IpAddr, SocketAddr};

use subtle::ConstantTimeEq;
use thiserror::Error;

use crate::config::StationConfig;

/// The tokens of the shipped `config/station.toml`, known to everyone who read the README.
pub const REHEARSAL_TOKENS: [&str; 2] = ["operator-token", "viewer-token"];

pub use crate::config::NOT_LOOPBACK_ENV;

/// Why the station will not listen where it was asked to.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum ExposureError {
    /// A configured token is a rehearsal token and the address is not loopback.
    #[error(
        "`{field}` (entry {entry} of the config's `[[tokens]]`) is the shipped rehearsal token \
         `{token}`, known to anyone who read the README: it works on loopback only, and the \
         station would listen on {listen}. Make a token with `stx token new` and put it in \
         `{field}` (or listen on 127.0.0.1)"
    )]
    RehearsalToken {
        /// The configuration field holding it (`tokens[0].token`).
        field: String,
        /// Which `[[tokens]]` entry that is, counted from 1.
        entry: usize,
        /// The rehearsal token.
        token: &'static str,
        /// Where the station would listen.
        listen: SocketAddr,
    },
    /// Beyond loopback without `[tls]`, and `--insecure-http` not given.
    #[error(
        "the station would listen on {listen} over plain HTTP: its tokens (the operator's too) \
         and all it shows would cross the network in clear, readable by anyone on it. Configure \
         `[tls]` (deploy/README.md), or pass --insecure-http to go on in clear"
    )]
    ClearText {
        /// Where the station would listen.
        listen: SocketAddr,
    },
}

/// The rehearsal token `token` is, if it is one (compared in constant time, as every token).
pub fn rehearsal_token(token: &str) -> Option<&'static str> {
    REHEARSAL_TOKENS
        .into_iter()
        .find(|r| bool::from(r.as_bytes().ct_eq(token.as_bytes())))
}

impl StationConfig {
    /// Whether `ip` is this machine (loopback, less the test's [`NOT_LOOPBACK_ENV`]).
    pub fn is_loopback(&self, ip: IpAddr) -> bool {
        let ip = ip.to_canonical();
        ip.is_loopback() && !self.not_loopback.contains(&ip)
    }
}

/// Whether the station may listen on its `listen` address: `Ok` on loopback; beyond it, no
/// configured token may be a rehearsal token, and without `[tls]` only with `insecure_http`.
pub fn check_listen(config: &StationConfig, insecure_http: bool) -> Result<(), ExposureError> {
    let listen = config.listen;
    if config.is_loopback(listen.ip()) {
        return Ok(());
    }
    for (i, t) in config.tokens.iter().enumerate() {
        if let Some(token) = rehearsal_token(&t.token) {
            return Err(ExposureError::RehearsalToken {
                field: format!("tokens[{i}].token"),
                entry: i + 1,
                token,
                listen,
            });
        }
    }
    if config.tls.is_none() && !insecure_http {
        return Err(ExposureError::ClearText { listen });
    }
    Ok(())
}

/// Whether `token`, known to the station, is accepted from `peer` (`None`: unknown): a
/// rehearsal token from loopback only.
pub fn accepted_from(config: &StationConfig, token: &str, peer: Option<IpAddr>) -> bool {
    rehearsal_token(token).is_none() || peer.is_some_and(|ip| config.is_loopback(ip))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{DEFAULT_STATION_TOML, TlsSettings};

    fn shipped(listen: &str) -> StationConfig {
        let mut c = StationConfig::from_toml_str(DEFAULT_STATION_TOML).expect("shipped");
        c.listen = listen.parse().expect("address");
        c
    }

    fn with_own_tokens(listen: &str) -> StationConfig {
        let mut c = shipped(listen);
        for (i, t) in c.tokens.iter_mut().enumerate() {
            t.token = format!("{i}f3a9c1e5b7d2048e6a1c3f5b7d9e0a2c4");
        }
        c
    }

    #[test]
    fn the_shipped_tokens_are_the_rehearsal_tokens() {
        let c = shipped("127.0.0.1:8080");
        let mut tokens: Vec<&str> = c.tokens.iter().map(|t| t.token.as_str()).collect();
        tokens.sort_unstable();
        assert_eq!(tokens, REHEARSAL_TOKENS);
    }

    #[test]
    fn on_loopback_anything_goes() {
        for listen in ["127.0.0.1:8080", "127.0.0.2:0", "[::1]:8080"] {
            assert_eq!(check_listen(&shipped(listen), false), Ok(()), "{listen}");
        }
    }

    /// Regression: `stx serve --listen 0.0.0.0:8140` with the shipped config started without a
    /// word, and anyone on the field's Wi-Fi who had read the README could cut the payload down.
    #[test]
    fn beyond_loopback_the_rehearsal_tokens_are_refused_naming_the_field_and_the_fix() {
        for listen in ["0.0.0.0:8140", "192.168.8.10:8080", "[::]:8080"] {
            let err = check_listen(&shipped(listen), true).expect_err(listen);
            assert!(
                matches!(&err, ExposureError::RehearsalToken { field, .. } if field == "tokens[0].token"),
                "{err:?}"
            );
            let text = err.to_string();
            assert!(
                text.contains("stx token new") && text.contains("`tokens[0].token`"),
                "{text}"
            );
        }
        // The viewer's alone is refused as well.
        let mut c = with_own_tokens("0.0.0.0:8140");
        c.tokens[1].token = "viewer-token".into();
        let err = check_listen(&c, true).expect_err("the viewer's rehearsal token");
        assert!(err.to_string().contains("tokens[1].token"), "{err}");
    }

    #[test]
    fn beyond_loopback_plain_http_needs_insecure_http_and_tls_does_not() {
        let c = with_own_tokens("0.0.0.0:8140");
        let err = check_listen(&c, false).expect_err("in clear");
        let text = err.to_string();
        assert!(
            text.contains("in clear") && text.contains("--insecure-http"),
            "{text}"
        );
        assert!(text.contains("[tls]"), "{text}");
        assert_eq!(check_listen(&c, true), Ok(()));
        let mut tls = c;
        tls.tls = Some(TlsSettings {
            cert_path: "/etc/stx/station.crt".into(),
            key_path: "/etc/stx/station.key".into(),
        });
        assert_eq!(check_listen(&tls, false), Ok(()));
    }

    #[test]
    fn the_test_switch_makes_a_loopback_address_remote_and_nothing_else() {
        let env = |v: &'static str| move |k: &str| (k == NOT_LOOPBACK_ENV).then(|| v.into());
        let not_loopback =
            crate::config::not_loopback_from_env(env("127.0.0.2, ::1")).expect("addresses");
        let mut c = shipped("127.0.0.2:0");
        c.not_loopback = not_loopback;
        assert!(!c.is_loopback("127.0.0.2".parse().unwrap()));
        assert!(!c.is_loopback("::ffff:127.0.0.2".parse().unwrap()));
        assert!(!c.is_loopback("::1".parse().unwrap()));
        assert!(c.is_loopback("127.0.0.1".parse().unwrap()));
        assert!(!c.is_loopback("192.168.8.10".parse().unwrap()));
        assert!(matches!(
            check_listen(&c, true),
            Err(ExposureError::RehearsalToken { .. })
        ));
        assert!(crate::config::not_loopback_from_env(env("localhost")).is_err());
        assert_eq!(
            crate::config::not_loopback_from_env(|_| None),
            Ok(Vec::new())
        );
    }

    #[test]
    fn a_rehearsal_token_is_accepted_from_loopback_only() {
        let mut c = shipped("127.0.0.1:8080");
        c.not_loopback = vec!["127.0.0.2".parse().unwrap()];
        let strong = "0f3a9c1e5b7d2048e6a1c3f5b7d9e0a2c4";
        for (token, peer, accepted) in [
            ("operator-token", Some("127.0.0.1"), true),
            ("operator-token", Some("::ffff:127.0.0.1"), true),
            ("operator-token", Some("192.168.8.23"), false),
            ("viewer-token", Some("127.0.0.2"), false),
            ("viewer-token", None, false),
            (strong, Some("192.168.8.23"), true),
            (strong, None, true),
        ] {
            let peer = peer.map(|p| p.parse().unwrap());
            assert_eq!(
                accepted_from(&c, token, peer),
                accepted,
                "{token} from {peer:?}"
            );
        }
    }
}
