//! The flight model's integration tests, one file per subject, built as one test binary.
//! `cargo test -p stx-dynamics --test dynamics physics::` runs one file's tests.

mod pendant_pole;
mod physics;
mod seed_appendix_a;
