//! The hanging bodies' two angles, and the two charts they are read in.
//!
//! The capsule and the transponder are point masses on their lines (seed §4.4.2 neglects their
//! own rotation), so what each one's two states hold is a direction on a sphere and its rate.
//! No pair of angles covers a sphere: the seed's roll-then-pitch pair (eqs. 4.11, 4.12, 4.33)
//! has a pole where the line lies along the parent's y axis, where `θ̇ = q / cos φ` has no
//! value, and a line that swings there stops any integrator (the failed Monte Carlo runs of
//! `crates/stx-gnc/GNC_NOTES.md`, "Failed runs"). So each pendant's angles are read in one of
//! two charts: the seed's, or the same pair taken from the parent's axes turned 90° about its
//! z axis, whose pole lies along the parent's x axis instead. [`rechart`] moves a pendant to
//! the other chart when its roll passes [`SWITCH_ROLL_RAD`]; there it starts 30° or less from
//! hanging straight, so each chart's pole stays at least 30° of swing away.
//!
//! The chart rides in the roll itself, so that a state vector stays the whole truth for
//! everything that reads one (recordings, replays, the station's stack view) and the state's
//! layout (seed eq. 4.14) is unchanged: a roll within π of 0 is in the seed's chart, a roll
//! within π of 2π in the turned one. Sines, cosines and tangents do not see the 2π, so only the
//! parent-to-body matrix, [`t_parent_to_pendant`], reads it.
//!
//! Moving a pendant to the other chart turns it about its own line, which nothing in the model
//! feels (a point mass has no spin); but the spin rate a chart gives is its own (`−tan φ·q`),
//! so the transponder, whose angles are taken from the capsule's axes, is read again in the
//! capsule's new axes with its rates corrected for the capsule's new spin.

use std::f64::consts::TAU;

use nalgebra::{Matrix3, Vector3};

use crate::rotation::t_from_roll_pitch;
use crate::state::{StateVector, idx};

/// Roll (from the chart's own axes) past which a pendant moves to the other chart, rad.
pub const SWITCH_ROLL_RAD: f64 = 60.0 * std::f64::consts::PI / 180.0;

/// Which axes a pendant's angles are taken from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Chart {
    /// The seed's: roll then pitch from the parent's axes; pole along the parent's y axis.
    Seed,
    /// Roll then pitch from the parent's axes turned 90° about z; pole along its x axis.
    Turned,
}

impl Chart {
    /// The chart a stored roll is in.
    pub fn of_roll(phi_rad: f64) -> Self {
        if (phi_rad / TAU).round().rem_euclid(2.0) == 0.0 {
            Chart::Seed
        } else {
            Chart::Turned
        }
    }

    fn other(self) -> Self {
        match self {
            Chart::Seed => Chart::Turned,
            Chart::Turned => Chart::Seed,
        }
    }

    /// What the stored roll adds to the chart's own roll, rad.
    fn roll_offset_rad(self) -> f64 {
        match self {
            Chart::Seed => 0.0,
            Chart::Turned => TAU,
        }
    }

    /// Parent-to-chart-axes matrix.
    fn base(self) -> Matrix3<f64> {
        match self {
            Chart::Seed => Matrix3::identity(),
            // Yaw of 90°: the chart's x axis is the parent's y axis.
            Chart::Turned => Matrix3::new(0.0, 1.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 1.0),
        }
    }

    /// The stored angles that put a pendant's line (its body z axis) along `line_in_parent`
    /// (a unit vector in the parent's frame).
    fn angles_of(self, line_in_parent: &Vector3<f64>) -> (f64, f64) {
        // The seed's pair puts the body z axis at (cos φ sin θ, −sin φ, cos φ cos θ).
        let u = self.base() * line_in_parent;
        let phi = (-u.y).clamp(-1.0, 1.0).asin();
        let theta = u.x.atan2(u.z);
        (phi + self.roll_offset_rad(), theta)
    }
}

/// Parent-to-body matrix of a pendant from its stored angles, in whichever chart the roll
/// says.
pub fn t_parent_to_pendant(phi_rad: f64, theta_rad: f64) -> Matrix3<f64> {
    let t = t_from_roll_pitch(phi_rad, theta_rad);
    // Every evaluation walks the chain through here: the seed's chart, nearly always the one,
    // costs no product with its identity base.
    match Chart::of_roll(phi_rad) {
        Chart::Seed => t,
        turned => t * turned.base(),
    }
}

/// Angular velocity of a hanging body relative to its parent, in its own frame, from its
/// two states: with the roll-then-pitch sequence and no relative yaw, `[φ̇, cos φ·θ̇, −sin φ·θ̇]`
/// (seed eq. 4.33), and the states are its x and y components `p = φ̇`, `q = cos φ·θ̇`. The
/// chart's constant base turn adds no rate.
pub fn pendant_rel_rate(phi_rad: f64, p: f64, q: f64) -> Vector3<f64> {
    Vector3::new(p, q, -phi_rad.tan() * q)
}

fn near_pole(phi_rad: f64) -> bool {
    phi_rad.sin().abs() > SWITCH_ROLL_RAD.sin()
}

