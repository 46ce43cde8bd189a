//! Tests of the sensors against their configuration: rates, latencies, noise, biases,
//! dropouts and the determinism of the seeded streams.

use super::*;
use std::sync::Arc;
use stx_dynamics::atmosphere::{Atmosphere, StandardAtmosphere};
use stx_dynamics::model::Environment;
use stx_dynamics::rotation::wrap_pi;
use stx_dynamics::state::Pose;
use stx_dynamics::vehicle::Vehicle;
use stx_dynamics::wind::ConstantWind;
use stx_gnc::measurement::{AirDataSample, AttitudeSample, GpsFix};

const TICK_S: f64 = 0.05;

/// A drone gliding north-east at 1000 m with 7 m/s along its x axis.
fn truth_at(time_s: f64) -> Truth {
    Truth {
        time_s,
        position_ned_m: Vector3::new(100.0, -50.0, -1000.0),
        velocity_ned_mps: Vector3::new(4.0, 3.0, 3.0),
        euler_rad: Vector3::new(0.05, -0.1, 0.6),
        euler_rate_rad_s: Vector3::zeros(),
        air_velocity_body_mps: Vector3::new(7.0, 0.3, 2.2),
        wind_ned_mps: Vector3::new(-1.0, 2.0, 0.0),
        air: StandardAtmosphere.air_at(1000.0),
    }
}

/// A configuration with every error switched off, for exact checks.
fn noiseless() -> SensorConfig {
    let mut c = SensorConfig::default();
    let g = &mut c.gps;
    g.horizontal_noise_m = 0.0;
    g.vertical_noise_m = 0.0;
    g.horizontal_wander_m = 0.0;
    g.vertical_wander_m = 0.0;
    g.velocity_noise_mps = 0.0;
    g.vertical_velocity_noise_mps = 0.0;
    let a = &mut c.ahrs;
    a.roll_noise_deg = 0.0;
    a.pitch_noise_deg = 0.0;
    a.yaw_noise_deg = 0.0;
    a.roll_bias_sigma_deg = 0.0;
    a.pitch_bias_sigma_deg = 0.0;
    a.yaw_bias_sigma_deg = 0.0;
    a.yaw_bias_random_walk_deg_per_sqrt_s = 0.0;
    let p = &mut c.pitot;
    p.differential_noise_pa = 0.0;
    p.differential_offset_sigma_pa = 0.0;
    p.differential_offset_random_walk_pa_per_sqrt_s = 0.0;
    p.static_noise_pa = 0.0;
    p.static_bias_sigma_pa = 0.0;
    p.temperature_noise_k = 0.0;
    p.temperature_bias_sigma_k = 0.0;
    c
}

/// Every delivery of a run of `duration_s` ticked every 0.05 s.
fn run(config: &SensorConfig, seed: u64, duration_s: f64) -> Vec<Delivery> {
    let mut suite = SensorSuite::new(config, seed).expect("valid config");
    let ticks = (duration_s / TICK_S).round() as usize;
    (0..ticks)
        .flat_map(|k| {
            let t = k as f64 * TICK_S;
            suite.sample(t, &truth_at(t))
        })
        .collect()
}

fn gps(d: &[Delivery]) -> Vec<GpsFix> {
    d.iter()
        .filter_map(|d| match d.measurement {
            Measurement::Gps(g) => Some(g),
            _ => None,
        })
        .collect()
}

fn attitude(d: &[Delivery]) -> Vec<AttitudeSample> {
    d.iter()
        .filter_map(|d| match d.measurement {
            Measurement::Attitude(a) => Some(a),
            _ => None,
        })
        .collect()
}

fn air_data(d: &[Delivery]) -> Vec<AirDataSample> {
    d.iter()
        .filter_map(|d| match d.measurement {
            Measurement::AirData(a) => Some(a),
            _ => None,
        })
        .collect()
}

fn mean_and_sigma(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let v: Vec<f64> = values.collect();
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, var.sqrt())
}

