//! `stx montecarlo` over shards and dispersion files, through the real binary: a campaign split
//! into shards and merged gives the one-machine report; bad parts and bad dispersion files are
//! refused with a clear message and exit code 2; capsules landed in keep-out zones are counted;
//! vehicle files flown around and planned with are named in the report.

use crate::common;

use common::stx;

use std::path::{Path, PathBuf};
use std::process::Output;

fn temp_dir(name: &str) -> PathBuf {
    common::temp_dir("montecarlo", name)
}

/// A small campaign: short flights, realistic dispersions.
const CAMPAIGN: [&str; 9] = [
    "montecarlo",
    "--runs",
    "5",
    "--seed",
    "9",
    "--altitude",
    "120",
    "--dispersions",
    "realistic",
];

fn json(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut v: serde_json::Value =
        serde_json::from_slice(&out.stdout).expect("one JSON object on stdout");
    v.as_object_mut().expect("an object").remove("wall_time_s");
    v
}

fn shard(dir: &Path, k: usize, n: usize) -> PathBuf {
    let out = dir.join(format!("part{k}.json"));
    let spec = format!("{k}/{n}");
    let mut args = CAMPAIGN.to_vec();
    args.extend(["--shard", &spec, "--out", out.to_str().expect("utf-8 path")]);
    let run = stx(&args);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    out
}

#[test]
fn shards_merged_give_exactly_the_one_machine_report() {
    let dir = temp_dir("merge");
    let mut whole = CAMPAIGN.to_vec();
    whole.extend(["--json", "--details", "--threads", "2"]);
    let one_machine = json(&stx(&whole));
    assert_eq!(one_machine["runs"], 5);
    assert_eq!(one_machine["dispersions"]["name"], "realistic");

    let parts: Vec<PathBuf> = (1..=3).map(|k| shard(&dir, k, 3)).collect();
    let mut merge = vec!["montecarlo", "merge", "--json", "--details"];
    // Given in another order than flown: the merge sorts the runs.
    for p in parts.iter().rev() {
        merge.push(p.to_str().expect("utf-8 path"));
    }
    let merged = json(&stx(&merge));
    assert_eq!(
        merged, one_machine,
        "every statistic and every run, wall time aside"
    );

    // A part missing, or one from another campaign, is refused by name.
    let missing = stx(&[
        "montecarlo",
        "merge",
        parts[0].to_str().expect("path"),
        parts[1].to_str().expect("path"),
    ]);
    assert_eq!(missing.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&missing.stderr).contains("each of 1…3 must be given once"),
        "{}",
        String::from_utf8_lossy(&missing.stderr)
    );
    let other = dir.join("other.json");
    let run = stx(&[
        "montecarlo",
        "--runs",
        "5",
        "--seed",
        "10",
        "--altitude",
        "120",
        "--dispersions",
        "realistic",
        "--shard",
        "3/3",
        "--out",
        other.to_str().expect("path"),
    ]);
    assert!(run.status.success());
    let mixed = stx(&[
        "montecarlo",
        "merge",
        parts[0].to_str().expect("path"),
        parts[1].to_str().expect("path"),
        other.to_str().expect("path"),
    ]);
    assert_eq!(mixed.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&mixed.stderr).contains("another campaign"));
    let not_a_part = dir.join("garbage.json");
    std::fs::write(&not_a_part, "{\"runs\": 3}").expect("write");
    let garbage = stx(&["montecarlo", "merge", not_a_part.to_str().expect("path")]);
    assert_eq!(garbage.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&garbage.stderr).contains("is not a campaign part"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_bad_dispersion_file_or_shard_is_refused_by_name() {
    let dir = temp_dir("bad");
    let file = dir.join("d.toml");
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config/dispersions/realistic.toml"),
    )
    .expect("the shipped file")
    .replace("mass_sigma = 0.10", "mass_sigma = -0.1");
    std::fs::write(&file, text).expect("write");
    let out = stx(&[
        "montecarlo",
        "--runs",
        "1",
        "--dispersions",
        file.to_str().expect("path"),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("mass.mass_sigma"), "{err}");
    let out = stx(&[
        "montecarlo",
        "--runs",
        "1",
        "--dispersions",
        "/nonexistent.toml",
    ]);
    assert_eq!(out.status.code(), Some(2));
    // The simulated drone reads the same files, and refuses the same way.
    let out = stx(&["drone", "--dispersions", file.to_str().expect("path")]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("mass.mass_sigma"));
    let out = stx(&[
        "montecarlo",
        "--runs",
        "4",
        "--shard",
        "5/4",
        "--out",
        "x.json",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("K/N"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A FeatureCollection of one rectangle `name`, north `n0`…`n1` and east `e0`…`e1` of the
/// campaign's target (the default site), in metres (a flat-earth conversion, metre-accurate
/// over these distances).
fn rectangle(name: &str, [n0, n1]: [f64; 2], [e0, e1]: [f64; 2]) -> String {
    let (lat0, lon0) = (38.5333_f64, -7.8889_f64);
    let m_per_deg_lat = 111_000.0;
    let m_per_deg_lon = m_per_deg_lat * lat0.to_radians().cos();
    let at = |n: f64, e: f64| {
        format!(
            "[{}, {}]",
            lon0 + e / m_per_deg_lon,
            lat0 + n / m_per_deg_lat
        )
    };
    format!(
        r#"{{"type": "FeatureCollection", "features": [{{"type": "Feature",
        "properties": {{"name": "{name}"}}, "geometry": {{"type": "Polygon", "coordinates": [[
        {}, {}, {}, {}, {}]]}}}}]}}"#,
        at(n0, e0),
        at(n0, e1),
        at(n1, e1),
        at(n1, e0),
        at(n0, e0)
    )
}

