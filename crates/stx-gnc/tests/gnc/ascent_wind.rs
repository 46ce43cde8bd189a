//! The ascent-wind estimator on simulated ascents through a known sheared and veering wind,
//! many seeds: is each band's estimate within its stated 2 σ of the truth as often as it
//! claims, and close in absolute terms?
//!
//! The simulated balloon rises at 5 m/s from the ground to 20 km and bursts. Its horizontal
//! velocity follows the air (the profile plus short gusts) with a first-order lag; the
//! payload swings under it; the GPS adds white noise to position and velocity and, in the
//! realistic scenario, slow Gauss–Markov drifts. The truth a band is judged against is the
//! profile's mean over the altitudes the balloon truly flew through during the band's
//! passage — what the band claims to measure — not the gusts the balloon happened to meet.

use std::f64::consts::PI;

use nalgebra::Vector3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use stx_gnc::ascent_wind::{
    AscentFix, AscentWindConfig, AscentWindEstimator, BandMethod, WindBand,
};
use stx_types::wind::{ProfileRow, WindField, WindProfile};

const ASCENT_RATE_MPS: f64 = 5.0;
const BURST_ALTITUDE_M: f64 = 20_000.0;
const GROUND_WAIT_S: f64 = 60.0;
const STEP_S: f64 = 0.05;

/// Wind speed (m/s) and direction it blows from (degrees) at altitude `h` m: 3 m/s from
/// 220° at the ground, strengthening and veering through 100° to 20 km, with a jet of
/// +10 m/s around 11 km.
fn true_speed_from(h: f64) -> (f64, f64) {
    let speed = 3.0 + 0.0006 * h + 10.0 * (-((h - 11_000.0) / 2_000.0).powi(2)).exp();
    (speed, 220.0 + 100.0 * h / BURST_ALTITUDE_M)
}

/// North and east components of the true profile (where the air goes), m/s.
fn true_wind(h: f64) -> [f64; 2] {
    let (speed, from) = true_speed_from(h);
    let (s, c) = from.to_radians().sin_cos();
    [-speed * c, -speed * s]
}

/// Mean of the true profile over `[h0, h1]`, by the midpoint rule on 1-m steps.
fn true_mean(h0: f64, h1: f64) -> [f64; 2] {
    let n = ((h1 - h0).ceil() as usize).max(1);
    let dh = (h1 - h0) / n as f64;
    let mut sum = [0.0, 0.0];
    for i in 0..n {
        let w = true_wind(h0 + (i as f64 + 0.5) * dh);
        sum[0] += w[0];
        sum[1] += w[1];
    }
    [sum[0] / n as f64, sum[1] / n as f64]
}

/// What the simulated world and receiver are like.
#[derive(Clone, Copy, Debug)]
struct World {
    /// GPS fixes per second.
    gps_rate_hz: f64,
    /// Whether fixes carry a velocity.
    with_velocity: bool,
    /// Balloon's horizontal response time to the air, s (0: follows it exactly).
    balloon_lag_s: f64,
    /// Gusts: 1-σ per component (m/s) and correlation time (s).
    gust_sigma_mps: f64,
    gust_time_s: f64,
    /// Payload swing amplitude, m, and period, s.
    swing_m: f64,
    swing_period_s: f64,
    /// GPS white noise: horizontal and vertical position (m), velocity per component (m/s).
    position_noise_m: f64,
    altitude_noise_m: f64,
    velocity_noise_mps: f64,
    /// GPS slow drifts (Gauss–Markov): position σ (m) and time (s), velocity σ (m/s), time (s).
    position_drift_m: f64,
    position_drift_time_s: f64,
    velocity_drift_mps: f64,
    velocity_drift_time_s: f64,
}

impl World {
    /// Only errors whose correlation the scatter can see: white GPS noise, a 10-s swing and
    /// 5-s gusts; the balloon follows the air at once.
    fn statistical(with_velocity: bool) -> Self {
        Self {
            gps_rate_hz: if with_velocity { 2.0 } else { 1.0 },
            with_velocity,
            balloon_lag_s: 0.0,
            gust_sigma_mps: 0.3,
            gust_time_s: 5.0,
            swing_m: 1.5,
            swing_period_s: 10.0,
            position_noise_m: 1.5,
            altitude_noise_m: 3.0,
            velocity_noise_mps: 0.1,
            position_drift_m: 0.0,
            position_drift_time_s: 1.0,
            velocity_drift_mps: 0.0,
            velocity_drift_time_s: 1.0,
        }
    }

