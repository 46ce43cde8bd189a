//! `stx relay` as a process: it runs at the lowest priority unless told otherwise (every
//! thread of it, so its viewers never take a core the station's telemetry needs), and a bad
//! certificate file or upstream address is refused before it starts.

use std::process::{Command, Stdio};

use crate::common::{Killed, banner, stx};

/// Starts `stx relay` with `extra` on a loopback port (its upstream need not answer).
fn relay(extra: &[&str]) -> Killed {
    let mut child = Command::new(env!("CARGO_BIN_EXE_stx"))
        .args([
            "relay",
            "--upstream",
            "http://127.0.0.1:9/",
            "--listen",
            "127.0.0.1:0",
        ])
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("stx relay starts");
    let line = banner(&mut child);
    assert!(line.starts_with("stx relay:"), "{line}");
    Killed(child)
}

/// (nice, scheduling policy) of every thread of `pid`, from `/proc/PID/task/*/stat`.
fn threads(pid: u32) -> Vec<(i64, i64)> {
    std::fs::read_dir(format!("/proc/{pid}/task"))
        .expect("the relay's threads")
        .map(|t| {
            let stat =
                std::fs::read_to_string(t.expect("a thread").path().join("stat")).expect("stat");
            // Fields after the command name (which may hold spaces): nice is the 19th field,
            // the policy the 41st.
            let fields: Vec<&str> = stat[stat.rfind(')').expect("name") + 2..]
                .split(' ')
                .collect();
            (
                fields[16].parse().expect("nice"),
                fields[38].parse().expect("policy"),
            )
        })
        .collect()
}

#[test]
fn a_relay_runs_every_thread_at_the_lowest_priority_unless_told() {
    const SCHED_IDLE: i64 = 5;
    let low = relay(&[]);
    let seen = threads(low.0.id());
    assert!(seen.len() >= 2, "the runtime's threads: {seen:?}");
    assert!(
        seen.iter().all(|&t| t == (19, SCHED_IDLE)),
        "nice 19 and the idle class on every thread: {seen:?}"
    );
    let full = relay(&["--full-priority"]);
    assert!(
        threads(full.0.id())
            .iter()
            .all(|&(_, policy)| policy != SCHED_IDLE),
        "--full-priority keeps the usual class"
    );
}

#[test]
fn bad_upstreams_and_certificate_files_are_refused_before_start() {
    let out = stx(&[
        "relay",
        "--upstream",
        "ftp://station/",
        "--listen",
        "127.0.0.1:0",
    ]);
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    assert!(String::from_utf8_lossy(&out.stderr).contains("ftp://station/"));
    let out = stx(&[
        "relay",
        "--upstream",
        "https://127.0.0.1:9/",
        "--upstream-ca",
        "/no/such/station.crt",
        "--listen",
        "127.0.0.1:0",
    ]);
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("/no/such/station.crt"), "{err}");
}
