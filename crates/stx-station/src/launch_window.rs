//! Launch windows: the pre-flight plan asked for every launch time of a window over a GFS
//! forecast (`stx plan --gfs … --window FROM..TO --every 1h`, the Plan page's window strip
//! through `POST /api/plan/window`). For each launch time the wind over the launch site at
//! that time ([`GfsField::profile`], linear between forecast hours) is flown by the ordinary
//! plan ([`stx_gnc::flight_path::plan`]) with the same request and seed, so the launches
//! differ by their wind alone (common random numbers: a better share is the wind's, not the
//! draws'). Each launch gives its unsteered landing, its burst point and the share of samples
//! from which steering reaches the target, and the launches are ranked: the highest share
//! first, ties by how far the unsteered landing lies from the target.
//!
//! Pure: the field, the request and the times in, the report out. The launches are spread
//! over `threads` scoped threads (the caller decides how many cores a window may take: all of
//! them for `stx plan`, fewer on the station, whose link comes first).

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use stx_gnc::flight_path::{PlanError, PlanReport, PlanRequest, plan_each};
use stx_weather::{GfsError, GfsField, OffsetDateTime, format_time};

/// Most launch times one window may ask for (a week, hourly).
pub const MAX_LAUNCHES: usize = 168;

/// How many of the best-ranked launches are marked best.
pub const BEST_MARKED: u32 = 3;

/// The launch times of a window: from `from` to `to` (both RFC 3339, `to` included when the
/// step lands on it) every `every_s` seconds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct WindowTimes {
    /// The first launch time, RFC 3339.
    pub from: String,
    /// The last launch time at most, RFC 3339.
    pub to: String,
    /// Between launch times, s (≥ 60).
    pub every_s: u32,
}

/// A point of one launch's plan: the mean over its samples.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, JsonSchema)]
pub struct WindowPoint {
    /// Latitude, degrees north.
    pub lat_deg: f64,
    /// Longitude, degrees east.
    pub lon_deg: f64,
    /// Altitude above mean sea level, m.
    pub alt_msl_m: f64,
    /// Mean time after launch, s.
    pub time_s: f64,
}

/// One launch time of the window.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct WindowLaunch {
    /// The launch time, RFC 3339.
    pub launch_time: String,
    /// Where the balloon bursts.
    pub burst: WindowPoint,
    /// Where the parafoil lands unsteered.
    pub landing_unsteered: WindowPoint,
    /// Semi-major axis of the unsteered landing's 1-σ ellipse, m.
    pub landing_sigma_m: f64,
    /// Fraction of the samples from whose deploy point steering reaches the target, 0…1.
    pub reach_share: f64,
    /// Distance from the target to the mean unsteered landing, m.
    pub target_from_landing_m: f64,
    /// 1 for the best launch of the window, then 2, … (highest `reach_share` first, ties by
    /// the smaller `target_from_landing_m`, then the earlier time).
    pub rank: u32,
    /// Whether it is among the [`BEST_MARKED`] best-ranked.
    pub best: bool,
}

/// `POST /api/plan/window`'s answer and `stx plan --window --json`'s output.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct WindowReport {
    /// The GFS run the winds come from (its reference time), RFC 3339.
    pub gfs_run: String,
    /// The forecast hours the files cover, first and last, RFC 3339.
    pub forecast_span: [String; 2],
    /// The request every launch flew (its `forecast` empty: each launch flies the GFS wind
    /// over the launch site at its own time).
    pub request: PlanRequest,
    /// The window asked for.
    pub window: WindowTimes,
    /// Every launch time, earliest first.
    pub launches: Vec<WindowLaunch>,
}

