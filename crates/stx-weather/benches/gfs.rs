//! The goals of issue 31, measured: a 0.25° GFS subset of 50 × 50 points, 31 levels and 20
//! forecast hours opens in 2 s or less, and a 500-sample plan over its wind in 1 s or less; a
//! 72-hour launch window of hourly launches × 200 samples (`stx plan --window`, on every core)
//! in 10 s or less.
//!
//! The subsets are written once by ecCodes (`testdata/make_fixtures.py --bench` and
//! `--window-bench`, in GFS' complex packing) into `target/`, with the workspace's `.venv`
//! Python or `$STX_PYTHON`; later runs reuse them.
//!
//! `cargo bench -p stx-weather --bench gfs` (`-- window` for the window alone)

use std::path::{Path, PathBuf};
use std::process::Command;

use criterion::{Criterion, criterion_group, criterion_main};
use stx_gnc::flight_path::{PlanRequest, plan};
use stx_gnc::geo::LocalFrame;
use stx_station::launch_window::{WindowTimes, plan_window};
use stx_weather::GfsField;

/// The file `name` in `target/`, written by `make_fixtures.py flag` if missing.
fn subset(name: &str, flag: &str) -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let file = root.join("target").join(name);
    if !file.exists() {
        let python = std::env::var_os("STX_PYTHON")
            .map(PathBuf::from)
            .unwrap_or_else(|| root.join(".venv/bin/python"));
        let status = Command::new(&python)
            .arg(root.join("crates/stx-weather/testdata/make_fixtures.py"))
            .arg(flag)
            .arg(&file)
            .status()
            .unwrap_or_else(|e| panic!("{} with ecCodes writes the subset: {e}", python.display()));
        assert!(status.success(), "make_fixtures.py {flag} failed");
    }
    file
}

fn open(file: &Path) -> GfsField {
    let bytes = std::fs::read(file).unwrap();
    GfsField::from_files([("bench", bytes.as_slice())]).unwrap()
}

fn benches(c: &mut Criterion) {
    let file = subset("gfs-bench-50x50x31x20.grib2", "--bench");
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

/// The launch window: 73 hourly launches (0 to 72 h) × 200 samples, on every core.
fn window(c: &mut Criterion) {
    let field = open(&subset("gfs-window-20x20x31x26.grib2", "--window-bench"));
    assert_eq!(field.valid_times().len(), 26);
    let launch = LocalFrame {
        lat_deg: 43.8,
        lon_deg: 6.1,
        alt_msl_m: 300.0,
    };
    let mut request = PlanRequest::new(launch, Vec::new());
    request.runs = 200;
    request.target_lat_lon_deg = Some([43.7, 6.5]);
    let first = field.valid_times()[0];
    let window = WindowTimes {
        from: stx_weather::format_time(first),
        to: stx_weather::format_time(first + std::time::Duration::from_secs(72 * 3600)),
        every_s: 3600,
    };
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut group = c.benchmark_group("window");
    group.sample_size(10);
    group.bench_function(
        format!("72 h hourly x 200 samples on {threads} threads (goal <= 10 s)"),
        |b| {
            b.iter(|| {
                let report = plan_window(&field, &request, &window, threads).unwrap();
                assert_eq!(report.launches.len(), 73);
                report
            })
        },
    );
    group.finish();
}

criterion_group!(gfs, benches, window);
criterion_main!(gfs);