#[test]
fn each_sensor_samples_at_its_own_rate_and_phase() {
    let mut c = SensorConfig::default();
    c.gps.rate_hz = 4.0;
    c.gps.phase_s = 0.1;
    c.ahrs.rate_hz = 10.0;
    c.pitot.rate_hz = 5.0;
    let d = run(&c, 1, 100.0);
    let fixes = gps(&d);
    assert_eq!(fixes.len(), 400);
    assert!((fixes[0].time_s - 0.1).abs() < 1e-9);
    for pair in fixes.windows(2) {
        assert!((pair[1].time_s - pair[0].time_s - 0.25).abs() < 1e-9);
    }
    assert_eq!(attitude(&d).len(), 1000);
    assert_eq!(air_data(&d).len(), 500);
}

#[test]
fn a_tick_coarser_than_the_period_skips_samples_rather_than_bunching_them() {
    let mut c = SensorConfig::default();
    c.ahrs.rate_hz = 50.0;
    let mut suite = SensorSuite::new(&c, 1).expect("valid");
    let mut count = 0;
    for k in 0..100 {
        let t = k as f64 * 0.1;
        count += attitude(&suite.sample(t, &truth_at(t))).len();
    }
    assert_eq!(count, 100, "one sample per call, none invented");
}

#[test]
fn arrival_is_the_sampled_instant_plus_the_sensors_latency() {
    let mut c = SensorConfig::default();
    c.gps.latency_s = 0.3;
    c.ahrs.latency_s = 0.02;
    c.pitot.latency_s = 0.07;
    for d in run(&c, 2, 10.0) {
        let latency = match d.measurement {
            Measurement::Gps(_) => 0.3,
            Measurement::Attitude(_) => 0.02,
            Measurement::AirData(_) => 0.07,
        };
        assert!((d.arrival_s - d.measurement.time_s() - latency).abs() < 1e-12);
    }
}

#[test]
fn without_errors_the_sensors_report_the_truth() {
    let d = run(&noiseless(), 3, 5.0);
    let truth = truth_at(0.0);
    let fix = gps(&d)[3];
    assert!((fix.position_ned_m - truth.position_ned_m).norm() < 1e-12);
    assert!((fix.velocity_ned_mps - truth.velocity_ned_mps).norm() < 1e-12);
    let a = attitude(&d)[3];
    assert!((Vector3::new(a.roll_rad, a.pitch_rad, a.yaw_rad) - truth.euler_rad).norm() < 1e-12);
    let p = air_data(&d)[3];
    assert!((p.static_pressure_pa - truth.air.pressure_pa).abs() < 1e-9);
    assert!((p.temperature_k - truth.air.temperature_k).abs() < 1e-9);
    // Bernoulli with the density from p and T gives back u_x (the ideal-gas constants
    // of the atmosphere and the measurement agree to 1e-6).
    let u_x = truth.air_velocity_body_mps.x;
    assert!((p.indicated_airspeed_mps() - u_x).abs() < 1e-4 * u_x);
}

#[test]
fn air_from_behind_gives_a_negative_differential_pressure_and_no_airspeed() {
    let mut suite = SensorSuite::new(&noiseless(), 4).expect("valid");
    let mut truth = truth_at(0.0);
    truth.air_velocity_body_mps.x = -3.0;
    let p = air_data(&suite.sample(0.0, &truth))[0];
    let rho = truth.air.density_kg_per_m3;
    assert!((p.differential_pressure_pa + 0.5 * rho * 9.0).abs() < 1e-9);
    assert_eq!(p.indicated_airspeed_mps(), 0.0);
}

