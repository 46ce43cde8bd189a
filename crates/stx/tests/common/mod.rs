//! Helpers the `stx` command-line tests share: run the real binary, and a fresh scratch
//! directory per test.

use std::path::PathBuf;
use std::process::{Command, Output};

/// Runs the `stx` binary under test with `args`.
pub fn stx(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_stx"))
        .args(args)
        .output()
        .expect("stx runs")
}

/// An empty directory `stx-cli-{suite}-{name}-{pid}` under the system's temporary directory.
pub fn temp_dir(suite: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("stx-cli-{suite}-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}
