//! A transponder whipped sideways round its capsule flies through the place where the seed's
//! two angles have their pole (its line along the capsule's y axis), which stopped the
//! integrator in the failed Monte Carlo runs; read in two charts it flies on, and its motion
//! does not depend on which chart it started in.

use nalgebra::{SVector, Vector3};
use stx_dynamics::integrate::{Hooks, OdeSystem, Rk4, integrate};
use stx_dynamics::model::pendant::{Chart, in_charts};
use stx_dynamics::model::{Body, Environment, Kinematics, ParafoilModel};
use stx_dynamics::state::{N_STATES, Pose, StateVector, idx};
use stx_dynamics::vehicle::Vehicle;

fn model() -> ParafoilModel {
    ParafoilModel::new(Vehicle::straplex(), Environment::calm())
}

/// The model flown in the seed's chart only, as before the charts: it never re-charts.
struct SeedChartOnly(ParafoilModel);

impl OdeSystem<N_STATES> for SeedChartOnly {
    fn derivative(&mut self, time_s: f64, state: &SVector<f64, N_STATES>) -> StateVector {
        self.0.derivative(time_s, state)
    }
}

/// The steady glide with the transponder kicked sideways at `rate` rad/s about the capsule's x
/// axis.
fn whipped(rate: f64) -> StateVector {
    let mut x = Pose::seed_release(500.0).to_state();
    x[idx::TRANSPONDER_RATES] = rate;
    x
}

/// The transponder's line in the capsule's axes, and its inertial position (NED, m).
type TrackPoint = (Vector3<f64>, Vector3<f64>);

/// The transponder's track after every step of `step_s` over 3 s.
fn fly(
    system: &mut impl OdeSystem<N_STATES>,
    x0: &StateVector,
    step_s: f64,
) -> Result<Vec<TrackPoint>, String> {
    let vehicle = Vehicle::straplex();
    let mut track = Vec::new();
    let mut observer = |_t: f64, x: &StateVector| {
        let k = Kinematics::new(&vehicle, x, 0.0);
        let line = k.t_cap_t.transpose() * Vector3::z();
        track.push((line, k.position_ned_m[Body::Transponder as usize]));
    };
    integrate(
        &mut Rk4::new(step_s),
        system,
        0.0,
        x0,
        3.0,
        Hooks {
            observer: Some(&mut observer),
            ..Hooks::default()
        },
    )
    .map_err(|e| e.to_string())?;
    Ok(track)
}

#[test]
fn a_transponder_whipped_round_its_capsule_flies_through_the_seed_charts_pole() {
    let x0 = whipped(20.0);
    // Read in the seed's two angles only, it stops where its line passes the capsule's y axis.
    let error = fly(&mut SeedChartOnly(model()), &x0, 0.01).expect_err("stops at the pole");
    assert!(error.contains("non-finite"), "{error}");
    fly(&mut model(), &x0, 0.01).expect("re-charted, it flies through");

    // Started in the turned chart, it changes charts at other times; with a step short enough
    // for the whip (RK4's error is then ~1e-6 m), the motion is the same.
    let track = fly(&mut model(), &x0, 0.002).expect("flies through");
    let closest = track
        .iter()
        .map(|(line, _)| line.y.abs())
        .fold(0.0, f64::max);
    assert!(
        closest > 0.99,
        "the line came no nearer than {:.1}° to the seed chart's pole",
        closest.acos().to_degrees()
    );
    let turned = in_charts(&x0, Chart::Seed, Chart::Turned);
    let track_turned = fly(&mut model(), &turned, 0.002).expect("flies through");
    let apart = track
        .iter()
        .zip(&track_turned)
        .map(|((_, a), (_, b))| (a - b).norm())
        .fold(0.0, f64::max);
    assert!(
        apart < 1e-4,
        "the two flights' transponders were {apart} m apart"
    );
}