#[test]
fn noise_has_the_configured_spread_and_biases_are_drawn_once() {
    let mut c = noiseless();
    c.gps.horizontal_noise_m = 0.8;
    c.gps.velocity_noise_mps = 0.2;
    c.ahrs.yaw_noise_deg = 1.5;
    c.ahrs.yaw_bias_sigma_deg = 3.0;
    c.pitot.differential_noise_pa = 0.5;
    c.pitot.differential_offset_sigma_pa = 0.4;
    let truth = truth_at(0.0);
    let d = run(&c, 5, 1000.0);
    let fixes = gps(&d);
    let (mean, sigma) = mean_and_sigma(
        fixes
            .iter()
            .map(|f| f.position_ned_m.x - truth.position_ned_m.x),
    );
    assert!(
        mean.abs() < 0.05 && (sigma / 0.8 - 1.0).abs() < 0.05,
        "{mean} {sigma}"
    );
    let (mean, sigma) = mean_and_sigma(
        fixes
            .iter()
            .map(|f| f.velocity_ned_mps.y - truth.velocity_ned_mps.y),
    );
    assert!(
        mean.abs() < 0.02 && (sigma / 0.2 - 1.0).abs() < 0.05,
        "{mean} {sigma}"
    );

    let suite = SensorSuite::new(&c, 5).expect("valid");
    let bias = suite.ahrs_bias_rad().z;
    let (mean, sigma) = mean_and_sigma(
        attitude(&d)
            .iter()
            .map(|a| wrap_pi(a.yaw_rad - truth.euler_rad.z)),
    );
    assert!((mean - bias).abs() < 1e-3, "mean {mean} is the bias {bias}");
    assert!((sigma / 1.5f64.to_radians() - 1.0).abs() < 0.05);

    let offset = suite.differential_offset_pa();
    let rho = truth.air.density_kg_per_m3;
    let u_x = truth.air_velocity_body_mps.x;
    let (mean, sigma) = mean_and_sigma(
        air_data(&d)
            .iter()
            .map(|p| p.differential_pressure_pa - 0.5 * rho * u_x * u_x),
    );
    assert!(
        (mean - offset).abs() < 0.02,
        "mean {mean} is the offset {offset}"
    );
    assert!((sigma / 0.5 - 1.0).abs() < 0.05);

    // Over seeds the biases spread as configured.
    let biases: Vec<f64> = (0..400)
        .map(|seed| {
            SensorSuite::new(&c, seed)
                .expect("valid")
                .ahrs_bias_rad()
                .z
                .to_degrees()
        })
        .collect();
    let (mean, sigma) = mean_and_sigma(biases.into_iter());
    assert!(
        mean.abs() < 0.5 && (sigma / 3.0 - 1.0).abs() < 0.1,
        "{mean} {sigma}"
    );
}

#[test]
fn gps_wander_is_a_slow_gauss_markov_error() {
    let mut c = noiseless();
    c.gps.horizontal_wander_m = 2.0;
    c.gps.wander_correlation_s = 20.0;
    let truth = truth_at(0.0);
    let errors: Vec<f64> = gps(&run(&c, 6, 4000.0))
        .iter()
        .map(|f| f.position_ned_m.y - truth.position_ned_m.y)
        .collect();
    let (_, sigma) = mean_and_sigma(errors.iter().copied());
    assert!((sigma / 2.0 - 1.0).abs() < 0.15, "stationary σ {sigma}");
    // Correlation over one fix (0.25 s) is e^(−0.25/20) ≈ 0.988; over 20 s, e^(−1).
    let correlation = |lag: usize| {
        let n = errors.len() - lag;
        let c: f64 = (0..n).map(|i| errors[i] * errors[i + lag]).sum::<f64>() / n as f64;
        c / sigma.powi(2)
    };
    assert!((correlation(1) - 0.988).abs() < 0.01, "{}", correlation(1));
    assert!(
        (correlation(80) - (-1f64).exp()).abs() < 0.12,
        "{}",
        correlation(80)
    );
}

#[test]
fn the_same_seed_gives_the_same_deliveries_and_another_seed_others() {
    let c = SensorConfig::default();
    assert_eq!(run(&c, 7, 30.0), run(&c, 7, 30.0));
    assert_ne!(run(&c, 7, 30.0), run(&c, 8, 30.0));
}

