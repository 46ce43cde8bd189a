//! ecCodes run live (`tests/peers/read_grib.py`, the `eccodes` package from PyPI, pinned
//! below) on every fixture and on the real GFS message, every value of the fixtures and
//! twenty thousand of the GFS field held against stx's decoding to [`ECCODES_TOLERANCE`].
//!
//! Python: `$STX_PYTHON`, or `.venv/bin/python` at the workspace root. To set it up:
//! `python3 -m venv .venv && .venv/bin/pip install eccodes==2.50.0 eccodeslib==2.50.0.33`
//! (tests/run-all does).

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

use crate::common::{compare_decoding, testdata};

const ECCODES: &str = "2.50.0";

fn python() -> PathBuf {
    let p = std::env::var_os("STX_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../.venv/bin/python"));
    assert!(
        p.exists(),
        "no Python at {} (set STX_PYTHON, or create the venv at the workspace root: \
         `python3 -m venv .venv && .venv/bin/pip install eccodes=={ECCODES} eccodeslib`)",
        p.display()
    );
    p
}

fn eccodes_reads(sample: Option<usize>, files: &[&str]) -> Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/peers/read_grib.py");
    let mut command = Command::new(python());
    command.arg(&script).current_dir(testdata(""));
    if let Some(n) = sample {
        command.arg("--sample").arg(n.to_string());
    }
    let out = command.args(files).output().expect("python runs");
    assert!(
        out.status.success(),
        "read_grib.py failed ({}): {}\n(is eccodes installed? `pip install eccodes=={ECCODES} eccodeslib`)",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).expect("JSON from read_grib.py");
    assert_eq!(
        v["eccodes"], ECCODES,
        "the test is pinned to ecCodes {ECCODES}"
    );
    v
}

#[test]
fn eccodes_live_reads_every_fixture_value_and_the_gfs_field_as_stx_does() {
    let fixtures = [
        "gfs_0p25_subset.grib2",
        "gfs_0p50_simple.grib2",
        "no_hgt.grib2",
    ];
    let v = eccodes_reads(None, &fixtures);
    let mut compared = 0;
    for name in fixtures {
        compared += compare_decoding(name, v["files"][name].as_array().unwrap());
    }
    // Every value: 99 + 24 messages of 357 and 99 points, and 4 of 9.
    assert_eq!(compared, 99 * 357 + 24 * 99 + 4 * 9);
    let gfs = "gdas.t12z.pgrb2.0p25.f000.12";
    let v = eccodes_reads(Some(20_000), &[gfs]);
    assert!(compare_decoding(gfs, v["files"][gfs].as_array().unwrap()) >= 20_000);
}
