//! The cost of refusing RK4 steps that lose the solution (`Rk4::with_max_error`, what the
//! simulator's `fly_period` steps with since issue 29 item 4), side by side with the plain
//! step in one run: one second of the shipped stack's flight (20 steps of 0.05 s) from a steady
//! glide and from the seed's unsettled initial conditions, each way. The bound costs no
//! evaluation of the model, only the difference of two derivatives it already has.

use std::sync::Arc;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use stx_dynamics::atmosphere::StandardAtmosphere;
use stx_dynamics::integrate::{Hooks, Rk4, integrate};
use stx_dynamics::model::{Environment, ParafoilModel};
use stx_dynamics::state::{Pose, StateVector};
use stx_dynamics::vehicle::Vehicle;
use stx_dynamics::wind::Calm;

fn model() -> ParafoilModel {
    ParafoilModel::new(
        Vehicle::straplex(),
        Environment {
            atmosphere: Arc::new(StandardAtmosphere),
            wind: Arc::new(Calm),
            ground_altitude_msl_m: 0.0,
        },
    )
}

/// The seed's uncontrolled-flight initial conditions (§4.6), 1,000 m up.
fn seed_state() -> StateVector {
    Pose::seed_release(1000.0).to_state()
}

fn fly_one_second(model: &mut ParafoilModel, mut method: Rk4, x0: &StateVector) -> StateVector {
    let outcome = integrate(&mut method, model, 0.0, x0, 1.0, Hooks::default());
    outcome.expect("a second of flight").state
}

fn bench(c: &mut Criterion) {
    let template = model();
    // 40 s from the seed's conditions settle into the steady glide.
    let glide = (0..40).fold(seed_state(), |x, _| {
        fly_one_second(&mut template.clone(), Rk4::new(0.02), &x)
    });
    let mut group = c.benchmark_group("one second of flight, 20 RK4 steps of 0.05 s");
    for (start, x0) in [("steady glide", glide), ("seed release", seed_state())] {
        for (name, method) in [
            ("plain", Rk4::new(0.05)),
            ("bounded", Rk4::new(0.05).with_max_error(1.0)),
        ] {
            group.bench_function(format!("{start}, {name}"), |b| {
                b.iter_batched(
                    || template.clone(),
                    |mut m| fly_one_second(&mut m, method, &x0),
                    BatchSize::SmallInput,
                )
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
