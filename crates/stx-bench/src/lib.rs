//! The measured speed and load figures behind `stx bench`: each part runs the real thing from
//! outside, as a drone, the operators' pages or the field network see it, and returns a report
//! (JSON through serde, text through `Display`); the command line parses the flags, prints and
//! picks the exit code.
//!
//! How the parts fit:
//! - [`station`]: the station daemon in this process, the simulated drone on its link and
//!   WebSocket pages, timing telemetry → page and command → drone; while it times, [`abuse`]
//!   floods the station from other loopback addresses and [`lab_load`] keeps the Lab busy
//!   over the API (both optional), with one HTTP helper, [`http`];
//! - [`memory`]: the daemon and the drone as `stx serve` and `stx drone` child processes
//!   through a three-hour day, the daemon's memory and file descriptors read from `/proc`
//!   (Linux only), which [`abuse`] reads too;
//! - [`relay`]: the station and a public relay as child processes (the station's child is
//!   [`memory`]'s), the drone and [`station`]'s timing pages here, and a thousand viewers on
//!   the relay: what the audience costs the station;
//! - [`agreement`]: whole missions flown by `stx_agreement`, held against its goals.
//!
//! `stx bench dynamics` is `stx_sim::speed` itself and needs nothing here.
//!
//! Errors are `anyhow`, unlike the other libraries': a bench's failure ends the run and is
//! told to whoever started it, with its context; no caller matches on it.

pub mod abuse;
pub mod agreement;
pub mod http;
pub mod lab_load;
pub mod memory;
pub mod relay;
pub mod station;
