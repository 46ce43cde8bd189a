//! HTTPS on loopback with a certificate made for the test: the API and the WebSocket work over
//! TLS, plain HTTP is not served on that port, and unusable files are refused before start.

use crate::common;

use std::sync::Arc;

use common::*;
use futures_util::StreamExt;
use stx_station::config::TlsSettings;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio_rustls::TlsConnector;
use tokio_rustls::rustls;

/// A self-signed certificate for `localhost` and 127.0.0.1, written to a fresh directory.
pub(crate) struct TestCert {
    pub(crate) dir: std::path::PathBuf,
    der: rustls::pki_types::CertificateDer<'static>,
}

impl TestCert {
    pub(crate) fn new(tag: &str) -> Self {
        let certified =
            rcgen::generate_simple_self_signed(vec!["localhost".into(), "127.0.0.1".into()])
                .expect("certificate");
        let dir = std::env::temp_dir().join(format!("stx-tls-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        std::fs::write(dir.join("station.crt"), certified.cert.pem()).expect("cert");
        std::fs::write(
            dir.join("station.key"),
            certified.signing_key.serialize_pem(),
        )
        .expect("key");
        Self {
            der: certified.cert.der().clone(),
            dir,
        }
    }

    pub(crate) fn settings(&self) -> TlsSettings {
        TlsSettings {
            cert_path: self.dir.join("station.crt"),
            key_path: self.dir.join("station.key"),
        }
    }

    pub(crate) async fn connect(
        &self,
        addr: std::net::SocketAddr,
    ) -> tokio_rustls::client::TlsStream<TcpStream> {
        let mut roots = rustls::RootCertStore::empty();
        roots.add(self.der.clone()).expect("root");
        let config = rustls::ClientConfig::builder_with_provider(Arc::new(
            rustls::crypto::ring::default_provider(),
        ))
        .with_safe_default_protocol_versions()
        .expect("protocols")
        .with_root_certificates(roots)
        .with_no_client_auth();
        let tcp = TcpStream::connect(addr).await.expect("tcp");
        TlsConnector::from(Arc::new(config))
            .connect(
                rustls::pki_types::ServerName::try_from("localhost").expect("name"),
                tcp,
            )
            .await
            .expect("TLS handshake with the station")
    }
}

impl Drop for TestCert {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

#[tokio::test]
async fn the_api_and_the_websocket_are_served_over_tls() {
    let cert = TestCert::new("serve");
    let settings = cert.settings();
    let station = start_station(config(move |c| c.tls = Some(settings))).await;
    assert_eq!(station.running.scheme, "https");
    let addr = station.http();

    let mut tls = cert.connect(addr).await;
    tls.write_all(
        format!(
            "GET /api/session HTTP/1.1\r\nHost: localhost:{}\r\nAuthorization: Bearer {VIEWER}\r\nConnection: close\r\n\r\n",
            addr.port()
        )
        .as_bytes(),
    )
    .await
    .expect("write");
    let mut response = String::new();
    tls.read_to_string(&mut response).await.expect("read");
    assert!(response.starts_with("HTTP/1.1 200"), "{response}");
    assert!(response.contains(r#""role":"viewer""#), "{response}");

    // The dashboard's WebSocket (wss://) over the same TLS.
    let tls = cert.connect(addr).await;
    let (mut ws, _) = tokio_tungstenite::client_async(
        format!("wss://localhost:{}/api/ws?token={VIEWER}", addr.port()),
        tls,
    )
    .await
    .expect("WebSocket over TLS");
    let hello = ws.next().await.expect("a message").expect("ok");
    assert!(hello.to_text().expect("text").contains(r#""type":"hello""#));

    // The KML link points Google Earth at https.
    let mut tls = cert.connect(addr).await;
    tls.write_all(
        format!(
            "GET /kml?token={VIEWER} HTTP/1.1\r\nHost: localhost:{}\r\nConnection: close\r\n\r\n",
            addr.port()
        )
        .as_bytes(),
    )
    .await
    .expect("write");
    let mut kml = String::new();
    tls.read_to_string(&mut kml).await.expect("read");
    assert!(
        kml.contains(&format!("https://localhost:{}/kml/live", addr.port())),
        "{kml}"
    );

    // Plain HTTP on the TLS port gets no page.
    let mut plain = TcpStream::connect(addr).await.expect("tcp");
    plain
        .write_all(b"GET /api/state HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n")
        .await
        .expect("write");
    let mut bytes = Vec::new();
    let _ = plain.read_to_end(&mut bytes).await;
    assert!(
        !String::from_utf8_lossy(&bytes).contains("\"link\""),
        "state served in clear text"
    );
}

#[tokio::test]
async fn unusable_certificate_files_are_named_before_the_station_starts() {
    let cert = TestCert::new("bad");
    let mut missing = cert.settings();
    missing.cert_path = cert.dir.join("no-such.crt");
    let err = stx_station::daemon::tls_config(&missing)
        .expect_err("a missing certificate is refused")
        .to_string();
    assert!(
        err.contains("tls.cert_path") && err.contains("no-such.crt"),
        "{err}"
    );
    let mut swapped = cert.settings();
    swapped.key_path = swapped.cert_path.clone();
    let err = stx_station::daemon::tls_config(&swapped)
        .expect_err("a certificate is no key")
        .to_string();
    assert!(err.contains("tls.key_path"), "{err}");
    assert!(stx_station::daemon::tls_config(&cert.settings()).is_ok());
}
