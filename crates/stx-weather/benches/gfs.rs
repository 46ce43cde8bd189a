//! The goals of issue 31, measured: a 0.25° GFS subset of 50 × 50 points, 31 levels and 20
//! forecast hours opens in 2 s or less, and a 500-sample plan over its wind in 1 s or less.
//!
//! The subset is written once by ecCodes (`testdata/make_fixtures.py --bench`, in GFS' complex
//! packing) into `target/gfs-bench-50x50x31x20.grib2`, with the workspace's `.venv` Python or
//! `$STX_PYTHON`; later runs reuse it.
//!
//! `cargo bench -p stx-weather --bench gfs`

use std::path::{Path, PathBuf};
use std::process::Command;

use criterion::{Criterion, criterion_group, criterion_main};
use stx_gnc::flight_path::{PlanRequest, plan};
use stx_gnc::geo::LocalFrame;
use stx_weather::GfsField;

fn subset() -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let file = root.join("target/gfs-bench-50x50x31x20.grib2");
    if !file.exists() {
        let python = std::env::var_os("STX_PYTHON")
            .map(PathBuf::from)
            .unwrap_or_else(|| root.join(".venv/bin/python"));
        let status = Command::new(&python)
            .arg(root.join("crates/stx-weather/testdata/make_fixtures.py"))
            .arg("--bench")
            .arg(&file)
            .status()
            .unwrap_or_else(|e| panic!("{} with ecCodes writes the subset: {e}", python.display()));
        assert!(status.success(), "make_fixtures.py --bench failed");
    }
    file
}

fn open(file: &Path) -> GfsField {
    let bytes = std::fs::read(file).unwrap();
    GfsField::from_files([("bench", bytes.as_slice())]).unwrap()
}

fn benches(c: &mut Criterion) {
    let file = subset();
    let field = open(&file);
    assert_eq!(field.shape(), (50, 50));
    assert_eq!(
        (field.levels_pa().len(), field.valid_times().len()),
        (31, 20)
    );
    let mut group = c.benchmark_group("gfs");
    group.sample_size(10);
    group.bench_function("open 50x50x31x20 subset (goal <= 2 s)", |b| {
        b.iter(|| open(&file))
    });
    // Launch in the box, between forecast hours, the rows as `stx plan --gfs` takes them.
    let at = field.valid_times()[4] + std::time::Duration::from_secs(5400);
    let rows = stx_station::forecast_file::gfs_rows(&field, 43.8, 6.1, Some(at)).unwrap();
    let launch = LocalFrame {
        lat_deg: 43.8,
        lon_deg: 6.1,
        alt_msl_m: 300.0,
    };
    let mut request = PlanRequest::new(launch, rows);
    request.runs = 500;
    request.target_lat_lon_deg = Some([43.7, 6.5]);
    group.bench_function("plan 500 samples over the GFS wind (goal <= 1 s)", |b| {
        b.iter(|| plan(&request).unwrap())
    });
    group.bench_function("profile at a place and time", |b| {
        b.iter(|| field.profile(43.8, 6.1, at).unwrap())
    });
    group.finish();
}

criterion_group!(gfs, benches);
criterion_main!(gfs);
