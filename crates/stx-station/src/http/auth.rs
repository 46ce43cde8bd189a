//! Who is calling: the token from `Authorization: Bearer …` or `?token=` (the WebSocket and
//! Google Earth cannot set headers), its name and role from the station config (a rehearsal
//! token only from loopback, `crate::exposure`); and the percent-encoding of tokens in URLs
//! (`percent-encoding` and `form_urlencoded`, the URL crates' own).

use std::net::SocketAddr;

use axum::extract::{ConnectInfo, FromRequestParts};
use axum::http::request::Parts;
use axum::http::{StatusCode, header};
use percent_encoding::{AsciiSet, NON_ALPHANUMERIC, utf8_percent_encode};

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
    parts.uri.query().and_then(token_from_query)
}

/// The `token` of a query string, decoded as browsers and `form_urlencoded` encode it: `%2B`
/// is `+`, a bare `+` a space, a broken `%` sequence kept as written.
fn token_from_query(query: &str) -> Option<String> {
    form_urlencoded::parse(query.as_bytes())
        .find(|(k, _)| k == "token")
        .map(|(_, v)| v.into_owned())
}

/// What a token keeps as written in a URL: RFC 3986's unreserved characters; every other
/// byte is percent-encoded (so `+` is `%2B`, never read back as a space).
const TOKEN_IN_URL: &AsciiSet = &NON_ALPHANUMERIC
    .remove(b'-')
    .remove(b'.')
    .remove(b'_')
    .remove(b'~');

/// `s` as a URL query value (see [`TOKEN_IN_URL`]).
pub(crate) fn percent_encode(s: &str) -> String {
    utf8_percent_encode(s, TOKEN_IN_URL).to_string()
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_in_urls_decode_as_before_and_survive_a_round_trip() {
        assert_eq!(token_from_query("token=a%2Bb").as_deref(), Some("a+b"));
        assert_eq!(token_from_query("x=1&token=a+b").as_deref(), Some("a b"));
        assert_eq!(token_from_query("token=100%").as_deref(), Some("100%"));
        assert_eq!(token_from_query("token=%zz1").as_deref(), Some("%zz1"));
        assert_eq!(token_from_query("tokens=a"), None);
        let token = "a+b/c=d e~f_g.h-ü";
        let encoded = percent_encode(token);
        assert_eq!(encoded, "a%2Bb%2Fc%3Dd%20e~f_g.h-%C3%BC");
        let query = format!("token={encoded}");
        assert_eq!(token_from_query(&query).as_deref(), Some(token));
    }
}
