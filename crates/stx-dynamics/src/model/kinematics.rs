//! The kinematic chain (seed §4.3): from the 31 states to every body's orientation, angular
//! velocity, position and velocity, walking canopy → line frame → drone → capsule →
//! transponder.
//!
//! Positions and velocities are plain values; accelerations are [`Affine`] in the 14
//! generalized-speed derivatives, because the equations of motion solve for those: the chain
//! that gives a body's acceleration also gives the columns of the mass matrix (flight-model.md,
//! "A robust way to build it"), so nothing of the garbled appendix A.11 is transcribed.

use nalgebra::{Matrix3, SMatrix, Vector3};

use super::pendant::{pendant_rel_rate, t_parent_to_pendant};
use crate::rotation::{t_from_euler, t_pitch};
use crate::state::{StateVector, idx, vec3_at};
use crate::vehicle::Vehicle;

/// The four bodies, in the order every per-body array uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Body {
    /// The parafoil canopy.
    Canopy = 0,
    /// The control drone.
    Drone = 1,
    /// The payload capsule.
    Capsule = 2,
    /// The transponder.
    Transponder = 3,
}

impl Body {
    /// All bodies, top to bottom.
    pub const ALL: [Body; 4] = [Body::Canopy, Body::Drone, Body::Capsule, Body::Transponder];

    /// Lower-case name for tables.
    pub fn name(self) -> &'static str {
        match self {
            Body::Canopy => "canopy",
            Body::Drone => "drone",
            Body::Capsule => "capsule",
            Body::Transponder => "transponder",
        }
    }
}

/// Orientation, rates, positions and velocities of every body for one state.
#[derive(Debug, Clone)]
pub struct Kinematics {
    /// Inertial → canopy, canopy → line, line → drone, drone → capsule, capsule → transponder.
    pub t_i_c: Matrix3<f64>,
    pub t_c_l: Matrix3<f64>,
    pub t_l_d: Matrix3<f64>,
    pub t_d_cap: Matrix3<f64>,
    pub t_cap_t: Matrix3<f64>,
    /// Inertial → body frame of each body, in [`Body`] order (the line frame is not a body).
    pub t_i_body: [Matrix3<f64>; 4],
    /// Inertial → line frame.
    pub t_i_l: Matrix3<f64>,
    /// Angular velocity of each body relative to the inertial frame, in its own frame, rad/s.
    pub omega_body: [Vector3<f64>; 4],
    /// Angular velocity of the line frame relative to the inertial frame, line frame, rad/s.
    pub omega_line: Vector3<f64>,
    /// Drone relative to the line frame, drone frame, rad/s (states 17–19).
    pub omega_drone_rel: Vector3<f64>,
    /// Capsule relative to the drone, capsule frame: `[p, q, −tan φ · q]`, rad/s.
    pub omega_capsule_rel: Vector3<f64>,
    /// Transponder relative to the capsule, transponder frame, rad/s.
    pub omega_transponder_rel: Vector3<f64>,
    /// Bottom of the main lines (mean drone end) from their mean canopy end, line frame, m;
    /// moves sideways with the main-line servo.
    pub line_drop_m: Vector3<f64>,
    /// Its rate of change in the line frame, m/s.
    pub line_drop_rate_mps: Vector3<f64>,
    /// Unit vectors of the right and left main lines, canopy end to drone end, line frame.
    pub main_line_dir: [Vector3<f64>; 2],
    /// Rate of the main-line servo ΔL̇, m/s.
    pub main_line_rate_mps: f64,
    /// CM position of each body, inertial NED, m.
    pub position_ned_m: [Vector3<f64>; 4],
    /// CM velocity of each body relative to the inertial frame, in its own frame, m/s.
    pub velocity_body_mps: [Vector3<f64>; 4],
}

