//! A report read by `head`: `stx analyze | head -3` ends quietly when `head` stops reading.
//!
//! Regression: the report commands panicked ("failed printing to stdout: Broken pipe") because
//! Rust ignores SIGPIPE and `println!` panics on the error.

use std::io::{BufRead, BufReader, Read};
use std::os::unix::process::ExitStatusExt;
use std::process::{Command, Stdio};

#[test]
fn a_report_into_a_closed_pipe_ends_without_a_panic() {
    let out_dir = std::env::temp_dir().join(format!("stx-cli-pipe-{}", std::process::id()));
    let mut child = Command::new(env!("CARGO_BIN_EXE_stx"))
        .arg("analyze")
        .arg("--out-dir")
        .arg(&out_dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("stx starts");
    let mut stdout = BufReader::new(child.stdout.take().expect("stdout"));
    let mut first = String::new();
    stdout.read_line(&mut first).expect("a first line");
    assert!(first.starts_with("Trim at"), "the report starts: {first:?}");
    drop(stdout); // what `head -1` does once it has its line
    let mut stderr = String::new();
    child
        .stderr
        .take()
        .expect("stderr")
        .read_to_string(&mut stderr)
        .expect("stderr is read");
    let status = child.wait().expect("stx ends");
    let _ = std::fs::remove_dir_all(&out_dir);
    assert!(!stderr.contains("panicked"), "no panic: {stderr}");
    assert!(
        status.success() || status.signal() == Some(libc_sigpipe()),
        "ended by SIGPIPE (as `cat` would be) or done: {status:?}"
    );
}

/// SIGPIPE's number on Linux (and every other Unix stx is built for).
fn libc_sigpipe() -> i32 {
    13
}
