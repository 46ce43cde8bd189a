//! The transports' integration tests, one file per subject, built as one test binary.
//! `cargo test -p stx-link-tokio --test link_tokio udp_peer::` runs one file's tests.

mod transport;
mod udp_peer;
