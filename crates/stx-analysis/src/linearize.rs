//! Numerical linearisation of the flight model about a trim (seed §6.1, eqs. 6.5–6.7).
//!
//! All 31 states are kept, in the layout of seed eq. 4.14, so the matrices compare with
//! appendix A.12 entry by entry and the seed's four zero eigenvalues appear for the reason the
//! seed gives: in calm air over a flat Earth nothing depends on the north and east position
//! or on the heading, so their columns of `A` vanish (x, y, ψ), and the altitude enters only
//! through the slow density gradient (z: an eigenvalue of order 10⁻⁴ s⁻¹ rather than 0).
//! Reducing the model to 27 states would hide that, and the output equation needs positions.
//!
//! Inputs (seed §6.1, p = 2): `U_L`, the differential main-line command (m), and `U_S`, the
//! symmetric brake command driving both brake servos (0…1). A trim with released brakes sits
//! at the bottom of the brakes' range, so `U_S` is stepped forwards only; the brake command
//! enters the model only through the servo lags `Δ̇ = K (U − Δ)`, which are linear in it, so
//! the forward difference is exact there.
//!
//! Outputs (seed eq. 6.4): the drone's inertial position x, y, z (m), its velocity in the
//! inertial NED frame u, v, w (m/s) and its attitude φ, θ, ψ relative to the inertial frame
//! (rad) — what its GPS and AHRS measure. `D` is not zero: the main-line servo's rate moves
//! the drone sideways (seed §3.6.1), and that rate is `K (U_L − ΔL)`.

use nalgebra::{DMatrix, DVector};
use stx_dynamics::model::{Body, Kinematics, ParafoilModel};
use stx_dynamics::rotation::euler_from_t;
use stx_dynamics::state::{Controls, N_STATES, StateVector, idx};
use stx_dynamics::vehicle::Vehicle;

use crate::jacobian::{Step, jacobian, step_size};
use crate::lti::LinearSystem;
use crate::trim::{Trim, calm_environment};

/// Names of the two inputs.
pub const INPUT_NAMES: [&str; 2] = ["U_L (main line, m)", "U_S (symmetric brake, 0..1)"];
/// Names of the nine outputs of seed eq. 6.4.
pub const OUTPUT_NAMES: [&str; 9] = [
    "x_d", "y_d", "z_d", "u_d", "v_d", "w_d", "phi_d", "theta_d", "psi_d",
];

/// The flight model linearised about a trim.
#[derive(Debug, Clone)]
pub struct LinearModel {
    /// The trim it was linearised about.
    pub trim: Trim,
    /// `A`, `B`, `C`, `D` in deviations from the trim (states in SI units and radians).
    pub system: LinearSystem,
    /// Servo rate constants K (main line, right brake, left brake), 1/s: the eigenvalues −K.
    pub servo_rates_per_s: [f64; 3],
}

/// Typical size of each state, the floor of its finite-difference step: 1 m, 1 m/s, 1 rad,
/// 1 rad/s, the brakes' full travel, and 1 cm of main line (its travel is 1.5 cm).
pub fn state_scales() -> [f64; N_STATES] {
    let mut s = [1.0; N_STATES];
    s[idx::MAIN_LINE] = 0.01;
    s
}

/// The input vector `[U_L, U_S]` of a command.
pub fn input_vector(controls: &Controls) -> DVector<f64> {
    DVector::from_vec(vec![
        controls.main_line_m,
        0.5 * (controls.brake_right + controls.brake_left),
    ])
}

/// The command of an input vector.
pub fn controls_of(u: &DVector<f64>) -> Controls {
    Controls {
        main_line_m: u[0],
        brake_right: u[1],
        brake_left: u[1],
    }
}

/// The outputs of seed eq. 6.4 for state `x` and main-line command `u_l`.
pub fn outputs(vehicle: &Vehicle, x: &StateVector, main_line_command_m: f64) -> DVector<f64> {
    let k = Kinematics::new(vehicle, x, main_line_command_m);
    let p = k.position_ned_m[Body::Drone as usize];
    let v = k.velocity_ned_mps(Body::Drone);
    let e = euler_from_t(&k.t_i_body[Body::Drone as usize]);
    DVector::from_vec(vec![p.x, p.y, p.z, v.x, v.y, v.z, e.x, e.y, e.z])
}

