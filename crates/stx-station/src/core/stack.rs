//! The station's picture of the stack: where the canopy, capsule and transponder are around
//! the drone, from their attitudes and the vehicle's rigging.
//!
//! The link carries the drone's attitude (its AHRS) and, when a body carries an IMU of its
//! own, that body's ATTITUDE from its own component (`stx_types::stack::BodyImu`). A body
//! heard within [`BODY_MEASURED_WITHIN_S`] is drawn at its measured attitude; one not heard
//! hangs straight down (level, at the drone's heading), which is where a slack-free rigging
//! puts it in a steady glide. Positions then follow the seed's kinematic chain
//! (`stx_dynamics::model::Kinematics`) with one unknown left out: the pitch of the main lines
//! against the canopy (θ_L/C), which no IMU measures; it is taken as zero, the lines along
//! the canopy's z axis. In a steady glide it is about −5°, so the canopy is drawn some 0.3 m
//! off along its chord: well inside a stroke of the drawing, and the lines are drawn between
//! the bodies' own attachment points, so they always join what they join.

use nalgebra::{Matrix3, Vector3};
use stx_dynamics::rotation::{euler_from_t, t_from_euler};
use stx_dynamics::vehicle::Vehicle;
use stx_link::telemetry::Attitude;
use stx_types::stack::BodyImu;

use crate::messages::{BodySource, StackBody, StackBodyView, StackLine, StackLineView, StackView};

/// A body's own attitude older than this is no longer shown as measured, s (four of its
/// 2 Hz messages missed, or a link gone quiet).
pub const BODY_MEASURED_WITHIN_S: f64 = 3.0;

/// The newest attitude of each body IMU, with the station time it arrived.
#[derive(Debug, Clone, Default)]
pub(crate) struct BodyAttitudes {
    latest: [Option<(Attitude, f64)>; 3],
}

fn slot(body: BodyImu) -> usize {
    match body {
        BodyImu::Canopy => 0,
        BodyImu::Capsule => 1,
        BodyImu::Transponder => 2,
    }
}

impl BodyAttitudes {
    /// Takes one body's ATTITUDE heard at `now_s`; a non-finite one is dropped.
    pub(crate) fn heard(&mut self, body: BodyImu, attitude: Attitude, now_s: f64) {
        let finite = [attitude.roll_rad, attitude.pitch_rad, attitude.yaw_rad]
            .iter()
            .all(|v| v.is_finite());
        if finite {
            self.latest[slot(body)] = Some((attitude, now_s));
        }
    }

    /// A body's attitude if heard recently enough at `now_s`, with its age, s.
    fn measured(&self, body: BodyImu, now_s: f64) -> Option<(Vector3<f64>, f64)> {
        let (a, at) = self.latest[slot(body)]?;
        let age = (now_s - at).max(0.0);
        (age <= BODY_MEASURED_WITHIN_S)
            .then(|| (Vector3::new(a.roll_rad, a.pitch_rad, a.yaw_rad), age))
    }
}

/// NED → east/north/up.
fn enu(v: Vector3<f64>) -> [f64; 3] {
    [v.y, v.x, -v.z]
}

/// A body's attitude and where it came from.
struct Placed {
    /// Inertial (NED) → body.
    t: Matrix3<f64>,
    source: BodySource,
    age_s: Option<f64>,
}