impl Kinematics {
    /// Walks the chain for state `x` with main-line command `main_line_command_m` (needed
    /// because the servo's rate moves the drone).
    pub fn new(vehicle: &Vehicle, x: &StateVector, main_line_command_m: f64) -> Self {
        let t_i_c = t_from_euler(&vec3_at(x, idx::CANOPY_EULER));
        let t_c_l = t_pitch(x[idx::LINE_PITCH]);
        let t_l_d = t_from_euler(&vec3_at(x, idx::DRONE_EULER));
        let (phi_cap, theta_cap) = (x[idx::CAPSULE_ANGLES], x[idx::CAPSULE_ANGLES + 1]);
        let t_d_cap = t_parent_to_pendant(phi_cap, theta_cap);
        let (phi_t, theta_t) = (x[idx::TRANSPONDER_ANGLES], x[idx::TRANSPONDER_ANGLES + 1]);
        let t_cap_t = t_parent_to_pendant(phi_t, theta_t);
        let t_i_l = t_c_l * t_i_c;
        let t_i_d = t_l_d * t_i_l;
        let t_i_cap = t_d_cap * t_i_d;
        let t_i_t = t_cap_t * t_i_cap;

        let omega_c = vec3_at(x, idx::CANOPY_RATES);
        let omega_line = t_c_l * omega_c + Vector3::new(0.0, x[idx::LINE_PITCH_RATE], 0.0);
        let omega_drone_rel = vec3_at(x, idx::DRONE_RATES);
        let omega_d = t_l_d * omega_line + omega_drone_rel;
        let omega_capsule_rel =
            pendant_rel_rate(phi_cap, x[idx::CAPSULE_RATES], x[idx::CAPSULE_RATES + 1]);
        let omega_cap = t_d_cap * omega_d + omega_capsule_rel;
        let omega_transponder_rel = pendant_rel_rate(
            phi_t,
            x[idx::TRANSPONDER_RATES],
            x[idx::TRANSPONDER_RATES + 1],
        );
        let omega_t = t_cap_t * omega_cap + omega_transponder_rel;

        let shift_per_line = vehicle.lateral_shift_per_line_m;
        let main_line = x[idx::MAIN_LINE];
        let main_line_rate_mps = vehicle.servo_rate_per_s.x * (main_line_command_m - main_line);
        let lateral = Vector3::new(0.0, shift_per_line * main_line, 0.0);
        let line_drop_m = vehicle.line_mean_m + lateral;
        let line_drop_rate_mps = Vector3::new(0.0, shift_per_line * main_line_rate_mps, 0.0);
        let main_line_dir = [
            (vehicle.lines_m[0] + lateral).normalize(),
            (vehicle.lines_m[1] + lateral).normalize(),
        ];

        let r_capsule = Vector3::new(0.0, 0.0, vehicle.capsule_line_length_m);
        let r_transponder = Vector3::new(0.0, 0.0, vehicle.transponder_line_length_m);

        let p_c = vec3_at(x, idx::POSITION);
        let p_d = p_c
            + t_i_c.transpose() * vehicle.r_line_top_m
            + t_i_l.transpose() * line_drop_m
            + t_i_d.transpose() * vehicle.r_drone_from_line_bottom_m;
        let p_cap = p_d
            + t_i_d.transpose() * vehicle.r_capsule_line_on_drone_m
            + t_i_cap.transpose() * r_capsule;
        let p_t = p_cap + t_i_t.transpose() * r_transponder;

        let v_c = vec3_at(x, idx::CANOPY_VELOCITY);
        let v_line_top = v_c + omega_c.cross(&vehicle.r_line_top_m);
        let v_line_bottom =
            t_c_l * v_line_top + omega_line.cross(&line_drop_m) + line_drop_rate_mps;
        let v_d = t_l_d * v_line_bottom + omega_d.cross(&vehicle.r_drone_from_line_bottom_m);
        let v_cap_top = v_d + omega_d.cross(&vehicle.r_capsule_line_on_drone_m);
        let v_cap = t_d_cap * v_cap_top + omega_cap.cross(&r_capsule);
        let v_t = t_cap_t * v_cap + omega_t.cross(&r_transponder);

        Self {
            t_i_c,
            t_c_l,
            t_l_d,
            t_d_cap,
            t_cap_t,
            t_i_body: [t_i_c, t_i_d, t_i_cap, t_i_t],
            t_i_l,
            omega_body: [omega_c, omega_d, omega_cap, omega_t],
            omega_line,
            omega_drone_rel,
            omega_capsule_rel,
            omega_transponder_rel,
            line_drop_m,
            line_drop_rate_mps,
            main_line_dir,
            main_line_rate_mps,
            position_ned_m: [p_c, p_d, p_cap, p_t],
            velocity_body_mps: [v_c, v_d, v_cap, v_t],
        }
    }

    /// CM velocity of a body in the inertial NED frame, m/s.
    pub fn velocity_ned_mps(&self, body: Body) -> Vector3<f64> {
        let i = body as usize;
        self.t_i_body[i].transpose() * self.velocity_body_mps[i]
    }

