//! Rotation matrices and Euler-angle kinematics in the seed's conventions (§4.1.2).
//!
//! A matrix named `t_a_to_b` maps the components of a vector in frame A to its components in
//! frame B (`v_b = t_a_to_b * v_a`), as the seed's `T_{A−B}`. Euler angles follow the
//! aerospace 3-2-1 sequence: yaw ψ about z, then pitch θ about the new y, then roll φ about the
//! new x, so `T = Tφ·Tθ·Tψ` (eq. 4.8).
//!
//! The flight model calls these on its hot path from another crate (`stx-dynamics`), so the
//! small ones are marked `#[inline]`: they inline there as they did when they lived beside it.

use nalgebra::{Matrix3, Vector3};

/// Plane rotation about x by `phi_rad` (eq. 4.5).
#[inline]
pub fn t_roll(phi_rad: f64) -> Matrix3<f64> {
    let (s, c) = phi_rad.sin_cos();
    Matrix3::new(1.0, 0.0, 0.0, 0.0, c, s, 0.0, -s, c)
}

/// Plane rotation about y by `theta_rad` (eq. 4.6).
#[inline]
pub fn t_pitch(theta_rad: f64) -> Matrix3<f64> {
    let (s, c) = theta_rad.sin_cos();
    Matrix3::new(c, 0.0, -s, 0.0, 1.0, 0.0, s, 0.0, c)
}

/// Plane rotation about z by `psi_rad` (eq. 4.7).
#[inline]
pub fn t_yaw(psi_rad: f64) -> Matrix3<f64> {
    let (s, c) = psi_rad.sin_cos();
    Matrix3::new(c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0)
}

/// Parent-to-body matrix of the 3-2-1 Euler angles `[φ, θ, ψ]` (eq. 4.8), written out
/// because it sits on the model's hot path.
#[inline]
pub fn t_from_euler(euler_rad: &Vector3<f64>) -> Matrix3<f64> {
    let (sf, cf) = euler_rad.x.sin_cos();
    let (st, ct) = euler_rad.y.sin_cos();
    let (sp, cp) = euler_rad.z.sin_cos();
    Matrix3::new(
        ct * cp,
        ct * sp,
        -st,
        sf * st * cp - cf * sp,
        sf * st * sp + cf * cp,
        sf * ct,
        cf * st * cp + sf * sp,
        cf * st * sp - sf * cp,
        cf * ct,
    )
}

/// Parent-to-body matrix of a roll–pitch pair with no relative yaw, `Tφ·Tθ` (eqs. 4.11,
/// 4.12): the capsule and transponder hang from a point and their spin is neglected.
#[inline]
pub fn t_from_roll_pitch(phi_rad: f64, theta_rad: f64) -> Matrix3<f64> {
    let (sf, cf) = phi_rad.sin_cos();
    let (st, ct) = theta_rad.sin_cos();
    Matrix3::new(ct, 0.0, -st, sf * st, cf, sf * ct, cf * st, -sf, cf * ct)
}

/// The 3-2-1 Euler angles `[φ, θ, ψ]` of a parent-to-body matrix, ψ in (−π, π].
#[inline]
pub fn euler_from_t(t: &Matrix3<f64>) -> Vector3<f64> {
    let phi = t[(1, 2)].atan2(t[(2, 2)]);
    let theta = (-t[(0, 2)]).clamp(-1.0, 1.0).asin();
    let psi = t[(0, 1)].atan2(t[(0, 0)]);
    Vector3::new(phi, theta, psi)
}

/// Euler-angle rates `[φ̇, θ̇, ψ̇]` from body rates `[p, q, r]` (the inverse in eq. 4.20).
/// Singular at θ = ±90°, as every 3-2-1 parameterisation is.
#[inline]
pub fn euler_rates(euler_rad: &Vector3<f64>, body_rate_rad_s: &Vector3<f64>) -> Vector3<f64> {
    let (sf, cf) = euler_rad.x.sin_cos();
    let (st, ct) = euler_rad.y.sin_cos();
    let (p, q, r) = (body_rate_rad_s.x, body_rate_rad_s.y, body_rate_rad_s.z);
    let q_sf_r_cf = q * sf + r * cf;
    Vector3::new(p + st / ct * q_sf_r_cf, q * cf - r * sf, q_sf_r_cf / ct)
}

/// Skew-symmetric matrix with `skew(a) * b == a × b`.
#[inline]
pub fn skew(a: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -a.z, a.y, a.z, 0.0, -a.x, -a.y, a.x, 0.0)
}

/// Wraps an angle to (−π, π].
#[inline]
pub fn wrap_pi(angle_rad: f64) -> f64 {
    let wrapped =
        (angle_rad + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
    if wrapped <= -std::f64::consts::PI {
        wrapped + std::f64::consts::TAU
    } else {
        wrapped
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn assert_close(a: &Matrix3<f64>, b: &Matrix3<f64>) {
        assert!((a - b).abs().max() < 1e-12, "{a} != {b}");
    }

    #[test]
    fn euler_matrix_is_the_product_of_plane_rotations() {
        let e = Vector3::new(0.3, -0.7, 2.1);
        assert_close(
            &t_from_euler(&e),
            &(t_roll(e.x) * t_pitch(e.y) * t_yaw(e.z)),
        );
        assert_close(
            &t_from_roll_pitch(0.2, -0.4),
            &(t_roll(0.2) * t_pitch(-0.4)),
        );
    }

    #[test]
    fn euler_angles_round_trip_through_the_matrix() {
        for e in [
            Vector3::new(0.3, -0.7, 2.1),
            Vector3::new(-1.2, 1.3, -3.0),
            Vector3::new(0.0, 0.0, PI),
        ] {
            let back = euler_from_t(&t_from_euler(&e));
            assert!((back - e).abs().max() < 1e-12, "{e} -> {back}");
        }
    }

    #[test]
    fn positive_yaw_turns_north_into_negative_body_y() {
        // A body yawed 90° to the east sees north on its left (−y).
        let north_in_body = t_from_euler(&Vector3::new(0.0, 0.0, PI / 2.0)) * Vector3::x();
        assert!((north_in_body - Vector3::new(0.0, -1.0, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn euler_rates_match_a_finite_difference_of_the_rotation() {
        // Poisson: d/dt T = −[ω]× T, so the angles advanced by their rates reproduce it.
        let e = Vector3::new(0.4, -0.3, 1.0);
        let w = Vector3::new(0.2, -0.5, 0.7);
        let h = 1e-6;
        let t0 = t_from_euler(&e);
        let t1 = t_from_euler(&(e + euler_rates(&e, &w) * h));
        let dt_dt = (t1 - t0) / h;
        assert!((dt_dt + skew(&w) * t0).abs().max() < 1e-5);
    }

    #[test]
    fn wrap_pi_keeps_angles_in_the_half_open_interval() {
        assert!((wrap_pi(3.0 * PI) - PI).abs() < 1e-12);
        assert!((wrap_pi(-PI) - PI).abs() < 1e-12);
        assert!((wrap_pi(-3.5 * PI) - 0.5 * PI).abs() < 1e-12);
        assert_eq!(wrap_pi(0.25), 0.25);
    }
}
