//! The analysis tools' integration tests, one file per subject, built as one test binary.
//! `cargo test -p stx-analysis --test analysis seed_chapter_6::` runs one file's tests.

mod identified_landing;
mod linearisation;
mod seed_chapter_6;
