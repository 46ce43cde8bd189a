//! The Google Earth feed: `/kml` is a network link that refreshes `/kml/live` (the track,
//! the vehicle, the target, the pattern and the predicted landings) at the address Google
//! Earth used to reach the station.

use axum::extract::State;
use axum::http::header;
use axum::response::{IntoResponse, Response};

use super::auth::{Caller, percent_encode};
use super::shared::AppState;

/// The address Google Earth used to reach the station (the `Host` header): the listen
/// address may be `0.0.0.0`, which names no machine. Without a usable header, the listen
/// address with `0.0.0.0` read as loopback.
fn public_host(headers: &axum::http::HeaderMap, listen: std::net::SocketAddr) -> String {
    let valid = |h: &str| {
        !h.is_empty()
            && h.len() <= 255
            && h.chars()
                .all(|c| c.is_ascii_alphanumeric() || "-.:[]_".contains(c))
    };
    match headers.get(header::HOST).and_then(|v| v.to_str().ok()) {
        Some(h) if valid(h) => h.to_string(),
        _ => {
            let ip = if listen.ip().is_unspecified() {
                std::net::IpAddr::from([127, 0, 0, 1])
            } else {
                listen.ip()
            };
            std::net::SocketAddr::new(ip, listen.port()).to_string()
        }
    }
}

pub(crate) async fn kml_link(
    State(state): State<AppState>,
    caller: Caller,
    headers: axum::http::HeaderMap,
) -> Response {
    let token = state
        .config
        .tokens
        .iter()
        .find(|t| t.name == caller.name)
        .map(|t| t.token.clone())
        .unwrap_or_default();
    let scheme = if state.config.tls.is_some() {
        "https"
    } else {
        "http"
    };
    let host = public_host(&headers, state.config.listen);
    let body = crate::kml::network_link(
        &state.config.name,
        &format!(
            "{scheme}://{host}/kml/live?token={}",
            percent_encode(&token)
        ),
        2.0,
    );
    (
        [(header::CONTENT_TYPE, "application/vnd.google-earth.kml+xml")],
        body,
    )
        .into_response()
}

pub(crate) async fn kml_live(State(state): State<AppState>, _caller: Caller) -> Response {
    let now = state.now_s();
    let core = state.core();
    let body = crate::kml::live(
        &state.config.name,
        &core.track(1.0),
        &core.state_msg_now(now),
    );
    drop(core);
    (
        [(header::CONTENT_TYPE, "application/vnd.google-earth.kml+xml")],
        body,
    )
        .into_response()
}