    /// Everything, including what only the configured floor covers: the balloon's 3-s lag
    /// and the receiver's slow drifts.
    fn realistic(with_velocity: bool) -> Self {
        Self {
            balloon_lag_s: 3.0,
            position_drift_m: 2.0,
            position_drift_time_s: 120.0,
            velocity_drift_mps: 0.03,
            velocity_drift_time_s: 300.0,
            ..Self::statistical(with_velocity)
        }
    }
}

/// A first-order Gauss–Markov process stepped exactly.
struct GaussMarkov {
    value: f64,
    sigma: f64,
    time_s: f64,
}

impl GaussMarkov {
    fn new(rng: &mut ChaCha8Rng, sigma: f64, time_s: f64) -> Self {
        Self {
            value: sigma * gauss(rng),
            sigma,
            time_s,
        }
    }

    fn step(&mut self, rng: &mut ChaCha8Rng, dt: f64) -> f64 {
        let a = (-dt / self.time_s).exp();
        self.value = a * self.value + self.sigma * (1.0 - a * a).sqrt() * gauss(rng);
        self.value
    }
}

fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    StandardNormal.sample(rng)
}

/// Flies one ascent (with a ground wait before and 2 minutes of fall after the burst) and
/// feeds the estimator its GPS fixes.
fn fly(world: &World, config: AscentWindConfig, seed: u64) -> AscentWindEstimator {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut est = AscentWindEstimator::new(config).expect("valid config");
    let mut gusts =
        [0, 1].map(|_| GaussMarkov::new(&mut rng, world.gust_sigma_mps, world.gust_time_s));
    let mut position_drift = [0, 1].map(|_| {
        GaussMarkov::new(
            &mut rng,
            world.position_drift_m,
            world.position_drift_time_s,
        )
    });
    let mut velocity_drift = [0, 1].map(|_| {
        GaussMarkov::new(
            &mut rng,
            world.velocity_drift_mps,
            world.velocity_drift_time_s,
        )
    });
    let swing_axis = 2.0 * PI * rand_unit(&mut rng);
    let swing_phase = 2.0 * PI * rand_unit(&mut rng);
    let swing_omega = 2.0 * PI / world.swing_period_s;
    let ascent_end_s = GROUND_WAIT_S + BURST_ALTITUDE_M / ASCENT_RATE_MPS;
    let end_s = ascent_end_s + 120.0;
    let gps_every = (1.0 / (world.gps_rate_hz * STEP_S)).round() as usize;

    let mut balloon_ne = [0.0, 0.0];
    let mut balloon_v = true_wind(0.0);
    let mut step = 0usize;
    loop {
        let t = step as f64 * STEP_S;
        if t > end_s {
            break;
        }
        let (altitude, climb) = if t < GROUND_WAIT_S {
            (0.0, 0.0)
        } else if t <= ascent_end_s {
            (ASCENT_RATE_MPS * (t - GROUND_WAIT_S), ASCENT_RATE_MPS)
        } else {
            // After the burst: falling at 40 m/s and tumbling sideways.
            (BURST_ALTITUDE_M - 40.0 * (t - ascent_end_s), -40.0)
        };
        let gust = [
            gusts[0].step(&mut rng, STEP_S),
            gusts[1].step(&mut rng, STEP_S),
        ];
        let drift_p = [0, 1].map(|i| position_drift[i].step(&mut rng, STEP_S));
        let drift_v = [0, 1].map(|i| velocity_drift[i].step(&mut rng, STEP_S));
        if step.is_multiple_of(gps_every) {
            let (s, c) = swing_axis.sin_cos();
            let swing = world.swing_m * (swing_omega * t + swing_phase).sin();
            let swing_v = world.swing_m * swing_omega * (swing_omega * t + swing_phase).cos();
            let (mut p, mut v) = ([0.0; 2], [0.0; 2]);
            for i in 0..2 {
                let along = if i == 0 { c } else { s };
                let tumble = if t > ascent_end_s {
                    15.0 * (0.7 * t).sin()
                } else {
                    0.0
                };
                p[i] = balloon_ne[i]
                    + along * swing
                    + drift_p[i]
                    + world.position_noise_m * gauss(&mut rng);
                v[i] = balloon_v[i]
                    + along * swing_v
                    + tumble
                    + drift_v[i]
                    + world.velocity_noise_mps * gauss(&mut rng);
            }
            let down = -(altitude + world.altitude_noise_m * gauss(&mut rng));
            let fix = AscentFix {
                time_s: t,
                position_ned_m: Vector3::new(p[0], p[1], down),
                velocity_ned_mps: world.with_velocity.then_some(Vector3::new(
                    v[0],
                    v[1],
                    -climb + 2.0 * world.velocity_noise_mps * gauss(&mut rng),
                )),
            };
            est.push_fix(&fix).expect("finite fix");
        }
        // The balloon's horizontal velocity relaxes to the air's; on the ground it is held.
        let air = true_wind(altitude.max(0.0));
        for i in 0..2 {
            let target = if t < GROUND_WAIT_S {
                0.0
            } else {
                air[i] + gust[i]
            };
            if world.balloon_lag_s > 0.0 {
                balloon_v[i] +=
                    (target - balloon_v[i]) * (1.0 - (-STEP_S / world.balloon_lag_s).exp());
            } else {
                balloon_v[i] = target;
            }
            balloon_ne[i] += balloon_v[i] * STEP_S;
        }
        step += 1;
    }
    est
}

