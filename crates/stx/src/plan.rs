//! `stx plan --launch LAT,LON[,ALT] --forecast FILE …`: the pre-flight plan (burst, deploy
//! and landing regions, the target's reachability) from a forecast file (rows, GFS GRIB2 files
//! with `--gfs`, or a sounding with `--sounding`) and, if given, the wind an earlier recording
//! measured on its ascent. Argument parsing only; the files become rows in
//! `stx_station::forecast_file`, and the plan and the recording's wind are
//! `stx_station::preflight::preflight_plan`, as the station's `POST /api/plan`.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use stx_gnc::flight_path::plan::{MAX_RUNS, PlannedPoint};
use stx_gnc::flight_path::{Forecast, PlanRequest};
use stx_gnc::geo::LocalFrame;
use stx_station::forecast_file;
use stx_station::preflight::{MeasuredAscentView, preflight_plan};

use crate::BadInput;

#[derive(Args, Debug)]
pub struct PlanArgs {
    /// Launch site: latitude and longitude in degrees, and the ground's altitude above mean
    /// sea level in metres (default 0).
    #[arg(long, value_name = "LAT,LON[,ALT]", value_parser = parse_launch)]
    launch: LocalFrame,
    /// Forecast wind file, TOML or CSV (format: README, "Pre-flight planning").
    #[arg(
        long,
        value_name = "FILE",
        required_unless_present_any = ["from_recording", "gfs", "sounding"],
        conflicts_with_all = ["gfs", "sounding"]
    )]
    forecast: Option<PathBuf>,
    /// GFS GRIB2 files of one run (pgrb2 0.25° or 0.5°, or a NOMADS filter subset with UGRD,
    /// VGRD and HGT on isobaric levels around the launch site): the wind over the launch site
    /// at --launch-time.
    #[arg(long, value_name = "FILE", num_args = 1.., conflicts_with = "sounding")]
    gfs: Vec<PathBuf>,
    /// When the wind is taken from the GFS files, RFC 3339 (2026-11-30T12:00:00Z); default:
    /// their first forecast time.
    #[arg(long, value_name = "RFC3339", requires = "gfs", value_parser = parse_time)]
    launch_time: Option<stx_weather::OffsetDateTime>,
    /// A launch window over the GFS files: the plan for every launch time from FROM to TO
    /// (RFC 3339) every --every, printed as a table with the best times marked (needs
    /// --target).
    #[arg(
        long,
        value_name = "FROM..TO",
        requires_all = ["gfs", "target"],
        conflicts_with_all = ["launch_time", "from_recording"],
        value_parser = crate::plan_window::parse_window
    )]
    window: Option<(String, String)>,
    /// Between launch times of --window: 1h, 30m, 3h, 2h30m.
    #[arg(long, value_name = "DURATION", default_value = "1h", requires = "window", value_parser = crate::plan_window::parse_every)]
    every: u32,
    /// A radiosonde sounding as the University of Wyoming prints it (TEXT:LIST).
    #[arg(long, value_name = "FILE")]
    sounding: Option<PathBuf>,
    /// An earlier recording (MCAP) whose measured ascent wind replaces the forecast where it
    /// reaches.
    #[arg(long, value_name = "FILE.mcap")]
    from_recording: Option<PathBuf>,
    /// Mean ascent rate from launch to burst, m/s.
    #[arg(long, default_value_t = 5.0, value_name = "M/S")]
    ascent_rate: f64,
    /// 1-σ of the ascent rate, m/s.
    #[arg(long, default_value_t = 0.5, value_name = "M/S")]
    ascent_rate_sigma: f64,
    /// Burst altitude above mean sea level, m.
    #[arg(long, default_value_t = 35_000.0, value_name = "M")]
    burst_alt: f64,
    /// 1-σ of the burst altitude, m.
    #[arg(long, default_value_t = 1500.0, value_name = "M")]
    burst_alt_sigma: f64,
    /// Height above the launch site at which the parafoil deploys, m (onboard MIS_DEPLOY_M).
    #[arg(long, value_name = "M")]
    deploy_height: Option<f64>,
    /// 1-σ of each wind component where the forecast gives none, m/s.
    #[arg(long, default_value_t = 1.5, value_name = "M/S")]
    wind_sigma: f64,
    /// Landing target: latitude and longitude, degrees.
    #[arg(long, value_name = "LAT,LON", value_parser = parse_target)]
    target: Option<[f64; 2]>,
    /// Monte Carlo samples.
    #[arg(long, default_value_t = 500, value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_RUNS)))]
    runs: u32,
    /// Seed of the samples.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Print the plan as JSON (the station's POST /api/plan answer) instead of text.
    #[arg(long)]
    json: bool,
}

fn numbers(text: &str, counts: &[usize]) -> Result<Vec<f64>, String> {
    let values: Result<Vec<f64>, _> = text.split(',').map(|v| v.trim().parse::<f64>()).collect();
    match values {
        Ok(v) if counts.contains(&v.len()) && v.iter().all(|x| x.is_finite()) => Ok(v),
        _ => Err(format!(
            "expected {counts:?} comma-separated numbers, got `{text}`"
        )),
    }
}

fn parse_launch(text: &str) -> Result<LocalFrame, String> {
    let v = numbers(text, &[2, 3])?;
    Ok(LocalFrame {
        lat_deg: v[0],
        lon_deg: v[1],
        alt_msl_m: v.get(2).copied().unwrap_or(0.0),
    })
}

fn parse_time(text: &str) -> Result<stx_weather::OffsetDateTime, String> {
    stx_weather::parse_time(text).map_err(|e| format!("not an RFC 3339 time ({e}): `{text}`"))
}

