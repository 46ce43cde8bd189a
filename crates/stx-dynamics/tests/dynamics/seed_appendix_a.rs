//! The seed's equations of motion (appendix A.11, `M [Ẋ; F_C] = N`) against ours, block by
//! block where the extracted text can be read (MODEL_NOTES.md, "Appendix A").
//!
//! Our mass matrix is generated from the kinematic chain, so its blocks are not written out;
//! what can be compared is what each row's right-hand side and its mass blocks stand for. The
//! canopy's rows can: `N3`, `N4`, `M3,2`, `M4,3` (the last two as the Newton–Euler balance in
//! physics.rs), and the main lines' direction in `M3,15`, `M4,15`. The rows of the drone,
//! capsule and transponder (`M7`–`M12`, `N7`–`N12`) run over several lines of nested products
//! with subscripts lost in the extraction; they are not compared term by term here.

use std::sync::Arc;

use nalgebra::{Matrix3, Vector3};
use stx_dynamics::atmosphere::StandardAtmosphere;
use stx_dynamics::integrate::{Hooks, Rk4, integrate};
use stx_dynamics::model::{Environment, Kinematics, ParafoilModel, aero};
use stx_dynamics::state::{Controls, Pose, StateVector, idx, vec3_at};
use stx_dynamics::vehicle::{STRAPLEX_TOML, Vehicle};
use stx_dynamics::wind::ConstantWind;

fn model(vehicle: Vehicle) -> ParafoilModel {
    let mut m = ParafoilModel::new(
        vehicle,
        Environment {
            atmosphere: Arc::new(StandardAtmosphere),
            wind: Arc::new(ConstantWind::from_speed_direction(3.0, 300.0).expect("wind")),
            ground_altitude_msl_m: 0.0,
        },
    );
    // Turning with asymmetric brakes: every term of the canopy's rows is at work.
    m.set_controls(Controls {
        main_line_m: 0.01,
        brake_right: 0.6,
        brake_left: 0.1,
    });
    m
}

/// States of a 6 s flight from the seed's initial conditions, one every half second.
fn flight(m: &ParafoilModel) -> Vec<(f64, StateVector)> {
    let x0 = Pose::seed_release(300.0).to_state();
    let mut states = Vec::new();
    let mut x = x0;
    for k in 0..12 {
        let t = 0.5 * f64::from(k);
        let flown = integrate(
            &mut Rk4::new(0.005),
            &mut m.clone(),
            t,
            &x,
            t + 0.5,
            Hooks::default(),
        )
        .expect("flies");
        x = flown.state;
        states.push((t + 0.5, x));
    }
    states
}

/// The seed's `N3` and `N4` (A.11.2) at state `x`, the canopy's aerodynamics taken from the
/// model (physics.rs checks them against the coefficients independently):
/// - `N3 = −M_C S_ω V − M_APP S_ω T_I−C V_A − S_ω M_APP V_C/A + F_w + F_A`
/// - `N4 = S_R_CP F_A + M_A − S_ω (I_C + I_APP) ω`
fn seed_n3_n4(m: &ParafoilModel, t: f64, x: &StateVector) -> (Vector3<f64>, Vector3<f64>) {
    let v = &m.vehicle;
    let k = Kinematics::new(v, x, m.controls().main_line_m);
    let rho = m.evaluate(t, x).canopy_air.density_kg_per_m3;
    let wind_c = k.t_i_c * m.environment.wind.wind_ned_mps(t, &k.position_ned_m[0]);
    let velocity = vec3_at(x, idx::CANOPY_VELOCITY);
    let omega = vec3_at(x, idx::CANOPY_RATES);
    let v_rel = velocity - wind_c;
    let m_app = Matrix3::from_diagonal(&(v.apparent.mass_per_density_m3 * rho));
    let i_app = Matrix3::from_diagonal(&(v.apparent.inertia_per_density_m5 * rho));
    let (wrench, _) = aero::canopy(
        v,
        rho,
        &v_rel,
        &omega,
        x[idx::BRAKE_RIGHT],
        x[idx::BRAKE_LEFT],
    );
    let weight = k.t_i_c * Vector3::new(0.0, 0.0, v.canopy_mass_kg * v.gravity_mps2);
    let n3 = -v.canopy_mass_kg * omega.cross(&velocity)
        - m_app * omega.cross(&wind_c)
        - omega.cross(&(m_app * v_rel))
        + weight
        + wrench.force_n;
    // The model's aerodynamic moment already carries the pressure centre's S_R_CP F_A.
    let n4 = wrench.moment_nm - omega.cross(&((v.canopy_inertia + i_app) * omega));
    (n3, n4)
}

