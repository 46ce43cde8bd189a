//! Aerodynamic forces and moments (seed §4.4): the canopy's lift, drag and side force with
//! brakes and rate damping, and the pure drag of the hanging bodies.

use nalgebra::Vector3;

use crate::vehicle::Vehicle;

/// The canopy's air data at one instant.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CanopyAir {
    /// Airspeed of the canopy CM, m/s.
    pub airspeed_mps: f64,
    /// Angle of attack α = atan2(w, u) of the air-relative velocity, rad.
    pub alpha_rad: f64,
    /// Sideslip β = asin(v / V), rad.
    pub beta_rad: f64,
    /// Air density, kg/m³.
    pub density_kg_per_m3: f64,
}

/// Force and moment about the CM, both in the body's frame.
#[derive(Debug, Clone, Copy)]
pub struct Wrench {
    /// Force, N.
    pub force_n: Vector3<f64>,
    /// Moment about the CM, N·m.
    pub moment_nm: Vector3<f64>,
}

/// Canopy aerodynamics for air-relative velocity `v_rel` and angular velocity `omega` (canopy
/// frame) with brake servo positions `brake_right`, `brake_left` (0…1).
///
/// Force `F = −½ρV²S (C_D x_A + C_Y y_A + C_L z_A)` with `x_A` along the relative wind, `z_A`
/// perpendicular to it in the canopy's x–z plane (so lift is `−C_L z_A`) and `y_A = z_A × x_A`
/// (eqs. 4.60–4.63, 4.13). Moments: the seed prints positive damping coefficients under a
/// leading minus (eq. 4.87), so `Cl_p`, `Cm_q`, `Cn_r` enter with the sign that opposes the
/// rate; `Cn_β` keeps the seed's sign (negative turns the nose into the relative wind). Brakes
/// add `C_Lδs δs`, `C_Dδs δs`, `C_lδa δa`, `C_nδa δa`. The rate terms are written as
/// `ρ V S b² p / 4` rather than `q S b (b p / 2V)` so that they stay finite at zero airspeed.
pub fn canopy(
    vehicle: &Vehicle,
    density: f64,
    v_rel: &Vector3<f64>,
    omega: &Vector3<f64>,
    brake_right: f64,
    brake_left: f64,
) -> (Wrench, CanopyAir) {
    let canopy = &vehicle.config.canopy;
    let aero = &canopy.aero;
    let brakes = &canopy.brakes;
    let speed = v_rel.norm();
    let alpha = v_rel.z.atan2(v_rel.x);
    let beta = if speed > 0.0 {
        (v_rel.y / speed).clamp(-1.0, 1.0).asin()
    } else {
        0.0
    };
    let symmetric = 0.5 * (brake_right + brake_left);
    let asymmetric = brake_right - brake_left;
    let cl = aero.cl0 + aero.cl_alpha * alpha + brakes.cl_ds * symmetric;
    let cd = aero.cd0 + aero.cd_alpha2 * alpha * alpha + brakes.cd_ds * symmetric;
    let cy = aero.cy_beta * beta;

    let (s_alpha, c_alpha) = alpha.sin_cos();
    let (s_beta, c_beta) = beta.sin_cos();
    let x_a = Vector3::new(c_alpha * c_beta, s_beta, s_alpha * c_beta);
    let y_a = Vector3::new(-c_alpha * s_beta, c_beta, -s_alpha * s_beta);
    let z_a = Vector3::new(-s_alpha, 0.0, c_alpha);
    let area = canopy.area_m2;
    let q_s = 0.5 * density * speed * speed * area;
    let force = -q_s * (cd * x_a + cy * y_a + cl * z_a);

    let (b, c) = (canopy.span_m, canopy.chord_m);
    let rate_scale = 0.25 * density * speed * area;
    let moment = Vector3::new(
        -rate_scale * b * b * aero.clp * omega.x + q_s * b * brakes.cl_da * asymmetric,
        -rate_scale * c * c * aero.cmq * omega.y,
        -rate_scale * b * b * aero.cnr * omega.z - q_s * b * aero.cn_beta * beta
            + q_s * b * brakes.cn_da * asymmetric,
    ) + vehicle.r_cp_canopy_m.cross(&force);
    (
        Wrench {
            force_n: force,
            moment_nm: moment,
        },
        CanopyAir {
            airspeed_mps: speed,
            alpha_rad: alpha,
            beta_rad: beta,
            density_kg_per_m3: density,
        },
    )
}

/// Drone aerodynamics (eqs. 4.69, 4.95–4.98): drag along the relative wind with the same
/// coefficient in every direction, rate damping, and the drag's moment about the CM from the
/// pressure centre.
pub fn drone(
    vehicle: &Vehicle,
    density: f64,
    v_rel: &Vector3<f64>,
    omega: &Vector3<f64>,
) -> Wrench {
    let d = &vehicle.config.drone;
    let speed = v_rel.norm();
    let force = drag(density, vehicle.drone_drag_area_m2, v_rel);
    let rate_scale = 0.25 * density * speed * d.area_m2;
    let (b, c) = (d.width_m, d.length_m);
    let moment = Vector3::new(
        -rate_scale * b * b * d.clp * omega.x,
        -rate_scale * c * c * d.cmq * omega.y,
        -rate_scale * b * b * d.cnr * omega.z,
    ) + vehicle.r_cp_drone_m.cross(&force);
    Wrench {
        force_n: force,
        moment_nm: moment,
    }
}