/// The same physical state with a pendant that has swung past [`SWITCH_ROLL_RAD`] moved to its
/// other chart, or `None` when both are well inside theirs. Every body's position and velocity,
/// and so the equations' solution, are unchanged (see the module doc).
pub fn rechart(x: &StateVector) -> Option<StateVector> {
    let (phi_c, phi_t) = (x[idx::CAPSULE_ANGLES], x[idx::TRANSPONDER_ANGLES]);
    let capsule_moves = near_pole(phi_c);
    if !capsule_moves && !near_pole(phi_t) {
        return None;
    }
    let capsule = if capsule_moves {
        Chart::of_roll(phi_c).other()
    } else {
        Chart::of_roll(phi_c)
    };
    // The transponder is read again in the capsule's new axes, where it may be clear of its
    // pole already.
    let transponder = Chart::of_roll(phi_t);
    let y = in_charts(x, capsule, transponder);
    Some(if near_pole(y[idx::TRANSPONDER_ANGLES]) {
        in_charts(x, capsule, transponder.other())
    } else {
        y
    })
}

/// The same physical state with the capsule's angles read in chart `capsule` and the
/// transponder's in chart `transponder`.
pub fn in_charts(x: &StateVector, capsule: Chart, transponder: Chart) -> StateVector {
    let read = |angles: usize, rates: usize| (x[angles], x[angles + 1], x[rates], x[rates + 1]);
    let (phi_c, theta_c, p_c, q_c) = read(idx::CAPSULE_ANGLES, idx::CAPSULE_RATES);
    let (phi_t, theta_t, p_t, q_t) = read(idx::TRANSPONDER_ANGLES, idx::TRANSPONDER_RATES);
    let z = Vector3::z();

    // The capsule: `turn` takes a vector in its old axes to its new ones.
    let t_c = t_parent_to_pendant(phi_c, theta_c);
    let ((new_phi_c, new_theta_c), turn) = if capsule == Chart::of_roll(phi_c) {
        // Left exactly as it was, not read again through a round trip of rounding.
        ((phi_c, theta_c), Matrix3::identity())
    } else {
        let angles = capsule.angles_of(&(t_c.transpose() * z));
        (
            angles,
            t_parent_to_pendant(angles.0, angles.1) * t_c.transpose(),
        )
    };
    let rate_c = turn * pendant_rel_rate(phi_c, p_c, q_c);
    let (new_p_c, new_q_c) = (rate_c.x, rate_c.y);
    // The capsule's spin about its line becomes the new chart's; the transponder's rates
    // relative to it take up the difference.
    let spin_change = pendant_rel_rate(new_phi_c, new_p_c, new_q_c).z - rate_c.z;

    let t_t = t_parent_to_pendant(phi_t, theta_t);
    let (new_phi_t, new_theta_t) = transponder.angles_of(&(turn * (t_t.transpose() * z)));
    let new_t_t = t_parent_to_pendant(new_phi_t, new_theta_t);
    let turn_t = new_t_t * turn * t_t.transpose();
    let rate_t = turn_t * pendant_rel_rate(phi_t, p_t, q_t) - spin_change * (new_t_t * z);

    let mut out = *x;
    for (i, value) in [
        (idx::CAPSULE_ANGLES, new_phi_c),
        (idx::CAPSULE_ANGLES + 1, new_theta_c),
        (idx::CAPSULE_RATES, new_p_c),
        (idx::CAPSULE_RATES + 1, new_q_c),
        (idx::TRANSPONDER_ANGLES, new_phi_t),
        (idx::TRANSPONDER_ANGLES + 1, new_theta_t),
        (idx::TRANSPONDER_RATES, rate_t.x),
        (idx::TRANSPONDER_RATES + 1, rate_t.y),
    ] {
        out[i] = value;
    }
    out
}

#[cfg(test)]
mod tests {
    use nalgebra::SMatrix;

    use super::*;
    use crate::model::{Body, Environment, Kinematics, ParafoilModel};
    use crate::state::Pose;
    use crate::vehicle::Vehicle;

    fn model() -> ParafoilModel {
        ParafoilModel::new(Vehicle::straplex(), Environment::calm())
    }

    /// A stack in flight with the drone turning and both pendants swinging: `capsule` and
    /// `transponder` are `[roll°, pitch°, p, q]` (rates in rad/s).
    fn swinging(capsule: [f64; 4], transponder: [f64; 4]) -> StateVector {
        let mut x = Pose::seed_release(500.0).to_state();
        x[idx::CANOPY_RATES + 2] = 0.3;
        x[idx::DRONE_RATES] = 0.4;
        x[idx::DRONE_RATES + 2] = -0.8;
        for (angles, rates, [roll, pitch, p, q]) in [
            (idx::CAPSULE_ANGLES, idx::CAPSULE_RATES, capsule),
            (idx::TRANSPONDER_ANGLES, idx::TRANSPONDER_RATES, transponder),
        ] {
            x[angles] = roll.to_radians();
            x[angles + 1] = pitch.to_radians();
            x[rates] = p;
            x[rates + 1] = q;
        }
        x
    }