/// The canopy's rows of our equations at `x`: the applied force and moment less the
/// rigid-body terms the seed writes into `N3` and `N4` rather than into the accelerations.
fn our_n3_n4(m: &ParafoilModel, t: f64, x: &StateVector) -> (Vector3<f64>, Vector3<f64>) {
    let v = &m.vehicle;
    let e = m.evaluate(t, x);
    let rho = e.canopy_air.density_kg_per_m3;
    let velocity = vec3_at(x, idx::CANOPY_VELOCITY);
    let omega = vec3_at(x, idx::CANOPY_RATES);
    let inertia =
        v.canopy_inertia + Matrix3::from_diagonal(&(v.apparent.inertia_per_density_m5 * rho));
    (
        e.external_force_n[0] - v.canopy_mass_kg * omega.cross(&velocity),
        e.external_moment_nm[0] - omega.cross(&(inertia * omega)),
    )
}

#[test]
fn seed_a11_the_canopys_rows_n3_and_n4_are_ours_term_by_term() {
    let m = model(Vehicle::straplex());
    let states = flight(&m);
    for (t, x) in &states {
        let (seed, ours) = (seed_n3_n4(&m, *t, x), our_n3_n4(&m, *t, x));
        let scale = seed.0.norm() + 1.0;
        assert!(
            (seed.0 - ours.0).norm() < 1e-9 * scale,
            "N3 at {t}: {seed:?} {ours:?}"
        );
        assert!(
            (seed.1 - ours.1).norm() < 1e-9 * scale,
            "N4 at {t}: {seed:?} {ours:?}"
        );
    }
}

#[test]
fn with_the_munk_moment_our_n4_differs_from_the_seeds_by_it_alone() {
    let text = STRAPLEX_TOML.replace("munk_moment = false", "munk_moment = true");
    let m = model(Vehicle::from_toml_str(&text).expect("valid"));
    let mut largest = 0.0_f64;
    for (t, x) in &flight(&m) {
        let (seed, ours) = (seed_n3_n4(&m, *t, x), our_n3_n4(&m, *t, x));
        let v = &m.vehicle;
        let rho = m.evaluate(*t, x).canopy_air.density_kg_per_m3;
        let k = Kinematics::new(v, x, m.controls().main_line_m);
        let wind_c = k.t_i_c * m.environment.wind.wind_ned_mps(*t, &k.position_ned_m[0]);
        let v_rel = vec3_at(x, idx::CANOPY_VELOCITY) - wind_c;
        let m_app = Matrix3::from_diagonal(&(v.apparent.mass_per_density_m3 * rho));
        let munk = -v_rel.cross(&(m_app * v_rel));
        assert!(
            (seed.0 - ours.0).norm() < 1e-9 * (seed.0.norm() + 1.0),
            "N3 at {t}"
        );
        assert!(
            (ours.1 - seed.1 - munk).norm() < 1e-9 * (seed.1.norm() + munk.norm() + 1.0),
            "N4 at {t}: {seed:?} {ours:?} {munk:?}"
        );
        largest = largest.max(munk.norm());
    }
    assert!(
        largest > 10.0,
        "the flight exercised the term: {largest} N·m"
    );
}

#[test]
fn seed_a11_main_line_direction_drops_the_line_frames_x_component() {
    // A.11 pulls along R_T1 = [0; cos(atan2(z, y)); sin(atan2(z, y))] of the tabled line
    // R_T1D/T1C = (−8, 85, 255) cm: the line's x component is dropped. We pull along the full
    // line (MODEL_NOTES.md, "Readings of the seed"): 1.70° apart, 3.0 % of each tension
    // fore and aft.
    let v = Vehicle::straplex();
    let x = Pose::default().to_state();
    let ours = Kinematics::new(&v, &x, 0.0).main_line_dir;
    for (k, line) in v.lines_m.iter().enumerate() {
        let angle = line.z.atan2(line.y);
        let seed = Vector3::new(0.0, angle.cos(), angle.sin());
        let apart = seed.angle(&ours[k]).to_degrees();
        assert!((apart - 1.70).abs() < 0.01, "line {k}: {apart}°");
        assert!((ours[k].x + 0.0298).abs() < 1e-3, "line {k}: {:?}", ours[k]);
        // Otherwise the same direction: its y–z part is the seed's.
        let yz = Vector3::new(0.0, ours[k].y, ours[k].z).normalize();
        assert!((yz - seed).norm() < 1e-12, "line {k}");
    }
}