/// Drag `−½ ρ |V| C_D S V` of a bluff body (eqs. 4.75, 4.80), N.
pub fn drag(density: f64, drag_area_m2: f64, v_rel: &Vector3<f64>) -> Vector3<f64> {
    -0.5 * density * drag_area_m2 * v_rel.norm() * v_rel
}

#[cfg(test)]
mod tests {
    use super::*;

    const RHO: f64 = 1.225;

    fn forward_glide() -> Vector3<f64> {
        // 7 m/s at α = 20°, no sideslip.
        let alpha = 20f64.to_radians();
        Vector3::new(alpha.cos(), 0.0, alpha.sin()) * 7.0
    }

    #[test]
    fn lift_pulls_up_and_forward_and_drag_back_along_the_wind() {
        let v = Vehicle::straplex();
        let v_rel = forward_glide();
        let (w, air) = canopy(&v, RHO, &v_rel, &Vector3::zeros(), 0.0, 0.0);
        assert!((air.alpha_rad - 20f64.to_radians()).abs() < 1e-12);
        // Decompose along and across the relative wind.
        let along = w.force_n.dot(&v_rel.normalize());
        let q_s = 0.5 * RHO * 49.0 * 3.0;
        let a = air.alpha_rad;
        let (cl, cd) = (0.25 + 2.3 * a, 0.15 + a * a);
        assert!((along + q_s * cd).abs() < 1e-9, "drag {along}");
        let lift = w.force_n - v_rel.normalize() * along;
        assert!((lift.norm() - q_s * cl).abs() < 1e-9);
        assert!(
            lift.z < 0.0 && lift.x > 0.0,
            "lift {lift:?} must point up and forward"
        );
        assert!(w.force_n.y.abs() < 1e-12);
    }

    #[test]
    fn rate_terms_oppose_the_rates() {
        let v = Vehicle::straplex();
        let v_rel = forward_glide();
        let (still, _) = canopy(&v, RHO, &v_rel, &Vector3::zeros(), 0.0, 0.0);
        for axis in 0..3 {
            let mut omega = Vector3::zeros();
            omega[axis] = 0.5;
            let (w, _) = canopy(&v, RHO, &v_rel, &omega, 0.0, 0.0);
            let damping = w.moment_nm - still.moment_nm;
            assert!(damping[axis] < 0.0, "canopy axis {axis}: {damping:?}");
            let d = drone(&v, RHO, &v_rel, &omega);
            let d0 = drone(&v, RHO, &v_rel, &Vector3::zeros());
            assert!(
                (d.moment_nm - d0.moment_nm)[axis] < 0.0,
                "drone axis {axis}"
            );
        }
    }

    #[test]
    fn sideslip_yaws_the_canopy_into_the_relative_wind_and_is_resisted() {
        let v = Vehicle::straplex();
        // Air coming from the right: the canopy moves right relative to it (v > 0, β > 0).
        let v_rel = forward_glide() + Vector3::new(0.0, 1.0, 0.0);
        let (w, air) = canopy(&v, RHO, &v_rel, &Vector3::zeros(), 0.0, 0.0);
        assert!(air.beta_rad > 0.0);
        let (straight, _) = canopy(&v, RHO, &forward_glide(), &Vector3::zeros(), 0.0, 0.0);
        assert!(
            w.moment_nm.z > straight.moment_nm.z,
            "nose turns right, into the wind"
        );
        assert!(w.force_n.y < 0.0, "side force opposes sideslip");
    }

    #[test]
    fn brakes_add_lift_and_more_drag_and_a_right_brake_yaws_right() {
        let v = Vehicle::straplex();
        let v_rel = forward_glide();
        let (free, _) = canopy(&v, RHO, &v_rel, &Vector3::zeros(), 0.0, 0.0);
        let (braked, _) = canopy(&v, RHO, &v_rel, &Vector3::zeros(), 1.0, 1.0);
        let dir = v_rel.normalize();
        let drag = |f: &Vector3<f64>| -f.dot(&dir);
        let lift = |f: &Vector3<f64>| (f - dir * f.dot(&dir)).norm();
        assert!(drag(&braked.force_n) > drag(&free.force_n));
        assert!(lift(&braked.force_n) > lift(&free.force_n));
        assert!(
            lift(&braked.force_n) / drag(&braked.force_n)
                < lift(&free.force_n) / drag(&free.force_n),
            "symmetric brake lowers the canopy's L/D"
        );
        let (right, _) = canopy(&v, RHO, &v_rel, &Vector3::zeros(), 1.0, 0.0);
        assert!(right.moment_nm.z > braked.moment_nm.z);
    }

    #[test]
    fn no_air_no_force_and_zero_airspeed_is_finite() {
        let v = Vehicle::straplex();
        let (w, air) = canopy(
            &v,
            0.0,
            &forward_glide(),
            &Vector3::new(1.0, 1.0, 1.0),
            1.0,
            0.0,
        );
        assert_eq!(w.force_n, Vector3::zeros());
        assert_eq!(w.moment_nm, Vector3::zeros());
        assert!(air.airspeed_mps > 0.0);
        let (w, air) = canopy(
            &v,
            RHO,
            &Vector3::zeros(),
            &Vector3::new(1.0, 0.0, 0.0),
            0.0,
            0.0,
        );
        assert!(
            w.force_n
                .iter()
                .chain(w.moment_nm.iter())
                .all(|c| c.is_finite())
        );
        assert_eq!(air.beta_rad, 0.0);
        assert_eq!(drag(RHO, 0.5, &Vector3::zeros()), Vector3::zeros());
    }
}
