//! `stx plan --gfs FILE… --window FROM..TO --every 1h --target LAT,LON`: the plan for every
//! launch time of a window (`stx_station::launch_window`, as the Plan page's window strip),
//! printed as a table with the best launch times marked, or as JSON. Parsing of the window's
//! flags and the printing only.

use stx_gnc::flight_path::PlanRequest;
use stx_station::launch_window::{BEST_MARKED, WindowReport, WindowTimes, plan_window};
use stx_weather::GfsField;

use crate::BadInput;

/// `FROM..TO`, two RFC 3339 times.
pub fn parse_window(text: &str) -> Result<(String, String), String> {
    let (from, to) = text
        .split_once("..")
        .ok_or_else(|| format!("expected FROM..TO (two RFC 3339 times), got `{text}`"))?;
    for t in [from, to] {
        stx_weather::parse_time(t).map_err(|e| format!("not an RFC 3339 time ({e}): `{t}`"))?;
    }
    Ok((from.to_string(), to.to_string()))
}

/// A step such as `1h`, `30m`, `90s` or `2h30m`, in seconds.
pub fn parse_every(text: &str) -> Result<u32, String> {
    let bad = || format!("expected a duration such as 1h, 30m, 3h or 90m, got `{text}`");
    let mut total: u64 = 0;
    let mut digits = String::new();
    for c in text.trim().chars() {
        if c.is_ascii_digit() {
            digits.push(c);
            continue;
        }
        let unit = match c {
            'h' => 3600,
            'm' => 60,
            's' => 1,
            _ => return Err(bad()),
        };
        let n: u64 = digits.parse().map_err(|_| bad())?;
        total = total.saturating_add(n.saturating_mul(unit));
        digits.clear();
    }
    if !digits.is_empty() || total == 0 {
        return Err(bad());
    }
    u32::try_from(total).map_err(|_| bad())
}

/// Plans the window over `field` and prints it.
pub fn run(
    field: &GfsField,
    request: &PlanRequest,
    (from, to): (String, String),
    every_s: u32,
    json: bool,
) -> anyhow::Result<()> {
    let window = WindowTimes { from, to, every_s };
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let started = std::time::Instant::now();
    let report = plan_window(field, request, &window, threads).map_err(|e| BadInput(e.into()))?;
    eprintln!(
        "{} launches × {} samples in {:.1} s on {threads} threads",
        report.launches.len(),
        request.runs,
        started.elapsed().as_secs_f64()
    );
    if json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_table(&report);
    }
    Ok(())
}

fn print_table(report: &WindowReport) {
    let r = &report.request;
    let [lat, lon] = r.target_lat_lon_deg.unwrap_or([f64::NAN; 2]);
    println!(
        "launch window from {:.5}, {:.5}: GFS run {}, {} samples a launch, seed {}, target {lat:.5}, {lon:.5}",
        r.launch_lat_deg, r.launch_lon_deg, report.gfs_run, r.runs, r.seed
    );
    println!(
        "{:<22} {:>9} {:>10} {:>7}  {:>9} {:>10} {:>7}  {:>6} {:>9}  {:>4}",
        "launch (UTC)",
        "burst lat",
        "burst lon",
        "alt m",
        "land lat",
        "land lon",
        "1σ m",
        "reach",
        "target m",
        "rank"
    );
    for l in &report.launches {
        let (b, g) = (&l.burst, &l.landing_unsteered);
        println!(
            "{:<22} {:>9.5} {:>10.5} {:>7.0}  {:>9.5} {:>10.5} {:>7.0}  {:>5.0}% {:>9.0}  {:>4}{}",
            l.launch_time,
            b.lat_deg,
            b.lon_deg,
            b.alt_msl_m,
            g.lat_deg,
            g.lon_deg,
            l.landing_sigma_m,
            100.0 * l.reach_share,
            l.target_from_landing_m,
            l.rank,
            if l.best { "  ★ best" } else { "" }
        );
    }
    println!(
        "★: the {BEST_MARKED} best launch times (the highest share of samples from which steering reaches the target; ties: the unsteered landing nearer the target)"
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_and_windows_parse_or_say_what_they_expect() {
        assert_eq!(parse_every("1h"), Ok(3600));
        assert_eq!(parse_every("90m"), Ok(5400));
        assert_eq!(parse_every("2h30m"), Ok(9000));
        assert_eq!(parse_every("45s"), Ok(45));
        for bad in ["", "h", "1", "1d", "0h", "-1h"] {
            assert!(parse_every(bad).is_err(), "{bad}");
        }
        let w = parse_window("2026-11-30T06:00:00Z..2026-12-03T06:00:00Z").unwrap();
        assert_eq!(w.1, "2026-12-03T06:00:00Z");
        assert!(parse_window("2026-11-30T06:00:00Z").is_err());
        assert!(parse_window("2026-11-30T06:00:00Z..tomorrow").is_err());
    }
}