#[test]
fn dropout_windows_and_random_losses_remove_samples_and_nothing_else() {
    let base = SensorConfig::default();
    let mut c = base.clone();
    c.gps.dropouts_s = vec![[10.0, 20.0]];
    c.pitot.dropout_probability = 0.3;
    let full = run(&base, 9, 60.0);
    let lossy = run(&c, 9, 60.0);
    let fixes = gps(&lossy);
    assert!(fixes.iter().all(|f| !(10.0..=20.0).contains(&f.time_s)));
    // 41 fixes fall in [10, 20] at 4 Hz.
    assert_eq!(fixes.len(), gps(&full).len() - 41);
    // The fixes that remain are the very same: a dropout does not reshuffle the noise.
    assert!(fixes.iter().all(|f| gps(&full).contains(f)));
    assert_eq!(attitude(&lossy), attitude(&full));
    let kept = air_data(&lossy).len() as f64 / air_data(&full).len() as f64;
    assert!((kept - 0.7).abs() < 0.05, "kept {kept}");
    assert!(air_data(&lossy).iter().all(|p| air_data(&full).contains(p)));
}

#[test]
fn invalid_settings_are_refused_with_the_field_named() {
    let mut c = SensorConfig::default();
    c.gps.rate_hz = 0.0;
    assert!(matches!(
        SensorSuite::new(&c, 0),
        Err(SensorConfigError::Invalid {
            field: "gps.rate_hz",
            ..
        })
    ));
    let mut c = SensorConfig::default();
    c.pitot.differential_noise_pa = f64::NAN;
    assert!(matches!(
        c.validate(),
        Err(SensorConfigError::Invalid {
            field: "pitot.differential_noise_pa",
            ..
        })
    ));
    let mut c = SensorConfig::default();
    c.ahrs.dropouts_s = vec![[5.0, 6.0], [8.0, 7.0]];
    assert!(matches!(
        c.validate(),
        Err(SensorConfigError::DropoutWindow {
            field: "ahrs.dropouts_s",
            index: 1,
            ..
        })
    ));
    let mut c = SensorConfig::default();
    c.gps.dropout_probability = 1.5;
    let message = c.validate().expect_err("refused").to_string();
    assert!(message.contains("gps.dropout_probability"), "{message}");
}

#[test]
fn toml_names_only_what_it_changes_and_unknown_keys_are_refused() {
    let c: SensorConfig = toml::from_str(
        "[gps]\nlatency_s = 0.4\ndropouts_s = [[60.0, 70.0]]\n[ahrs]\nyaw_bias_sigma_deg = 5.0\n",
    )
    .expect("valid TOML");
    assert_eq!(c.gps.latency_s, 0.4);
    assert_eq!(c.gps.dropouts_s, vec![[60.0, 70.0]]);
    assert_eq!(c.ahrs.yaw_bias_sigma_deg, 5.0);
    assert_eq!(c.pitot, PitotConfig::default());
    assert!(toml::from_str::<SensorConfig>("[gps]\nlatncy_s = 0.4\n").is_err());
    assert!(toml::from_str::<SensorConfig>("[magnetometer]\n").is_err());
}

#[test]
fn the_queue_hands_out_deliveries_in_arrival_order_when_due() {
    let mut q = DeliveryQueue::new();
    let mut suite = SensorSuite::new(&SensorConfig::default(), 10).expect("valid");
    for d in suite.sample(0.0, &truth_at(0.0)) {
        q.push(d);
    }
    // AHRS and pitot arrive at 0.02 s, GPS at 0.25 s.
    assert!(q.pop_due(0.01).is_none());
    let first = q.pop_due(0.05).expect("due");
    let second = q.pop_due(0.05).expect("due");
    assert!(matches!(first.measurement, Measurement::Attitude(_)));
    assert!(matches!(second.measurement, Measurement::AirData(_)));
    assert!(q.pop_due(0.05).is_none());
    assert_eq!(q.len(), 1);
    assert!(matches!(
        q.pop_due(0.25).expect("due").measurement,
        Measurement::Gps(_)
    ));
    assert!(q.is_empty());
}

