//! The point-mass summary guidance plans with (`stx_gnc::performance::GlidePerformance`) is
//! measured from the 14-DOF model; this pins it, so a change to either shows up here.

use stx_dynamics::vehicle::Vehicle;
use stx_gnc::performance::GlidePerformance;
use stx_sim::open_loop::run;
use stx_sim::scenario::{ControlStep, MainLineCommand, Scenario};

fn steady(brake: f64, main_line_m: f64) -> (f64, f64, f64) {
    let mut scenario = Scenario::builtin("uncontrolled").expect("built-in");
    // From 180 m, so that the averaging window (20–40 s) is flown about 100 m up, the table's
    // reference height.
    scenario.duration_s = 40.0;
    scenario.initial.position_ned_m[2] = -180.0;
    scenario.controls = vec![ControlStep {
        at_s: 0.0,
        main_line: MainLineCommand::Metres(main_line_m),
        brake_right: brake,
        brake_left: brake,
    }];
    let r = run(&scenario, &Vehicle::straplex()).expect("flies");
    // Averages over 20–40 s, settled in the glide or the turn.
    let tail: Vec<_> = r
        .samples
        .iter()
        .filter(|x| x.time_s > 20.0 && x.time_s <= 40.0)
        .collect();
    let mean = |f: &dyn Fn(&stx_dynamics::output::Sample) -> f64| {
        tail.iter().map(|x| f(x)).sum::<f64>() / tail.len().max(1) as f64
    };
    // Heading rate of the canopy from its unwrapped yaw.
    let yaw: Vec<f64> = tail
        .iter()
        .map(|x| x.bodies[0].euler_deg[2].to_radians())
        .collect();
    let mut turned = 0.0;
    for pair in yaw.windows(2) {
        turned += stx_dynamics::rotation::wrap_pi(pair[1] - pair[0]);
    }
    let duration = tail.last().map_or(0.0, |x| x.time_s) - tail.first().map_or(0.0, |x| x.time_s);
    (
        mean(&|x| x.airspeed_mps),
        mean(&|x| x.bodies[0].velocity_ned_mps[2]),
        turned / duration.max(1e-9),
    )
}

#[test]
fn the_steady_glide_table_is_what_the_model_flies() {
    let p = GlidePerformance::default();
    for brake in [0.0, 0.4, 0.8, 1.0] {
        let (airspeed, sink, _) = steady(brake, 0.0);
        let table_airspeed = p.airspeed(brake, p.reference_density_kg_per_m3);
        let table_sink = p.sink_rate(brake, 0.0, p.reference_density_kg_per_m3);
        assert!(
            (airspeed - table_airspeed).abs() < 0.02 * table_airspeed,
            "brake {brake}: model {airspeed:.3} m/s, table {table_airspeed:.3}"
        );
        assert!(
            (sink - table_sink).abs() < 0.02 * table_sink,
            "brake {brake}: model sink {sink:.3} m/s, table {table_sink:.3}"
        );
    }
}

#[test]
fn the_turn_model_is_within_a_fifth_of_the_models_steady_turns() {
    let p = GlidePerformance::default();
    for main_line in [0.005, 0.01] {
        let (_, sink, turn) = steady(0.0, main_line);
        let predicted = p.turn_rate(main_line);
        assert!(
            (turn - predicted).abs() < 0.2 * turn.abs(),
            "main line {main_line} m: model {turn:.3} rad/s, predicted {predicted:.3}"
        );
        let predicted_sink = p.sink_rate(0.0, turn, p.reference_density_kg_per_m3);
        assert!(
            (sink - predicted_sink).abs() < 0.2 * sink,
            "main line {main_line} m: model sink {sink:.3} m/s, predicted {predicted_sink:.3}"
        );
    }
}
