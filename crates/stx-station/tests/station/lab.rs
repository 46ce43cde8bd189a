//! The Lab's comparison through a real daemon (`POST /api/lab/jobs`, kind `compare`): the
//! recording is checked before the job starts — a viewer is refused, a name outside the
//! recordings directory or not in it is `unknown_recording`, a file that is no recording is
//! `unreadable`, a recording without flight telemetry is `no_flight`, a window that is none
//! (`from_s` ≥ `to_s`, a negative time) or that the work finds past the flight is
//! `invalid_job` — and a good one reaches the Lab's
//! work as the file of the directory, whose result every page then reads.
//!
//! The work here is a stand-in that reads the file it is handed (the flying is stx-lab's,
//! tested in `crates/stx-lab/src/compare.rs` and by `tests/browser/lab.mjs`).

use crate::common;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use common::*;
use serde_json::{Value, json};
use stx_record::{CoreOptions, RecorderCore, RecordingInfo, foxglove};
use stx_station::lab::{
    CompareSeries, IdentifiedParam, IdentifySummary, JobControl, JobInputs, LabJobBody, LabResult,
    LabService, LabWorker,
};

/// Answers a comparison with the recording it was handed: its name and its positions.
struct ReadsTheRecording;

impl LabWorker for ReadsTheRecording {
    fn run(
        &self,
        job: &LabJobBody,
        inputs: &JobInputs,
        _control: &dyn JobControl,
    ) -> Result<LabResult, String> {
        let recording = match job {
            LabJobBody::Compare { recording, .. } => recording,
            LabJobBody::Identify {
                recording, params, ..
            } => {
                return Ok(LabResult::Identify(IdentifySummary {
                    recording: format!(
                        "{recording} at {}",
                        inputs
                            .recording
                            .as_deref()
                            .unwrap_or(Path::new("?"))
                            .display()
                    ),
                    params: params
                        .iter()
                        .map(|p| IdentifiedParam {
                            name: p.clone(),
                            ..IdentifiedParam::default()
                        })
                        .collect(),
                    ..IdentifySummary::default()
                }));
            }
            _ => return Err("only comparisons and identifications here".into()),
        };
        let path = inputs
            .recording
            .as_deref()
            .ok_or("no recording handed over")?;
        let opened = stx_record::Recording::open(path).map_err(|e| e.to_string())?;
        let positions = opened
            .channel("/telemetry/GLOBAL_POSITION_INT")
            .map_or(0, |c| c.message_count);
        Ok(LabResult::Compare(CompareSeries {
            recording: format!("{recording} at {}", path.display()),
            samples: positions as u32,
            ..CompareSeries::default()
        }))
    }

