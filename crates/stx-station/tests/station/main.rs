//! The station's integration tests, one file per subject, built as one test binary: each
//! binary links and monomorphises the whole daemon again (13 of them took about 9 CPU-minutes to
//! build), and in one binary the slow files run beside the quick ones.
//! `cargo test -p stx-station --test station replay::` runs one file's tests.

mod common;

mod api;
mod ascent_winds;
mod fence;
mod field_network;
mod flight_path;
mod lab;
mod plan;
mod polar;
mod radios;
mod recordings;
mod relay;
mod replay;
mod replica;
mod slow_page;
mod surface_wind;
mod tiles;
mod tls;
