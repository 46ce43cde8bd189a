//! The security headers on every answer: pages, assets, tiles, the API and its errors, the
//! KML feed and the WebSocket's upgrade.
//!
//! - `Content-Security-Policy`: scripts, styles, fonts and workers from the station only (the
//!   build makes no inline script or style; the pages set styles through the CSSOM, which the
//!   policy does not govern), images from the station and `data:` (the favicon, Leaflet's and
//!   the zone editor's icons in their CSS), and from the origin of an online `tile_url` when
//!   the config names one; connections to the station itself, its WebSocket named with the
//!   page's host as well, since Safari before 15.4 did not count `ws:`/`wss:` as `'self'`
//!   (WebKit bug 201591); no plugins, no `<base>`, forms to the station only, and no framing
//!   (`frame-ancestors 'none'`: another page cannot hide the cutdown button under a decoy).
//! - `X-Frame-Options: DENY`: the same for browsers that predate `frame-ancestors`.
//! - `X-Content-Type-Options: nosniff`: a file is what its type says, never a script.
//! - `Referrer-Policy: no-referrer`: the page's address carries its token (`?token=`), which a
//!   tile server must not read in a `Referer`.

use std::sync::Arc;

use axum::extract::{Request, State};
use axum::http::{HeaderName, HeaderValue, header};
use axum::middleware::Next;
use axum::response::Response;

use crate::config::StationConfig;

/// What the policy needs from the configuration, worked out once.
#[derive(Debug, Clone)]
pub(crate) struct SecurityHeaders {
    /// The WebSocket's scheme: `wss` with `[tls]`, else `ws`.
    socket_scheme: &'static str,
    /// The origin of an online tile server (`tile_url = "https://…"`), as a CSP source.
    tile_source: Option<String>,
}

impl SecurityHeaders {
    pub(crate) fn new(config: &StationConfig) -> Self {
        let tile_source = config.tile_url.as_deref().and_then(|url| {
            let source = tile_source(url);
            if source.is_none() && !url.starts_with('/') {
                tracing::warn!(
                    tile_url = url,
                    "tile_url's server cannot be named in the pages' Content-Security-Policy: \
                     the browser will not load its tiles (give it as https://HOST/…)"
                );
            }
            source
        });
        Self {
            socket_scheme: if config.tls.is_some() { "wss" } else { "ws" },
            tile_source,
        }
    }

    /// For a server with neither TLS nor online tiles (`stx relay`).
    pub(crate) fn plain() -> Self {
        Self {
            socket_scheme: "ws",
            tile_source: None,
        }
    }

    /// The policy for a page asked for under `host` (the request's `Host`, when it is one).
    pub(crate) fn policy(&self, host: Option<&str>) -> String {
        let tiles = self
            .tile_source
            .as_deref()
            .map_or(String::new(), |s| format!(" {s}"));
        let socket = host.map_or(String::new(), |h| format!(" {}://{h}", self.socket_scheme));
        format!(
            "default-src 'self'; script-src 'self'; style-src 'self'; img-src 'self' data:{tiles}; \
             connect-src 'self'{socket}; font-src 'self'; worker-src 'self'; manifest-src 'self'; \
             object-src 'none'; base-uri 'none'; form-action 'self'; frame-ancestors 'none'"
        )
    }
}

/// `host` if it is a host and port as a CSP source may name them (letters, digits, `.`, `-`,
/// `:` and the brackets of an IPv6 address); anything else, which no browser sends, is left
/// out rather than let into the header.
fn authority(host: &str) -> Option<&str> {
    let allowed = |c: char| c.is_ascii_alphanumeric() || matches!(c, '.' | '-' | ':' | '[' | ']');
    (!host.is_empty() && host.len() <= 255 && host.chars().all(allowed)).then_some(host)
}