/// The stack around a drone at attitude `drone_euler_rad` (roll, pitch, yaw) whose AHRS
/// sample is `drone_age_s` old, with the body IMUs heard so far, at station time `now_s`.
/// `canopy_out`: the parafoil flies (deploying or deployed); before it, and once landed, the
/// canopy and its main lines are not drawn in the air above the drone.
pub(crate) fn stack_view(
    vehicle: &Vehicle,
    drone_euler_rad: Vector3<f64>,
    drone_age_s: f64,
    bodies: &BodyAttitudes,
    now_s: f64,
    canopy_out: bool,
) -> StackView {
    // Hanging straight: level, facing where the drone faces.
    let hanging = t_from_euler(&Vector3::new(0.0, 0.0, drone_euler_rad.z));
    let place = |body: BodyImu| match bodies.measured(body, now_s) {
        Some((euler, age)) => Placed {
            t: t_from_euler(&euler),
            source: BodySource::Measured,
            age_s: Some(age),
        },
        None => Placed {
            t: hanging,
            source: BodySource::Rigging,
            age_s: None,
        },
    };
    let canopy = place(BodyImu::Canopy);
    let capsule = place(BodyImu::Capsule);
    let transponder = place(BodyImu::Transponder);
    let drone = Placed {
        t: t_from_euler(&drone_euler_rad),
        source: BodySource::Measured,
        age_s: Some(drone_age_s),
    };
    // Body → NED of each (the transposes), and the chain from the drone's CM.
    let (to_c, to_d, to_cap, to_t) = (
        canopy.t.transpose(),
        drone.t.transpose(),
        capsule.t.transpose(),
        transponder.t.transpose(),
    );
    let p_c = -(to_c * vehicle.r_line_top_m
        + to_c * vehicle.line_mean_m
        + to_d * vehicle.r_drone_from_line_bottom_m);
    let capsule_top = to_d * vehicle.r_capsule_line_on_drone_m;
    let p_cap = capsule_top + to_cap * Vector3::new(0.0, 0.0, vehicle.capsule_line_length_m);
    let p_t = p_cap + to_t * Vector3::new(0.0, 0.0, vehicle.transponder_line_length_m);
    let main = |line, side: usize| StackLineView {
        line,
        top_enu_m: enu(p_c + to_c * vehicle.r_lines_on_canopy_m[side]),
        bottom_enu_m: enu(to_d * vehicle.r_lines_on_drone_m[side]),
    };
    let lines = vec![
        main(StackLine::MainRight, 0),
        main(StackLine::MainLeft, 1),
        StackLineView {
            line: StackLine::Capsule,
            top_enu_m: enu(capsule_top),
            bottom_enu_m: enu(p_cap),
        },
        StackLineView {
            line: StackLine::Transponder,
            top_enu_m: enu(p_cap),
            bottom_enu_m: enu(p_t),
        },
    ];
    let c = &vehicle.config;
    let view = |body, placed: &Placed, p: Vector3<f64>, size_m| {
        let e = euler_from_t(&placed.t);
        StackBodyView {
            body,
            roll_deg: e.x.to_degrees(),
            pitch_deg: e.y.to_degrees(),
            yaw_deg: e.z.to_degrees(),
            position_enu_m: enu(p),
            size_m,
            source: placed.source,
            age_s: placed.age_s,
        }
    };
    let pendant = |p: &stx_dynamics::vehicle::PendantConfig| [p.length_m, p.width_m, p.height_m];
    let bodies = vec![
        view(
            StackBody::Canopy,
            &canopy,
            p_c,
            [
                c.canopy.chord_m,
                c.canopy.span_m,
                c.canopy.arc_height_m + c.canopy.thickness_m,
            ],
        ),
        view(
            StackBody::Drone,
            &drone,
            Vector3::zeros(),
            [c.drone.length_m, c.drone.width_m, c.drone.height_m],
        ),
        view(StackBody::Capsule, &capsule, p_cap, pendant(&c.capsule)),
        view(
            StackBody::Transponder,
            &transponder,
            p_t,
            pendant(&c.transponder),
        ),
    ];
    if canopy_out {
        StackView { bodies, lines }
    } else {
        StackView {
            bodies: bodies
                .into_iter()
                .filter(|b| b.body != StackBody::Canopy)
                .collect(),
            lines: lines
                .into_iter()
                .filter(|l| !matches!(l.line, StackLine::MainRight | StackLine::MainLeft))
                .collect(),
        }
    }
}

#[cfg(test)]
#[path = "stack_tests.rs"]
mod tests;
