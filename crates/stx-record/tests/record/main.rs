//! The recorder's integration tests, one file per subject, built as one test binary (one link
//! instead of four). `cargo test -p stx-record --test record full_disk::` runs one file's tests.

mod common;

mod file_adapter;
mod full_disk;
mod python_mcap;
mod read_recover;
