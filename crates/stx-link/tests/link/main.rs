//! The MAVLink link's integration tests, one file per subject, built as one test binary.
//! `cargo test -p stx-link --test link endpoint::` runs one file's tests.

mod common;

mod body_imu;
mod datagram_source;
mod decoder_props;
mod endpoint;
mod fuzz_seeds;
mod pymavlink_peer;
