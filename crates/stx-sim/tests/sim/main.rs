//! The simulator's integration tests, one file per subject, built as one test binary: one
//! link instead of thirteen, and the long campaigns run beside the short checks.
//! `cargo test -p stx-sim --test sim seed_behaviour::` runs one file's tests.

mod body_imus;
mod campaign_header;
mod campaign_regression;
mod drone_core;
mod drone_vehicle;
mod failed_runs;
mod flight_path_matches_mission;
mod footprint_against_full_model;
mod guided_scenarios;
mod keep_out_campaign;
mod linked_drone;
mod montecarlo_stop;
mod performance_matches_model;
mod runner;
mod seed_behaviour;
mod sensors_estimator;
