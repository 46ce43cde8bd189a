//! The HTTP side (axum): the REST endpoints and the WebSocket of `API.md`, the KML feed,
//! offline tiles and the built dashboard.
//!
//! - `shared`: what every handler shares ([`Shared`]) and the `{error, reason}` answers;
//! - `auth`: tokens, names and roles; `headers`: the security headers on every answer;
//! - `rest`: the reading endpoints; `commands`: the commanding ones (operators only);
//! - `keep_out`: the keep-out zones, read by anyone, edited by operators;
//! - `plan`: the Plan page's pre-flight plans, for anyone, one at a time, off the async
//!   workers;
//! - `tawhiri`: Tawhiri's prediction API (`/api/v1/`) over the station's forecast, for anyone;
//! - `ws`: the WebSocket (state, events, command results; operators' sticks);
//! - `kml`: the Google Earth feed; `replay`: the replay's pause, seek and speed;
//! - `recordings`: the past recordings: list, download, open in a replay;
//! - `tiles`: the offline map's tiles, from the tile pack and the tiles directory;
//! - `lab`: the Lab's jobs, vehicle and gains files;
//! - `sondehub`: a recovery phone's position for the SondeHub upload's chase car.
//!
//! Handlers only lock the core for a moment, build their answer, and wake the daemon when they
//! gave the core something for the link ([`Shared::link_due`]); nothing here waits on the
//! radio. Every page's counts are in `GET /api/clients`.

mod auth;
mod commands;
pub(crate) mod headers;
mod keep_out;
mod kml;
mod lab;
mod plan;
mod readiness;
mod recordings;
mod rehearse;
mod replay;
mod rest;
mod shared;
mod sondehub;
mod state_flow;
mod surface_wind;
mod tawhiri;
mod tiles;
mod ws;

use axum::Router;
use axum::routing::{any, get, post};
use tower_http::services::{ServeDir, ServeFile};

pub use auth::Caller;
pub use shared::{
    ClientCounters, HttpError, RehearsalRequest, Rehearsals, ReplayRefusal, ReplayRequest, Shared,
    SondehubShare, StateFrame, SummaryCache,
};

use crate::requests::{CourseBody, HeadingBody, LocalizerBody, ModeBody, PlanBody, TargetBody};
use commands::{arm_cutdown, command, confirm_cutdown, set_param};
use rest::{
    api_not_found, ascent_wind, clients, command_result, events, params, session, state_now, track,
};

/// The router of the whole station.
pub fn router(state: std::sync::Arc<Shared>) -> Router {
    let web_dir = state.config.web_dir.clone();
    let index = web_dir.join("index.html");
    let mut app = Router::new()
        .route("/api/session", get(session))
        .route("/api/state", get(state_now))
        .route("/api/params", get(params))
        .route("/api/params/{name}", post(set_param))
        .route("/api/ascent_wind", get(ascent_wind))
        .route("/api/events", get(events))
        .route("/api/track", get(track))
        .route("/api/commands/{id}", get(command_result))
        .route("/api/commands/mode", post(command::<ModeBody>))
        .route("/api/commands/heading", post(command::<HeadingBody>))
        .route("/api/commands/course", post(command::<CourseBody>))
        .route("/api/commands/localizer", post(command::<LocalizerBody>))
        .route("/api/commands/target", post(command::<TargetBody>))
        .route("/api/commands/plan", post(command::<PlanBody>))
        .route(
            "/api/keep-out",
            get(keep_out::keep_out).put(keep_out::set_keep_out),
        )
        .route("/api/plan", post(plan::make_plan))
        .route("/api/plan/defaults", get(plan::plan_defaults))
        .route(
            "/api/plan/forecast",
            post(plan::upload_forecast).layer(axum::extract::DefaultBodyLimit::max(
                crate::forecast_upload::MAX_BYTES,
            )),
        )
        .route("/api/plan/window", post(plan::plan_window))
        .route("/api/v1/", get(tawhiri::prediction))
        .route("/api/v1", get(tawhiri::prediction))
        .route("/api/readiness", get(readiness::board))
        .route("/api/readiness/{id}", post(readiness::tick))
        .route("/api/sharing", get(readiness::sharing))
        .route("/api/sondehub/chase", post(sondehub::chase_car))
        .route(
            "/api/surface_wind",
            get(surface_wind::view)
                .post(surface_wind::set)
                .delete(surface_wind::clear),
        )
        .route("/api/cutdown/arm", post(arm_cutdown))
        .route("/api/cutdown/confirm", post(confirm_cutdown))
        .route("/api/clients", get(clients))
        .route(
            "/api/replay",
            get(replay::replay_status).post(replay::replay_control),
        )
        .route("/api/recordings", get(recordings::recordings))
        .route("/api/recordings/{name}", get(recordings::download))
        .route(
            "/api/recordings/{name}/replay",
            post(recordings::open_replay),
        )
        .route("/api/lab", get(lab::status))
        .route("/api/lab/jobs", post(lab::start))
        .route("/api/lab/cancel", post(lab::cancel))
        .route("/api/lab/rehearse", post(rehearse::rehearse))
        .route("/api/lab/vehicle", get(lab::vehicle_fields))
        .route("/api/lab/vehicle/check", post(lab::vehicle_check))
        .route("/api/lab/vehicle/save", post(lab::vehicle_save))
        .route("/api/lab/gains", get(lab::gains))
        .route("/api/lab/gains/save", post(lab::gains_save))
        .route("/api/lab/gains/send", post(lab::gains_send))
        .route("/api/ws", get(ws::websocket))
        // An API path that does not exist is an API error, never the dashboard's page.
        .route("/api", any(api_not_found))
        .route("/api/", any(api_not_found))
        .route("/api/{*rest}", any(api_not_found))
        .route("/kml", get(kml::kml_link))
        .route("/kml/live", get(kml::kml_live));
    if state.tiles.pack.is_some() {
        app = app.route("/tiles/{*path}", get(tiles::tile));
    } else if let Some(tiles) = &state.config.tiles_dir {
        app = app.nest_service("/tiles", ServeDir::new(tiles));
    }
    let security = std::sync::Arc::new(headers::SecurityHeaders::new(&state.config));
    app.fallback_service(ServeDir::new(web_dir).fallback(ServeFile::new(index)))
        .with_state(state)
        // Outermost, so every answer has them: pages, assets, tiles, the API and its errors.
        .layer(axum::middleware::from_fn_with_state(security, headers::add))
}
