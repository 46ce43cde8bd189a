//! HTTPS for `[tls]`: the certificate chain and key read and checked before anything starts,
//! served by rustls with the `ring` provider (HTTP/1.1, so the WebSocket upgrades over it).

use std::sync::Arc;

use axum_server::tls_rustls::RustlsConfig;

use super::DaemonError;
use crate::config::TlsSettings;

/// The rustls server configuration of `[tls]`, read and checked before anything starts.
pub fn tls_config(tls: &TlsSettings) -> Result<RustlsConfig, DaemonError> {
    use rustls_pki_types::pem::PemObject;
    use rustls_pki_types::{CertificateDer, PrivateKeyDer};
    let cert_err = |reason: String| DaemonError::Tls {
        field: "tls.cert_path",
        path: tls.cert_path.display().to_string(),
        reason,
    };
    let certs = CertificateDer::pem_file_iter(&tls.cert_path)
        .map_err(|e| cert_err(e.to_string()))?
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| cert_err(e.to_string()))?;
    if certs.is_empty() {
        return Err(cert_err("no PEM certificate in the file".into()));
    }
    let key = PrivateKeyDer::from_pem_file(&tls.key_path).map_err(|e| DaemonError::Tls {
        field: "tls.key_path",
        path: tls.key_path.display().to_string(),
        reason: e.to_string(),
    })?;
    let provider = Arc::new(rustls::crypto::ring::default_provider());
    let mut server = rustls::ServerConfig::builder_with_provider(provider)
        .with_safe_default_protocol_versions()
        .map_err(|e| cert_err(e.to_string()))?
        .with_no_client_auth()
        .with_single_cert(certs, key)
        .map_err(|e| DaemonError::Tls {
            field: "tls.key_path",
            path: tls.key_path.display().to_string(),
            reason: format!("does not fit the certificate: {e}"),
        })?;
    // HTTP/1.1 only: the dashboard's WebSocket upgrades over it.
    server.alpn_protocols = vec![b"http/1.1".to_vec()];
    Ok(RustlsConfig::from_config(Arc::new(server)))
}
