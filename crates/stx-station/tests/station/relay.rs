//! Public relays against a real station: the audience travels up a tree of relays to the
//! station's sharing panel, and a relay follows a station served over TLS when (and only when)
//! it trusts the station's certificate.

use crate::common;
use crate::tls::TestCert;

use std::net::SocketAddr;
use std::path::PathBuf;

use common::*;
use serde_json::Value;
use stx_station::relay::feed::RelaySettings;
use stx_station::relay::serve::{self, RelayOptions};
use tokio::sync::oneshot;

/// A running relay; dropping it stops it.
struct Relay {
    addr: SocketAddr,
    _stop: oneshot::Sender<()>,
}

async fn start_relay(upstream: String, upstream_ca: Option<PathBuf>) -> Relay {
    let listener = serve::bind("127.0.0.1:0".parse().expect("address"))
        .await
        .expect("bind");
    let addr = listener.local_addr().expect("address");
    let (stop, stopped) = oneshot::channel::<()>();
    let options = RelayOptions {
        upstream,
        upstream_ca,
        web_dir: std::env::temp_dir().join("stx-relay-test-no-web"),
        settings: RelaySettings::new(0.0, 0.0).expect("settings"),
        max_viewers: 100,
    };
    tokio::spawn(async move {
        let shutdown = async move {
            let _ = stopped.await;
        };
        if let Err(e) = serve::run(options, listener, shutdown).await {
            panic!("relay failed: {e}");
        }
    });
    Relay { addr, _stop: stop }
}

async fn viewer(relay: SocketAddr) -> Ws {
    let (ws, _) = tokio_tungstenite::connect_async(format!("ws://{relay}/api/ws"))
        .await
        .expect("a viewer's socket");
    ws
}

/// The station's `relays` of `GET /api/sharing`.
async fn station_relays(station: SocketAddr) -> Vec<Value> {
    let (status, body) = http(station, "GET", "/api/sharing", Some(VIEWER), None).await;
    assert_eq!(status, 200, "{body}");
    body["relays"].as_array().cloned().unwrap_or_default()
}

/// Waits until the station counts `pages` public pages in all, through `relays` relays.
async fn until_station_counts(station: SocketAddr, relays: usize, pages: u64) -> Vec<Value> {
    let deadline = tokio::time::Instant::now() + std::time::Duration::from_secs(8);
    loop {
        let seen = station_relays(station).await;
        let total: u64 = seen.iter().filter_map(|r| r["viewers"].as_u64()).sum();
        if (seen.len() == relays && total == pages) || tokio::time::Instant::now() > deadline {
            return seen;
        }
        tokio::time::sleep(std::time::Duration::from_millis(100)).await;
    }
}

#[tokio::test]
async fn the_audience_of_a_tree_of_relays_reaches_the_station() {
    let station = start_station(config(|_| {})).await;
    let near = start_relay(format!("http://{}/?token={VIEWER}", station.http()), None).await;
    let far = start_relay(format!("http://{}/", near.addr), None).await;
    // One page on the near relay, two on the relay below it: three public pages in all.
    let _a = viewer(near.addr).await;
    let _b = viewer(far.addr).await;
    let c = viewer(far.addr).await;
    let seen = until_station_counts(station.http(), 1, 3).await;
    assert_eq!(seen.len(), 1, "one relay on the station: {seen:?}");
    assert_eq!(seen[0]["viewers"], 3, "{seen:?}");
    assert_eq!(seen[0]["name"], "viewer", "the relay's token: {seen:?}");
    // The near relay itself: two sockets (a page and the relay below), three pages.
    let (status, status_body) = http(near.addr, "GET", "/api/relay", None, None).await;
    assert_eq!(status, 200);
    assert_eq!(status_body["viewers"], 2, "{status_body}");
    assert_eq!(status_body["audience"], 3, "{status_body}");
    // The station's list of sockets names the relay's audience too.
    let (_, clients) = http(station.http(), "GET", "/api/clients", Some(OPERATOR), None).await;
    let relayed: Vec<_> = clients["clients"]
        .as_array()
        .expect("clients")
        .iter()
        .filter_map(|c| c["relay_viewers"].as_u64())
        .collect();
    assert_eq!(relayed, vec![3], "{clients}");
    // A page leaves the far relay: the station hears it.
    drop(c);
    let seen = until_station_counts(station.http(), 1, 2).await;
    assert_eq!(seen[0]["viewers"], 2, "{seen:?}");
}

#[tokio::test]
async fn a_relay_follows_a_tls_station_only_when_it_trusts_its_certificate() {
    let cert = TestCert::new("relay");
    let settings = cert.settings();
    let ca = settings.cert_path.clone();
    let station = start_station(config(move |c| c.tls = Some(settings))).await;
    let upstream = format!(
        "https://localhost:{}/?token={VIEWER}",
        station.http().port()
    );

    // Mozilla's roots alone do not know a field station's self-signed certificate.
    let untrusting = start_relay(upstream.clone(), None).await;
    // Given the station's certificate, the relay connects and reports its page.
    let trusting = start_relay(upstream, Some(ca)).await;
    let _page = viewer(trusting.addr).await;
    let mut on_untrusting = viewer(untrusting.addr).await;

    let (_, body) = http(trusting.addr, "GET", "/api/relay", None, None).await;
    assert_eq!(
        body["upstream"],
        format!("https://localhost:{}/", station.http().port())
    );
    let relays = {
        let deadline = tokio::time::Instant::now() + std::time::Duration::from_secs(8);
        loop {
            let r = https_sharing(&cert, station.http()).await;
            if !r.is_empty() || tokio::time::Instant::now() > deadline {
                break r;
            }
            tokio::time::sleep(std::time::Duration::from_millis(100)).await;
        }
    };
    assert_eq!(
        relays.len(),
        1,
        "only the trusting relay is on the station: {relays:?}"
    );
    assert_eq!(relays[0]["viewers"], 1, "{relays:?}");
    let (_, trusted) = http(trusting.addr, "GET", "/api/relay", None, None).await;
    assert_eq!(trusted["upstream_connected"], true, "{trusted}");
    // The station's picture reaches a page through the TLS relay.
    let mut page = viewer(trusting.addr).await;
    let state = ws_until(&mut page, 8.0, |m| m["type"] == "public_state").await;
    assert!(state.is_some(), "no public state through the TLS relay");
    let (_, untrusted) = http(untrusting.addr, "GET", "/api/relay", None, None).await;
    assert_eq!(untrusted["upstream_connected"], false, "{untrusted}");
    assert!(
        ws_until(&mut on_untrusting, 1.0, |m| m["type"] == "public_state")
            .await
            .is_none(),
        "a relay that does not trust the certificate shows nothing"
    );
}

/// `GET /api/sharing` over TLS: the station's `relays`.
async fn https_sharing(cert: &TestCert, station: SocketAddr) -> Vec<Value> {
    use tokio::io::{AsyncReadExt, AsyncWriteExt};
    let mut tls = cert.connect(station).await;
    let request = format!(
        "GET /api/sharing HTTP/1.1\r\nHost: localhost:{}\r\nAuthorization: Bearer {VIEWER}\r\nConnection: close\r\n\r\n",
        station.port()
    );
    tls.write_all(request.as_bytes()).await.expect("write");
    let mut response = String::new();
    tls.read_to_string(&mut response).await.expect("read");
    let body = response
        .split_once("\r\n\r\n")
        .map(|(_, b)| b)
        .unwrap_or("");
    let value: Value = serde_json::from_str(body).unwrap_or(Value::Null);
    value["relays"].as_array().cloned().unwrap_or_default()
}
