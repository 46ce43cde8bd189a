//! `GET /tiles/{z}/{x}/{y}[.ext]` with a tile pack: the pack's tile, else the tiles directory's
//! file, else 404; 400 for an address that is not a tile's. Without a pack, `/tiles/` is the
//! directory alone (`ServeDir`, in the router).
//!
//! No token is asked, as for the tiles directory: the map's `<img>` requests come by the dozen
//! when it pans, and counting them against the caller's request budget would starve the API;
//! tiles are the map of the field, not mission data.

use axum::body::Body;
use axum::extract::{Path, State};
use axum::http::{HeaderValue, Request, StatusCode, header};
use axum::response::{IntoResponse, Response};
use tower_http::services::ServeDir;

use super::shared::{AppState, error};
use crate::tile_pack::TileCoord;

/// Tiles do not change while the station runs; a page reloaded in the field then draws its map
/// without asking again.
const CACHE_CONTROL: &str = "public, max-age=3600";

pub(crate) async fn tile(State(state): State<AppState>, Path(path): Path<String>) -> Response {
    let coord = match TileCoord::parse(&path) {
        Ok(coord) => coord,
        Err(reason) => {
            return error(StatusCode::BAD_REQUEST, "bad_request", reason).into_response();
        }
    };
    if let Some(pack) = &state.tiles.pack {
        match pack.tile(coord).await {
            Ok(Some(tile)) => {
                let mut response = (
                    [
                        (header::CONTENT_TYPE, tile.content_type),
                        (header::CACHE_CONTROL, CACHE_CONTROL),
                    ],
                    tile.data,
                )
                    .into_response();
                if let Some(encoding) = tile.content_encoding {
                    response
                        .headers_mut()
                        .insert(header::CONTENT_ENCODING, HeaderValue::from_static(encoding));
                }
                return response;
            }
            Ok(None) => {}
            Err(e) => {
                tracing::warn!("{e}");
                return error(
                    StatusCode::INTERNAL_SERVER_ERROR,
                    "tile_pack",
                    e.to_string(),
                )
                .into_response();
            }
        }
    }
    if let Some(dir) = &state.config.tiles_dir {
        let request = Request::builder()
            .uri(format!("/{path}"))
            .body(Body::empty());
        if let Ok(request) = request
            && let Ok(response) = ServeDir::new(dir).try_call(request).await
            && response.status().is_success()
        {
            return response.map(Body::new);
        }
    }
    error(
        StatusCode::NOT_FOUND,
        "not_found",
        format!("no tile {coord} in the tile pack"),
    )
    .into_response()
}
