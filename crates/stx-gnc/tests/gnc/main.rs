//! Guidance, navigation and control's integration tests, one file per subject, built as one
//! test binary. `cargo test -p stx-gnc --test gnc estimator::` runs one file's tests.

mod ascent_wind;
mod estimator;
mod estimator_calibration;
mod flight_path;
mod flight_plan;
mod guidance;
mod guidance_keep_out;
mod synthetic_flight;
