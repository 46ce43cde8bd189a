//! `stx drone --vehicle FILE` and `stx serve --sim --sim-vehicle FILE` from the outside: a
//! vehicle file is flown as the truth, and a bad one exits with code 2 naming the field.

use crate::common;

use std::net::UdpSocket;
use std::path::Path;

use common::{stx, temp_dir};

/// The shipped vehicle file with `from` replaced by `to`, as a path string.
fn vehicle_file(dir: &Path, name: &str, from: &str, to: &str) -> String {
    let path = common::vehicle_file(dir, name, from, to);
    path.to_str().expect("utf-8").to_string()
}

/// The rehearsal (under the parafoil from 900 m) at `--speed max`, to a socket nobody reads;
/// its JSON summary.
fn rehearsal(extra: &[&str]) -> serde_json::Value {
    let socket = UdpSocket::bind("127.0.0.1:0").expect("udp socket");
    let connect = format!("udpout:{}", socket.local_addr().expect("bound"));
    let mut args = vec!["drone", "--connect", &connect];
    args.extend([
        "--scenario",
        "rehearsal",
        "--speed",
        "max",
        "--summary-json",
    ]);
    args.extend(extra);
    let out = stx(&args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(stdout.lines().last().unwrap_or_default())
        .unwrap_or_else(|e| panic!("summary is not JSON ({e}): {stdout}"))
}

#[test]
fn a_vehicle_file_is_flown_to_a_landing_as_the_truth() {
    let dir = temp_dir("drone-vehicle", "good");
    let weaker = vehicle_file(&dir, "weaker.toml", "cl_alpha = 2.300", "cl_alpha = 1.840");
    let shipped = rehearsal(&[]);
    let flown = rehearsal(&["--vehicle", &weaker]);
    assert_eq!(flown["landed"], true, "{flown}");
    assert_eq!(flown["landing"]["under_parafoil"], true, "{flown}");
    let landed_s = |s: &serde_json::Value| s["landing"]["time_s"].as_f64().expect("landing time");
    // 20 % less lift slope is a different descent: the file was flown, not the shipped vehicle.
    assert!(
        (landed_s(&shipped) - landed_s(&flown)).abs() > 5.0,
        "shipped {} s, file {} s",
        landed_s(&shipped),
        landed_s(&flown)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_bad_vehicle_file_exits_with_code_2_naming_the_field() {
    let dir = temp_dir("drone-vehicle", "bad");
    let negative = vehicle_file(&dir, "negative.toml", "mass_kg = 0.700", "mass_kg = -0.700");
    let unknown = vehicle_file(&dir, "unknown.toml", "cl_alpha =", "cl_alfa =");
    let missing = dir.join("missing.toml");
    let missing = missing.to_str().expect("utf-8");
    for (file, says) in [
        (negative.as_str(), "canopy.mass_kg"),
        (unknown.as_str(), "cl_alfa"),
        (missing, "missing.toml"),
    ] {
        for args in [
            vec!["drone", "--speed", "max", "--vehicle", file],
            vec![
                "serve",
                "--sim",
                "--no-record",
                "--listen",
                "127.0.0.1:0",
                "--sim-vehicle",
                file,
            ],
        ] {
            let out = stx(&args);
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
            assert!(stderr.contains(says), "{args:?} names {says}: {stderr}");
            assert!(stderr.contains("vehicle"), "{args:?}: {stderr}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