/// Why a window cannot be planned: each one the request's or the files' fault.
#[derive(Debug, thiserror::Error)]
pub enum WindowError {
    /// A time is not RFC 3339.
    #[error("window.{field}: not an RFC 3339 time (2026-11-30T06:00:00Z): {text:?}")]
    Time {
        /// `from` or `to`.
        field: &'static str,
        /// What was given.
        text: String,
    },
    /// The times do not make a window.
    #[error("window: {0}")]
    Shape(String),
    /// The window reaches outside the files' forecast hours.
    #[error(
        "window {from}..{to} is outside the GFS files' forecast hours {first}..{last}: give \
         the files of the hours the window needs, or a window inside them"
    )]
    OutsideHours {
        /// The window's first launch, RFC 3339.
        from: String,
        /// Its last.
        to: String,
        /// The files' first forecast time.
        first: String,
        /// Their last.
        last: String,
    },
    /// A window ranks launches by their target: it needs one.
    #[error(
        "request.target_lat_lon_deg: a launch window needs a target (it ranks launches by how often steering reaches it)"
    )]
    NoTarget,
    /// The GFS field cannot give the wind over the launch site.
    #[error("{0}")]
    Gfs(#[from] GfsError),
    /// A launch's plan was refused.
    #[error("launch at {time}: request: {source}")]
    Plan {
        /// The launch time, RFC 3339.
        time: String,
        /// Why.
        #[source]
        source: PlanError,
    },
}

/// The launch times of `window` (see [`WindowTimes`]).
pub fn launch_times(window: &WindowTimes) -> Result<Vec<OffsetDateTime>, WindowError> {
    let parse = |field: &'static str, text: &str| {
        stx_weather::parse_time(text).map_err(|_| WindowError::Time {
            field,
            text: text.to_string(),
        })
    };
    let (from, to) = (parse("from", &window.from)?, parse("to", &window.to)?);
    if to < from {
        return Err(WindowError::Shape(format!(
            "`to` {} is before `from` {}",
            window.to, window.from
        )));
    }
    if window.every_s < 60 {
        return Err(WindowError::Shape(format!(
            "every_s = {}: launches at least 60 s apart",
            window.every_s
        )));
    }
    let count = ((to - from).whole_seconds() / i64::from(window.every_s)) as usize + 1;
    if count > MAX_LAUNCHES {
        return Err(WindowError::Shape(format!(
            "{count} launch times: at most {MAX_LAUNCHES} (a longer step, or a shorter window)"
        )));
    }
    let every_s = u64::from(window.every_s);
    Ok((0..count as u64)
        .map(|k| from + std::time::Duration::from_secs(every_s * k))
        .collect())
}

/// The window `times` over `field` for `request` (its forecast is replaced, launch by
/// launch), computed on `threads` threads (at least one).
pub fn plan_window(
    field: &GfsField,
    request: &PlanRequest,
    window: &WindowTimes,
    threads: usize,
) -> Result<WindowReport, WindowError> {
    let times = launch_times(window)?;
    let Some(target) = request.target_lat_lon_deg else {
        return Err(WindowError::NoTarget);
    };
    let valid = field.valid_times();
    let (first, last) = (valid[0], valid[valid.len() - 1]);
    let (from, to) = (times[0], times[times.len() - 1]);
    if from < first || to > last {
        return Err(WindowError::OutsideHours {
            from: format_time(from),
            to: format_time(to),
            first: format_time(first),
            last: format_time(last),
        });
    }
    // The launch site outside the files' box is said once, before any plan.
    field.profile(request.launch_lat_deg, request.launch_lon_deg, from)?;
    let threads = threads.clamp(1, times.len());
    let batch = PATHS_AT_ONCE / (request.runs as usize).max(1);
    // Interleaved, so each thread gets early and late launches alike. Each thread works its
    // samples' wind-free part out once for all its launches (`plan_each`): the same draws at
    // every launch are what lets it.
    let results: Vec<Result<Vec<(usize, PlanReport)>, WindowError>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|k| {
                let times = &times;
                s.spawn(move || {
                    let mine: Vec<usize> = (k..times.len()).step_by(threads).collect();
                    let at: Vec<OffsetDateTime> = mine.iter().map(|&i| times[i]).collect();
                    plan_at(field, request, &at, batch)
                        .map(|reports| mine.into_iter().zip(reports).collect())
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|_| Ok(Vec::new())))
            .collect()
    });
    let mut reports: Vec<Option<PlanReport>> = vec![None; times.len()];
    for r in results {
        for (i, report) in r? {
            reports[i] = Some(report);
        }
    }
    let mut launches = Vec::with_capacity(times.len());
    for (time, report) in times.iter().zip(reports) {
        // A thread that panicked left its launches out; never expected of the planner.
        let report = report.ok_or_else(|| WindowError::Shape("a launch was not planned".into()))?;
        launches.push(launch_of(*time, &report));
    }
    rank(&mut launches);
    let mut request = request.clone();
    request.forecast.clear();
    request.target_lat_lon_deg = Some(target);
    Ok(WindowReport {
        gfs_run: format_time(field.reference_time()),
        forecast_span: [format_time(first), format_time(last)],
        request,
        window: window.clone(),
        launches,
    })
}

