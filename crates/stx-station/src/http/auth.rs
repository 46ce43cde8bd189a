//! Who is calling: the token from `Authorization: Bearer …` or `?token=` (the WebSocket and
//! Google Earth cannot set headers), its name and role from the station config (a rehearsal
//! token only from loopback, `crate::exposure`); and the percent-encoding of tokens in URLs.

use std::net::SocketAddr;

use axum::extract::{ConnectInfo, FromRequestParts};
use axum::http::request::Parts;
use axum::http::{StatusCode, header};

use super::shared::{AppState, HttpError, error};
use crate::config::Role;
use crate::limits::Verdict;

/// The authenticated caller.
pub struct Caller {
    /// Name from the station config.
    pub name: String,
    /// Role.
    pub role: Role,
    /// The station is replaying a recording: nobody commands.
    pub replay: bool,
}

impl Caller {
    pub(crate) fn operator(&self) -> Result<(), HttpError> {
        if self.replay {
            return Err(HttpError::replaying());
        }
        match self.role {
            Role::Operator => Ok(()),
            Role::Viewer => Err(error(
                StatusCode::FORBIDDEN,
                "forbidden",
                "viewers cannot command: operator role required",
            )),
        }
    }
}

fn token_from(parts: &Parts) -> Option<String> {
    if let Some(value) = parts.headers.get(header::AUTHORIZATION)
        && let Ok(text) = value.to_str()
        && let Some(token) = text.strip_prefix("Bearer ")
    {
        return Some(token.trim().to_string());
    }
    parts.uri.query().and_then(|q| {
        q.split('&').find_map(|pair| {
            let (k, v) = pair.split_once('=')?;
            (k == "token").then(|| percent_decode(v))
        })
    })
}

pub(crate) fn percent_encode(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for b in s.bytes() {
        if b.is_ascii_alphanumeric() || b"-._~".contains(&b) {
            out.push(char::from(b));
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

fn percent_decode(s: &str) -> String {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'%' if i + 2 < bytes.len() => {
                let hex = std::str::from_utf8(&bytes[i + 1..i + 3]).ok();
                match hex.and_then(|h| u8::from_str_radix(h, 16).ok()) {
                    Some(b) => {
                        out.push(b);
                        i += 3;
                    }
                    None => {
                        out.push(b'%');
                        i += 1;
                    }
                }
            }
            b'+' => {
                out.push(b' ');
                i += 1;
            }
            b => {
                out.push(b);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

impl FromRequestParts<AppState> for Caller {
    type Rejection = HttpError;

    async fn from_request_parts(parts: &mut Parts, state: &AppState) -> Result<Self, HttpError> {
        let address = parts
            .extensions
            .get::<ConnectInfo<SocketAddr>>()
            .map(|c| c.0.ip());
        let now = state.elapsed_s();
        // An address that has sent too many wrong tokens is not heard until its bucket
        // refills, whatever it sends (so a guesser cannot tell a right guess from the wait).
        if let Some(ip) = address
            && let Err(retry) = state.limits().may_try(now, ip)
        {
            return Err(HttpError::too_many(
                "too many wrong tokens from this address",
                retry,
            ));
        }
        let Some(token) = token_from(parts) else {
            return Err(error(
                StatusCode::UNAUTHORIZED,
                "unauthorized",
                "a token is needed: Authorization: Bearer <token> or ?token=",
            ));
        };
        let known = state.config.authenticate(&token);
        if let Some((name, _)) = known
            && !crate::exposure::accepted_from(&state.config, &token, address)
        {
            // Everyone who read the README knows it: from the network it is a wrong token.
            tracing::warn!(token = name, address = ?address, "a rehearsal token from beyond loopback: refused");
            return Err(wrong_token(
                state,
                now,
                address,
                "rehearsal tokens work on the station's own machine only (loopback): \
                 make a token with `stx token new` for the station's config",
            ));
        }
        match known {
            Some((name, role)) => match state.limits().requests.take(now, &name.to_string()) {
                Verdict::Allowed => Ok(Caller {
                    name: name.to_string(),
                    role,
                    replay: state.replay.is_some(),
                }),
                Verdict::Refused { retry, first } => {
                    if first {
                        tracing::warn!(token = name, address = ?address, "too many requests: slowed");
                    }
                    Err(HttpError::too_many(
                        "too many requests with this token",
                        retry,
                    ))
                }
            },
            None => {
                tracing::info!(address = ?address, "request with an unknown token");
                Err(wrong_token(state, now, address, "unknown token"))
            }
        }
    }
}

/// The answer to a wrong token (`reason`): 401, or 429 once `address` has sent too many.
fn wrong_token(
    state: &AppState,
    now: f64,
    address: Option<std::net::IpAddr>,
    reason: &'static str,
) -> HttpError {
    if let Some(ip) = address
        && let Verdict::Refused { retry, first } = state.limits().bad_tokens.take(now, &ip)
    {
        if first {
            tracing::warn!(%ip, "wrong tokens: address locked out for {} s", retry.0);
        }
        return HttpError::too_many("too many wrong tokens from this address", retry);
    }
    error(StatusCode::UNAUTHORIZED, "unauthorized", reason)
}