fn parse_target(text: &str) -> Result<[f64; 2], String> {
    let v = numbers(text, &[2])?;
    Ok([v[0], v[1]])
}

pub fn run(args: PlanArgs) -> anyhow::Result<()> {
    let forecast = match &args.forecast {
        None if !args.gfs.is_empty() => {
            let field = forecast_file::read_gfs(&args.gfs).map_err(bad_input)?;
            if let Some(window) = args.window.clone() {
                let request = request_of(&args, Vec::new());
                return crate::plan_window::run(&field, &request, window, args.every, args.json);
            }
            let at = args.launch_time.unwrap_or_else(|| field.valid_times()[0]);
            let rows =
                forecast_file::gfs_rows(&field, args.launch.lat_deg, args.launch.lon_deg, Some(at))
                    .map_err(bad_input)?;
            eprintln!(
                "GFS run {}: the wind at {} over the launch site, {} levels",
                stx_weather::format_time(field.reference_time()),
                stx_weather::format_time(at),
                rows.len()
            );
            rows
        }
        None if args.sounding.is_some() => {
            let path = args.sounding.as_deref().expect("matched");
            forecast_file::read_sounding(path).map_err(bad_input)?
        }
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read the forecast {}", path.display()))
                .map_err(BadInput)?;
            Forecast::parse(&text)
                .with_context(|| format!("forecast {}", path.display()))
                .map_err(BadInput)?
                .rows()
                .to_vec()
        }
        // clap requires --from-recording then, whose bands make the forecast.
        None => Vec::new(),
    };
    let request = request_of(&args, forecast);
    let recording = args
        .from_recording
        .as_ref()
        .map(|p| (p.display().to_string(), p.clone()));
    let report = preflight_plan(
        request,
        recording
            .as_ref()
            .map(|(name, path)| (name.as_str(), path.as_path())),
    )
    .map_err(|e| BadInput(e.into()))?;
    if let Some(measured) = &report.measured_ascent {
        print_measured(measured);
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(());
    }
    let request = &report.plan.request;
    let report = &report.plan;
    let line = |name: &str, p: &PlannedPoint| {
        println!(
            "{name:<26} {:>10.5} {:>10.5} {:>7.0} m MSL  {:>6.0} m N {:>7.0} m E  T+{} ±{:.0} s  1σ {:.0} × {:.0} m at {:.0}°",
            p.lat_deg,
            p.lon_deg,
            p.alt_msl_m,
            p.north_m,
            p.east_m,
            clock(p.time_s),
            p.time_sigma_s,
            p.ellipse.semi_major_m,
            p.ellipse.semi_minor_m,
            p.ellipse.major_axis_rad.to_degrees().rem_euclid(180.0)
        );
    };
    println!(
        "plan from {:.5}, {:.5} ({:.0} m MSL): {} samples, seed {}",
        request.launch_lat_deg,
        request.launch_lon_deg,
        request.launch_alt_msl_m,
        request.runs,
        request.seed
    );
    line("burst", &report.burst);
    line("parafoil deploy", &report.deploy);
    line("landing, unsteered", &report.landing_unsteered);
    line("landing, round chute only", &report.round_chute_landing);
    println!(
        "steering reaches {:.0} m around the drifted air mass on average ({})",
        report.steered_reach_radius_m, report.reach_method
    );
    println!(
        "no point is reached in more than {:.0} % of the samples; the steered region is reached in {:.0} % or more",
        100.0 * report.steered_region_best_probability,
        100.0 * report.steered_region_probability
    );
    if let Some(t) = &report.target {
        println!(
            "target {:.5}, {:.5}: reachable in {:.0} % of the samples, {:.0} m from the unsteered landing",
            t.lat_deg,
            t.lon_deg,
            100.0 * t.reachable_probability,
            t.from_unsteered_landing_m
        );
    }
    Ok(())
}

/// The plan request of the flags, over `forecast`.
fn request_of(args: &PlanArgs, forecast: Vec<stx_gnc::flight_path::ForecastRow>) -> PlanRequest {
    let mut request = PlanRequest::new(args.launch, forecast);
    request.ascent_rate_mps = args.ascent_rate;
    request.ascent_rate_sigma_mps = args.ascent_rate_sigma;
    request.burst_altitude_msl_m = args.burst_alt;
    request.burst_altitude_sigma_m = args.burst_alt_sigma;
    if let Some(h) = args.deploy_height {
        request.deploy_height_m = h;
    }
    request.default_wind_sigma_mps = args.wind_sigma;
    request.target_lat_lon_deg = args.target;
    request.runs = args.runs;
    request.seed = args.seed;
    request
}

/// The recording's bands on stderr, each merged or refused with its reason.
fn print_measured(measured: &MeasuredAscentView) {
    let merged = measured
        .bands
        .iter()
        .filter(|b| b.refused.is_none())
        .count();
    eprintln!(
        "{}: {} measured wind bands, {merged} merged into the forecast:",
        measured.recording,
        measured.bands.len()
    );
    for b in &measured.bands {
        let sigma = b.sigma_north_mps.max(b.sigma_east_mps);
        let verdict = b
            .refused
            .as_ref()
            .map_or("merged".to_string(), |r| format!("REFUSED: {r}"));
        eprintln!(
            "  {:>6.0}–{:<6.0} m MSL  {:>6.1} m/s from {:>3.0}°  1σ {:.2} m/s  {verdict}",
            b.alt_min_msl_m, b.alt_max_msl_m, b.speed_mps, b.from_deg, sigma
        );
    }
}

fn bad_input(message: String) -> BadInput {
    BadInput(anyhow::anyhow!(message))
}

/// `h:mm:ss`.
fn clock(seconds: f64) -> String {
    let s = seconds.max(0.0).round() as u64;
    format!("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}