/// The plans of `request` over the wind at the launch site at each of `times`, `batch`
/// launches at a time.
fn plan_at(
    field: &GfsField,
    request: &PlanRequest,
    times: &[OffsetDateTime],
    batch: usize,
) -> Result<Vec<PlanReport>, WindowError> {
    let mut forecasts = Vec::with_capacity(times.len());
    for &at in times {
        let levels = field.profile(request.launch_lat_deg, request.launch_lon_deg, at)?;
        forecasts.push(crate::forecast_file::rows(&levels));
    }
    let batch = batch.max(1);
    let mut reports = Vec::with_capacity(times.len());
    for (b, forecasts) in forecasts.chunks(batch).enumerate() {
        let planned = plan_each(request, forecasts).map_err(|(i, source)| WindowError::Plan {
            time: format_time(times[b * batch + i]),
            source,
        })?;
        reports.extend(planned);
    }
    Ok(reports)
}

/// Most sample paths one thread holds at once (about 170 bytes each): `plan_each` holds every
/// sample's path of every launch it is given until it takes their spreads, so launches go to it
/// in batches, and a week of 5000-sample launches stays within tens of megabytes for a
/// wind-free part worked out once a batch.
const PATHS_AT_ONCE: usize = 100_000;

fn launch_of(at: OffsetDateTime, report: &PlanReport) -> WindowLaunch {
    let point = |p: &stx_gnc::flight_path::plan::PlannedPoint| WindowPoint {
        lat_deg: p.lat_deg,
        lon_deg: p.lon_deg,
        alt_msl_m: p.alt_msl_m,
        time_s: p.time_s,
    };
    let target = report.target.as_ref();
    WindowLaunch {
        launch_time: format_time(at),
        burst: point(&report.burst),
        landing_unsteered: point(&report.landing_unsteered),
        landing_sigma_m: report.landing_unsteered.ellipse.semi_major_m,
        reach_share: target.map_or(0.0, |t| t.reachable_probability),
        target_from_landing_m: target.map_or(f64::NAN, |t| t.from_unsteered_landing_m),
        rank: 0,
        best: false,
    }
}

