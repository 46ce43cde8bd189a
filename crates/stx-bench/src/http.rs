//! The station benchmarks' HTTP client side: one POST on a kept-alive HTTP/1.1 connection,
//! shared by the command timing ([`crate::station`]) and the Lab load ([`crate::lab_load`]).

use std::net::SocketAddr;

use http_body_util::{BodyExt, Full};
use hyper::body::Bytes;

/// One HTTP/1.1 POST on the kept-alive connection; the status.
pub async fn post(
    sender: &mut hyper::client::conn::http1::SendRequest<Full<Bytes>>,
    http: SocketAddr,
    path: &str,
    token: &str,
    body: String,
) -> anyhow::Result<u16> {
    let request = hyper::Request::post(format!("http://{http}{path}"))
        .header("authorization", format!("Bearer {token}"))
        .header("content-type", "application/json")
        .header("host", http.to_string())
        .body(Full::new(Bytes::from(body)))?;
    let response = sender.send_request(request).await?;
    let status = response.status().as_u16();
    response.into_body().collect().await?;
    Ok(status)
}