/// The CSP source of an online tile URL template: its scheme and host, Leaflet's `{s}`
/// subdomain as `*`; `None` for the station's own tiles (a path) or a host it cannot name.
fn tile_source(url: &str) -> Option<String> {
    let (scheme, rest) = url.split_once("://")?;
    if !matches!(scheme, "http" | "https") {
        return None;
    }
    let host = rest.split(['/', '?', '#']).next()?;
    let host = match host.strip_prefix("{s}.") {
        Some(domain) => format!("*.{}", authority(domain)?),
        None => authority(host)?.to_owned(),
    };
    Some(format!("{scheme}://{host}"))
}

/// Adds the security headers to the answer to `request`.
pub(crate) async fn add(
    State(headers): State<Arc<SecurityHeaders>>,
    request: Request,
    next: Next,
) -> Response {
    let host = request
        .headers()
        .get(header::HOST)
        .and_then(|h| h.to_str().ok())
        .and_then(authority)
        .map(str::to_owned);
    let mut response = next.run(request).await;
    let policy = headers.policy(host.as_deref());
    let out = response.headers_mut();
    if let Ok(policy) = HeaderValue::from_str(&policy) {
        out.insert(header::CONTENT_SECURITY_POLICY, policy);
    }
    let fixed: [(HeaderName, &str); 3] = [
        (header::X_FRAME_OPTIONS, "DENY"),
        (header::X_CONTENT_TYPE_OPTIONS, "nosniff"),
        (header::REFERRER_POLICY, "no-referrer"),
    ];
    for (name, value) in fixed {
        out.insert(name, HeaderValue::from_static(value));
    }
    response
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::DEFAULT_STATION_TOML;

    fn headers(edit: impl FnOnce(&mut StationConfig)) -> SecurityHeaders {
        let mut c = StationConfig::from_toml_str(DEFAULT_STATION_TOML).expect("shipped");
        edit(&mut c);
        SecurityHeaders::new(&c)
    }

    #[test]
    fn the_policy_allows_the_station_alone_and_no_framing() {
        let p = headers(|_| {}).policy(Some("192.168.8.10:8080"));
        for part in [
            "default-src 'self'",
            "script-src 'self';",
            "style-src 'self';",
            "img-src 'self' data:;",
            "connect-src 'self' ws://192.168.8.10:8080;",
            "object-src 'none'",
            "base-uri 'none'",
            "frame-ancestors 'none'",
        ] {
            assert!(p.contains(part), "{part} in {p}");
        }
        assert!(!p.contains("unsafe"), "{p}");
        let tls = headers(|c| {
            c.tls = Some(crate::config::TlsSettings {
                cert_path: "c".into(),
                key_path: "k".into(),
            })
        });
        assert!(
            tls.policy(Some("[::1]:8443"))
                .contains("connect-src 'self' wss://[::1]:8443;")
        );
    }

    #[test]
    fn a_host_that_is_no_host_stays_out_of_the_header() {
        let h = headers(|_| {});
        for bad in ["evil; script-src *", "a b", "", "x\"y"] {
            assert_eq!(authority(bad), None, "{bad}");
        }
        assert!(h.policy(None).contains("connect-src 'self';"));
    }

    #[test]
    fn an_online_tile_server_is_named_and_the_stations_own_tiles_need_nothing() {
        for (url, source) in [
            ("/tiles/{z}/{x}/{y}.png", None),
            (
                "https://tile.openstreetmap.org/{z}/{x}/{y}.png",
                Some("https://tile.openstreetmap.org"),
            ),
            (
                "https://{s}.tile.example.org:8443/{z}/{x}/{y}.png?key=1",
                Some("https://*.tile.example.org:8443"),
            ),
            ("ftp://tiles.example.org/{z}/{x}/{y}.png", None),
            ("https://{z}.example.org/{x}/{y}.png", None),
        ] {
            assert_eq!(tile_source(url).as_deref(), source, "{url}");
        }
        let h =
            headers(|c| c.tile_url = Some("https://tile.openstreetmap.org/{z}/{x}/{y}.png".into()));
        assert!(
            h.policy(None)
                .contains("img-src 'self' data: https://tile.openstreetmap.org;")
        );
    }
}