fn rand_unit(rng: &mut ChaCha8Rng) -> f64 {
    rng.random::<f64>()
}

/// The truth a band claims: the profile's mean over the altitudes truly flown through from
/// its first fix to its last.
fn truth(band: &WindBand) -> [f64; 2] {
    let h = |t: f64| ASCENT_RATE_MPS * (t - GROUND_WAIT_S);
    true_mean(h(band.time_start_s), h(band.time_end_s))
}

/// Coverage statistics over many seeds.
#[derive(Debug, Default)]
struct Tally {
    components: usize,
    within_2_sigma: usize,
    sum_z2: f64,
    sum_sigma: f64,
    sum_err2: f64,
    worst_err: f64,
    bands_per_flight: Vec<usize>,
}

impl Tally {
    fn coverage(&self) -> f64 {
        self.within_2_sigma as f64 / self.components as f64
    }
    fn rms_z(&self) -> f64 {
        (self.sum_z2 / self.components as f64).sqrt()
    }
    fn mean_sigma(&self) -> f64 {
        self.sum_sigma / self.components as f64
    }
    fn rms_err(&self) -> f64 {
        (self.sum_err2 / self.components as f64).sqrt()
    }
}

fn tally(world: &World, config: AscentWindConfig, seeds: std::ops::Range<u64>) -> Tally {
    let mut t = Tally::default();
    let method = if world.with_velocity {
        BandMethod::GpsVelocity
    } else {
        BandMethod::PositionDifferences
    };
    for seed in seeds {
        let est = fly(world, config, seed);
        assert!(
            est.ascent_over_at_s().is_some(),
            "seed {seed}: burst not seen"
        );
        let bands = est.profile();
        t.bands_per_flight.push(bands.len());
        for b in &bands {
            assert_eq!(b.method, method, "seed {seed}: {b:?}");
            let truth = truth(b);
            let estimate = [b.wind_north_mps, b.wind_east_mps];
            let sigma = [b.sigma_north_mps, b.sigma_east_mps];
            for i in 0..2 {
                let err = estimate[i] - truth[i];
                t.components += 1;
                t.within_2_sigma += usize::from(err.abs() <= 2.0 * sigma[i]);
                t.sum_z2 += (err / sigma[i]).powi(2);
                t.sum_sigma += sigma[i];
                t.sum_err2 += err * err;
                t.worst_err = t.worst_err.max(err.abs());
            }
        }
    }
    println!(
        "{world:?}\n  {} components: within 2σ {:.1} %, rms(err/σ) {:.2}, mean σ {:.3} m/s, \
         rms err {:.3} m/s, worst {:.3} m/s, bands per flight {:?}…",
        t.components,
        100.0 * t.coverage(),
        t.rms_z(),
        t.mean_sigma(),
        t.rms_err(),
        t.worst_err,
        &t.bands_per_flight[..t.bands_per_flight.len().min(5)],
    );
    t
}