    /// Refuses a window starting after the recording's last position (4 a second from 0 s):
    /// the station's side of the question is what is tested here.
    fn check_window(&self, job: &LabJobBody, inputs: &JobInputs) -> Result<(), (String, String)> {
        let (LabJobBody::Compare { from_s, .. } | LabJobBody::Identify { from_s, .. }) = job else {
            return Ok(());
        };
        let refused = |e: String| ("recording".to_string(), e);
        let path = inputs
            .recording
            .as_deref()
            .ok_or_else(|| refused("none".into()))?;
        let opened = stx_record::Recording::open(path).map_err(|e| refused(e.to_string()))?;
        let positions = opened
            .channel("/telemetry/GLOBAL_POSITION_INT")
            .map_or(0, |c| c.message_count);
        let last_s = positions.saturating_sub(1) as f64 / 4.0;
        match from_s {
            Some(from) if *from > last_s => Err((
                "from_s, to_s".into(),
                format!("the flight ends at {last_s} s"),
            )),
            _ => Ok(()),
        }
    }
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("stx-lab-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// A closed recording with `counts` messages on each telemetry topic, 4 a second.
fn write_recording(path: &Path, counts: &[(&str, u64)]) {
    let info = RecordingInfo::new("test", "straplex-2", "lab test");
    let mut core = RecorderCore::new(CoreOptions::default(), info, Duration::ZERO).unwrap();
    let t0 = 1_767_225_600_000_000_000u64;
    for (name, n) in counts {
        let spec = foxglove::log_channel(format!("/telemetry/{name}")).unwrap();
        let ch = core.add_channel(Duration::ZERO, spec).unwrap();
        for i in 0..*n {
            let t = t0 + i * 250_000_000;
            core.write(Duration::from_millis(250 * i), ch, t, t, b"{}")
                .unwrap();
        }
    }
    std::fs::write(path, finished_recording(core)).unwrap();
}

const FLIGHT: [(&str, u64); 3] = [
    ("GLOBAL_POSITION_INT", 40),
    ("ATTITUDE", 40),
    ("SERVO_OUTPUT_RAW", 10),
];

async fn station_with_lab(dir: Option<PathBuf>) -> Station {
    let station = start_station(config(move |c| c.recording.dir = dir)).await;
    let lab = LabService::new(
        Arc::new(ReadsTheRecording),
        std::env::temp_dir().join("stx-lab-test-files"),
        60.0,
    );
    assert!(station.running.shared.lab.set(Arc::new(lab)).is_ok());
    station
}

async fn start(station: &Station, token: &'static str, body: Value) -> (u16, Value) {
    let body = body.to_string();
    http(
        station.http(),
        "POST",
        "/api/lab/jobs",
        Some(token),
        Some(&body),
    )
    .await
}

/// The Lab's last outcome once the job has finished (`null` after 5 s).
async fn last_outcome(station: &Station) -> Value {
    let mut last = Value::Null;
    for _ in 0..100 {
        let (_, lab) = http(station.http(), "GET", "/api/lab", Some(VIEWER), None).await;
        last = lab["last"].clone();
        if !last.is_null() {
            break;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    last
}

#[tokio::test]
async fn bad_recordings_are_refused_with_their_kind_before_a_job_starts() {
    let dir = temp_dir("bad");
    write_recording(&dir.join("flight.mcap"), &FLIGHT);
    write_recording(
        &dir.join("idle.mcap"),
        &[("HEARTBEAT", 20), ("GLOBAL_POSITION_INT", 2)],
    );
    std::fs::write(dir.join("broken.mcap"), b"not an MCAP file").unwrap();
    std::fs::write(dir.parent().unwrap().join("outside.mcap"), b"x").unwrap();
    let station = station_with_lab(Some(dir.clone())).await;
    let compare = |name: &str| json!({"kind": "compare", "recording": name});

    let (status, body) = start(&station, VIEWER, compare("flight.mcap")).await;
    assert_eq!((status, body["error"].as_str()), (403, Some("forbidden")));
    for name in [
        "missing.mcap",
        "../outside.mcap",
        "..%2Foutside.mcap",
        "/etc/passwd",
        "flight",
    ] {
        let (status, body) = start(&station, OPERATOR, compare(name)).await;
        assert_eq!(
            (status, body["error"].as_str()),
            (404, Some("unknown_recording")),
            "{name}: {body}"
        );
    }
    let (status, body) = start(&station, OPERATOR, compare("broken.mcap")).await;
    assert_eq!(
        (status, body["error"].as_str()),
        (422, Some("unreadable")),
        "{body}"
    );
    let (status, body) = start(&station, OPERATOR, compare("idle.mcap")).await;
    assert_eq!((status, body["error"].as_str()), (422, Some("no_flight")));
    let reason = body["reason"].as_str().unwrap_or_default();
    assert!(
        reason.contains("GLOBAL_POSITION_INT (2 of at least 3") && reason.contains("ATTITUDE"),
        "{reason}"
    );
    let (status, body) = start(&station, OPERATOR, compare(" ")).await;
    assert_eq!((status, body["error"].as_str()), (400, Some("invalid_job")));
    let edited =
        json!({"kind": "compare", "recording": "flight.mcap", "vehicle": {"canopy.mass_kg": -1.0}});
    let (status, body) = start(&station, OPERATOR, edited).await;
    assert_eq!(
        (status, body["error"].as_str()),
        (400, Some("invalid_vehicle"))
    );
    // Nothing ran.
    let (_, lab) = http(station.http(), "GET", "/api/lab", Some(VIEWER), None).await;
    assert_eq!((&lab["job"], &lab["last"]), (&Value::Null, &Value::Null));

    let without = station_with_lab(None).await;
    let (status, body) = start(&without, OPERATOR, compare("flight.mcap")).await;
    assert_eq!(
        (status, body["error"].as_str()),
        (404, Some("unknown_recording"))
    );
}

#[tokio::test]
async fn a_recording_of_the_directory_is_compared_and_every_page_sees_the_result() {
    let dir = temp_dir("good");
    write_recording(&dir.join("flight-1.mcap"), &FLIGHT);
    let station = station_with_lab(Some(dir.clone())).await;
    let (status, body) = start(
        &station,
        OPERATOR,
        json!({"kind": "compare", "recording": "flight-1.mcap"}),
    )
    .await;
    assert_eq!(status, 202, "{body}");
    assert_eq!(body["kind"], "compare");
    let last = last_outcome(&station).await;
    assert_eq!(last["outcome"], "done", "{last}");
    assert_eq!(last["kind"], "compare");
    let result = &last["result"];
    assert_eq!(result["kind"], "compare");
    let expected = format!("flight-1.mcap at {}", dir.join("flight-1.mcap").display());
    assert_eq!(result["recording"], json!(expected));
    assert_eq!(result["samples"], 40);
}

#[tokio::test]
async fn an_identification_is_checked_as_a_comparison_and_its_parameters_before_it_starts() {
    let dir = temp_dir("identify");
    write_recording(&dir.join("flight.mcap"), &FLIGHT);
    let station = station_with_lab(Some(dir.clone())).await;
    let identify = |name: &str, params: Value| json!({"kind": "identify", "recording": name, "params": params});
    let (status, body) = start(
        &station,
        VIEWER,
        identify("flight.mcap", json!(["cl_alpha"])),
    )
    .await;
    assert_eq!((status, body["error"].as_str()), (403, Some("forbidden")));
    for params in [
        json!([]),
        json!(["cl_alpha", "wingspan"]),
        json!(["cd0", "CD0"]),
    ] {
        let (status, body) =
            start(&station, OPERATOR, identify("flight.mcap", params.clone())).await;
        assert_eq!(
            (status, body["error"].as_str()),
            (400, Some("invalid_job")),
            "{params}: {body}"
        );
        let reason = body["reason"].as_str().unwrap_or_default();
        assert!(reason.starts_with("params: "), "{reason}");
    }
    let (_, body) = start(
        &station,
        OPERATOR,
        identify("flight.mcap", json!(["wingspan"])),
    )
    .await;
    let reason = body["reason"].as_str().unwrap_or_default();
    assert!(
        reason.contains("\"wingspan\"") && reason.contains("cl_alpha"),
        "{reason}"
    );
    for name in ["missing.mcap", "../outside.mcap", "flight"] {
        let (status, body) = start(&station, OPERATOR, identify(name, json!(["cl_alpha"]))).await;
        assert_eq!(
            (status, body["error"].as_str()),
            (404, Some("unknown_recording")),
            "{name}: {body}"
        );
    }
    let (_, lab) = http(station.http(), "GET", "/api/lab", Some(VIEWER), None).await;
    assert_eq!((&lab["job"], &lab["last"]), (&Value::Null, &Value::Null));

    let (status, body) = start(
        &station,
        OPERATOR,
        identify("flight.mcap", json!(["cl_alpha", "cd0"])),
    )
    .await;
    assert_eq!(
        (status, body["kind"].as_str()),
        (202, Some("identify")),
        "{body}"
    );
    let last = last_outcome(&station).await;
    assert_eq!(
        (&last["outcome"], &last["kind"]),
        (&json!("done"), &json!("identify")),
        "{last}"
    );
    let result = &last["result"];
    assert_eq!(result["kind"], "identify");
    let expected = format!("flight.mcap at {}", dir.join("flight.mcap").display());
    assert_eq!(result["recording"], json!(expected));
    assert_eq!(result["params"][1]["name"], "cd0");
}

#[tokio::test]
async fn a_window_that_is_none_or_past_the_flight_is_refused_before_a_job_starts() {
    let dir = temp_dir("window");
    write_recording(&dir.join("flight.mcap"), &FLIGHT);
    let station = station_with_lab(Some(dir)).await;
    let compare = json!({"kind": "compare", "recording": "flight.mcap"});
    let identify = json!({"kind": "identify", "recording": "flight.mcap", "params": ["cd0"]});
    for job in [&compare, &identify] {
        for (from_s, to_s, field) in [
            (json!(40.0), json!(40.0), "to_s: "),
            (json!(40.0), json!(10.0), "to_s: "),
            (json!(-1.0), Value::Null, "from_s: "),
        ] {
            let mut body = job.clone();
            body["from_s"] = from_s.clone();
            body["to_s"] = to_s.clone();
            let (status, answer) = start(&station, OPERATOR, body).await;
            assert_eq!(
                (status, answer["error"].as_str()),
                (400, Some("invalid_job")),
                "{job} {from_s} {to_s}: {answer}"
            );
            let reason = answer["reason"].as_str().unwrap_or_default();
            assert!(reason.starts_with(field), "{reason}");
        }
    }
    let (_, lab) = http(station.http(), "GET", "/api/lab", Some(VIEWER), None).await;
    assert_eq!((&lab["job"], &lab["last"]), (&Value::Null, &Value::Null));
    // One the flight does not reach is refused too, the work having read the recording.
    let mut body = identify.clone();
    body["from_s"] = json!(12.0);
    let (status, answer) = start(&station, OPERATOR, body).await;
    assert_eq!(
        (status, answer["error"].as_str(), answer["reason"].as_str()),
        (
            400,
            Some("invalid_job"),
            Some("from_s, to_s: the flight ends at 9.75 s")
        )
    );
    let (_, lab) = http(station.http(), "GET", "/api/lab", Some(VIEWER), None).await;
    assert_eq!((&lab["job"], &lab["last"]), (&Value::Null, &Value::Null));
    // A window with its end after its start, or one end only, starts the job.
    let mut body = compare.clone();
    body["from_s"] = json!(2.5);
    body["to_s"] = json!(8.0);
    let (status, answer) = start(&station, OPERATOR, body).await;
    assert_eq!(status, 202, "{answer}");
    assert_eq!(last_outcome(&station).await["outcome"], "done");
}