/// Ranks `launches` (earliest first) in place: see [`WindowLaunch::rank`].
fn rank(launches: &mut [WindowLaunch]) {
    let mut order: Vec<usize> = (0..launches.len()).collect();
    order.sort_by(|&a, &b| {
        let (a_l, b_l) = (&launches[a], &launches[b]);
        b_l.reach_share
            .total_cmp(&a_l.reach_share)
            .then(
                a_l.target_from_landing_m
                    .total_cmp(&b_l.target_from_landing_m),
            )
            .then(a.cmp(&b))
    });
    for (r, i) in order.into_iter().enumerate() {
        let rank = r as u32 + 1;
        launches[i].rank = rank;
        launches[i].best = rank <= BEST_MARKED;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use stx_gnc::flight_path::plan;

    fn window(from: &str, to: &str, every_s: u32) -> WindowTimes {
        WindowTimes {
            from: from.into(),
            to: to.into(),
            every_s,
        }
    }

    #[test]
    fn launch_times_step_from_the_start_and_stop_at_the_end() {
        let t = launch_times(&window(
            "2026-11-30T06:00:00Z",
            "2026-11-30T09:30:00Z",
            3600,
        ))
        .unwrap();
        let shown: Vec<String> = t.iter().map(|t| format_time(*t)).collect();
        assert_eq!(
            shown,
            [
                "2026-11-30T06:00:00Z",
                "2026-11-30T07:00:00Z",
                "2026-11-30T08:00:00Z",
                "2026-11-30T09:00:00Z"
            ]
        );
        let one = launch_times(&window("2026-11-30T06:00:00Z", "2026-11-30T06:00:00Z", 60));
        assert_eq!(one.unwrap().len(), 1);
    }

    #[test]
    fn bad_windows_are_refused_naming_what_is_wrong() {
        let cases = [
            (window("noon", "2026-11-30T06:00:00Z", 3600), "window.from"),
            (window("2026-11-30T06:00:00Z", "later", 3600), "window.to"),
            (
                window("2026-11-30T06:00:00Z", "2026-11-30T05:00:00Z", 3600),
                "is before",
            ),
            (
                window("2026-11-30T06:00:00Z", "2026-11-30T07:00:00Z", 59),
                "at least 60 s",
            ),
            (
                window("2026-11-01T00:00:00Z", "2026-11-30T00:00:00Z", 3600),
                "at most 168",
            ),
        ];
        for (w, expected) in cases {
            let e = launch_times(&w).unwrap_err().to_string();
            assert!(e.contains(expected), "{w:?}: {e}");
        }
    }

    fn launch(share: f64, distance_m: f64) -> WindowLaunch {
        let p = WindowPoint {
            lat_deg: 0.0,
            lon_deg: 0.0,
            alt_msl_m: 0.0,
            time_s: 0.0,
        };
        WindowLaunch {
            launch_time: String::new(),
            burst: p,
            landing_unsteered: p,
            landing_sigma_m: 0.0,
            reach_share: share,
            target_from_landing_m: distance_m,
            rank: 0,
            best: false,
        }
    }

    fn field() -> GfsField {
        let file = format!(
            "{}/../stx-weather/testdata/gfs_0p25_subset.grib2",
            env!("CARGO_MANIFEST_DIR")
        );
        crate::forecast_file::read_gfs(&[file.into()]).unwrap()
    }

    fn request() -> PlanRequest {
        let site = stx_gnc::geo::LocalFrame {
            lat_deg: 38.0,
            lon_deg: -8.0,
            alt_msl_m: 100.0,
        };
        let mut r = PlanRequest::new(site, Vec::new());
        r.runs = 40;
        r.burst_altitude_msl_m = 20_000.0;
        r.target_lat_lon_deg = Some([38.0, -7.5]);
        r
    }

    #[test]
    fn each_launch_is_the_plan_over_the_wind_at_its_time_on_any_number_of_threads() {
        let field = field();
        let w = window("2026-11-30T06:00:00Z", "2026-11-30T12:00:00Z", 5400);
        let report = plan_window(&field, &request(), &w, 2).unwrap();
        assert_eq!(report.gfs_run, "2026-11-30T06:00:00Z");
        assert_eq!(report.launches.len(), 5);
        assert!(report.request.forecast.is_empty());
        for (l, at) in report.launches.iter().zip(launch_times(&w).unwrap()) {
            assert_eq!(l.launch_time, format_time(at));
            let mut alone = request();
            alone.forecast = crate::forecast_file::gfs_rows(&field, 38.0, -8.0, Some(at)).unwrap();
            let p = plan(&alone).unwrap();
            assert_eq!(l.landing_unsteered.lat_deg, p.landing_unsteered.lat_deg);
            assert_eq!(l.burst.lon_deg, p.burst.lon_deg);
            assert_eq!(l.reach_share, p.target.unwrap().reachable_probability);
        }
        // The winds change with the hours (the fixture's grow 0.5 m/s an hour): so do the
        // landings.
        let first = report.launches[0].landing_unsteered;
        let last = report.launches[4].landing_unsteered;
        assert!(
            (first.lon_deg - last.lon_deg).abs() > 1e-3,
            "{first:?} {last:?}"
        );
        assert_eq!(plan_window(&field, &request(), &w, 1).unwrap(), report);
        let mut ranks: Vec<u32> = report.launches.iter().map(|l| l.rank).collect();
        ranks.sort_unstable();
        assert_eq!(ranks, [1, 2, 3, 4, 5]);
    }

    #[test]
    fn a_window_outside_the_hours_or_without_a_target_is_refused() {
        let field = field();
        let late = window("2026-11-30T10:00:00Z", "2026-11-30T13:00:00Z", 3600);
        let e = plan_window(&field, &request(), &late, 1)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(
                "outside the GFS files' forecast hours 2026-11-30T06:00:00Z..2026-11-30T12:00:00Z"
            ),
            "{e}"
        );
        let w = window("2026-11-30T06:00:00Z", "2026-11-30T07:00:00Z", 3600);
        let mut no_target = request();
        no_target.target_lat_lon_deg = None;
        let e = plan_window(&field, &no_target, &w, 1)
            .unwrap_err()
            .to_string();
        assert!(e.contains("target_lat_lon_deg"), "{e}");
        let mut far = request();
        far.launch_lat_deg = 45.0;
        let e = plan_window(&field, &far, &w, 1).unwrap_err().to_string();
        assert!(e.contains("outside the file's box"), "{e}");
        let mut bad = request();
        bad.runs = 0;
        let e = plan_window(&field, &bad, &w, 1).unwrap_err().to_string();
        assert!(
            e.contains("launch at 2026-11-30T06:00:00Z: request: `runs`"),
            "{e}"
        );
    }

    /// Pins the window's output from before each sample's wind-free part was worked out once
    /// for all launches (`stx plan --window` of that commit, 1ba4461): the restructuring
    /// does the same arithmetic in the same order, so the figures are the same to the last
    /// bit.
    #[test]
    fn regression_window_landings_are_those_of_the_launch_by_launch_planner() {
        let field = field();
        let mut r = request();
        r.target_lat_lon_deg = Some([37.85, -6.3]);
        let w = window("2026-11-30T06:00:00Z", "2026-11-30T12:00:00Z", 5400);
        let report = plan_window(&field, &r, &w, 2).unwrap();
        // Landing (lat, lon), burst (lat, lon), landing 1-σ, reach share, rank.
        let pinned: [([f64; 5], f64, u32); 5] = [
            (
                [
                    37.88831652607354,
                    -6.375257017427966,
                    37.958321594302866,
                    -6.948447913596561,
                    13512.862843124914,
                ],
                0.025,
                4,
            ),
            (
                [
                    37.85218876220431,
                    -6.319409076446586,
                    37.936024871074714,
                    -6.912893699083407,
                    13667.768772783755,
                ],
                0.1,
                1,
            ),
            (
                [
                    37.816093039804045,
                    -6.263558640139682,
                    37.913716531468516,
                    -6.877347560469708,
                    13844.986886075898,
                ],
                0.025,
                3,
            ),
            (
                [
                    37.782600860746996,
                    -6.208971397021413,
                    37.89280373676746,
                    -6.843275176982188,
                    14004.200647046306,
                ],
                0.1,
                2,
            ),
            (
                [
                    37.749157345399425,
                    -6.154360164564028,
                    37.87189011284021,
                    -6.809198119160678,
                    14182.008937246273,
                ],
                0.025,
                5,
            ),
        ];
        for (l, (figures, share, rank)) in report.launches.iter().zip(pinned) {
            let got = [
                l.landing_unsteered.lat_deg,
                l.landing_unsteered.lon_deg,
                l.burst.lat_deg,
                l.burst.lon_deg,
                l.landing_sigma_m,
            ];
            assert_eq!(got, figures, "{}", l.launch_time);
            assert_eq!((l.reach_share, l.rank), (share, rank), "{}", l.launch_time);
            assert_eq!(l.burst.time_s, 3961.9560255401475);
        }
        // Launches batched apart are planned as launches planned together.
        let times = launch_times(&w).unwrap();
        let one_by_one = plan_at(&field, &r, &times, 1).unwrap();
        assert_eq!(one_by_one, plan_at(&field, &r, &times, 5).unwrap());
    }

    #[test]
    fn the_highest_share_ranks_first_and_ties_go_to_the_nearer_landing() {
        let mut l = vec![
            launch(0.2, 900.0),
            launch(0.5, 4000.0),
            launch(0.5, 3000.0),
            launch(0.0, 100.0),
            launch(0.2, 800.0),
        ];
        rank(&mut l);
        let ranks: Vec<u32> = l.iter().map(|l| l.rank).collect();
        assert_eq!(ranks, [4, 2, 1, 5, 3]);
        let best: Vec<bool> = l.iter().map(|l| l.best).collect();
        assert_eq!(best, [false, true, true, false, true]);
    }
}
