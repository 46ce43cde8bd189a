//! The station's recording through the real daemon (`stx serve --sim`): killed with SIGKILL
//! mid-flight, its file still reads up to about a second before the kill and `stx record
//! recover` makes it whole; stopped cleanly, the file is whole and holds every channel of a
//! flight; given a directory it cannot write, the station keeps flying and says so; on a
//! full disk (a tmpfs filled up) it leaves no empty files, says since when and the next try,
//! and resumes when space returns; `stx replay` refuses what it cannot play. (Replay itself
//! is driven from a browser: tests/browser/live.mjs.)

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use serde_json::Value;
use stx_record::{IndexSource, Recording};

/// Kills the daemon when the test ends, passed or not.
struct Daemon {
    child: Child,
    http: String,
    token: String,
}

impl Drop for Daemon {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn temp_dir(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("stx-record-station-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// `stx serve --sim` at 10× recording into `record_dir`.
fn serve(record_dir: &Path) -> Daemon {
    let mut child = Command::new(env!("CARGO_BIN_EXE_stx"))
        .args([
            "serve",
            "--sim",
            // Under the parafoil from the start: the station predicts landings only there.
            "--sim-scenario",
            "rehearsal",
            "--sim-speed",
            "10",
            "--listen",
            "127.0.0.1:0",
            "--link",
            "udpin:127.0.0.1:0",
            "--record-dir",
        ])
        .arg(record_dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("stx serve starts");
    let (http, token) = crate::common::read_started(&mut child);
    Daemon { http, token, child }
}

fn state(d: &Daemon) -> Option<Value> {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .ok()?;
    rt.block_on(async {
        use tokio::io::{AsyncReadExt, AsyncWriteExt};
        let mut s = tokio::net::TcpStream::connect(&d.http).await.ok()?;
        let req = format!(
            "GET /api/state HTTP/1.1\r\nHost: {}\r\nAuthorization: Bearer {}\r\nConnection: close\r\n\r\n",
            d.http, d.token
        );
        s.write_all(req.as_bytes()).await.ok()?;
        let mut body = Vec::new();
        s.read_to_end(&mut body).await.ok()?;
        let text = String::from_utf8_lossy(&body);
        let json = text.split_once("\r\n\r\n")?.1;
        serde_json::from_str(json).ok()
    })
}

/// Waits until `pred` holds for the station's state (at most `secs`).
fn wait_for(d: &Daemon, secs: f64, pred: impl Fn(&Value) -> bool) -> Value {
    let until = Instant::now() + Duration::from_secs_f64(secs);
    loop {
        if let Some(s) = state(d)
            && pred(&s)
        {
            return s;
        }
        assert!(
            Instant::now() < until,
            "the station's state never got there"
        );
        std::thread::sleep(Duration::from_millis(200));
    }
}

fn only_file(dir: &Path) -> PathBuf {
    let files: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("recordings dir")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "mcap"))
        .collect();
    assert_eq!(files.len(), 1, "one file per station run: {files:?}");
    files[0].clone()
}

/// Log time of the last message on `topic`, ns.
fn last_on(rec: &mut Recording<std::fs::File>, topic: &str) -> Option<u64> {
    rec.messages()
        .expect("messages")
        .filter_map(Result::ok)
        .filter(|m| &*m.topic == topic)
        .map(|m| m.log_time)
        .max()
}

/// `read_mcap.py summary FILE` (stx-record's peer script) with `$STX_PYTHON` (or the
/// workspace's `.venv`).
fn python_summary(file: &Path) -> Value {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let python = std::env::var_os("STX_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join(".venv/bin/python"));
    let out = Command::new(&python)
        .arg(root.join("crates/stx-record/tests/peers/read_mcap.py"))
        .arg("summary")
        .arg(file)
        .output()
        .unwrap_or_else(|e| panic!("{} runs (set STX_PYTHON): {e}", python.display()));
    assert!(
        out.status.success(),
        "read_mcap.py: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON")
}

fn unix_ns() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .expect("clock")
        .as_nanos() as u64
}

#[test]
fn a_station_killed_mid_flight_keeps_all_but_about_its_last_second() {
    let dir = temp_dir("kill");
    let mut d = serve(&dir);
    // Flying, with an estimate, and some chunks on disk.
    wait_for(&d, 60.0, |s| {
        s["estimate"].is_object() && s["recording"]["messages_written"].as_u64() > Some(500)
    });
    std::thread::sleep(Duration::from_secs(2));
    let killed_at = unix_ns();
    d.child.kill().expect("SIGKILL");
    d.child.wait().expect("reaped");
    let file = only_file(&dir);
    let mut rec = Recording::open(&file).expect("a killed station's file reads");
    assert!(
        matches!(rec.index(), IndexSource::Scan { .. }),
        "no summary after a kill: read by a scan"
    );
    for topic in [
        stx_station::recording::FRAMES,
        stx_station::recording::STATE,
        stx_station::recording::CONFIG,
    ] {
        assert!(
            rec.channel(topic).is_some_and(|c| c.message_count > 0),
            "{topic} recorded before the kill"
        );
    }
    // The raw link carries many frames a second at 10×: the last one on disk is at most
    // about a second (the chunk's age limit) before the kill, plus the writer's turn.
    let last_frame = last_on(&mut rec, stx_station::recording::FRAMES).expect("frames");
    let lost_s = killed_at.saturating_sub(last_frame) as f64 / 1e9;
    assert!(lost_s < 2.0, "{lost_s:.2} s of frames lost to the kill");
    // `stx record recover` writes a whole copy holding the same messages.
    let out = dir.join("recovered.mcap");
    let status = Command::new(env!("CARGO_BIN_EXE_stx"))
        .args(["record", "recover"])
        .arg(&file)
        .arg("--out")
        .arg(&out)
        .status()
        .expect("stx record recover");
    assert!(status.success(), "recover: {status}");
    let whole = Recording::open(&out).expect("the recovered copy reads");
    assert_eq!(whole.index(), IndexSource::Summary, "the copy is whole");
    assert_eq!(whole.message_count(), rec.message_count());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_clean_stop_leaves_a_whole_file_with_the_flight_s_channels() {
    let dir = temp_dir("clean");
    let mut d = serve(&dir);
    let s = wait_for(&d, 60.0, |s| {
        s["estimate"].is_object() && s["prediction"].is_object()
    });
    assert_eq!(s["recording"]["state"], "on", "{}", s["recording"]);
    // A few recorded states (1 Hz) with the prediction in them.
    std::thread::sleep(Duration::from_secs(3));
    // SIGINT: the station stops, closing the file with its summary.
    let pid = d.child.id().to_string();
    Command::new("kill")
        .args(["-INT", &pid])
        .status()
        .expect("kill -INT");
    let until = Instant::now() + Duration::from_secs(20);
    while d.child.try_wait().expect("wait").is_none() {
        assert!(Instant::now() < until, "the station did not stop");
        std::thread::sleep(Duration::from_millis(100));
    }
    let file = only_file(&dir);
    let rec = Recording::open(&file).expect("reads");
    assert_eq!(
        rec.index(),
        IndexSource::Summary,
        "a clean stop writes the summary"
    );
    let (info, _) = rec.info().expect("metadata record");
    assert_eq!(info.station_version(), env!("CARGO_PKG_VERSION"));
    assert!(info.token_names().iter().any(|n| n == "operator"));
    for topic in [
        stx_station::recording::FRAMES,
        stx_station::recording::STATE,
        stx_station::recording::ESTIMATE_POSITION,
        stx_station::recording::PREDICTED_LANDING,
        stx_station::recording::EVENTS,
        stx_station::recording::LOG,
        stx_station::recording::PARAMS,
        stx_station::recording::CONFIG,
        stx_station::recording::VEHICLE_GPS,
        stx_station::recording::VEHICLE_ATTITUDE,
        "/telemetry/GPS_RAW_INT",
        "/telemetry/ATTITUDE",
        "/telemetry/HEARTBEAT",
    ] {
        assert!(
            rec.channel(topic).is_some_and(|c| c.message_count > 0),
            "{topic} recorded: {:?}",
            rec.channels()
        );
    }
    // An independent reader (Python `mcap` from PyPI) finds every channel, schema and count.
    let theirs = python_summary(&file);
    assert_eq!(theirs["missing_fields"], serde_json::json!([]), "{theirs}");
    assert_eq!(theirs["message_count"].as_u64(), Some(rec.message_count()));
    for ours in rec.channels() {
        let found = theirs["channels"]
            .as_array()
            .expect("channels")
            .iter()
            .find(|c| c["topic"] == *ours.topic)
            .unwrap_or_else(|| panic!("{} not found by Python mcap", ours.topic));
        assert_eq!(found["schema_name"], ours.schema_name.as_str());
        assert_eq!(
            found["count"].as_u64(),
            Some(ours.message_count),
            "{}",
            ours.topic
        );
        let read = theirs["read"][&*ours.topic].as_u64().unwrap_or(0);
        assert_eq!(read, ours.message_count, "{} messages read", ours.topic);
    }
    // Exported for spreadsheets, Google Earth and phones.
    let out = dir.join("export");
    let exported = Command::new(env!("CARGO_BIN_EXE_stx"))
        .arg("export")
        .arg(&file)
        .arg("--csv")
        .arg(&out)
        .arg("--gpx")
        .arg(dir.join("flight.gpx"))
        .arg("--kml")
        .arg(dir.join("flight.kml"))
        .output()
        .expect("stx export");
    assert!(
        exported.status.success(),
        "{}",
        String::from_utf8_lossy(&exported.stderr)
    );
    let gps_csv = std::fs::read_to_string(out.join("vehicle_gps.csv")).expect("GPS CSV");
    assert_eq!(
        gps_csv.lines().count() as u64,
        rec.channel(stx_station::recording::VEHICLE_GPS)
            .expect("gps")
            .message_count
            + 1,
        "a row per fix under the header"
    );
    let state_csv = std::fs::read_to_string(out.join("station_state.csv")).expect("state CSV");
    assert!(
        state_csv
            .lines()
            .next()
            .is_some_and(|h| h.contains("estimate.alt_msl_m [m]")),
        "units in the header"
    );
    let gpx = std::fs::read_to_string(dir.join("flight.gpx")).expect("GPX");
    assert!(gpx.matches("<trkpt ").count() > 10, "{gpx}");
    assert!(
        std::fs::read_to_string(dir.join("flight.kml")).is_ok_and(|k| k.contains("<LineString>"))
    );
    // Never a token in the file.
    let bytes = std::fs::read(&file).expect("file");
    for secret in ["operator-token", "viewer-token"] {
        assert!(
            !bytes.windows(secret.len()).any(|w| w == secret.as_bytes()),
            "{secret} in the recording"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_unwritable_directory_leaves_the_station_flying_and_saying_so() {
    let dir = temp_dir("unwritable");
    // A file where the directory should be: nothing can be created under it.
    let blocked = dir.join("not-a-directory");
    std::fs::write(&blocked, b"x").expect("file");
    let d = serve(&blocked);
    let s = wait_for(&d, 60.0, |s| {
        s["estimate"].is_object() && s["recording"]["messages_lost"].as_u64() > Some(0)
    });
    assert_eq!(s["recording"]["state"], "failing", "{}", s["recording"]);
    assert!(
        s["recording"]["problem"]
            .as_str()
            .is_some_and(|p| !p.is_empty()),
        "the problem is said: {}",
        s["recording"]
    );
    // Still flying: the estimate moves on.
    let t0 = s["time_s"].as_f64().expect("time");
    let later = wait_for(&d, 30.0, |s| s["time_s"].as_f64() > Some(t0 + 2.0));
    assert!(later["estimate"].is_object());
    let _ = std::fs::remove_dir_all(&dir);
}

/// A small tmpfs mounted for a test, unmounted when it ends (declare it before the daemon
/// writing to it, so the daemon stops first). Mounting needs root, as CI runs; without it the
/// test fails and says so: it is never skipped.
struct Tmpfs {
    dir: PathBuf,
}

impl Tmpfs {
    fn mount(name: &str, size: &str) -> Self {
        let dir = temp_dir(name);
        let out = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(&dir)
            .output()
            .expect("mount runs");
        assert!(
            out.status.success(),
            "this test mounts a tmpfs to fill it up, which needs root: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        Self { dir }
    }

    /// Fills the file system with one file, `filler`, until the disk refuses.
    fn fill(&self) -> PathBuf {
        use std::io::Write;
        let path = self.dir.join("filler");
        let mut f = std::fs::File::create(&path).expect("filler");
        let block = vec![0u8; 64 * 1024];
        let err = loop {
            if let Err(e) = f.write_all(&block) {
                break e;
            }
        };
        assert_eq!(err.kind(), std::io::ErrorKind::StorageFull, "{err}");
        path
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg("-l").arg(&self.dir).status();
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

fn mcap_files(dir: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "mcap"))
                .collect()
        })
        .unwrap_or_default()
}

#[test]
fn a_full_disk_leaves_no_empty_files_says_when_it_tries_again_and_resumes_when_space_returns() {
    let fs = Tmpfs::mount("full-disk", "1m");
    let filler = fs.fill();
    let dir = fs.dir.join("recordings");
    let d = serve(&dir);
    // Tries at 5 and 15 s after the first failure: none leaves a file behind.
    let s = wait_for(&d, 60.0, |s| {
        s["estimate"].is_object() && s["recording"]["failed_tries"].as_u64() >= Some(2)
    });
    let rec = &s["recording"];
    assert_eq!(rec["state"], "failing", "{rec}");
    assert!(
        rec["problem"]
            .as_str()
            .is_some_and(|p| p.contains("No space left")),
        "{rec}"
    );
    let since = rec["failing_since_ms"].as_u64().expect("since when");
    let wall = s["wall_ms"].as_u64().expect("wall");
    assert!(since <= wall && wall - since < 60_000, "{rec}");
    let next = rec["next_try_in_s"].as_f64().expect("the next try");
    assert!(
        (0.0..=20.0).contains(&next),
        "the third try 20 s after the second: {rec}"
    );
    assert!(rec["messages_lost"].as_u64() > Some(0), "{rec}");
    assert_eq!(
        mcap_files(&dir),
        Vec::<PathBuf>::new(),
        "no file of a failed try"
    );
    // Space returns: the next try resumes, and the station says when.
    std::fs::remove_file(&filler).expect("space freed");
    let s = wait_for(&d, 60.0, |s| s["recording"]["state"] == "on");
    let rec = &s["recording"];
    assert!(
        rec["resumed_ms"].as_u64().is_some_and(|r| r > since),
        "{rec}"
    );
    assert!(rec["resumed_after_s"].as_f64() >= Some(14.0), "{rec}");
    assert!(
        rec["failing_since_ms"].is_null() && rec["next_try_in_s"].is_null(),
        "{rec}"
    );
    // The run's one file, file 1, holds the flight from the resumption on.
    let written = rec["messages_written"].as_u64().expect("written");
    wait_for(&d, 30.0, |s| {
        s["recording"]["messages_written"].as_u64() > Some(written + 100)
    });
    let file = only_file(&dir);
    assert!(
        file.to_string_lossy().ends_with("-001.mcap"),
        "{}",
        file.display()
    );
    let rec = Recording::open(&file).expect("the file reads");
    assert!(rec.message_count() > 100, "{}", rec.message_count());
    drop(d);
}

#[test]
fn replay_of_what_is_not_a_recording_or_at_a_bad_speed_is_bad_input() {
    let dir = temp_dir("bad-replay");
    let not_mcap = dir.join("notes.mcap");
    std::fs::write(&not_mcap, b"not a recording").expect("file");
    for args in [
        vec!["replay".to_string(), not_mcap.display().to_string()],
        vec!["replay".into(), "/nonexistent/flight.mcap".into()],
        vec![
            "replay".into(),
            not_mcap.display().to_string(),
            "--speed".into(),
            "100".into(),
        ],
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_stx"))
            .args(&args)
            .output()
            .expect("stx runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.starts_with("error: "), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