/// How each input may be stepped at command `u0`: the brake forwards while it is released.
fn input_steps(u0: &DVector<f64>) -> [Step; 2] {
    let brake_step = if u0[1] < step_size(u0[1], 1.0) {
        Step::Forward
    } else {
        Step::Central
    };
    [Step::Central, brake_step]
}

/// Linearises `vehicle` about `trim`.
pub fn linearize(vehicle: &Vehicle, trim: &Trim) -> LinearModel {
    let mut model = ParafoilModel::new(vehicle.clone(), calm_environment());
    let x0 = DVector::from_column_slice(trim.state.as_slice());
    let u0 = input_vector(&trim.controls);
    let state_of = |z: &DVector<f64>| StateVector::from_column_slice(z.as_slice());

    let scales = state_scales();
    let state_steps = [Step::Central; N_STATES];
    model.set_controls(trim.controls);
    let a = jacobian(
        |z| {
            let d = model.evaluate(0.0, &state_of(z)).derivative;
            DVector::from_column_slice(d.as_slice())
        },
        &x0,
        &scales,
        &state_steps,
    );
    let b = jacobian(
        |u| {
            let mut m = model.clone();
            m.set_controls(controls_of(u));
            let d = m.evaluate(0.0, &trim.state).derivative;
            DVector::from_column_slice(d.as_slice())
        },
        &u0,
        &[0.01, 1.0],
        &input_steps(&u0),
    );
    let c = jacobian(
        |z| outputs(vehicle, &state_of(z), u0[0]),
        &x0,
        &scales,
        &state_steps,
    );
    let d = jacobian(
        |u| outputs(vehicle, &trim.state, u[0]),
        &u0,
        &[0.01, 1.0],
        &input_steps(&u0),
    );
    LinearModel {
        trim: trim.clone(),
        system: LinearSystem { a, b, c, d },
        servo_rates_per_s: vehicle.servo_rate_per_s.into(),
    }
}

/// Gradient of a scalar function of the state at the trim, by the same central differences.
pub fn state_gradient(trim: &Trim, f: impl Fn(&StateVector) -> f64) -> DMatrix<f64> {
    let x0 = DVector::from_column_slice(trim.state.as_slice());
    jacobian(
        |z| DVector::from_element(1, f(&StateVector::from_column_slice(z.as_slice()))),
        &x0,
        &state_scales(),
        &[Step::Central; N_STATES],
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trim::trim;

    #[test]
    fn input_matrix_has_the_servo_gains_and_drives_only_what_it_should() {
        let v = Vehicle::straplex();
        let t = trim(&v, 100.0, Controls::default()).expect("trim");
        let lin = linearize(&v, &t);
        let b = &lin.system.b;
        let k = v.servo_rate_per_s;
        assert!(
            (b[(idx::MAIN_LINE, 0)] - k.x).abs() < 1e-6,
            "{}",
            b[(idx::MAIN_LINE, 0)]
        );
        assert!((b[(idx::BRAKE_RIGHT, 1)] - k.y).abs() < 1e-9);
        assert!((b[(idx::BRAKE_LEFT, 1)] - k.z).abs() < 1e-9);
        // The brake command acts through the servo lag only.
        for i in 0..idx::BRAKE_RIGHT {
            assert!(b[(i, 1)].abs() < 1e-9, "{} {}", idx::NAMES[i], b[(i, 1)]);
        }
        // The main-line command's rate moves the drone: lateral accelerations, no
        // longitudinal ones (symmetric trim).
        assert!(b[(idx::CANOPY_VELOCITY + 1, 0)].abs() > 1e-3);
        assert!(b[(idx::CANOPY_VELOCITY, 0)].abs() < 1e-6);
        // Calm air over a flat Earth: nothing depends on x, y or ψ but the position rates
        // (ψ turns the velocity).
        let a = &lin.system.a;
        for j in [0, 1, idx::CANOPY_EULER + 2] {
            let dynamics = a.view((3, j), (N_STATES - 3, 1)).amax();
            assert!(dynamics < 1e-9, "column {} {dynamics}", idx::NAMES[j]);
        }
        assert!(a.column(0).amax() < 1e-9 && a.column(1).amax() < 1e-9);
        assert!(a[(1, idx::CANOPY_EULER + 2)] > 4.0, "ẏ = V_h ψ");
        // Output: the drone's north position follows the canopy's.
        assert!((lin.system.c[(0, 0)] - 1.0).abs() < 1e-9);
    }
}
