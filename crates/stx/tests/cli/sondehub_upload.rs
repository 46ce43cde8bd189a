//! The SondeHub-Amateur upload (`[sondehub]`) of a running `stx serve --sim`, against the test
//! server written from SondeHub's API (`tests/peers/sondehub_server.py`: it checks what the
//! real one checks) with its faults, and held against pysondehub 0.3.2 (PyPI), SondeHub's own
//! Python uploader, sending the same point (`tests/peers/sondehub_pysondehub.py`).
//!
//! Scaled for a test's time: the outage is 45 s instead of a minute, the server's 24-hour
//! window 30 s and the station's `historical_after_s` 20 s, its back-off capped at 2 s.

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

use crate::common::mavproxy::{python, run_peer};
use crate::common::station::Station;
use crate::common::{Killed, request_json, temp_dir};

const PAYLOAD: &str = "STRAPLEX-T1";
const PERIOD_S: f64 = 2.0;

/// The test server, killed when dropped.
struct Server {
    api: u16,
    control: String,
    _process: Killed,
}

impl Server {
    fn start(window_s: f64) -> Self {
        let script = root().join("tests/peers/sondehub_server.py");
        let mut child = Command::new(python())
            .arg(&script)
            .args(["--window-s", &window_s.to_string()])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .expect("the test server starts");
        let mut line = String::new();
        BufReader::new(child.stdout.take().expect("stdout"))
            .read_line(&mut line)
            .expect("its ports");
        let ports: Value = serde_json::from_str(&line).expect("ports as JSON");
        Self {
            api: ports["api"].as_u64().expect("api port") as u16,
            control: format!("127.0.0.1:{}", ports["control"]),
            _process: Killed(child),
        }
    }

    fn fault(&self, fault: &str) {
        request_json(&self.control, "-", "POST", "/fault", fault).expect("fault set");
    }

    fn received(&self) -> Value {
        request_json(&self.control, "-", "GET", "/", "").expect("what it received")
    }

    /// The telemetry points kept from stx, in the order of their fixes.
    fn stx_points(&self) -> Vec<Value> {
        let mut p: Vec<Value> = self.received()["points"]
            .as_array()
            .cloned()
            .unwrap_or_default()
            .into_iter()
            .filter(|p| p["software_name"] == "stx" && p["payload_callsign"] == PAYLOAD)
            .collect();
        p.sort_by(|a, b| a["datetime"].as_str().cmp(&b["datetime"].as_str()));
        p
    }

