//! The stx ground station: holds the drone link, runs the same estimator, guidance and landing
//! predictor as the drone on the live telemetry, keeps the mission's state and serves the
//! dashboard and the API described in `API.md`.
//!
//! The pure station (no tokio, no sockets; `--no-default-features` builds only this):
//! - [`config`]: the station's TOML, validated before anything starts; [`exposure`]: what it
//!   lets through beyond this machine (rehearsal tokens on loopback only, plain HTTP only when
//!   asked for); [`checklist`]: the go/no-go board's settings and files; [`forward`]: the
//!   read-only MAVLink outputs for watching ground stations (their sockets are the daemon's);
//!   [`chase`]: the Horus UDP summaries for chase cars' maps; [`sondehub`]: the upload to
//!   SondeHub-Amateur (points, queue, retries; its HTTP client is the daemon's);
//!   [`surface_wind`]: the wind at the target (`[surface_wind]`), from a ground anemometer's
//!   NMEA sentences (its reader is the daemon's) or the operator, uplinked to the drone;
//! - [`core`]: the station's state and logic: telemetry, link events and operators' requests
//!   in, with the mission clock; messages for the dashboards and link actions (with ids and
//!   deadlines) out; the link's outcome of each action back in; retries and time-outs are its
//!   own timers;
//! - [`link`]: the ground endpoint as the link driver runs it, applying the core's link
//!   actions and reporting their outcomes with the endpoint's events;
//! - [`messages`] (with [`ascent_wind_msg`]) and [`replies`]: the API's JSON the station
//!   sends, [`requests`]: what it
//!   reads (parameter ranges, units and meanings come from the onboard catalogue,
//!   `stx_gnc::params`, shared with the drone); [`contract`]: all of them as one JSON Schema,
//!   the contract the dashboard's TypeScript types are generated from; [`forecast_file`]: a
//!   GFS GRIB2 file or a sounding as forecast rows (`[forecast_file]`), [`forecast_upload`]
//!   the same sent from the Plan page; [`kml`]: the Google
//!   Earth feed; [`keep_out`]: the keep-out zones' messages; [`lab`]: the Lab's jobs, requests and results (the work itself is
//!   stx-lab's); [`limits`]: requests per token, wrong tokens per address and pages at once,
//!   as token buckets on the station's clock; [`preflight`]: the Plan page's pre-flight plans
//!   (`POST /api/plan`); [`launch_window`]: that plan for every launch time of a window over a
//!   GFS forecast; [`tawhiri`]: Tawhiri's prediction API (`GET /api/v1/`) flown over the
//!   station's forecast; [`recording`]: what a flight's MCAP recording
//!   holds, under which topics; [`replay`]: a recording played back through the station;
//!   [`priority`] (daemon): the lowest priority for the Lab and a relay;
//!   [`relay`]: `stx relay`, the public picture for any audience (its server is the daemon's).
//!
//! With the default feature `daemon`, the adapters:
//! - `http`: the axum routes (auth, REST, WebSocket, KML, static files);
//! - `daemon`: the tokio wiring of link driver, core and HTTP, with graceful shutdown;
//! - `recorder`: the run's recording (stx-record's writer thread) fed from the station loop
//!   and the link driver;
//! - `tile_pack`: the offline map's tile pack (MBTiles or PMTiles), opened at start and read
//!   for `/tiles/`.

pub mod ascent_wind_msg;
pub mod chase;
pub mod checklist;
pub mod config;
pub mod contract;
pub mod core;
#[cfg(feature = "daemon")]
pub mod daemon;
pub mod exposure;
pub mod forecast_file;
pub mod forecast_upload;
pub mod forward;
#[cfg(feature = "daemon")]
pub mod http;
pub mod keep_out;
pub mod kml;
pub mod lab;
pub mod launch_window;
pub mod limits;
pub mod link;
pub mod messages;
pub mod preflight;
#[cfg(feature = "daemon")]
pub mod priority;
#[cfg(feature = "daemon")]
pub mod recorder;
pub mod recording;
pub mod relay;
pub mod replay;
pub mod replies;
pub mod requests;
pub mod sondehub;
pub mod surface_wind;
pub mod tawhiri;
#[cfg(feature = "daemon")]
pub mod tile_pack;
