//! The uploader on a fake clock: batching, back-off, answers, historical points, listeners.

use super::*;
use crate::sondehub::point::{Sample, utc_datetime};

const WALL0: u64 = 1_796_000_000_000;

fn config(extra: &str) -> SondehubConfig {
    toml::from_str(&format!(
        "uploader_callsign = \"CT1ABC\"\npayload_callsign = \"STRAPLEX1\"\nperiod_s = 10.0\n\
         retry_max_s = 60.0\n{extra}"
    ))
    .expect("parses")
}

fn uploader(extra: &str) -> Uploader {
    let c = config(extra);
    let q = Queue::new(c.queue_max_points);
    Uploader::new(c, q, Restored::default(), false, 0.0)
}

fn sample(fix_ms: u64) -> Sample {
    Sample::bare(fix_ms)
}

/// The points of a telemetry request as JSON.
fn points(r: &Request) -> Vec<serde_json::Value> {
    match r {
        Request::Telemetry { json, .. } => serde_json::from_slice(json).expect("json"),
        other => panic!("not telemetry: {other:?}"),
    }
}

fn ok() -> Answer {
    Answer::Status {
        code: 200,
        body: "^v^ telm logged".into(),
    }
}

fn status(code: u16) -> Answer {
    Answer::Status {
        code,
        body: "oops".into(),
    }
}

#[test]
fn points_go_in_batches_one_period_apart() {
    let mut u = uploader("");
    for i in 0..3 {
        u.add(sample(WALL0 + i * 1000));
    }
    let r = u.poll(0.0, WALL0 + 3000).expect("a batch");
    assert_eq!(r.path(), "/amateur/telemetry");
    assert_eq!(points(&r).len(), 3);
    // One request at a time.
    u.add(sample(WALL0 + 4000));
    assert_eq!(u.poll(0.5, WALL0 + 4500), None);
    assert_eq!(u.next_wake(), None);
    u.answered(1.0, WALL0 + 5000, ok());
    assert_eq!(u.next_wake(), Some(11.0));
    assert_eq!(u.poll(10.9, WALL0 + 14_900), None);
    let r = u.poll(11.0, WALL0 + 15_000).expect("the next period's");
    assert_eq!(points(&r)[0]["datetime"], utc_datetime(WALL0 + 4000));
    u.answered(11.2, WALL0 + 15_200, ok());
    let v = u.view();
    assert_eq!((v.made, v.sent, v.queued, v.failing), (4, 4, 0, false));
    assert_eq!(v.last_upload_wall_ms, Some(WALL0 + 15_200));
    assert_eq!(v.last_result.as_deref(), Some("200: 1 point taken"));
}

#[test]
fn failures_back_off_and_the_same_points_go_again_nothing_lost_nothing_twice() {
    let mut u = uploader("");
    u.add(sample(WALL0));
    let mut now = 0.0;
    let mut waits = Vec::new();
    let mut tries = 0;
    loop {
        let r = u.poll(now, WALL0).expect("due");
        tries += 1;
        assert_eq!(points(&r).len(), 1, "the same point, once per try");
        if tries == 8 {
            let out = u.answered(now, WALL0, ok());
            assert!(out.log.iter().any(|(_, l)| l.contains("answers again")));
            break;
        }
        let answer = if tries % 2 == 0 {
            status(503)
        } else {
            Answer::Failed("connection refused".into())
        };
        let out = u.answered(now, WALL0, answer);
        // Logged on the first failure only.
        assert_eq!(out.log.len(), usize::from(tries == 1), "{:?}", out.log);
        let v = u.view();
        assert!(v.failing && v.queued == 1, "{v:?}");
        let next = u.next_wake().expect("a retry");
        assert_eq!(u.poll(next - 0.01, WALL0), None, "not before the wait");
        waits.push(next - now);
        // A new point while failing waits with the first.
        now = next;
    }
    assert_eq!(waits, vec![5.0, 10.0, 20.0, 40.0, 60.0, 60.0, 60.0]);
    let v = u.view();
    assert_eq!(
        (v.sent, v.queued, v.failing, v.retry_wall_ms),
        (1, 0, false, None)
    );
    assert!(v.errors.len() == 7 && v.errors[0].text.contains("connection refused"));
}

#[test]
fn a_202_keeps_what_it_took_and_says_what_it_refused() {
    let mut u = uploader("");
    for i in 0..3 {
        u.add(sample(WALL0 + i));
    }
    u.poll(0.0, WALL0).expect("a batch");
    let body = serde_json::json!({
        "message": "some or all payloads could not be processed or have warnings",
        "errors": [{"error_message": "Missing lat field", "payload": {"datetime": "D1"}}],
        "warnings": [{"warning_message": "too far in the future", "payload": {}}],
    });
    let out = u.answered(
        1.0,
        WALL0 + 1000,
        Answer::Status {
            code: 202,
            body: body.to_string(),
        },
    );
    assert!(
        out.log
            .iter()
            .any(|(l, t)| *l == Level::Warn && t.contains("Missing lat field (point of D1)")),
        "{:?}",
        out.log
    );
    let v = u.view();
    assert_eq!((v.sent, v.refused, v.queued), (2, 1, 0));
    assert_eq!(v.errors[0].text, "Missing lat field (point of D1)");
    assert_eq!(v.warnings[0].text, "too far in the future");
    assert_eq!(
        v.last_result.as_deref(),
        Some("202: 2 of 3 points taken, 1 refused, 1 warning")
    );
    // Refused points are not sent again.
    assert_eq!(u.poll(20.0, WALL0 + 20_000), None);
}