#[test]
fn truth_from_the_model_is_the_drones_state_in_the_models_air() {
    let wind = ConstantWind::from_speed_direction(4.0, 270.0).expect("valid wind");
    let model = ParafoilModel::new(
        Vehicle::straplex(),
        Environment {
            atmosphere: Arc::new(StandardAtmosphere),
            wind: Arc::new(wind),
            ground_altitude_msl_m: 300.0,
        },
    );
    let x = Pose {
        position_ned_m: [0.0, 0.0, -500.0],
        canopy_euler_deg: [0.0, 6.5, 30.0],
        canopy_velocity_mps: [6.0, 0.0, 2.0],
        line_pitch_deg: -5.0,
        drone_euler_deg: [0.0, 5.0, 0.0],
        ..Default::default()
    }
    .to_state();
    let truth = Truth::from_model(&model, 3.0, &x);
    let kin = Kinematics::new(&model.vehicle, &x, 0.0);
    assert_eq!(
        truth.position_ned_m,
        kin.position_ned_m[Body::Drone as usize]
    );
    // Wind from the west blows east.
    assert!((truth.wind_ned_mps - Vector3::new(0.0, 4.0, 0.0)).norm() < 1e-12);
    // The air at the drone's altitude above sea level (ground at 300 m).
    let altitude = 300.0 - truth.position_ned_m.z;
    assert_eq!(truth.air, StandardAtmosphere.air_at(altitude));
    // Air-relative velocity in the drone frame has the same length as in NED.
    let speed = (truth.velocity_ned_mps - truth.wind_ned_mps).norm();
    assert!((truth.air_velocity_body_mps.norm() - speed).abs() < 1e-12);
    // The canopy yaws 30°, the drone hangs aligned with it.
    assert!((truth.euler_rad.z - 30f64.to_radians()).abs() < 1e-9);
}

/// The GPS's constant biases: the same offset on every fix of a run, drawn from the seed
/// (another seed, another offset), nothing without them.
#[test]
fn gps_bias_is_constant_over_a_run_and_drawn_from_the_seed() {
    let mut c = noiseless();
    let errors = |config: &SensorConfig, seed: u64| {
        let mut suite = SensorSuite::new(config, seed).expect("valid");
        let mut out = Vec::new();
        for k in 0..40 {
            let t = 0.25 * k as f64;
            let truth = truth_at(t);
            for d in suite.sample(t, &truth) {
                if let Measurement::Gps(g) = d.measurement {
                    out.push((
                        g.position_ned_m - truth.position_ned_m,
                        g.velocity_ned_mps - truth.velocity_ned_mps,
                    ));
                }
            }
        }
        out
    };
    let none = errors(&c, 7);
    assert!(none.iter().all(|(p, v)| p.norm() < 1e-9 && v.norm() < 1e-9));
    c.gps.horizontal_bias_sigma_m = 2.0;
    c.gps.vertical_bias_sigma_m = 3.0;
    c.gps.velocity_bias_sigma_mps = 0.2;
    let biased = errors(&c, 7);
    assert!(biased.len() > 30);
    let (p0, v0) = biased[0];
    assert!(p0.norm() > 1e-3 && v0.norm() > 1e-4, "{p0:?} {v0:?}");
    assert!(
        biased
            .iter()
            .all(|(p, v)| (p - p0).norm() < 1e-9 && (v - v0).norm() < 1e-9),
        "constant over the run"
    );
    assert_eq!(errors(&c, 7)[0].0, p0, "same seed, same bias");
    assert_ne!(errors(&c, 8)[0].0, p0, "another seed, another bias");
    c.gps.velocity_bias_sigma_mps = -1.0;
    assert!(SensorSuite::new(&c, 1).is_err());
}
