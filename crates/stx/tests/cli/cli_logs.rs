//! `stx`'s log lines as a file, a pipe or a log collector receives them: no terminal escape
//! codes in text, and with `--log-format json` one JSON object per line.
//!
//! Regression: `stx serve > log` (or under journald) wrote ANSI colour codes into the log.

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use serde_json::Value;

/// Runs `stx` with `args` (a station with its simulated drone, which logs at once), its stderr
/// piped, until it has logged `lines` lines or 20 s passed; stops it with SIGTERM and returns
/// everything it logged.
fn log_of(args: &[&str], lines: usize) -> String {
    let mut child = Command::new(env!("CARGO_BIN_EXE_stx"))
        .args(args)
        .env("RUST_LOG", "info")
        .env_remove("NO_COLOR")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("stx starts");
    let stderr = child.stderr.take().expect("stderr");
    let (tx, rx) = mpsc::channel();
    let reader = std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines() {
            let Ok(line) = line else { break };
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let mut log = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(20);
    while log.len() < lines && Instant::now() < deadline {
        if let Ok(line) = rx.recv_timeout(Duration::from_millis(100)) {
            log.push(line);
        }
    }
    let pid = child.id().to_string();
    let _ = Command::new("kill").args(["-TERM", &pid]).status();
    let _ = child.wait();
    let _ = reader.join();
    log.extend(rx.try_iter());
    assert!(
        log.len() >= lines,
        "only {} lines logged: {log:?}",
        log.len()
    );
    log.join("\n")
}

const SERVE: [&str; 7] = [
    "serve",
    "--sim",
    "--listen",
    "127.0.0.1:0",
    "--link",
    "udpin:127.0.0.1:0",
    "--no-record",
];

#[test]
fn text_logs_to_a_pipe_carry_no_escape_codes() {
    let log = log_of(&SERVE, 4);
    assert!(
        !log.contains('\u{1b}'),
        "escape codes in a piped log:\n{log:?}"
    );
    assert!(log.contains("INFO"), "{log}");
    assert!(log.contains("station listening"), "{log}");
}

#[test]
fn json_logs_are_one_object_per_line_with_level_target_and_fields() {
    // The flag is global: before or after the subcommand.
    let before: Vec<&str> = ["--log-format", "json"].into_iter().chain(SERVE).collect();
    let after: Vec<&str> = SERVE.into_iter().chain(["--log-format", "json"]).collect();
    for args in [before, after] {
        let log = log_of(&args, 4);
        assert!(!log.contains('\u{1b}'), "{log:?}");
        let mut messages = Vec::new();
        for line in log.lines() {
            let v: Value = serde_json::from_str(line)
                .unwrap_or_else(|e| panic!("not JSON ({e}): {line:?} in\n{log}"));
            assert!(v["level"].is_string(), "{line}");
            assert!(v["target"].is_string(), "{line}");
            assert!(v["fields"].is_object(), "{line}");
            assert!(v["timestamp"].is_string(), "{line}");
            messages.push(v["fields"]["message"].as_str().unwrap_or("").to_string());
        }
        let listening = log
            .lines()
            .filter_map(|l| serde_json::from_str::<Value>(l).ok())
            .find(|v| v["fields"]["message"] == "station listening")
            .unwrap_or_else(|| panic!("no `station listening` in {messages:?}"));
        assert_eq!(listening["level"], "INFO");
        assert_eq!(listening["target"], "stx_station::daemon");
        assert!(
            listening["fields"]["address"].is_string(),
            "fields are structured: {listening}"
        );
    }
}

#[test]
fn an_unknown_log_format_is_bad_input() {
    let out = Command::new(env!("CARGO_BIN_EXE_stx"))
        .args(["--log-format", "xml", "serve"])
        .output()
        .expect("stx runs");
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("xml") && stderr.contains("json"),
        "{stderr}"
    );
}
