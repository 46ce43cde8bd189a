//! One refresh of the reachable footprint (issue 15 item 1: ≤ 1 s of one core) from 1,000 m
//! and 3,000 m above the ground, in a sheared wind profile, with the default settings (400
//! draws, 25 m cells) and a standard atmosphere over ground 500 m above sea level.

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use stx_gnc::estimate::Estimate;
use stx_gnc::footprint::{FootprintConfig, FootprintInput, footprint};
use stx_gnc::performance::GlidePerformance;
use stx_gnc::pointmass::{Conditions, PointMass};
use stx_types::atmosphere::StandardAtmosphere;
use stx_types::controls::Controls;
use stx_types::wind::{ProfileRow, WindProfile};

fn estimate(height_m: f64) -> Estimate {
    let wind = Vector3::new(3.0, -2.0, 0.0);
    let mut mass = PointMass::new(0.0, Vector3::new(0.0, 0.0, -height_m), 0.0);
    mass.step(
        &GlidePerformance::default(),
        &Controls::default(),
        &Conditions::nominal(wind, 1.0),
        0.01,
    );
    let mut est = mass.estimate(&wind);
    est.wind_sigma_mps = Vector3::new(0.3, 0.3, 0.0);
    est.position_sigma_m = Vector3::new(2.0, 2.0, 3.0);
    est
}

fn profile() -> WindProfile {
    let row = |altitude_m: f64, speed_mps: f64, from_deg: f64| ProfileRow {
        altitude_m,
        speed_mps,
        from_deg,
    };
    WindProfile::new(vec![
        row(0.0, 2.0, 270.0),
        row(1000.0, 5.0, 250.0),
        row(3000.0, 9.0, 230.0),
    ])
    .expect("profile")
}

fn bench(c: &mut Criterion) {
    let perf = GlidePerformance::default();
    let air = StandardAtmosphere;
    let wind = profile();
    let config = FootprintConfig::default().validate().expect("config");
    for height in [1000.0, 3000.0] {
        let est = estimate(height);
        let input = FootprintInput {
            estimate: &est,
            performance: &perf,
            wind_below: Some(&wind),
            atmosphere: &air,
            ground_altitude_msl_m: 500.0,
        };
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        c.bench_function(&format!("footprint refresh from {height} m"), |b| {
            b.iter(|| footprint(&input, &config, &mut rng).expect("footprint"))
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
