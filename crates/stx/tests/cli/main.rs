//! The command line's end-to-end tests: each file runs the real `stx` binary (and peers nobody
//! here wrote: pymavlink, MAVProxy) on one subject. One test binary, so the files that wait on a
//! simulated flight wait side by side. `cargo test -p stx --test cli cli_serve::` runs one file's
//! tests.

mod common;

mod chase_horus;
mod cli_analysis;
mod cli_bench;
mod cli_compare;
mod cli_drone_vehicle;
mod cli_identify;
mod cli_import;
mod cli_logs;
mod cli_montecarlo;
mod cli_pipe;
mod cli_plan;
mod cli_plan_gfs;
mod cli_plan_window;
mod cli_polar;
mod cli_record;
mod cli_relay;
mod cli_serve;
mod cli_sim;
mod cli_token;
mod drone_link;
mod drone_mavproxy;
mod drone_pymavlink;
mod forward_mavproxy;
mod hostile_link;
mod http_abuse;
mod identify_rehearsal;
mod record_station;
mod sondehub_upload;
mod tawhiri_api;
