//! Helpers the `stx` command-line tests share: run the real binary, and a fresh scratch
//! directory per test.

use std::path::{Path, PathBuf};
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

/// The shipped vehicle file with `from` replaced by `to` (which must be there), written as
/// `dir/name`; its path. Only the tests that fly a vehicle file use it.
#[allow(dead_code)]
pub fn vehicle_file(dir: &Path, name: &str, from: &str, to: &str) -> PathBuf {
    let shipped = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config/vehicle/straplex.toml"),
    )
    .expect("shipped vehicle file");
    assert!(shipped.contains(from), "{from} in the shipped vehicle file");
    let path = dir.join(name);
    std::fs::write(&path, shipped.replacen(from, to, 1)).expect("write");
    path
}
