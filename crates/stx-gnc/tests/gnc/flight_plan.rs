//! The plan as the operator asks for it (`stx_gnc::flight_path::plan`): latitude and longitude
//! in and out, the request's rules, and a uniform forecast's closed form through the geodetic
//! frame.

use stx_gnc::flight_path::{ForecastRow, PlanRequest, plan};
use stx_gnc::geo::LocalFrame;

fn evora() -> LocalFrame {
    LocalFrame::default()
}

/// 5 m/s from the west at every level, no error.
fn westerly() -> Vec<ForecastRow> {
    vec![ForecastRow {
        alt_msl_m: 0.0,
        speed_mps: 5.0,
        from_deg: 270.0,
        sigma_mps: Some(0.0),
    }]
}

#[test]
fn a_uniform_forecast_without_spread_bursts_downwind_by_wind_times_climb_over_rate() {
    let mut request = PlanRequest::new(evora(), westerly());
    request.ascent_rate_sigma_mps = 0.0;
    request.burst_altitude_sigma_m = 0.0;
    request.burst_altitude_msl_m = 20_000.0;
    request.runs = 10;
    let report = plan(&request).unwrap();
    let t = (20_000.0 - evora().alt_msl_m) / 5.0;
    let b = report.burst;
    // The mean rate defines the time to burst (to the Simpson rule's 0.1 %).
    assert!((b.time_s - t).abs() < 1e-3 * t, "{}", b.time_s);
    assert!((b.east_m - 5.0 * t).abs() < 1e-3 * 5.0 * t, "{}", b.east_m);
    assert!(b.north_m.abs() < 1e-6);
    assert!((b.alt_msl_m - 20_000.0).abs() < 1e-6);
    // East of the launch at the launch's latitude, by the frame's own conversion.
    let p = evora().to_ned(b.lat_deg, b.lon_deg, evora().alt_msl_m);
    assert!((p.y - b.east_m).abs() < 1e-3 && p.x.abs() < 1e-3);
    assert!(b.ellipse.semi_major_m < 1e-6);
    assert_eq!(report.landing_samples_lat_lon_deg.len(), 10);
    // No spread: every sample's disc is the same, and the region is that disc.
    assert_eq!(report.steered_region_best_probability, 1.0);
    assert_eq!(report.steered_region_probability, 0.5);
    assert!(report.steered_region_lat_lon_deg.len() > 100);
    assert!(report.target.is_none());
}

#[test]
fn a_target_at_the_drifted_air_mass_is_reachable_and_one_far_upwind_is_not() {
    let mut request = PlanRequest::new(evora(), westerly());
    request.runs = 200;
    let first = plan(&request).unwrap();
    // The unsteered landing lies on the edge of its reach disc (it glided straight
    // downwind): about half the samples' discs hold the mean landing.
    let landing = first.landing_unsteered;
    request.target_lat_lon_deg = Some([landing.lat_deg, landing.lon_deg]);
    let edge = plan(&request)
        .unwrap()
        .target
        .unwrap()
        .reachable_probability;
    assert!((0.3..0.7).contains(&edge), "{edge}");
    // The disc's centre, one glide upwind of it, is inside most samples' discs: all but those
    // whose slower or faster balloon moved their disc by more than its radius (σ of 0.5 m/s on
    // 5 m/s over a 35-km climb moves it by about 3.5 km against a 5-km radius).
    let radius = first.steered_reach_radius_m;
    let frame = evora();
    let centre = nalgebra::Vector3::new(landing.north_m, landing.east_m - radius, 0.0);
    let (lat, lon, _) = frame.to_geodetic(&centre);
    request.target_lat_lon_deg = Some([lat, lon]);
    let reach = plan(&request).unwrap().target.unwrap();
    assert!(
        reach.reachable_probability > edge + 0.2,
        "{reach:?} vs {edge}"
    );
    assert!((reach.from_unsteered_landing_m - radius).abs() < 1.0);
    // 50 km upwind of the launch: no sample's glide gets there.
    request.target_lat_lon_deg = Some([evora().lat_deg, evora().lon_deg - 0.6]);
    let far = plan(&request).unwrap();
    assert_eq!(far.target.unwrap().reachable_probability, 0.0);
    // The same request gives the same plan.
    assert_eq!(far, plan(&request).unwrap());
}

/// A change that breaks a good request.
type Change = Box<dyn Fn(&mut PlanRequest)>;

#[test]
fn bad_requests_are_refused_with_the_field_named() {
    let good = PlanRequest::new(evora(), westerly());
    let cases: Vec<(Change, &str)> = vec![
        (Box::new(|r| r.runs = 0), "runs"),
        (Box::new(|r| r.runs = 1_000_000), "runs"),
        (Box::new(|r| r.launch_lat_deg = f64::NAN), "launch_lat_deg"),
        (
            Box::new(|r| r.burst_altitude_msl_m = 200.0),
            "burst_altitude_msl_m",
        ),
        (
            Box::new(|r| r.ascent_rate_mps = -1.0),
            "`ascent_rate_mps` = -1",
        ),
        (
            Box::new(|r| r.ascent_rate_mps = 1e-300),
            "`ascent_rate_mps`",
        ),
        (
            Box::new(|r| r.burst_altitude_msl_m = 1e9),
            "`burst_altitude_msl_m` = 1000000000",
        ),
        (
            Box::new(|r| r.deploy_height_m = 40_000.0),
            "`deploy_height_m`",
        ),
        (Box::new(|r| r.deploy_height_m = -1.0), "`deploy_height_m`"),
        (
            Box::new(|r| r.burst_altitude_sigma_m = f64::INFINITY),
            "`burst_altitude_sigma_m`",
        ),
        (
            Box::new(|r| r.default_wind_sigma_mps = 1e6),
            "`default_wind_sigma_mps`",
        ),
        (Box::new(|r| r.forecast.clear()), "no rows"),
        (
            Box::new(|r| r.target_lat_lon_deg = Some([95.0, 0.0])),
            "target latitude",
        ),
        (
            Box::new(|r| r.ascent_rate_sigma_mps = -0.1),
            "ascent_rate_sigma_mps",
        ),
    ];
    for (change, expected) in cases {
        let mut r = good.clone();
        change(&mut r);
        let e = plan(&r).unwrap_err().to_string();
        assert!(e.contains(expected), "{expected}: {e}");
    }
}
