//! The stx ground station: holds the drone link, runs the same estimator, guidance and landing
//! predictor as the drone on the live telemetry, keeps the mission's state and serves the
//! dashboard and the API described in `API.md`.
//!
//! - [`config`]: the station's TOML, validated before anything starts;
//! - [`core`]: the station's state and logic, pure (events and the mission clock in, messages
//!   and link actions out);
//! - [`messages`] and [`replies`]: the API's JSON the station sends, [`requests`]: what it reads
//!   (parameter ranges, units and meanings come from the onboard catalogue, `stx_gnc::params`,
//!   shared with the drone); [`contract`]: all of them as one JSON Schema, the contract the
//!   dashboard's TypeScript types are generated from; [`kml`]: the Google Earth feed;
//! - [`http`]: the axum routes (auth, REST, WebSocket, static files);
//! - [`daemon`]: the tokio wiring of link, core and HTTP, with graceful shutdown.

pub mod config;
pub mod contract;
pub mod core;
pub mod daemon;
pub mod http;
pub mod kml;
pub mod messages;
pub mod replies;
pub mod requests;
