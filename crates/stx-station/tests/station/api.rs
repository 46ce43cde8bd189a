//! The station's API end to end on loopback: a real daemon, a scripted drone on the other end
//! of the real MAVLink link, HTTP and WebSocket clients.

use crate::common;

use std::time::Duration;

use common::*;
use serde_json::{Value, json};
use stx_gnc::mission::FlightMode;
use stx_link::command::Command;

/// Polls a request until its outcome is final (not `in_progress`), for up to 10 s.
async fn final_outcome(addr: std::net::SocketAddr, id: &str) -> Value {
    for _ in 0..200 {
        let (_, r) = http(
            addr,
            "GET",
            &format!("/api/commands/{id}"),
            Some(VIEWER),
            None,
        )
        .await;
        if r["outcome"].is_string() && r["outcome"] != "in_progress" {
            return r;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    panic!("request {id} has no final outcome");
}

fn reason(v: &Value) -> String {
    v["reason"].as_str().unwrap_or_default().to_string()
}

#[tokio::test]
async fn every_request_needs_a_known_token() {
    let station = start_station(config(|_| {})).await;
    let (status, body) = http(station.http(), "GET", "/api/state", None, None).await;
    assert_eq!(status, 401);
    assert_eq!(body["error"], "unauthorized");
    assert!(reason(&body).contains("token"), "{body}");
    let (status, body) = http(
        station.http(),
        "GET",
        "/api/state",
        Some("not-a-token"),
        None,
    )
    .await;
    assert_eq!(status, 401, "{body}");
    let (status, _) = http(
        station.http(),
        "GET",
        "/api/state?token=viewer-token",
        None,
        None,
    )
    .await;
    assert_eq!(status, 200, "a token in the query is accepted");
    let (status, body) = http(station.http(), "GET", "/api/session", Some(VIEWER), None).await;
    assert_eq!(status, 200);
    assert_eq!(body["role"], "viewer");
    assert_eq!(body["station"]["modes"].as_array().map(Vec::len), Some(6));
}

#[tokio::test]
async fn a_viewer_is_refused_every_command_and_told_why() {
    let station = start_station(config(|_| {})).await;
    let drone = fake_drone(station.running.link_local.expect("link address")).await;
    let commands = [
        ("/api/commands/mode", r#"{"mode":"heading"}"#),
        ("/api/commands/heading", r#"{"heading_deg":90}"#),
        ("/api/commands/course", r#"{"course_deg":90}"#),
        (
            "/api/commands/target",
            r#"{"lat_deg":38.53,"lon_deg":-7.88,"alt_msl_m":245}"#,
        ),
        (
            "/api/commands/localizer",
            r#"{"lat_deg":38.53,"lon_deg":-7.88,"course_deg":90}"#,
        ),
        ("/api/commands/plan", r#"{"items":[]}"#),
        ("/api/params/HK1", r#"{"value":0.02}"#),
        ("/api/cutdown/arm", "{}"),
        ("/api/cutdown/confirm", r#"{"arm_id":"x"}"#),
    ];
    for (path, body) in commands {
        let (status, reply) = http(station.http(), "POST", path, Some(VIEWER), Some(body)).await;
        assert_eq!(status, 403, "{path}: {reply}");
        assert_eq!(reply["error"], "forbidden");
        assert!(reason(&reply).contains("operator"), "{path}: {reply}");
    }
    // Nothing reached the drone.
    tokio::time::sleep(Duration::from_millis(300)).await;
    assert!(drone.seen(|s| s.commands.is_empty() && s.param_changes.is_empty()));
}

#[tokio::test]
async fn malformed_requests_get_400_naming_the_problem() {
    let station = start_station(config(|_| {})).await;
    let cases = [
        ("/api/commands/mode", r#"{"mode":"loop_the_loop"}"#, "mode"),
        ("/api/commands/heading", r#"{"heading":90}"#, "heading_deg"),
        (
            "/api/commands/heading",
            r#"{"heading_deg":"east"}"#,
            "heading_deg",
        ),
        (
            "/api/commands/target",
            r#"{"lat_deg":138,"lon_deg":0,"alt_msl_m":0}"#,
            "lat_deg",
        ),
        ("/api/commands/mode", "not json", ""),
    ];
    for (path, body, field) in cases {
        let (status, reply) = http(station.http(), "POST", path, Some(OPERATOR), Some(body)).await;
        assert_eq!(status, 400, "{path} {body}: {reply}");
        assert_eq!(reply["error"], "bad_request");
        assert!(reason(&reply).contains(field), "{path} {body}: {reply}");
    }
}

#[tokio::test]
async fn a_mode_command_reaches_the_drone_and_its_result_comes_back() {
    let station = start_station(config(|_| {})).await;
    let drone = fake_drone(station.running.link_local.expect("link address")).await;
    let mut ws = ws_connect(station.http(), OPERATOR).await;
    let (status, reply) = http(
        station.http(),
        "POST",
        "/api/commands/mode",
        Some(OPERATOR),
        Some(r#"{"mode":"spiral_landing"}"#),
    )
    .await;
    assert_eq!(status, 202, "{reply}");
    assert_eq!(reply["status"], "sent");
    let id = reply["request_id"]
        .as_str()
        .expect("request id")
        .to_string();
    let result = command_result(&mut ws, &id).await;
    assert_eq!(result["outcome"], "accepted", "{result}");
    assert!(drone.seen(|s| {
        s.commands
            .contains(&Command::SetMode(FlightMode::SpiralLanding))
    }));
    let (status, polled) = http(
        station.http(),
        "GET",
        &format!("/api/commands/{id}"),
        Some(VIEWER),
        None,
    )
    .await;
    assert_eq!(status, 200);
    assert_eq!(polled["outcome"], "accepted");
    // The drone now reports the mode in its heartbeat, and the state shows it.
    let state = ws_until(&mut ws, 5.0, |m| {
        m["type"] == "state" && m["vehicle"]["mode"] == "spiral_landing"
    })
    .await;
    assert!(state.is_some(), "the state shows the drone's new mode");
    // The event log names who asked.
    let texts = event_texts(station.http()).await;
    assert!(
        texts
            .iter()
            .any(|t| t.starts_with("operator:") && t.contains("spiral")),
        "{texts:?}"
    );
}

#[tokio::test]
async fn an_unknown_request_id_is_404() {
    let station = start_station(config(|_| {})).await;
    let (status, reply) = http(
        station.http(),
        "GET",
        "/api/commands/no-such-id",
        Some(VIEWER),
        None,
    )
    .await;
    assert_eq!(status, 404, "{reply}");
    assert!(reply["reason"].is_string());
}

#[tokio::test]
async fn cutdown_needs_arm_then_confirm_from_an_operator() {
    let station = start_station(config(|c| c.cutdown_window_s = 0.6)).await;
    let drone = fake_drone(station.running.link_local.expect("link address")).await;
    let addr = station.http();
    // Confirm without arming: refused, nothing sent.
    let (status, reply) = http(
        addr,
        "POST",
        "/api/cutdown/confirm",
        Some(OPERATOR),
        Some(r#"{"arm_id":"guess"}"#),
    )
    .await;
    assert_eq!(status, 409, "{reply}");
    assert_eq!(reply["error"], "not_armed");
    // Arm: nothing is sent yet.
    let (status, armed) = http(addr, "POST", "/api/cutdown/arm", Some(OPERATOR), Some("{}")).await;
    assert_eq!(status, 200, "{armed}");
    let arm_id = armed["arm_id"].as_str().expect("arm id").to_string();
    assert!(armed["expires_in_s"].as_f64().expect("expiry") > 0.0);
    tokio::time::sleep(Duration::from_millis(300)).await;
    assert!(
        drone.seen(|s| !s.commands.contains(&Command::Cutdown)),
        "arming alone cut down"
    );
    // A wrong id does not confirm.
    let (status, _) = http(
        addr,
        "POST",
        "/api/cutdown/confirm",
        Some(OPERATOR),
        Some(r#"{"arm_id":"wrong"}"#),
    )
    .await;
    assert_eq!(status, 409);
    // Too late: the arm expired.
    tokio::time::sleep(Duration::from_millis(500)).await;
    let body = json!({ "arm_id": arm_id }).to_string();
    let (status, reply) = http(
        addr,
        "POST",
        "/api/cutdown/confirm",
        Some(OPERATOR),
        Some(&body),
    )
    .await;
    assert_eq!(status, 409, "an expired arm must not confirm: {reply}");
    assert!(drone.seen(|s| !s.commands.contains(&Command::Cutdown)));
    // Arm and confirm in time: the drone gets the cutdown.
    let (_, armed) = http(addr, "POST", "/api/cutdown/arm", Some(OPERATOR), Some("{}")).await;
    let body = json!({ "arm_id": armed["arm_id"] }).to_string();
    let (status, reply) = http(
        addr,
        "POST",
        "/api/cutdown/confirm",
        Some(OPERATOR),
        Some(&body),
    )
    .await;
    assert_eq!(status, 202, "{reply}");
    assert!(
        eventually(5.0, || drone
            .seen(|s| s.commands.contains(&Command::Cutdown)))
        .await
    );
    // Logged with who asked.
    let (_, events) = http(addr, "GET", "/api/events?since_s=0", Some(VIEWER), None).await;
    let logged = events["events"]
        .as_array()
        .expect("events")
        .iter()
        .any(|e| {
            e["text"]
                .as_str()
                .is_some_and(|t| t.contains("operator") && t.contains("CUTDOWN"))
        });
    assert!(logged, "{events}");
}

#[tokio::test]
async fn a_parameter_set_is_read_back_from_the_drone() {
    let station = start_station(config(|_| {})).await;
    let drone = fake_drone(station.running.link_local.expect("link address")).await;
    let addr = station.http();
    // The station fetches the table when the drone appears.
    let mut listed = Value::Null;
    for _ in 0..100 {
        let (_, params) = http(addr, "GET", "/api/params", Some(VIEWER), None).await;
        if params["complete"] == true {
            listed = params;
            break;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    let hk1 = listed["params"]
        .as_array()
        .and_then(|ps| ps.iter().find(|p| p["name"] == "HK1"))
        .unwrap_or_else(|| panic!("HK1 listed: {listed}"))
        .clone();
    assert!((hk1["value"].as_f64().expect("value") - 0.012).abs() < 1e-6);
    let (status, reply) = http(
        addr,
        "POST",
        "/api/params/HK1",
        Some(OPERATOR),
        Some(r#"{"value":0.02}"#),
    )
    .await;
    assert_eq!(status, 202, "{reply}");
    let id = reply["request_id"].as_str().expect("id").to_string();
    let outcome = final_outcome(addr, &id).await;
    assert_eq!(outcome["outcome"], "accepted", "{outcome}");
    assert!(
        outcome["detail"]
            .as_str()
            .is_some_and(|d| d.contains("0.02")),
        "{outcome}"
    );
    assert!(drone.seen(|s| {
        s.param_changes
            .iter()
            .any(|(n, v)| n == "HK1" && (v - 0.02).abs() < 1e-6)
    }));
    let (_, params) = http(addr, "GET", "/api/params", Some(VIEWER), None).await;
    let value = params["params"]
        .as_array()
        .and_then(|ps| ps.iter().find(|p| p["name"] == "HK1"))
        .and_then(|p| p["value"].as_f64());
    assert!(value.is_some_and(|v| (v - 0.02).abs() < 1e-6), "{params}");
    // Out of the drone's range: the drone refuses and the outcome says so.
    let (status, reply) = http(
        addr,
        "POST",
        "/api/params/HK1",
        Some(OPERATOR),
        Some(r#"{"value":5.0}"#),
    )
    .await;
    assert!(status == 400 || status == 202, "{reply}");
    if status == 202 {
        let id = reply["request_id"].as_str().expect("id").to_string();
        let outcome = final_outcome(addr, &id).await;
        assert_ne!(outcome["outcome"], "accepted", "{outcome}");
    }
    assert!(drone.seen(|s| !s.param_changes.iter().any(|(_, v)| *v > 1.0)));
    // A parameter of the onboard catalogue out of its range: refused by the station with the
    // range named, and nothing goes to the drone.
    let (status, reply) = http(
        addr,
        "POST",
        "/api/params/GN_HK1",
        Some(OPERATOR),
        Some(r#"{"value":7.5}"#),
    )
    .await;
    assert_eq!(status, 400, "{reply}");
    assert!(
        reply["reason"]
            .as_str()
            .is_some_and(|r| r.contains("GN_HK1") && r.contains("0.2")),
        "{reply}"
    );
    assert!(drone.seen(|s| !s.param_changes.iter().any(|(n, _)| n == "GN_HK1")));
}

#[tokio::test]
async fn the_websocket_greets_then_streams_live_state() {
    let station = start_station(config(|_| {})).await;
    let drone = fake_drone(station.running.link_local.expect("link address")).await;
    let mut ws = ws_connect(station.http(), VIEWER).await;
    let hello = ws_next(&mut ws, 5.0).await.expect("hello");
    assert_eq!(hello["type"], "hello");
    assert_eq!(hello["session"]["role"], "viewer");
    let first = ws_next(&mut ws, 5.0).await.expect("state");
    assert_eq!(first["type"], "state");
    let history = ws_next(&mut ws, 5.0).await.expect("history");
    assert_eq!(history["type"], "history");
    assert!(history["track"].is_array() && history["events"].is_array());
    // Once the drone's heartbeat is heard, each attitude it sends shows up in a state.
    assert!(
        ws_until(&mut ws, 5.0, |m| m["type"] == "state"
            && m["link"]["connected"] == true)
        .await
        .is_some(),
        "the link came up"
    );
    for stamp in [1_000_u32, 2_000, 3_000] {
        drone.send_attitude(stamp, 0.5).await;
        let seen = ws_until(&mut ws, 5.0, |m| {
            m["type"] == "state" && m["vehicle"]["attitude"]["time_boot_ms"] == stamp
        })
        .await
        .unwrap_or_else(|| panic!("attitude {stamp} reached the page"));
        let yaw = seen["vehicle"]["attitude"]["yaw_deg"]
            .as_f64()
            .expect("yaw");
        assert!((yaw - 0.5_f64.to_degrees()).abs() < 0.01, "{yaw}");
        assert_eq!(seen["link"]["stale"], false);
    }
    // ping / pong
    ws_send(&mut ws, json!({"type":"ping"})).await;
    assert!(
        ws_until(&mut ws, 5.0, |m| m["type"] == "pong")
            .await
            .is_some()
    );
    // A malformed message gets an error event back, and the socket stays open.
    ws_send(&mut ws, json!({"type":"teleport"})).await;
    let err = ws_until(&mut ws, 5.0, |m| {
        m["type"] == "event" && m["level"] == "error"
    })
    .await;
    assert!(err.is_some());
    ws_send(&mut ws, json!({"type":"ping"})).await;
    assert!(
        ws_until(&mut ws, 5.0, |m| m["type"] == "pong")
            .await
            .is_some()
    );
}

#[tokio::test]
async fn operator_sticks_reach_the_drone_and_stop_when_released() {
    let station = start_station(config(|_| {})).await;
    let drone = fake_drone(station.running.link_local.expect("link address")).await;
    let mut ws = ws_connect(station.http(), OPERATOR).await;
    for _ in 0..5 {
        ws_send(
            &mut ws,
            json!({"type":"manual","x":0.0,"y":0.5,"z":0.25,"r":0.0,"buttons":1}),
        )
        .await;
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    assert!(
        eventually(3.0, || drone
            .seen(|s| s.sticks.iter().any(|k| (k.y - 0.5).abs() < 0.01)))
        .await,
        "sticks reached the drone"
    );
    // Silence: the uplink stops within the station's 0.5 s.
    tokio::time::sleep(Duration::from_millis(800)).await;
    let count = drone.seen(|s| s.sticks.len());
    tokio::time::sleep(Duration::from_millis(700)).await;
    assert_eq!(
        drone.seen(|s| s.sticks.len()),
        count,
        "MANUAL_CONTROL kept flowing after release"
    );
}

#[tokio::test]
async fn viewer_sticks_are_refused_and_never_sent() {
    let station = start_station(config(|_| {})).await;
    let drone = fake_drone(station.running.link_local.expect("link address")).await;
    let mut ws = ws_connect(station.http(), VIEWER).await;
    ws_send(
        &mut ws,
        json!({"type":"manual","x":0.0,"y":0.9,"z":0.0,"r":0.0,"buttons":1}),
    )
    .await;
    let refusal = ws_until(&mut ws, 5.0, |m| {
        m["type"] == "event" && m["level"] == "error"
    })
    .await
    .expect("an error event");
    assert!(
        refusal["text"]
            .as_str()
            .is_some_and(|t| t.contains("operator")),
        "{refusal}"
    );
    tokio::time::sleep(Duration::from_millis(500)).await;
    assert!(drone.seen(|s| s.sticks.is_empty()));
}

#[tokio::test]
async fn kml_feeds_google_earth() {
    let station = start_station(config(|_| {})).await;
    let (status, link) =
        http_text(station.http(), "GET", "/kml?token=viewer-token", None, None).await;
    assert_eq!(status, 200);
    assert!(
        link.contains("<NetworkLink>") && link.contains("/kml/live?token=viewer-token"),
        "{link}"
    );
    let (status, live) = http_text(station.http(), "GET", "/kml/live", Some(VIEWER), None).await;
    assert_eq!(status, 200);
    assert!(live.starts_with("<?xml") && live.contains("<kml"), "{live}");
}

#[tokio::test]
async fn unknown_api_paths_are_404_with_a_reason_not_the_page() {
    let station = start_station(config(|_| {})).await;
    for path in ["/api/nope", "/api/commands/teleport/now", "/api", "/api/"] {
        for method in ["GET", "POST"] {
            let (status, body) = http(station.http(), method, path, Some(VIEWER), Some("{}")).await;
            assert_eq!(status, 404, "{method} {path}: {body}");
            assert_eq!(body["error"], "not_found", "{method} {path}: {body}");
            assert!(reason(&body).contains(path), "{body}");
        }
    }
    // Known endpoints still answer.
    let (status, _) = http(station.http(), "GET", "/api/state", Some(VIEWER), None).await;
    assert_eq!(status, 200);
}

#[tokio::test]
async fn manual_release_stops_the_sticks_at_once() {
    let station = start_station(config(|_| {})).await;
    let drone = fake_drone(station.running.link_local.expect("link address")).await;
    let mut ws = ws_connect(station.http(), OPERATOR).await;
    for _ in 0..6 {
        ws_send(
            &mut ws,
            json!({"type":"manual","x":0.0,"y":0.5,"z":0.0,"r":0.0,"buttons":1}),
        )
        .await;
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    assert!(
        eventually(3.0, || drone.seen(|s| !s.sticks.is_empty())).await,
        "sticks reached the drone"
    );
    // Released right after the last stick message: the station's silence timeout (0.5 s)
    // would keep streaming for half a second more; the release stops it now.
    ws_send(&mut ws, json!({"type":"manual_release"})).await;
    tokio::time::sleep(Duration::from_millis(120)).await;
    let at_release = drone.seen(|s| s.sticks.len());
    tokio::time::sleep(Duration::from_millis(600)).await;
    assert_eq!(
        drone.seen(|s| s.sticks.len()),
        at_release,
        "MANUAL_CONTROL went on after manual_release"
    );
    // No error came back for the message.
    let refused = ws_until(&mut ws, 0.5, |m| {
        m["type"] == "event" && m["level"] == "error"
    })
    .await;
    assert!(refused.is_none(), "{refused:?}");
}

#[tokio::test]
async fn the_kml_link_names_the_host_google_earth_used() {
    let station = start_station(config(|c| c.listen = "0.0.0.0:0".parse().expect("address"))).await;
    let port = station.http().port();
    let mut stream = tokio::net::TcpStream::connect(("127.0.0.1", port))
        .await
        .expect("connect");
    use tokio::io::{AsyncReadExt, AsyncWriteExt};
    let request = format!(
        "GET /kml?token=viewer-token HTTP/1.1\r\nHost: field-laptop.local:{port}\r\nConnection: close\r\n\r\n"
    );
    stream.write_all(request.as_bytes()).await.expect("write");
    let mut response = String::new();
    stream.read_to_string(&mut response).await.expect("read");
    assert!(response.starts_with("HTTP/1.1 200"), "{response}");
    assert!(
        response.contains(&format!(
            "<href>http://field-laptop.local:{port}/kml/live?token=viewer-token</href>"
        )),
        "{response}"
    );
    assert!(!response.contains("0.0.0.0"), "{response}");
}

/// A page that stops reading while far more events than the backlog are logged: it is told
/// exactly how many it missed, gets the newest in order, and its states are coalesced; a
/// page that reads along loses nothing without being told either. Both counted per page.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_slow_page_is_told_what_it_missed_and_states_are_coalesced() {
    const EVENTS: usize = 12_000;
    let station = start_station(config(|_| {})).await;
    let mut slow = ws_connect(station.http(), OPERATOR).await;
    let mut fast = ws_connect(station.http(), VIEWER).await;
    // Both greeted before the flood.
    for ws in [&mut slow, &mut fast] {
        assert!(
            ws_until(ws, 5.0, |m| m["type"] == "history")
                .await
                .is_some()
        );
    }
    let padding = "x".repeat(4000);
    {
        let mut core = station.running.shared.core.lock().expect("core");
        for i in 0..EVENTS {
            core.log(
                1.0,
                stx_station::messages::Level::Info,
                "station",
                format!("flood {i} {padding}"),
            );
        }
    }
    /// Reads until the last flood event; the flood events' numbers and the `missed` counts.
    async fn drain(ws: &mut Ws) -> (Vec<usize>, u64) {
        let mut seen = Vec::new();
        let mut missed = 0;
        while seen.last() != Some(&(EVENTS - 1)) {
            let m = ws_next(ws, 20.0).await.expect("the page is fed");
            if m["type"] == "lagged" {
                missed += m["missed"].as_u64().expect("missed");
            } else if let Some(text) = m["text"].as_str()
                && let Some(rest) = text.strip_prefix("flood ")
            {
                seen.push(
                    rest.split(' ')
                        .next()
                        .and_then(|n| n.parse().ok())
                        .expect("n"),
                );
            }
        }
        (seen, missed)
    }
    let (fast_seen, fast_missed) = drain(&mut fast).await;
    assert_eq!(fast_seen.len() as u64 + fast_missed, EVENTS as u64);
    // The slow page has read nothing for a while: states kept coming meanwhile.
    tokio::time::sleep(Duration::from_millis(1500)).await;
    let (_, clients) = http(station.http(), "GET", "/api/clients", Some(VIEWER), None).await;
    let slow_counts = clients["clients"]
        .as_array()
        .and_then(|c| c.iter().find(|c| c["name"] == "operator"))
        .cloned()
        .unwrap_or_else(|| panic!("the slow page is listed: {clients}"));
    // It is further behind than the backlog: it will be told so when it reads again.
    assert!(
        slow_counts["messages_behind"].as_u64()
            > Some(stx_station::daemon::RELIABLE_BACKLOG as u64),
        "{slow_counts}"
    );
    let (slow_seen, slow_missed) = drain(&mut slow).await;
    assert!(slow_missed > 0, "the slow page must have lagged");
    assert_eq!(
        slow_seen.len() as u64 + slow_missed,
        EVENTS as u64,
        "every event is either delivered or announced as missed"
    );
    assert!(slow_seen.windows(2).all(|w| w[0] < w[1]), "in order");
    // While it was blocked, states were replaced by newer ones, not queued.
    let next_state = ws_until(&mut slow, 5.0, |m| m["type"] == "state").await;
    assert!(next_state.is_some());
    let (_, clients) = http(station.http(), "GET", "/api/clients", Some(VIEWER), None).await;
    let slow_counts = clients["clients"]
        .as_array()
        .and_then(|c| c.iter().find(|c| c["name"] == "operator"))
        .cloned()
        .unwrap_or_default();
    assert_eq!(
        slow_counts["messages_missed"].as_u64(),
        Some(slow_missed),
        "the count per page is what the page was told: {slow_counts}"
    );
    assert!(
        slow_counts["lag_episodes"].as_u64() >= Some(1),
        "{slow_counts}"
    );
    assert!(
        slow_counts["states_coalesced"].as_u64() > Some(0),
        "{slow_counts}"
    );
}
