//! `stx polar FILE`: a vehicle file's planning polar as the drone's `PL_*` parameters, as a
//! parameter file or the station's send body; a file that is not a vehicle is refused.

use std::path::Path;
use std::process::{Command, Output};

use stx_gnc::params::OnboardSettings;
use stx_gnc::performance::GlidePerformance;

fn polar(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_stx"))
        .arg("polar")
        .args(args)
        .output()
        .expect("stx runs")
}

/// The `NAME VALUE` lines of a parameter file, comments skipped.
fn parm(out: &Output) -> Vec<(String, f64)> {
    assert!(out.status.success(), "{out:?}");
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| {
            let mut f = l.split_whitespace();
            let name = f.next().expect("name").to_string();
            (name, f.next().expect("value").parse().expect("number"))
        })
        .collect()
}

/// The settings the drone would have after taking every parameter in turn.
fn taken(params: &[(String, f64)]) -> GlidePerformance {
    let mut s = OnboardSettings::default();
    for (name, value) in params {
        s.apply(name, *value)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
    }
    s.guidance.performance
}

#[test]
fn a_vehicle_files_polar_is_a_parameter_file_the_drone_takes() {
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config/vehicle/straplex.toml");
    let shipped_text = std::fs::read_to_string(&shipped).expect("shipped vehicle");
    let params = parm(&polar(&[shipped.to_str().expect("path")]));
    assert_eq!(params.len(), 17, "{params:?}");
    // The shipped vehicle's trim is the shipped table (within 0.6 %, as identified_landing
    // finds): what the drone flies unless told otherwise.
    let nominal = GlidePerformance::default();
    let mine = taken(&params);
    for k in 0..nominal.brake_points.len() {
        assert!((mine.airspeed_mps[k] / nominal.airspeed_mps[k] - 1.0).abs() < 0.006);
        assert!((mine.sink_rate_mps[k] / nominal.sink_rate_mps[k] - 1.0).abs() < 0.006);
    }
    assert_eq!(mine.turn_time_constant_s, nominal.turn_time_constant_s);

    // A canopy with 20 % less lift sinks faster at every brake setting (by 13 % released).
    let dir = std::env::temp_dir().join(format!("stx-polar-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let weak = dir.join("lift08.toml");
    let text = shipped_text.replace("cl_alpha = 2.300", "cl_alpha = 1.840");
    assert_ne!(text, shipped_text, "the vehicle file names cl_alpha");
    std::fs::write(&weak, text).expect("write");
    let weak_polar = taken(&parm(&polar(&[weak.to_str().expect("path")])));
    for k in 0..nominal.brake_points.len() {
        assert!(
            weak_polar.sink_rate_mps[k] > 1.08 * mine.sink_rate_mps[k],
            "{weak_polar:?}"
        );
    }
    // `--json` is the body the station's send takes, the same values, unconfirmed.
    let out = polar(&[weak.to_str().expect("path"), "--json"]);
    assert!(out.status.success(), "{out:?}");
    let body: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    assert_eq!(body["confirm"], false);
    let gains = body["gains"].as_object().expect("gains");
    let from_json: Vec<(String, f64)> = gains
        .iter()
        .map(|(k, v)| (k.clone(), v.as_f64().expect("number")))
        .collect();
    let json_polar = taken(&from_json);
    for k in 0..nominal.brake_points.len() {
        assert!((json_polar.sink_rate_mps[k] - weak_polar.sink_rate_mps[k]).abs() < 1e-5);
    }

    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "gravity_mps2 = \"down\"\n").expect("write");
    for path in [bad, dir.join("missing.toml")] {
        let out = polar(&[path.to_str().expect("path")]);
        assert_eq!(out.status.code(), Some(2), "{out:?}");
        assert!(String::from_utf8_lossy(&out.stderr).contains("vehicle file"));
    }
    let _ = std::fs::remove_dir_all(&dir);
}
