//! The station's stack against the flight model's own kinematic chain.

use nalgebra::Vector3;
use stx_dynamics::model::{Body, Kinematics};
use stx_dynamics::rotation::euler_from_t;
use stx_dynamics::state::{StateVector, idx};
use stx_dynamics::vehicle::Vehicle;
use stx_link::telemetry::Attitude;
use stx_types::stack::BodyImu;

use super::*;
use crate::core::StationCore;

fn attitude(euler: Vector3<f64>) -> Attitude {
    Attitude {
        time_boot_ms: 0,
        roll_rad: euler.x,
        pitch_rad: euler.y,
        yaw_rad: euler.z,
        roll_rate_radps: 0.0,
        pitch_rate_radps: 0.0,
        yaw_rate_radps: 0.0,
    }
}

/// A swinging stack: every body tilted its own way, heading 120°.
fn state(line_pitch_rad: f64) -> StateVector {
    let mut x = StateVector::zeros();
    x[idx::CANOPY_EULER] = 0.15;
    x[idx::CANOPY_EULER + 1] = -0.12;
    x[idx::CANOPY_EULER + 2] = 120_f64.to_radians();
    x[idx::LINE_PITCH] = line_pitch_rad;
    x[idx::DRONE_EULER] = -0.05;
    x[idx::DRONE_EULER + 1] = 0.1;
    x[idx::DRONE_EULER + 2] = 0.04;
    x[idx::CAPSULE_ANGLES] = 0.2;
    x[idx::CAPSULE_ANGLES + 1] = -0.1;
    x[idx::TRANSPONDER_ANGLES] = -0.15;
    x[idx::TRANSPONDER_ANGLES + 1] = 0.25;
    x
}

/// The station's view of the stack in state `x`, every body IMU heard at time 10 s.
fn measured_view(vehicle: &Vehicle, k: &Kinematics, now_s: f64) -> StackView {
    let mut bodies = BodyAttitudes::default();
    for (imu, body) in [
        (BodyImu::Canopy, Body::Canopy),
        (BodyImu::Capsule, Body::Capsule),
        (BodyImu::Transponder, Body::Transponder),
    ] {
        bodies.heard(
            imu,
            attitude(euler_from_t(&k.t_i_body[body as usize])),
            10.0,
        );
    }
    let drone = euler_from_t(&k.t_i_body[Body::Drone as usize]);
    stack_view(vehicle, drone, 0.1, &bodies, now_s, true)
}

fn from_drone_enu(k: &Kinematics, p_ned: Vector3<f64>) -> Vector3<f64> {
    let d = p_ned - k.position_ned_m[Body::Drone as usize];
    Vector3::new(d.y, d.x, -d.z)
}

fn distance(a: [f64; 3], b: Vector3<f64>) -> f64 {
    (Vector3::from(a) - b).norm()
}

#[test]
fn measured_attitudes_place_every_body_and_line_where_the_model_has_them() {
    let vehicle = Vehicle::straplex();
    let k = Kinematics::new(&vehicle, &state(0.0), 0.0);
    let view = measured_view(&vehicle, &k, 11.0);
    for (b, body) in view.bodies.iter().zip(Body::ALL) {
        assert_eq!(b.source, BodySource::Measured, "{:?}", b.body);
        let truth = from_drone_enu(&k, k.position_ned_m[body as usize]);
        assert!(
            distance(b.position_enu_m, truth) < 1e-9,
            "{:?}: {:?} against {truth}",
            b.body,
            b.position_enu_m
        );
        let e = euler_from_t(&k.t_i_body[body as usize]);
        assert!((b.roll_deg - e.x.to_degrees()).abs() < 1e-9);
        assert!((b.yaw_deg - e.z.to_degrees()).abs() < 1e-9);
    }
    assert_eq!(view.bodies[2].age_s, Some(1.0));
    for (line, (top, bottom)) in view.lines.iter().zip(k.line_ends_ned_m(&vehicle)) {
        assert!(
            distance(line.top_enu_m, from_drone_enu(&k, top)) < 1e-9,
            "{:?}",
            line.line
        );
        assert!(
            distance(line.bottom_enu_m, from_drone_enu(&k, bottom)) < 1e-9,
            "{:?}",
            line.line
        );
    }
}

#[test]
fn the_unmeasured_line_pitch_of_a_steady_glide_moves_the_canopy_by_decimetres() {
    let vehicle = Vehicle::straplex();
    let k = Kinematics::new(&vehicle, &state(-5_f64.to_radians()), 0.0);
    let view = measured_view(&vehicle, &k, 10.5);
    let truth = from_drone_enu(&k, k.position_ned_m[Body::Canopy as usize]);
    let off = distance(view.bodies[0].position_enu_m, truth);
    assert!(off > 0.05 && off < 0.35, "canopy {off} m off");
    // The pendants hang from the drone: the line pitch does not reach them.
    let capsule = from_drone_enu(&k, k.position_ned_m[Body::Capsule as usize]);
    assert!(distance(view.bodies[2].position_enu_m, capsule) < 1e-9);
}