    /// Inertial positions of the two ends of each line, `[(top, bottom); 4]` for the right
    /// main line, the left main line, the capsule line and the transponder line, m.
    ///
    /// The tops and bottoms are taken from the bodies they are fixed to, not from the line
    /// vectors, so their distances test the chain.
    pub fn line_ends_ned_m(&self, vehicle: &Vehicle) -> [(Vector3<f64>, Vector3<f64>); 4] {
        let [p_c, p_d, p_cap, p_t] = self.position_ned_m;
        let [t_c, t_d, _, _] = self.t_i_body;
        let to_ned_c = t_c.transpose();
        let to_ned_d = t_d.transpose();
        let main = |side: usize| {
            (
                p_c + to_ned_c * vehicle.r_lines_on_canopy_m[side],
                p_d + to_ned_d * vehicle.r_lines_on_drone_m[side],
            )
        };
        [
            main(0),
            main(1),
            (p_d + to_ned_d * vehicle.r_capsule_line_on_drone_m, p_cap),
            (p_cap, p_t),
        ]
    }
}

/// A vector that is affine in the 14 generalized-speed derivatives `ν̇`: `bias + jac · ν̇`.
#[derive(Debug, Clone, Copy)]
pub struct Affine {
    /// The part that does not depend on `ν̇` (velocity-product terms, prescribed motion).
    pub bias: Vector3<f64>,
    /// How it depends on `ν̇`.
    pub jac: SMatrix<f64, 3, 14>,
}

impl Affine {
    /// A vector whose components are `ν̇[first..first + 3]`.
    pub fn speeds(first: usize) -> Self {
        let mut jac = SMatrix::<f64, 3, 14>::zeros();
        for k in 0..3 {
            jac[(k, first + k)] = 1.0;
        }
        Self {
            bias: Vector3::zeros(),
            jac,
        }
    }

    /// A vector whose component `axis` is `ν̇[speed]` and the others zero.
    pub fn single_speed(axis: usize, speed: usize) -> Self {
        let mut jac = SMatrix::<f64, 3, 14>::zeros();
        jac[(axis, speed)] = 1.0;
        Self {
            bias: Vector3::zeros(),
            jac,
        }
    }

    /// The same vector in another frame.
    pub fn rotated(&self, t: &Matrix3<f64>) -> Self {
        Self {
            bias: t * self.bias,
            jac: t * self.jac,
        }
    }

    /// `self × r` for a vector `r` that does not depend on `ν̇`.
    pub fn cross(&self, r: &Vector3<f64>) -> Self {
        // a × r = −r × a = −[r]× a
        let minus_r = crate::rotation::skew(&(-r));
        Self {
            bias: self.bias.cross(r),
            jac: minus_r * self.jac,
        }
    }

    /// `self + v` for a vector that does not depend on `ν̇`.
    pub fn plus(mut self, v: &Vector3<f64>) -> Self {
        self.bias += v;
        self
    }

    /// The sum of two affine vectors.
    pub fn plus_affine(mut self, other: &Affine) -> Self {
        self.bias += other.bias;
        self.jac += other.jac;
        self
    }

    /// The value for given `ν̇`.
    pub fn eval(&self, speeds_dot: &SMatrix<f64, 14, 1>) -> Vector3<f64> {
        self.bias + self.jac * speeds_dot
    }
}

/// Positions of the generalized-speed derivatives inside `ν̇` (see [`idx::SPEEDS`]).
pub mod nu {
    /// `u̇, v̇, ẇ` of the canopy.
    pub const CANOPY_VELOCITY: usize = 0;
    /// `ṗ, q̇, ṙ` of the canopy.
    pub const CANOPY_RATES: usize = 3;
    /// `q̇_L/C`.
    pub const LINE_PITCH_RATE: usize = 6;
    /// Drone relative rates.
    pub const DRONE_RATES: usize = 7;
    /// Capsule `ṗ, q̇`.
    pub const CAPSULE_RATES: usize = 10;
    /// Transponder `ṗ, q̇`.
    pub const TRANSPONDER_RATES: usize = 12;
}

/// Angular and CM accelerations of every body, affine in `ν̇`, each in its own frame.
pub struct Accelerations {
    /// Inertial angular acceleration of each body, own frame.
    pub angular: [Affine; 4],
    /// Inertial CM acceleration of each body, own frame.
    pub linear: [Affine; 4],
}

