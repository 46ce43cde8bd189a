//! The station as the field network meets it, through the real daemon and router: the shipped
//! rehearsal tokens refused from any address that is not loopback (127.0.0.2 stands for the
//! field network, by `StationConfig::not_loopback`, the test switch of `exposure`).

mod common;

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
