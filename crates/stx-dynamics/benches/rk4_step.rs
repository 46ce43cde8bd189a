//! What the simulator's way of stepping the model costs, each choice side by side with the
//! way before it in one run, over one second of the shipped stack's flight:
//! - refusing RK4 steps that lose the solution (`Rk4::with_max_error`, what `fly_period`
//!   steps with since issue 29 item 4) against the plain step, 20 steps of 0.05 s from a
//!   steady glide and from the seed's unsettled initial conditions. The bound costs no
//!   evaluation of the model, only the difference of two derivatives it already has.
//! - the hanging bodies' two charts (`model::pendant`, issue 29 item 4) against the seed's
//!   chart only, with the bounded step from the same two starts, where neither pendant nears
//!   a pole and the charts cost one sine per pendant per step; and a transponder whipped
//!   round its capsule (100 steps of 0.01 s), which changes charts as it swings.

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use nalgebra::SVector;
use stx_dynamics::integrate::{Hooks, OdeSystem, Rk4, integrate};
use stx_dynamics::model::{Environment, ParafoilModel};
use stx_dynamics::state::{N_STATES, Pose, StateVector, idx};
use stx_dynamics::vehicle::Vehicle;

fn model() -> ParafoilModel {
    ParafoilModel::new(Vehicle::straplex(), Environment::calm())
}

/// The seed's uncontrolled-flight initial conditions (§4.6), 1,000 m up.
fn seed_state() -> StateVector {
    Pose::seed_release(1000.0).to_state()
}

/// The model as it flew before the charts: the integrator never re-charts it.
#[derive(Clone)]
struct SeedChartOnly(ParafoilModel);

impl OdeSystem<N_STATES> for SeedChartOnly {
    fn derivative(&mut self, time_s: f64, state: &SVector<f64, N_STATES>) -> StateVector {
        self.0.derivative(time_s, state)
    }
}

fn fly_one_second(
    system: &mut impl OdeSystem<N_STATES>,
    mut method: Rk4,
    x0: &StateVector,
) -> StateVector {
    let outcome = integrate(&mut method, system, 0.0, x0, 1.0, Hooks::default());
    outcome.expect("a second of flight").state
}

/// Times one second of flight of a fresh copy of `template` from `x0`.
fn bench_flight<S: OdeSystem<N_STATES> + Clone>(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    name: String,
    template: &S,
    method: Rk4,
    x0: &StateVector,
) {
    group.bench_function(name, |b| {
        b.iter_batched(
            || template.clone(),
            |mut m| fly_one_second(&mut m, method, x0),
            BatchSize::SmallInput,
        )
    });
}

fn bench(c: &mut Criterion) {
    let template = model();
    // 40 s from the seed's conditions settle into the steady glide.
    let glide = (0..40).fold(seed_state(), |x, _| {
        fly_one_second(&mut template.clone(), Rk4::new(0.02), &x)
    });
    let bounded = Rk4::new(0.05).with_max_error(1.0);

    let mut group = c.benchmark_group("one second of flight, 20 RK4 steps of 0.05 s");
    for (start, x0) in [("steady glide", glide), ("seed release", seed_state())] {
        for (name, method) in [("plain", Rk4::new(0.05)), ("bounded", bounded)] {
            bench_flight(
                &mut group,
                format!("{start}, {name}"),
                &template,
                method,
                &x0,
            );
        }
    }
    group.finish();

    let mut whipped = Pose::seed_release(500.0).to_state();
    whipped[idx::TRANSPONDER_RATES] = 20.0;
    let seed_chart_only = SeedChartOnly(template.clone());
    let mut group = c.benchmark_group("one second of flight, pendants in two charts or one");
    for (start, x0, method) in [
        ("steady glide", glide, bounded),
        ("seed release", seed_state(), bounded),
        ("whipped transponder", whipped, Rk4::new(0.01)),
    ] {
        let name = |charts: &str| format!("{start}, {charts}");
        bench_flight(
            &mut group,
            name("seed chart only"),
            &seed_chart_only,
            method,
            &x0,
        );
        bench_flight(&mut group, name("two charts"), &template, method, &x0);
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
