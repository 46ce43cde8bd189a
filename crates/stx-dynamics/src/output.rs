//! What a simulation reports at each instant: per body, in the inertial frame, position,
//! velocity, Euler angles and rates; the four tensions; the canopy's air data; the servos.
//!
//! Angles here are degrees and wrapped, because people read them; the state keeps radians
//! and unwrapped yaw.

use serde::Serialize;

use crate::model::{Body, Kinematics, ParafoilModel, Tensions};
use crate::rotation::euler_from_t;
use crate::state::{StateVector, idx};

/// One body's motion.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct BodyOutput {
    /// CM position, inertial NED, m.
    pub position_ned_m: [f64; 3],
    /// CM velocity, inertial NED, m/s.
    pub velocity_ned_mps: [f64; 3],
    /// Roll, pitch, yaw of the body relative to the inertial frame, degrees (yaw in
    /// (−180, 180]).
    pub euler_deg: [f64; 3],
    /// Angular velocity relative to the inertial frame, in the body's frame, degrees/s.
    pub rates_deg_s: [f64; 3],
}

/// The whole vehicle at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Sample {
    /// Simulation time, s.
    pub time_s: f64,
    /// Canopy, drone, capsule, transponder.
    pub bodies: [BodyOutput; 4],
    /// Line tensions.
    pub tensions_n: [f64; 4],
    /// Canopy airspeed, m/s.
    pub airspeed_mps: f64,
    /// Canopy angle of attack, degrees.
    pub alpha_deg: f64,
    /// Canopy sideslip, degrees.
    pub beta_deg: f64,
    /// Line pitch relative to the canopy, degrees.
    pub line_pitch_deg: f64,
    /// Servo positions: ΔL (m), right brake, left brake (0…1).
    pub servos: [f64; 3],
}

impl Sample {
    /// The output of one body.
    pub fn body(&self, body: Body) -> &BodyOutput {
        &self.bodies[body as usize]
    }

    /// Total (inertial) speed of the canopy, m/s.
    pub fn canopy_speed_mps(&self) -> f64 {
        let v = self.body(Body::Canopy).velocity_ned_mps;
        (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
    }

    /// Column names for [`Sample::csv_row`].
    pub fn csv_header() -> String {
        let mut cols = vec!["time_s".to_string()];
        for body in Body::ALL {
            let b = body.name();
            for field in [
                "x_m",
                "y_m",
                "z_m",
                "vn_mps",
                "ve_mps",
                "vd_mps",
                "roll_deg",
                "pitch_deg",
                "yaw_deg",
                "p_deg_s",
                "q_deg_s",
                "r_deg_s",
            ] {
                cols.push(format!("{b}_{field}"));
            }
        }
        cols.extend(
            [
                "tension_right_main_n",
                "tension_left_main_n",
                "tension_capsule_n",
                "tension_transponder_n",
                "airspeed_mps",
                "alpha_deg",
                "beta_deg",
                "line_pitch_deg",
                "main_line_m",
                "brake_right",
                "brake_left",
            ]
            .map(String::from),
        );
        cols.join(",")
    }

    /// The sample as one CSV line, columns as [`Sample::csv_header`].
    pub fn csv_row(&self) -> String {
        let mut values = vec![self.time_s];
        for b in &self.bodies {
            values.extend(b.position_ned_m);
            values.extend(b.velocity_ned_mps);
            values.extend(b.euler_deg);
            values.extend(b.rates_deg_s);
        }
        values.extend(self.tensions_n);
        values.extend([
            self.airspeed_mps,
            self.alpha_deg,
            self.beta_deg,
            self.line_pitch_deg,
        ]);
        values.extend(self.servos);
        values
            .iter()
            .map(|v| format!("{v:.6}"))
            .collect::<Vec<_>>()
            .join(",")
    }
}

impl ParafoilModel {
    /// The outputs at one state (one model evaluation, not counted).
    pub fn sample(&self, time_s: f64, x: &StateVector) -> Sample {
        let evaluation = self.evaluate(time_s, x);
        let kin = Kinematics::new(&self.vehicle, x, self.controls().main_line_m);
        let bodies = Body::ALL.map(|body| {
            let i = body as usize;
            let e = euler_from_t(&kin.t_i_body[i]);
            let w = kin.omega_body[i];
            let p = kin.position_ned_m[i];
            let v = kin.velocity_ned_mps(body);
            BodyOutput {
                position_ned_m: [p.x, p.y, p.z],
                velocity_ned_mps: [v.x, v.y, v.z],
                euler_deg: [e.x.to_degrees(), e.y.to_degrees(), e.z.to_degrees()],
                rates_deg_s: [w.x.to_degrees(), w.y.to_degrees(), w.z.to_degrees()],
            }
        });
        let Tensions {
            right_main_n,
            left_main_n,
            capsule_n,
            transponder_n,
        } = evaluation.tensions;
        Sample {
            time_s,
            bodies,
            tensions_n: [right_main_n, left_main_n, capsule_n, transponder_n],
            airspeed_mps: evaluation.canopy_air.airspeed_mps,
            alpha_deg: evaluation.canopy_air.alpha_rad.to_degrees(),
            beta_deg: evaluation.canopy_air.beta_rad.to_degrees(),
            line_pitch_deg: x[idx::LINE_PITCH].to_degrees(),
            servos: [x[idx::MAIN_LINE], x[idx::BRAKE_RIGHT], x[idx::BRAKE_LEFT]],
        }
    }
}