#[test]
fn capsules_landed_in_keep_out_zones_are_counted_by_wind_and_bad_zones_are_refused() {
    let dir = temp_dir("zones");
    // Everything more than 3 m north of the target is a zone guidance does not know of: the
    // capsules landed there are exactly those counted.
    let north = dir.join("north.geojson");
    std::fs::write(&north, rectangle("North", [3.0, 3000.0], [-3000.0, 3000.0])).expect("write");
    let mut args = CAMPAIGN.to_vec();
    args.extend([
        "--json",
        "--details",
        "--keep-out",
        north.to_str().expect("path"),
        "--keep-out-unguided",
    ]);
    let report = json(&stx(&args));
    let z = &report["keep_out"];
    assert_eq!(z["zones"], serde_json::json!(["North"]));
    assert_eq!(z["guided"], false);
    let results = report["results"].as_array().expect("results");
    let north_of = |r: &serde_json::Value| r["payload_touchdown_ne_m"][0].as_f64().expect("n");
    // Well clear of the edge (the conversions differ by centimetres), so the test is sharp.
    assert!(results.iter().all(|r| (north_of(r) - 3.0).abs() > 0.5));
    let expected = results.iter().filter(|r| north_of(r) > 3.0).count();
    assert!(
        expected > 0 && expected < results.len(),
        "both kinds of landing: {expected}"
    );
    assert_eq!(z["in_zone"].as_u64(), Some(expected as u64), "{z}");
    assert_eq!(z["landings"].as_u64(), Some(results.len() as u64));
    let by_wind = z["by_wind"].as_array().expect("bins");
    let sum = |key: &str| {
        by_wind
            .iter()
            .map(|b| b[key].as_u64().unwrap_or(0))
            .sum::<u64>()
    };
    assert_eq!(sum("landings"), results.len() as u64);
    assert_eq!(sum("in_zone"), expected as u64);
    for run in z["runs"].as_array().expect("runs") {
        assert_eq!(run["zone"], "North");
    }

    // A target inside a zone, a file that is not zones, a missing file: refused by name.
    let over = dir.join("over.geojson");
    std::fs::write(&over, rectangle("Field", [-50.0, 50.0], [-50.0, 50.0])).expect("write");
    let not_zones = dir.join("bad.geojson");
    std::fs::write(&not_zones, r#"{"type": "Point", "coordinates": [0, 0]}"#).expect("write");
    for (file, says) in [
        (over.to_str().expect("path"), "lies in zone 'Field'"),
        (not_zones.to_str().expect("path"), "bad.geojson"),
        ("/nonexistent.geojson", "cannot read"),
    ] {
        let out = stx(&["montecarlo", "--runs", "1", "--keep-out", file]);
        assert_eq!(out.status.code(), Some(2), "{file}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(says), "{file}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--anemometer` flies every run with the ground anemometer and says so; each run carries
/// what guidance learned of the glide and the turn, and a different flight than without; the
/// report names the nominal single landing.
#[test]
fn a_campaign_with_the_ground_anemometer_says_so_and_every_run_shows_what_was_learned() {
    let mut with = CAMPAIGN.to_vec();
    with.extend(["--json", "--details", "--anemometer"]);
    let mut without = CAMPAIGN.to_vec();
    without.extend(["--json", "--details"]);
    let (with, without) = (json(&stx(&with)), json(&stx(&without)));
    assert_eq!(with["anemometer"], true);
    assert_eq!(without["anemometer"], false);
    let runs = with["results"].as_array().expect("results");
    assert_eq!(runs.len(), 5);
    for run in runs {
        let learned = &run["learned"];
        assert_eq!(learned["brake"], serde_json::json!([0.0, 0.5, 1.0]));
        for k in 0..3 {
            let sink = learned["sink_scale"][k].as_f64().expect("a scale");
            assert!((0.6..=1.6).contains(&sink), "{learned}");
        }
        assert!(
            learned["learned_s"].as_f64().expect("seconds") > 0.0,
            "{learned}"
        );
    }
    // Below the pattern guidance planned with another wind: the landings differ.
    assert_ne!(with["results"], without["results"]);
    // Beside the campaign, the nominal single landing, as `stx sim` flies it.
    let sim = stx(&["sim", "--scenario", "spiral-landing", "--summary-json"]);
    assert!(sim.status.success());
    let sim: serde_json::Value = serde_json::from_slice(&sim.stdout).expect("summary");
    assert_eq!(with["nominal_single_landing"], sim["landing"]);
    assert!(with["nominal_single_landing"]["miss_m"].as_f64().is_some());
    // And the payload's touchdown after it, the capsule's when the transponder touched first.
    assert_eq!(
        with["nominal_single_payload_landing"],
        sim["payload_landing"]
    );
    assert_eq!(sim["landing"]["body"], "transponder");
    assert_eq!(sim["payload_landing"]["body"], "capsule");
    assert!(
        sim["payload_landing"]["time_s"].as_f64() > sim["landing"]["time_s"].as_f64(),
        "{sim}"
    );
}

/// `--vehicle` and `--guidance-vehicle` fly around, and plan with, vehicle files, and the
/// report's header names each in the table and the JSON; a file that does not load is refused
/// by the flag's name with exit code 2.
#[test]
fn a_campaign_planned_with_a_vehicle_file_names_it_and_a_bad_file_is_refused() {
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config/vehicle/straplex.toml");
    let shipped = shipped.to_str().expect("utf-8 path");
    let tiny = [
        "montecarlo",
        "--runs",
        "2",
        "--altitude",
        "60",
        "--threads",
        "1",
    ];
    let mut args = tiny.to_vec();
    args.extend(["--guidance-vehicle", shipped, "--vehicle", shipped]);
    let table = stx(&args);
    assert!(
        table.status.success(),
        "{}",
        String::from_utf8_lossy(&table.stderr)
    );
    let header = String::from_utf8_lossy(&table.stdout)
        .lines()
        .next()
        .unwrap_or_default()
        .to_string();
    assert!(
        header.contains(&format!("guidance planned with: the glide of {shipped}"))
            && header.contains(&format!("vehicle: {shipped}")),
        "{header}"
    );
    args.push("--json");
    let report = json(&stx(&args));
    assert_eq!(report["guidance_vehicle"], shipped);
    assert_eq!(report["vehicle"], shipped);
    let mut plain = tiny.to_vec();
    plain.push("--json");
    let plain = json(&stx(&plain));
    assert!(plain.get("guidance_vehicle").is_none() && plain.get("vehicle").is_none());

    let dir = temp_dir("vehicle");
    let not_a_vehicle = dir.join("bad.toml");
    std::fs::write(&not_a_vehicle, "gravity_mps2 = \"down\"\n").expect("write");
    // A vehicle that loads but has no lift has no steady glide to plan with.
    let no_lift = dir.join("no-lift.toml");
    let text = std::fs::read_to_string(shipped)
        .expect("the shipped file")
        .replace("cl0 = 0.250", "cl0 = 0.0")
        .replace("cl_alpha = 2.300", "cl_alpha = 0.0")
        .replace("cl_ds = 0.21", "cl_ds = 0.0");
    std::fs::write(&no_lift, text).expect("write");
    let mut args = tiny.to_vec();
    args.extend(["--guidance-vehicle", no_lift.to_str().expect("path")]);
    let out = stx(&args);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--guidance-vehicle") && err.contains("no steady glide at symmetric brake 0"),
        "{err}"
    );
    for flag in ["--guidance-vehicle", "--vehicle"] {
        for file in [not_a_vehicle.to_str().expect("path"), "/nonexistent.toml"] {
            let mut args = tiny.to_vec();
            args.extend([flag, file]);
            let out = stx(&args);
            assert_eq!(out.status.code(), Some(2), "{flag} {file}");
            let err = String::from_utf8_lossy(&out.stderr);
            assert!(
                err.contains(flag) && err.contains(file),
                "{flag} {file}: {err}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
