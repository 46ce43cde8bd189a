//! `GET /api/v1/` ([`crate::tawhiri`]): Tawhiri's prediction API over the station's forecast,
//! for any role (it reads and commands nothing; the token as on every route, in
//! `Authorization` or `?token=`, which a Tawhiri client's base address can carry). Answers in
//! Tawhiri's shapes, errors included; a caller without a valid token gets the station's own
//! 401, as on every route.

use axum::Json;
use axum::extract::{RawQuery, State};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use stx_weather::OffsetDateTime;

use super::auth::Caller;
use super::shared::AppState;
use crate::tawhiri::{StationWind, TawhiriError, TawhiriMetadata, predict, utc};

pub(crate) async fn prediction(
    State(state): State<AppState>,
    caller: Caller,
    RawQuery(query): RawQuery,
) -> Response {
    let started = OffsetDateTime::now_utc();
    let pairs: Vec<(String, String)> = form_urlencoded::parse(query.unwrap_or_default().as_bytes())
        .into_owned()
        .filter(|(k, _)| k != "token")
        .collect();
    let shared = state.clone();
    // Reading the configured GFS files the first time takes a moment: off the async workers.
    let answer = tokio::task::spawn_blocking(move || {
        let ground = shared.config.origin.alt_msl_m;
        match shared.configured_field() {
            Some(Ok(field)) => predict(&pairs, &StationWind::Gfs(&field), ground),
            Some(Err(e)) => Err(TawhiriError::Prediction(format!(
                "The station's GFS forecast cannot be read: {e}"
            ))),
            None => predict(
                &pairs,
                &StationWind::Rows(&shared.config.forecast_wind),
                ground,
            ),
        }
    })
    .await
    .unwrap_or_else(|e| Err(TawhiriError::Prediction(e.to_string())));
    let metadata = TawhiriMetadata {
        start_datetime: utc(started),
        complete_datetime: utc(OffsetDateTime::now_utc()),
    };
    match answer {
        Ok(p) => {
            tracing::debug!(by = caller.name, "Tawhiri prediction");
            Json(p.answer(metadata)).into_response()
        }
        Err(e) => {
            let status =
                StatusCode::from_u16(e.status()).unwrap_or(StatusCode::INTERNAL_SERVER_ERROR);
            (status, Json(e.answer(metadata))).into_response()
        }
    }
}