    /// Every body's position, velocity and acceleration (NED), and the line tensions, agree
    /// between two states: what "the same physical state" means for point-mass pendants.
    fn assert_same_motion(a: &StateVector, b: &StateVector) {
        let m = model();
        let v = &m.vehicle;
        let u = m.controls().main_line_m;
        let (ea, eb) = (m.evaluate(0.0, a), m.evaluate(0.0, b));
        let (ka, kb) = (Kinematics::new(v, a, u), Kinematics::new(v, b, u));
        // Inertial accelerations in NED, from the chain the equations are built on.
        let accelerations = |k: &Kinematics, x: &StateVector, dx: &StateVector| {
            let main_line_accel = -v.servo_rate_per_s.x * k.main_line_rate_mps;
            let acc = k.accelerations(v, x, main_line_accel);
            let nu_dot = SMatrix::<f64, 14, 1>::from_fn(|j, _| dx[idx::SPEEDS[j]]);
            let acc: [Vector3<f64>; 4] =
                std::array::from_fn(|i| k.t_i_body[i].transpose() * acc.linear[i].eval(&nu_dot));
            acc
        };
        let acc_a = accelerations(&ka, a, &ea.derivative);
        let acc_b = accelerations(&kb, b, &eb.derivative);
        for body in Body::ALL {
            let i = body as usize;
            let dp = (ka.position_ned_m[i] - kb.position_ned_m[i]).norm();
            assert!(dp < 1e-9, "{} moved {dp} m", body.name());
            let dv = (ka.velocity_ned_mps(body) - kb.velocity_ned_mps(body)).norm();
            assert!(dv < 1e-9, "{}'s velocity changed by {dv} m/s", body.name());
            let da = (acc_a[i] - acc_b[i]).norm();
            assert!(
                da < 1e-9,
                "{}'s acceleration changed by {da} m/s²",
                body.name()
            );
        }
        let (ta, tb) = (ea.tensions.as_array(), eb.tensions.as_array());
        for (line, (ta, tb)) in ta.iter().zip(tb).enumerate() {
            assert!((ta - tb).abs() < 1e-6, "line {line}: {ta} N against {tb} N");
        }
    }

    #[test]
    fn pendants_inside_their_charts_are_left_alone() {
        let x = swinging([59.0, -20.0, 1.0, -0.5], [-59.0, 100.0, 2.0, 1.5]);
        assert_eq!(rechart(&x), None);
    }

    #[test]
    fn a_capsule_past_sixty_degrees_of_roll_moves_to_the_turned_chart_and_nothing_moves() {
        let x = swinging([65.0, 20.0, 0.7, -1.1], [30.0, -40.0, 1.5, 2.0]);
        let y = rechart(&x).expect("the capsule is past its switch");
        assert_eq!(Chart::of_roll(y[idx::CAPSULE_ANGLES]), Chart::Turned);
        // 65° of roll from the drone's y axis is at most 25° from its x–z plane: the turned
        // chart reads that as a roll of 25° or less.
        let roll = y[idx::CAPSULE_ANGLES] - TAU;
        assert!(roll.abs() <= 25.0_f64.to_radians() + 1e-12, "{roll}");
        assert_same_motion(&x, &y);
    }

    #[test]
    fn a_transponder_near_its_pole_moves_alone() {
        let x = swinging([10.0, -5.0, 0.2, 0.3], [-70.0, 150.0, -3.0, 2.5]);
        let y = rechart(&x).expect("the transponder is past its switch");
        assert_eq!(y[idx::CAPSULE_ANGLES], x[idx::CAPSULE_ANGLES]);
        assert_eq!(y[idx::CAPSULE_RATES + 1], x[idx::CAPSULE_RATES + 1]);
        assert_eq!(Chart::of_roll(y[idx::TRANSPONDER_ANGLES]), Chart::Turned);
        assert_same_motion(&x, &y);
    }

    #[test]
    fn a_capsule_near_the_turned_charts_pole_comes_back_to_the_seeds_chart() {
        let x = swinging([65.0, 20.0, 0.7, -1.1], [-70.0, 150.0, -3.0, 2.5]);
        let turned = rechart(&x).expect("both are past their switch");
        // Swing both back near the turned chart's pole (the drone's and capsule's x axes).
        let mut y = turned;
        y[idx::CAPSULE_ANGLES] = TAU + 62.0_f64.to_radians();
        y[idx::TRANSPONDER_ANGLES] = TAU - 75.0_f64.to_radians();
        let back = rechart(&y).expect("both are past the turned chart's switch");
        assert_eq!(Chart::of_roll(back[idx::CAPSULE_ANGLES]), Chart::Seed);
        // The transponder is read again from the capsule's new axes and lands in whichever
        // chart keeps it clear of a pole.
        let roll_t = back[idx::TRANSPONDER_ANGLES];
        assert!(roll_t.sin().abs() <= SWITCH_ROLL_RAD.sin(), "{roll_t}");
        assert_same_motion(&y, &back);
    }
}
