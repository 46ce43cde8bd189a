//! The other bodies' own IMUs on the simulated drone: under the parafoil the canopy, capsule and
//! transponder each report their attitude at 2 Hz, and what they report is the flight model's
//! attitude of that body at that instant.

use std::collections::HashMap;

use stx_dynamics::model::{Body, Kinematics};
use stx_dynamics::rotation::euler_from_t;
use stx_dynamics::state::idx;
use stx_dynamics::vehicle::Vehicle;
use stx_link::telemetry::Telemetry;
use stx_sim::drone::{Drone, MissionConfig, Output};
use stx_types::stack::{BODY_ATTITUDE_PERIOD_S, BodyImu};

#[test]
fn each_body_imu_reports_the_models_attitude_of_its_body_at_two_hertz() {
    let config = MissionConfig::builtin("rehearsal").expect("built-in mission");
    let mut d = Drone::new(&config, Vehicle::straplex()).expect("drone builds");
    let mut counts: HashMap<BodyImu, usize> = HashMap::new();
    let mut compared = 0;
    while d.time_s() < 30.0 {
        // The model's attitudes now: what this step's telemetry is built from.
        let (ms, truth) = {
            let (_, x) = d
                .physics()
                .parafoil()
                .expect("the rehearsal starts under the parafoil");
            let k = Kinematics::new(d.physics().vehicle(), x, x[idx::MAIN_LINE]);
            (
                (d.time_s() * 1000.0).round() as u32,
                k.t_i_body.map(|t| euler_from_t(&t)),
            )
        };
        d.step().expect("the flight goes on");
        while let Some(o) = d.poll_output() {
            let Output::Body {
                body,
                telemetry: Telemetry::Attitude(a),
            } = o
            else {
                continue;
            };
            *counts.entry(body).or_default() += 1;
            assert_eq!(
                a.time_boot_ms, ms,
                "{body:?}: stamped with the instant it was measured"
            );
            let i = match body {
                BodyImu::Canopy => Body::Canopy,
                BodyImu::Capsule => Body::Capsule,
                BodyImu::Transponder => Body::Transponder,
            } as usize;
            let e = truth[i];
            assert_eq!(
                [a.roll_rad, a.pitch_rad, a.yaw_rad],
                [e.x, e.y, e.z],
                "{body:?}"
            );
            compared += 1;
        }
    }
    let expected = (30.0 / BODY_ATTITUDE_PERIOD_S) as usize;
    for body in BodyImu::ALL {
        let n = counts.get(&body).copied().unwrap_or(0);
        assert!(
            n.abs_diff(expected) <= 1,
            "{body:?}: {n} in 30 s, expected {expected}"
        );
    }
    assert!(compared >= 3 * (expected - 1));
}