/// Derivative (in its own frame) of a hanging body's relative angular velocity
/// `[p, q, −tan φ · q]`, affine in its `ṗ, q̇` at column `first`.
pub fn pendant_rel_rate_dot(phi_rad: f64, p: f64, q: f64, first: usize) -> Affine {
    let tan_phi = phi_rad.tan();
    let sec2 = 1.0 + tan_phi * tan_phi;
    let mut jac = SMatrix::<f64, 3, 14>::zeros();
    jac[(0, first)] = 1.0;
    jac[(1, first + 1)] = 1.0;
    jac[(2, first + 1)] = -tan_phi;
    Affine {
        bias: Vector3::new(0.0, 0.0, -sec2 * p * q),
        jac,
    }
}

/// Acceleration of a point fixed in a rotating body at `r` from a point of known acceleration.
fn transfer(base: &Affine, omega_dot: &Affine, omega: &Vector3<f64>, r: &Vector3<f64>) -> Affine {
    base.plus_affine(&omega_dot.cross(r))
        .plus(&omega.cross(&omega.cross(r)))
}

impl Kinematics {
    /// Accelerations of the chain, given the state (for the pendant angles and rates) and the
    /// main-line servo's acceleration ΔL̈ (prescribed by the servo law).
    pub fn accelerations(
        &self,
        vehicle: &Vehicle,
        x: &StateVector,
        main_line_accel_mps2: f64,
    ) -> Accelerations {
        let [omega_c, omega_d, omega_cap, omega_t] = self.omega_body;
        let v_c = vec3_at(x, idx::CANOPY_VELOCITY);

        let alpha_c = Affine::speeds(nu::CANOPY_RATES);
        let q_line_dot = Affine::single_speed(1, nu::LINE_PITCH_RATE);
        let omega_line_rel = Vector3::new(0.0, x[idx::LINE_PITCH_RATE], 0.0);
        let alpha_line = alpha_c
            .rotated(&self.t_c_l)
            .plus_affine(&q_line_dot)
            .plus(&self.omega_line.cross(&omega_line_rel));
        let alpha_d = alpha_line
            .rotated(&self.t_l_d)
            .plus_affine(&Affine::speeds(nu::DRONE_RATES))
            .plus(&omega_d.cross(&self.omega_drone_rel));
        let alpha_cap = alpha_d
            .rotated(&self.t_d_cap)
            .plus_affine(&pendant_rel_rate_dot(
                x[idx::CAPSULE_ANGLES],
                x[idx::CAPSULE_RATES],
                x[idx::CAPSULE_RATES + 1],
                nu::CAPSULE_RATES,
            ))
            .plus(&omega_cap.cross(&self.omega_capsule_rel));
        let alpha_t = alpha_cap
            .rotated(&self.t_cap_t)
            .plus_affine(&pendant_rel_rate_dot(
                x[idx::TRANSPONDER_ANGLES],
                x[idx::TRANSPONDER_RATES],
                x[idx::TRANSPONDER_RATES + 1],
                nu::TRANSPONDER_RATES,
            ))
            .plus(&omega_t.cross(&self.omega_transponder_rel));

        let a_c = Affine::speeds(nu::CANOPY_VELOCITY).plus(&omega_c.cross(&v_c));
        let a_line_top = transfer(&a_c, &alpha_c, &omega_c, &vehicle.r_line_top_m);
        // The bottom of the lines moves in the line frame with the servo: Coriolis and
        // relative acceleration join the rigid transfer.
        let line_drop_accel = Vector3::new(
            0.0,
            vehicle.lateral_shift_per_line_m * main_line_accel_mps2,
            0.0,
        );
        let a_line_bottom = transfer(
            &a_line_top.rotated(&self.t_c_l),
            &alpha_line,
            &self.omega_line,
            &self.line_drop_m,
        )
        .plus(&(2.0 * self.omega_line.cross(&self.line_drop_rate_mps) + line_drop_accel));
        let a_d = transfer(
            &a_line_bottom.rotated(&self.t_l_d),
            &alpha_d,
            &omega_d,
            &vehicle.r_drone_from_line_bottom_m,
        );
        let a_cap_top = transfer(&a_d, &alpha_d, &omega_d, &vehicle.r_capsule_line_on_drone_m);
        let a_cap = transfer(
            &a_cap_top.rotated(&self.t_d_cap),
            &alpha_cap,
            &omega_cap,
            &Vector3::new(0.0, 0.0, vehicle.capsule_line_length_m),
        );
        let a_t = transfer(
            &a_cap.rotated(&self.t_cap_t),
            &alpha_t,
            &omega_t,
            &Vector3::new(0.0, 0.0, vehicle.transponder_line_length_m),
        );
        Accelerations {
            angular: [alpha_c, alpha_d, alpha_cap, alpha_t],
            linear: [a_c, a_d, a_cap, a_t],
        }
    }
}