const SEEDS: std::ops::Range<u64> = 0..40;

/// Every band from 500 m to the burst is reported (band 0 starts when the stack leaves the
/// ground, the top one is cut by the burst, and the fall adds nothing).
fn assert_full_profile(t: &Tally) {
    for &n in &t.bands_per_flight {
        assert!((39..=40).contains(&n), "{:?}", t.bands_per_flight);
    }
}

#[test]
fn the_scatter_alone_states_an_honest_uncertainty() {
    // No floor, no swing term: only the Newey–West standard error, in a world whose errors
    // it can see. Coverage near the nominal 95 %, and not bought with an inflated σ.
    let config = AscentWindConfig {
        velocity_floor_mps: 0.0,
        pendulum_amplitude_m: 0.0,
        ..Default::default()
    };
    for with_velocity in [true, false] {
        let t = tally(&World::statistical(with_velocity), config, SEEDS);
        assert_full_profile(&t);
        assert!(t.coverage() >= 0.90, "coverage {}", t.coverage());
        assert!(
            (0.6..=1.25).contains(&t.rms_z()),
            "rms(err/σ) {}: σ badly sized",
            t.rms_z()
        );
        assert!(t.worst_err < 0.5, "worst {}", t.worst_err);
    }
}

#[test]
fn with_the_default_floor_a_realistic_ascent_is_covered() {
    let config = AscentWindConfig::default();
    for with_velocity in [true, false] {
        let t = tally(&World::realistic(with_velocity), config, SEEDS);
        assert_full_profile(&t);
        assert!(t.coverage() >= 0.90, "coverage {}", t.coverage());
        assert!(t.rms_err() < 0.2, "rms err {}", t.rms_err());
        assert!(t.worst_err < 0.6, "worst {}", t.worst_err);
    }
}

#[test]
fn the_merged_profile_follows_the_truth_and_the_forecast_above() {
    // A forecast 20 % strong and 15° off, above ground on 1-km rows to 30 km.
    let forecast: Vec<ProfileRow> = (0..=30)
        .map(|k| {
            let h = 1000.0 * f64::from(k);
            let (speed, from) = true_speed_from(h.min(BURST_ALTITUDE_M));
            ProfileRow {
                altitude_m: h,
                speed_mps: 1.2 * speed,
                from_deg: from + 15.0,
            }
        })
        .collect();
    let est = fly(&World::realistic(true), AscentWindConfig::default(), 7);
    let merged = est.merged_with_forecast(&forecast).expect("valid");
    let top = est.profile().last().expect("bands").altitude_max_m;
    let at = |h: f64| merged.wind_ned_mps(0.0, &Vector3::new(0.0, 0.0, -h));
    // Within the measured span, the truth to the band's resolution.
    for h in [300.0, 2_750.0, 11_000.0, 19_500.0] {
        let w = at(h);
        let truth = true_wind(h);
        let err = (w.x - truth[0]).hypot(w.y - truth[1]);
        assert!(err < 0.5, "at {h} m: {w:?} vs {truth:?}");
    }
    // The rows: the forecast's surface row (under the first band's first fix, a few metres
    // up), every band, and the forecast rows above the top band's highest fix — none between.
    let bands = est.profile();
    let above = forecast.iter().filter(|r| r.altitude_m > top).count();
    assert_eq!(merged.rows().len(), 1 + bands.len() + above);
    assert_eq!(merged.rows()[0], forecast[0]);
    assert_eq!(
        above, 11,
        "20 km and up: the last seconds before the burst are withdrawn"
    );
    // Above, the forecast exactly.
    let forecast_only = WindProfile::new(forecast.clone()).expect("valid");
    for h in [21_000.0, 25_500.0] {
        let w = at(h);
        let f = forecast_only.wind_ned_mps(0.0, &Vector3::new(0.0, 0.0, -h));
        assert!((w - f).norm() < 1e-9, "at {h} m: {w:?} vs {f:?}");
    }
    // Descent fixes were never used.
    assert!(matches!(
        est.profile().last().map(|b| b.time_end_s),
        Some(t) if t <= GROUND_WAIT_S + BURST_ALTITUDE_M / ASCENT_RATE_MPS
    ));
}