    /// Telemetry requests answered with `status`.
    fn answered(&self, status: u64) -> usize {
        self.received()["requests"].as_array().map_or(0, |r| {
            r.iter()
                .filter(|q| q["path"] == "/amateur/telemetry" && q["status"] == status)
                .count()
        })
    }
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn config(server: &Server, queue: &Path) -> String {
    format!(
        "[sondehub]\nurl = \"http://127.0.0.1:{}\"\nuploader_callsign = \"STXTEST\"\n\
         payload_callsign = \"{PAYLOAD}\"\nperiod_s = {PERIOD_S}\n\
         station_position = {{ lat_deg = 38.53, lon_deg = -7.89, alt_m = 245.0 }}\n\
         queue_dir = {:?}\nhistorical_after_s = 20.0\nretry_max_s = 2.0\ntimeout_s = 5.0\n",
        server.api,
        queue.display().to_string()
    )
}

/// Polls `f` every 250 ms until it gives `Some` or `secs` pass.
fn until<T>(secs: u64, what: &str, mut f: impl FnMut() -> Option<T>) -> T {
    let end = Instant::now() + Duration::from_secs(secs);
    loop {
        if let Some(v) = f() {
            return v;
        }
        assert!(Instant::now() < end, "waited {secs} s for {what}");
        std::thread::sleep(Duration::from_millis(250));
    }
}

fn sondehub(station: &Station) -> Value {
    station
        .get("/api/sharing")
        .map(|s| s["sondehub"].clone())
        .unwrap_or(Value::Null)
}

/// Unix seconds of a SondeHub time (`YYYY-MM-DDTHH:MM:SS.ffffffZ`), within the day.
fn seconds_of(datetime: &Value) -> f64 {
    let t = datetime.as_str().expect("a time");
    let hms = &t[11..t.len() - 1];
    let mut parts = hms.split(':').map(|p| p.parse::<f64>().expect("a number"));
    let (h, m, s) = (
        parts.next().unwrap_or(0.0),
        parts.next().unwrap_or(0.0),
        parts.next().unwrap_or(0.0),
    );
    h * 3600.0 + m * 60.0 + s
}

#[test]
fn sondehub_gets_every_point_through_an_outage_a_restart_and_the_servers_faults() {
    let server = Server::start(30.0);
    let dir = temp_dir("sondehub", "upload");
    let extra = config(&server, &dir.join("queue"));
    let station = Station::start_logged(&dir, &extra, &dir.join("first.log"));
    until(60, "the first points", || {
        (server.stx_points().len() >= 3).then_some(())
    });

    // Down for 45 s; the station is killed 20 s into it and started again on the same queue.
    server.fault(r#"{"down_s": 45}"#);
    std::thread::sleep(Duration::from_secs(20));
    let before = sondehub(&station);
    assert!(
        before["failing"] == true && before["queued"].as_u64() >= Some(5),
        "{before}"
    );
    drop(station);
    let station = Station::start_logged(&dir, &extra, &dir.join("second.log"));
    let after = sondehub(&station);
    assert!(
        after["restored"].as_u64() >= before["queued"].as_u64(),
        "restored {after} / before the kill {before}"
    );
    until(90, "the queue drained once the server was back", || {
        let s = sondehub(&station);
        (s["queued"] == 0 && s["failing"] == false && s["sent"].as_u64() > Some(0)).then_some(())
    });

    // 500s, slow answers, a 202 with an error.
    server.fault(r#"{"status": 500, "count": 3}"#);
    until(60, "three 500s", || {
        (server.answered(500) >= 3).then_some(())
    });
    server.fault(r#"{"slow_s": 3, "count": 2}"#);
    std::thread::sleep(Duration::from_secs(8));
    server.fault(r#"{"reject_first": true, "count": 1}"#);
    let shown = until(30, "the 202's error on the page", || {
        let s = sondehub(&station);
        s["errors"]
            .as_array()?
            .iter()
            .any(|e| {
                e["text"]
                    .as_str()
                    .is_some_and(|t| t.contains("test fault: refused"))
            })
            .then_some(s)
    });
    assert_eq!(shown["refused"], 1, "{shown}");
    // The recovery phone as a chase car.
    let answer = request_json(
        &station.http,
        &station.token,
        "POST",
        "/api/sondehub/chase",
        r#"{"lat_deg": 38.54, "lon_deg": -7.88, "alt_m": 250.0}"#,
    )
    .expect("an answer");
    assert_eq!(answer["uploader_callsign"], "STXTEST", "{answer}");
    until(30, "the chase car and an empty queue", || {
        let r = server.received();
        let car = r["listeners"]
            .as_array()?
            .iter()
            .any(|l| l["mobile"] == true && l["uploader_callsign"] == "STXTEST_CHASE");
        (car && sondehub(&station)["queued"] == 0).then_some(())
    });

    // Every point arrived once, none hidden; those older than the window as historical.
    let points = server.stx_points();
    let mut seen = BTreeMap::new();
    for p in &points {
        *seen
            .entry(p["datetime"].as_str().unwrap_or("").to_string())
            .or_insert(0) += 1;
        assert_eq!(p["telemetry_hidden"], false, "hidden: {p}");
    }
    let twice: Vec<_> = seen.iter().filter(|(_, n)| **n > 1).collect();
    assert!(twice.is_empty(), "sent twice: {twice:?}");
    assert!(
        points.iter().filter(|p| p["historical"] == true).count() >= 3,
        "points queued through the outage went as historical"
    );
    // Fixes every period, through the outage: the gaps are the restart (a new simulated
    // drone and its first fix) and the point the 202 refused.
    let gaps: Vec<f64> = points
        .windows(2)
        .map(|w| seconds_of(&w[1]["datetime"]) - seconds_of(&w[0]["datetime"]))
        .filter(|g| *g > 2.0 * PERIOD_S + 1.0)
        .collect();
    assert!(
        gaps.len() <= 2 && gaps.iter().all(|g| *g < 20.0),
        "gaps in the track: {gaps:?} s over {} points",
        points.len()
    );
    let last = sondehub(&station);
    assert!(
        points.len() as u64 >= last["sent"].as_u64().unwrap_or(0) && last["dropped"] == 0,
        "{last}"
    );
    let received = server.received();
    let requests = received["requests"].as_array().expect("requests");
    for r in requests
        .iter()
        .filter(|r| r["path"] == "/amateur/telemetry")
    {
        let h = &r["headers"];
        assert!(
            h["content-encoding"] == "gzip"
                && h["content-type"] == "application/json"
                && h["user-agent"]
                    .as_str()
                    .is_some_and(|u| u.starts_with("stx-"))
                && h["date"].as_str().is_some_and(|d| d.ends_with(" GMT")),
            "{r}"
        );
    }
    let station_listener = received["listeners"]
        .as_array()
        .and_then(|l| l.iter().find(|l| l["mobile"] == false).cloned())
        .expect("the station's position");
    assert_eq!(
        station_listener["uploader_position"],
        serde_json::json!([38.53, -7.89, 245.0])
    );
    let log = std::fs::read_to_string(dir.join("second.log")).expect("the log");
    assert!(
        log.contains("test fault: refused") && log.contains("SondeHub"),
        "the 202's error in the log:\n{log}"
    );
    drop(station);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Each field's JSON type as the test server saw it (`float`, `int`, `str`, …).
fn typed(request: &Value) -> BTreeMap<String, String> {
    request["points"][0]
        .as_object()
        .map(|o| {
            o.iter()
                .map(|(k, v)| (k.clone(), v.as_str().unwrap_or("").to_string()))
                .collect()
        })
        .unwrap_or_default()
}

#[test]
fn stx_sends_a_point_as_pysondehub_does() {
    let server = Server::start(86_400.0);
    let dir = temp_dir("sondehub", "pysondehub");
    let station = Station::start(&dir, &config(&server, &dir.join("queue")));
    let point = until(60, "a point from stx", || {
        server.stx_points().first().cloned()
    });
    let mut kept = point.clone();
    if let Some(o) = kept.as_object_mut() {
        o.remove("telemetry_hidden");
        o.remove("upload_time");
    }
    let base = format!("http://127.0.0.1:{}", server.api);
    run_peer("sondehub_pysondehub.py", &[&base, &kept.to_string()]);
    drop(station);

    let received = server.received();
    let requests = received["requests"].as_array().expect("requests");
    let by = |agent: &str, path: &str| {
        requests
            .iter()
            .find(|r| {
                r["path"] == path
                    && r["headers"]["user-agent"]
                        .as_str()
                        .is_some_and(|u| u.starts_with(agent))
            })
            .cloned()
            .unwrap_or_else(|| panic!("no {path} from {agent}: {received}"))
    };
    let (ours, theirs) = (
        by("stx-", "/amateur/telemetry"),
        by("pysondehub-", "/amateur/telemetry"),
    );
    assert_eq!(typed(&ours), typed(&theirs), "field names and JSON types");
    for header in ["content-encoding", "content-type"] {
        assert_eq!(
            ours["headers"][header], theirs["headers"][header],
            "{header}"
        );
    }
    assert!(ours["headers"]["date"].is_string() && theirs["headers"]["date"].is_string());
    let their_point = received["points"]
        .as_array()
        .and_then(|p| {
            p.iter()
                .find(|p| p["software_name"] == "pysondehub-peer")
                .cloned()
        })
        .expect("pysondehub's point kept");
    for key in [
        "datetime",
        "time_received",
        "lat",
        "lon",
        "alt",
        "sats",
        "uploader_position",
    ] {
        assert_eq!(point[key], their_point[key], "{key}");
    }
    // The listener: what stx sends of the station is what pysondehub sends, less its empty
    // contact address and its `dev` flag.
    let (ours, theirs) = (
        typed(&by("stx-", "/amateur/listeners")),
        typed(&by("pysondehub-", "/amateur/listeners")),
    );
    for (k, t) in &ours {
        assert_eq!(
            theirs.get(k),
            Some(t),
            "listener field {k}: {ours:?} / {theirs:?}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