#[test]
fn a_400_drops_the_batch_and_the_next_goes_on() {
    let mut u = uploader("");
    u.add(sample(WALL0));
    u.poll(0.0, WALL0).expect("a batch");
    let out = u.answered(0.1, WALL0, status(400));
    assert_eq!(out.persist.mark, Some(1));
    let v = u.view();
    assert_eq!((v.refused, v.queued, v.failing), (1, 0, false));
    assert!(v.errors[0].text.starts_with("HTTP 400"));
    u.add(sample(WALL0 + 1));
    assert!(u.poll(10.1, WALL0 + 10_100).is_some());
}

#[test]
fn points_older_than_the_window_go_as_historical() {
    let mut u = uploader("historical_after_s = 60.0");
    u.add(sample(WALL0));
    u.add(sample(WALL0 + 30_000));
    let r = u.poll(0.0, WALL0 + 75_000).expect("a batch");
    let p = points(&r);
    assert_eq!(p[0]["historical"], true);
    assert!(p[1].get("historical").is_none(), "{}", p[1]);
    u.answered(0.1, WALL0 + 75_000, ok());
    assert_eq!(u.view().historical, 1);
}

#[test]
fn a_backlog_drains_in_full_batches_without_waiting_for_the_period() {
    let mut u = uploader("");
    for i in 0..(2 * BATCH_MAX as u64 + 5) {
        u.add(sample(WALL0 + i * 100));
    }
    let mut sizes = Vec::new();
    let mut now = 0.0;
    while let Some(r) = u.poll(now, WALL0) {
        sizes.push(points(&r).len());
        u.answered(now, WALL0, ok());
        now += 0.1;
    }
    assert_eq!(sizes, vec![BATCH_MAX, BATCH_MAX, 5]);
}

#[test]
fn the_station_goes_first_and_every_6_h_and_a_chase_car_at_most_every_10_s() {
    let mut u = uploader("station_position = { lat_deg = 38.5, lon_deg = -7.9, alt_m = 245.0 }");
    let r = u.poll(0.0, WALL0).expect("the station");
    let Request::Listener { json, mobile } = &r else {
        panic!("{r:?}")
    };
    let body: serde_json::Value = serde_json::from_slice(json).expect("json");
    assert!(!mobile);
    assert_eq!(
        body["uploader_position"],
        serde_json::json!([38.5, -7.9, 245.0])
    );
    assert_eq!(body["uploader_callsign"], "CT1ABC");
    u.answered(0.1, WALL0 + 100, ok());
    assert_eq!(u.view().station_uploaded_wall_ms, Some(WALL0 + 100));
    assert_eq!(u.next_wake(), Some(0.1 + STATION_EVERY_S));

    u.chase_car([38.6, -7.8, 200.0]);
    let Some(Request::Listener { json, mobile: true }) = u.poll(1.0, WALL0 + 1000) else {
        panic!("the chase car")
    };
    let body: serde_json::Value = serde_json::from_slice(&json).expect("json");
    assert_eq!(body["uploader_callsign"], "CT1ABC_CHASE");
    u.answered(1.1, WALL0 + 1100, ok());
    u.chase_car([38.61, -7.8, 200.0]);
    assert_eq!(u.poll(5.0, WALL0 + 5000), None, "too soon");
    assert_eq!(u.next_wake(), Some(11.0));
    assert!(matches!(
        u.poll(11.0, WALL0 + 11_000),
        Some(Request::Listener { mobile: true, .. })
    ));
    u.answered(11.1, WALL0 + 11_100, ok());
    let car = u.view().chase_car.expect("a chase car");
    assert_eq!(
        (car.position, car.uploaded_wall_ms),
        ([38.61, -7.8, 200.0], Some(WALL0 + 11_100))
    );
    assert!(
        u.poll(STATION_EVERY_S + 1.0, WALL0).is_some(),
        "the station again"
    );
}

#[test]
fn a_restored_queue_is_sent_first_and_counted() {
    let c = config("");
    let mut q = Queue::new(100);
    let mut file = Vec::new();
    for i in 0..4 {
        file.extend(q.push(sample(WALL0 + i)).append);
    }
    let (q, restored) = Queue::restore(100, file.iter().map(String::as_str), 0);
    let mut u = Uploader::new(c, q, restored, true, 0.0);
    let v = u.view();
    assert_eq!((v.restored, v.queued, v.on_disk), (4, 4, true));
    let r = u.poll(0.0, WALL0 + 100).expect("at once");
    assert_eq!(points(&r).len(), 4);
}
