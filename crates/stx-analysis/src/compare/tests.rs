use super::*;
use crate::flight_log::synthetic::{SyntheticFlight, simulate};
use stx_dynamics::vehicle::{STRAPLEX_TOML, VehicleConfig};

fn nominal() -> VehicleConfig {
    VehicleConfig::from_toml_str(STRAPLEX_TOML).unwrap()
}

fn figures(report: &CompareReport) -> String {
    report
        .channels
        .iter()
        .map(|c| {
            format!(
                "{} rms {:.3} max {:.3} bias {:.3}",
                c.name, c.error.rms, c.error.max_abs, c.error.bias
            )
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn the_same_vehicle_follows_its_flight_and_a_perturbed_one_does_not() {
    let truth = nominal().validate().unwrap();
    let log = simulate(&truth, &SyntheticFlight::manoeuvres(1)).unwrap();
    let same = compare(&log, &truth, &CompareOptions::default()).unwrap();
    eprintln!("same vehicle:\n{}", figures(&same));
    let mut other = nominal();
    other.canopy.aero.cl_alpha *= 0.75;
    other.canopy.aero.cd0 *= 1.3;
    other.canopy.brakes.cn_da *= 1.5;
    let other = compare(&log, &other.validate().unwrap(), &CompareOptions::default()).unwrap();
    eprintln!("perturbed vehicle:\n{}", figures(&other));
    assert_eq!(same.time_s.len(), log.samples().len());
    assert_eq!(same.channels.len(), 9);
    let rms = |r: &CompareReport, c: &str| r.channel(c).unwrap().error.rms;
    // Bounds from the measured figures (printed above) with room for the noise.
    for (c, bound) in [
        ("north_m", 5.0),
        ("east_m", 5.0),
        ("height_m", 5.0),
        ("roll_deg", 3.0),
        ("pitch_deg", 3.0),
        ("yaw_deg", 8.0),
        ("turn_rate_deg_s", 5.0),
        ("airspeed_mps", 0.5),
        ("sink_mps", 0.3),
    ] {
        assert!(rms(&same, c) < bound, "{c}: {} ≥ {bound}", rms(&same, c));
    }
    for c in ["north_m", "east_m", "height_m", "yaw_deg"] {
        assert!(
            rms(&other, c) > 3.0 * rms(&same, c),
            "{c}: perturbed {} vs same {}",
            rms(&other, c),
            rms(&same, c)
        );
    }
}

#[test]
fn error_figures_and_wrapping() {
    let f = ErrorFigures::of([1.0, -3.0, f64::NAN]);
    assert_eq!(f.count, 2);
    assert_eq!(f.max_abs, 3.0);
    assert_eq!(f.bias, -1.0);
    assert!((f.rms - 5.0_f64.sqrt()).abs() < 1e-12);
    assert_eq!(wrap_deg(350.0), -10.0);
    assert_eq!(wrap_deg(-190.0), 170.0);
}

#[test]
fn a_watched_replay_reports_each_sample_and_stops_when_told() {
    let vehicle = nominal().validate().unwrap();
    let log = simulate(&vehicle, &SyntheticFlight::manoeuvres(2)).unwrap();
    let total = log.samples().len();
    let mut seen = Vec::new();
    let flown = fly_watched(&log, &vehicle, DEFAULT_STEP_S, |done, all| {
        seen.push((done, all));
        true
    })
    .unwrap();
    assert_eq!(flown.len(), total);
    assert_eq!(seen.first(), Some(&(1, total)));
    assert_eq!(seen.last(), Some(&(total, total)));
    let stop_at = 5;
    let stopped = fly_watched(&log, &vehicle, DEFAULT_STEP_S, |done, _| done < stop_at);
    assert_eq!(
        stopped,
        Err(ReplayError::Stopped {
            time_s: log.samples()[stop_at - 1].time_s
        })
    );
}
