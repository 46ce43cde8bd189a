//! The station as the field network meets it, through the real daemon and router: the security
//! headers on every kind of answer (a page, an asset, a tile, the API and its refusals), and the
//! shipped rehearsal tokens refused from any address that is not loopback (127.0.0.2 stands for
//! the field network, by `StationConfig::not_loopback`, the test switch of `exposure`).

use crate::common;

use std::net::IpAddr;

use common::{OPERATOR, VIEWER, config, get_from, start_station};

/// `GET path` from the address `from` to the station at `to` with `token`: the status, the
/// head (lower-case) and the body.
async fn get(
    from: &str,
    to: std::net::SocketAddr,
    path: &str,
    token: Option<&str>,
) -> (u16, String, String) {
    get_from(from.parse::<IpAddr>().expect("address"), to, path, token).await
}

/// A phone or laptop on the field network, played by a second loopback address.
const FIELD_PEER: &str = "127.0.0.2";
const STRONG: &str = "9b1c4e7a2d5f8036c9e2b5a8d1f4c7e0";

/// A built dashboard in miniature: two pages and a script.
fn web_dir() -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("stx-field-network-web-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("assets")).expect("dir");
    std::fs::write(dir.join("index.html"), "<!doctype html><title>live</title>").expect("page");
    std::fs::write(dir.join("lab.html"), "<!doctype html><title>lab</title>").expect("page");
    std::fs::write(dir.join("assets/live.js"), "console.log(1);").expect("asset");
    dir
}

fn tiles_dir() -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("stx-field-network-tiles-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("3/4")).expect("dir");
    std::fs::write(dir.join("3/4/5.png"), b"\x89PNG\r\n\x1a\n").expect("tile");
    dir
}

/// Regression: the pages were served without `Content-Security-Policy`, `X-Frame-Options`,
/// `X-Content-Type-Options` or `Referrer-Policy`, so another page could frame the dashboard,
/// cutdown button included.
#[tokio::test]
async fn every_answer_carries_the_security_headers() {
    let (web, tiles) = (web_dir(), tiles_dir());
    let station = start_station(config(|c| {
        c.web_dir = web.clone();
        c.tiles_dir = Some(tiles.clone());
    }))
    .await;
    let to = station.http();
    for (path, token, status) in [
        ("/", None, 200),
        ("/?token=viewer-token", None, 200),
        ("/lab.html", None, 200),
        ("/assets/live.js", None, 200),
        ("/tiles/3/4/5.png", None, 200),
        ("/api/session", Some(VIEWER), 200),
        ("/api/state", None, 401),
        ("/api/no-such-thing", Some(VIEWER), 404),
        ("/kml/live", Some(VIEWER), 200),
    ] {
        let (got, head, _) = get("127.0.0.1", to, path, token).await;
        assert_eq!(got, status, "{path}: {head}");
        let csp = head
            .lines()
            .find_map(|l| l.strip_prefix("content-security-policy: "))
            .unwrap_or_else(|| panic!("{path}: no Content-Security-Policy in {head}"));
        for part in [
            "default-src 'self'",
            "script-src 'self';",
            "style-src 'self';",
            "frame-ancestors 'none'",
            "connect-src 'self' ws://127.0.0.1:",
        ] {
            assert!(csp.contains(part), "{path}: {part} in {csp}");
        }
        for header in [
            "x-frame-options: deny",
            "x-content-type-options: nosniff",
            "referrer-policy: no-referrer",
        ] {
            assert!(head.contains(header), "{path}: {header} in {head}");
        }
    }
    let _ = std::fs::remove_dir_all(&web);
    let _ = std::fs::remove_dir_all(&tiles);
}

/// Regression: `stx serve --listen 0.0.0.0:8140` with the shipped config accepted
/// `operator-token` from anyone on the field's Wi-Fi. Whatever address the daemon listens on,
/// a rehearsal token counts only from loopback; the station's own tokens work from anywhere.
#[tokio::test]
async fn the_rehearsal_tokens_are_refused_from_the_field_network() {
    let station = start_station(config(|c| {
        c.not_loopback = vec![FIELD_PEER.parse().expect("address")];
        c.tokens.push(stx_station::config::TokenConfig {
            name: "field operator".into(),
            token: STRONG.into(),
            role: stx_station::config::Role::Operator,
        });
    }))
    .await;
    let to = station.http();
    for token in [OPERATOR, VIEWER] {
        let (status, _, body) = get(FIELD_PEER, to, "/api/session", Some(token)).await;
        assert_eq!(status, 401, "{token} from the field: {body}");
        assert!(body.contains("stx token new"), "{body}");
        let (status, _, body) =
            get(FIELD_PEER, to, &format!("/kml/live?token={token}"), None).await;
        assert_eq!(status, 401, "{token} in the URL from the field: {body}");
        let (status, _, body) = get("127.0.0.1", to, "/api/session", Some(token)).await;
        assert_eq!(status, 200, "{token} on loopback: {body}");
    }
    let (status, _, body) = get(FIELD_PEER, to, "/api/session", Some(STRONG)).await;
    assert_eq!(status, 200, "{body}");
    assert!(body.contains(r#""name":"field operator""#), "{body}");
}