#[test]
fn bodies_not_heard_or_heard_too_long_ago_hang_straight_by_the_rigging() {
    let vehicle = Vehicle::straplex();
    let mut bodies = BodyAttitudes::default();
    let tilted = Vector3::new(0.3, 0.2, 0.0);
    bodies.heard(BodyImu::Capsule, attitude(tilted), 0.0);
    // A level drone heading east; the capsule's attitude is older than the limit.
    let drone = Vector3::new(0.0, 0.0, 90_f64.to_radians());
    let view = stack_view(
        &vehicle,
        drone,
        0.0,
        &bodies,
        BODY_MEASURED_WITHIN_S + 0.5,
        true,
    );
    let sources: Vec<_> = view.bodies.iter().map(|b| b.source).collect();
    assert_eq!(
        sources,
        [
            BodySource::Rigging,
            BodySource::Measured,
            BodySource::Rigging,
            BodySource::Rigging
        ]
    );
    let [canopy, _, capsule, transponder] = [0, 1, 2, 3].map(|i| view.bodies[i].position_enu_m);
    // Canopy above by the rigging's height (lines 2.55 m, attachments 0.6 + 0.175 m).
    assert!((canopy[2] - 3.325).abs() < 1e-9, "{canopy:?}");
    // Capsule 3 m below its line's drone end (0.145 m under the drone's CM), transponder 5 m
    // under the capsule; straight down: no east/north beyond the drone's own offset.
    assert!((capsule[2] + 3.145).abs() < 1e-9, "{capsule:?}");
    assert!((transponder[2] - capsule[2] + 5.0).abs() < 1e-9);
    assert!(
        (transponder[0] - capsule[0]).abs() < 1e-9 && (transponder[1] - capsule[1]).abs() < 1e-9
    );
    assert!((view.bodies[0].yaw_deg - 90.0).abs() < 1e-9);
    assert_eq!(view.bodies[0].age_s, None);
    // A non-finite attitude from the link is not taken.
    bodies.heard(
        BodyImu::Canopy,
        attitude(Vector3::new(f64::NAN, 0.0, 0.0)),
        4.0,
    );
    let view = stack_view(&vehicle, drone, 0.0, &bodies, 4.0, true);
    assert_eq!(view.bodies[0].source, BodySource::Rigging);
    // Before the parafoil flies, no canopy and no main lines above the drone.
    let packed = stack_view(&vehicle, drone, 0.0, &bodies, 4.0, false);
    let names: Vec<_> = packed.bodies.iter().map(|b| b.body).collect();
    assert_eq!(
        names,
        [StackBody::Drone, StackBody::Capsule, StackBody::Transponder]
    );
    let lines: Vec<_> = packed.lines.iter().map(|l| l.line).collect();
    assert_eq!(lines, [StackLine::Capsule, StackLine::Transponder]);
}

#[test]
fn a_body_imus_attitude_is_that_bodys_never_the_drones() {
    use stx_link::endpoint::GroundEvent;
    use stx_link::telemetry::Telemetry;
    let mut core = crate::core::tests::core();
    let heard = |core: &mut StationCore, now_s: f64, component: u8, roll_rad: f64| {
        let mut a = attitude(Vector3::new(roll_rad, 0.0, 0.0));
        a.time_boot_ms = (now_s * 1000.0) as u32;
        let telemetry = Telemetry::Attitude(a);
        core.on_link_event(
            now_s,
            GroundEvent::Telemetry {
                from: (1, component),
                telemetry,
            },
        );
    };
    // The canopy alone: nothing of the drone is known, so there is no vehicle and no stack.
    heard(&mut core, 1.0, BodyImu::Canopy.component_id(), 0.4);
    let s = core.state_msg_now(1.0);
    assert!(s.vehicle.is_none() && s.stack.is_none() && s.estimate.is_none());
    // Under the parafoil, the drone's AHRS: its attitude is the drone's, the canopy keeps its own.
    crate::core::tests::hear_stage(&mut core, 1.2, stx_gnc::mission::FlightStage::Parafoil);
    heard(&mut core, 1.25, 1, -0.1);
    let s = core.state_msg_now(1.3);
    let shown = s
        .vehicle
        .and_then(|v| v.attitude)
        .expect("the drone's attitude");
    assert!((shown.roll_deg + 0.1_f64.to_degrees()).abs() < 1e-9);
    let stack = s.stack.expect("a stack once the drone is heard");
    assert_eq!(stack.bodies[0].source, BodySource::Measured);
    assert!((stack.bodies[0].roll_deg - 0.4_f64.to_degrees()).abs() < 1e-9);
    assert!((stack.bodies[1].roll_deg + 0.1_f64.to_degrees()).abs() < 1e-9);
    assert_eq!(stack.bodies[2].source, BodySource::Rigging);
    // Landed: the bodies lie where they fell, no stack is drawn hanging into the ground.
    crate::core::tests::hear_stage(&mut core, 1.5, stx_gnc::mission::FlightStage::Landed);
    heard(&mut core, 1.75, 1, 0.0);
    assert!(core.state_msg_now(1.8).stack.is_none());
}
