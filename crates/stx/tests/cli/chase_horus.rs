//! The chase cars' broadcast (`[chase]`) of a running station, heard on loopback and held
//! against horusdemodlib 0.6.2 (PyPI), the Horus tools' own PAYLOAD_SUMMARY sender
//! (`tests/peers/chase_horus.py`): the same fields with the same types, the payload where the
//! station's GPS says it is, the time of day in UTC, and the predicted landing as its own
//! callsign where the station predicts it.

use serde_json::Value;

use crate::common::mavproxy::run_peer;
use crate::common::station::{Station, free_udp_port};
use crate::common::temp_dir;

/// Metres between two points given in degrees (equirectangular: the points are close).
fn distance_m(a: (f64, f64), b: (f64, f64)) -> f64 {
    let r = 6_371_008.8_f64;
    let x = (b.1 - a.1).to_radians() * ((a.0 + b.0) / 2.0).to_radians().cos();
    let y = (b.0 - a.0).to_radians();
    r * x.hypot(y)
}

fn kinds(v: &Value) -> Vec<(String, &'static str)> {
    let mut k: Vec<(String, &'static str)> = v
        .as_object()
        .expect("an object")
        .iter()
        .map(|(k, v)| {
            (
                k.clone(),
                if v.is_number() {
                    "number"
                } else if v.is_string() {
                    "string"
                } else {
                    "other"
                },
            )
        })
        .collect();
    k.sort();
    k
}

#[test]
fn chase_cars_hear_the_payload_and_its_landing_as_horusdemodlib_sends_them() {
    let port = free_udp_port();
    let dir = temp_dir("chase", "horus");
    let station = Station::start(
        &dir,
        &format!(
            "[chase]\ncallsign = \"STRAPLEX1\"\naddress = \"127.0.0.1\"\nport = {port}\nperiod_s = 1.0\n"
        ),
    );
    let out = run_peer("chase_horus.py", &[&port.to_string(), "40"]);
    let heard: Value = serde_json::from_slice(&out).expect("the script's JSON");
    let state = station.get("/api/state").expect("the station's state");

    let stx = heard["stx"].as_array().expect("datagrams");
    let payloads: Vec<&Value> = stx
        .iter()
        .filter(|d| d["callsign"] == "STRAPLEX1")
        .collect();
    let landings: Vec<&Value> = stx
        .iter()
        .filter(|d| d["callsign"] == "STRAPLEX1_LANDING")
        .collect();
    assert!(payloads.len() >= 3 && !landings.is_empty(), "{heard}");
    assert_eq!(
        kinds(payloads[0]),
        kinds(&heard["horus"]),
        "stx {} / horusdemodlib {}",
        payloads[0],
        heard["horus"]
    );
    for key in [
        "type",
        "callsign",
        "latitude",
        "longitude",
        "altitude",
        "time",
        "speed",
        "sats",
        "batt_voltage",
        "comment",
    ] {
        assert_eq!(payloads[0][key], heard["horus"][key], "{key}");
    }

    // The last payload datagram against the station's own GPS and clock now (≤ 1 s later).
    let last = payloads.last().expect("a payload");
    let gps = &state["vehicle"]["gps"];
    let at = |v: &Value, lat: &str, lon: &str| {
        (
            v[lat].as_f64().unwrap_or(f64::NAN),
            v[lon].as_f64().unwrap_or(f64::NAN),
        )
    };
    let off = distance_m(
        at(last, "latitude", "longitude"),
        at(gps, "lat_deg", "lon_deg"),
    );
    assert!(off < 40.0, "{off} m from the station's fix: {last} / {gps}");
    let wall_s = state["wall_ms"].as_u64().expect("wall clock") / 1000;
    let hms = last["time"].as_str().expect("time");
    let parts: Vec<u64> = hms.split(':').filter_map(|p| p.parse().ok()).collect();
    assert_eq!(parts.len(), 3, "HH:MM:SS: {hms}");
    let sent_s = parts[0] * 3600 + parts[1] * 60 + parts[2];
    let behind = (wall_s % 86_400 + 86_400 - sent_s) % 86_400;
    assert!(
        behind <= 10,
        "{hms} is {behind} s behind the station's clock"
    );

    let landing = landings.last().expect("a landing");
    let predicted = &state["prediction"];
    let touchdown = if predicted["planned"].is_object() {
        &predicted["planned"]
    } else {
        &predicted["uncontrolled"]
    };
    let off = distance_m(
        at(landing, "latitude", "longitude"),
        at(touchdown, "lat_deg", "lon_deg"),
    );
    assert!(
        off < 50.0,
        "{off} m from the station's prediction: {landing} / {touchdown}"
    );
    // The pages are told what was sent.
    let chase = &station.get("/api/sharing").expect("sharing")["chase"];
    assert_eq!(
        (chase["callsign"].as_str(), chase["to"].as_str()),
        (
            Some("STRAPLEX1"),
            Some(format!("127.0.0.1:{port}").as_str())
        )
    );
    assert!(chase["sent"].as_u64() >= Some(stx.len() as u64), "{chase}");
    let _ = std::fs::remove_dir_all(&dir);
}
