//! Laws the flight model must obey, checked along simulated flights: Newton–Euler for every
//! body with the solved tensions, the kinematic chain against finite differences, rigid lines,
//! free fall without air, and symmetry without wind or control.

use std::sync::Arc;

use nalgebra::{Matrix3, Vector3};
use stx_dynamics::atmosphere::{StandardAtmosphere, Vacuum};
use stx_dynamics::model::{Body, Environment, Evaluation, Kinematics, ParafoilModel};
use stx_dynamics::state::{Controls, Pose, StateVector, idx, vec3_at};
use stx_dynamics::vehicle::Vehicle;
use stx_dynamics::wind::{Calm, ConstantWind, WindField};

/// The seed's uncontrolled-flight initial conditions (§4.6), at `altitude_m`.
fn seed_pose(altitude_m: f64) -> Pose {
    Pose {
        position_ned_m: [0.0, 0.0, -altitude_m],
        canopy_euler_deg: [0.0, 6.5, 0.0],
        canopy_velocity_mps: [3.3, 0.0, 1.0],
        line_pitch_deg: -9.0,
        drone_euler_deg: [0.0, 20.0, 0.0],
        capsule_angles_deg: [0.0, -7.0],
        transponder_angles_deg: [0.0, 5.0],
        ..Default::default()
    }
}

fn model(wind: Arc<dyn WindField>) -> ParafoilModel {
    ParafoilModel::new(
        Vehicle::straplex(),
        Environment {
            atmosphere: Arc::new(StandardAtmosphere),
            wind,
            ground_altitude_msl_m: 0.0,
        },
    )
}

fn rk4_step(m: &mut ParafoilModel, t: f64, x: &StateVector, h: f64) -> StateVector {
    let k1 = m.derivative(t, x);
    let k2 = m.derivative(t + 0.5 * h, &(x + k1 * (0.5 * h)));
    let k3 = m.derivative(t + 0.5 * h, &(x + k2 * (0.5 * h)));
    let k4 = m.derivative(t + h, &(x + k3 * h));
    x + (k1 + 2.0 * k2 + 2.0 * k3 + k4) * (h / 6.0)
}

/// Flies `duration_s` with step `h`, changing the controls by `schedule(t)`, and returns every
/// state.
fn fly(
    m: &mut ParafoilModel,
    x0: StateVector,
    duration_s: f64,
    h: f64,
    schedule: impl Fn(f64) -> Controls,
) -> Vec<(f64, StateVector)> {
    let steps = (duration_s / h).round() as usize;
    let mut out = Vec::with_capacity(steps + 1);
    let mut x = x0;
    for k in 0..=steps {
        let t = k as f64 * h;
        out.push((t, x));
        m.set_controls(schedule(t));
        x = rk4_step(m, t, &x, h);
    }
    out
}

/// Controls that excite every mode: a right turn, then asymmetric brakes, then a flare.
fn exciting_schedule(t: f64) -> Controls {
    match t {
        t if t < 2.0 => Controls::default(),
        t if t < 4.0 => Controls {
            main_line_m: 0.02,
            ..Default::default()
        },
        t if t < 6.0 => Controls {
            main_line_m: -0.01,
            brake_right: 0.8,
            brake_left: 0.1,
        },
        _ => Controls::symmetric_brake(1.0),
    }
}

/// Force that each line's tension puts on each body, per unit tension, in that body's frame.
struct LineDirections {
    /// Right and left main line, canopy end to drone end, canopy frame.
    main_c: [Vector3<f64>; 2],
    /// The same in the drone frame.
    main_d: [Vector3<f64>; 2],
    /// Capsule line, drone to capsule, drone frame.
    capsule_d: Vector3<f64>,
    /// Transponder line, capsule to transponder, capsule frame.
    transponder_cap: Vector3<f64>,
}

fn line_directions(k: &Kinematics) -> LineDirections {
    LineDirections {
        main_c: k.main_line_dir.map(|e| k.t_c_l.transpose() * e),
        main_d: k.main_line_dir.map(|e| k.t_l_d * e),
        capsule_d: k.t_d_cap.transpose() * Vector3::z(),
        transponder_cap: k.t_cap_t.transpose() * Vector3::z(),
    }
}

fn assert_balanced(what: &str, t: f64, lhs: Vector3<f64>, rhs: Vector3<f64>, scale: f64) {
    let error = (lhs - rhs).norm();
    assert!(
        error < 1e-4 * scale,
        "{what} at t = {t:.3} s: m·a or I·ω̇ side {lhs:?} vs forces {rhs:?} (error {error:.3e}, \
         scale {scale:.3e})"
    );
}

#[test]
fn newton_euler_holds_for_every_body_with_the_solved_tensions() {
    let mut m = model(Arc::new(
        ConstantWind::from_speed_direction(3.0, 300.0).expect("valid wind"),
    ));
    let h = 1e-3;
    let flight = fly(
        &mut m,
        seed_pose(200.0).to_state(),
        8.0,
        h,
        exciting_schedule,
    );
    let v = m.vehicle.clone();
    let weight = v.total_mass_kg() * v.gravity_mps2;
    let mut checked = 0;
    for k in (500..flight.len() - 1).step_by(250) {
        let (t, x) = flight[k];
        // The controls were changed at the start of step k, so the neighbours bracketing t
        // were flown with the controls of step k−1 only if nothing changed: skip switch times.
        if [2.0, 4.0, 6.0].iter().any(|s| (t - s).abs() < 2.0 * h) {
            continue;
        }
        m.set_controls(exciting_schedule(t));
        let (xm, xp) = (flight[k - 1].1, flight[k + 1].1);
        let u = m.controls().main_line_m;
        let (km, k0, kp) = (
            Kinematics::new(&v, &xm, u),
            Kinematics::new(&v, &x, u),
            Kinematics::new(&v, &xp, u),
        );
        let eval: Evaluation = m.evaluate(t, &x);
        let tension = eval.tensions;
        let dirs = line_directions(&k0);
        // Inertial CM accelerations by central differences, expressed in each body's frame.
        let accel = |body: Body| {
            let a_ned = (kp.velocity_ned_mps(body) - km.velocity_ned_mps(body)) / (2.0 * h);
            k0.t_i_body[body as usize] * a_ned
        };
        let omega_dot = |body: Body| {
            let i = body as usize;
            (kp.omega_body[i] - km.omega_body[i]) / (2.0 * h)
        };

        // Canopy: its own mass plus the apparent mass on the canopy-frame velocity derivative.
        let rho = eval.canopy_air.density_kg_per_m3;
        let m_app = Matrix3::from_diagonal(&(v.apparent.mass_per_density_m3 * rho));
        let i_app = Matrix3::from_diagonal(&(v.apparent.inertia_per_density_m5 * rho));
        let v_dot_c =
            (vec3_at(&xp, idx::CANOPY_VELOCITY) - vec3_at(&xm, idx::CANOPY_VELOCITY)) / (2.0 * h);
        let main_force_c =
            dirs.main_c[0] * tension.right_main_n + dirs.main_c[1] * tension.left_main_n;
        assert_balanced(
            "canopy translation",
            t,
            accel(Body::Canopy) * v.canopy_mass_kg + m_app * v_dot_c,
            eval.external_force_n[0] + main_force_c,
            weight,
        );
        let inertia_c = v.canopy_inertia + i_app;
        let w_c = k0.omega_body[0];
        let line_moments_c = v.r_lines_on_canopy_m[0]
            .cross(&(dirs.main_c[0] * tension.right_main_n))
            + v.r_lines_on_canopy_m[1].cross(&(dirs.main_c[1] * tension.left_main_n));
        assert_balanced(
            "canopy rotation",
            t,
            inertia_c * omega_dot(Body::Canopy) + w_c.cross(&(inertia_c * w_c)),
            eval.external_moment_nm[0] + line_moments_c,
            weight * 0.1,
        );

        // Drone.
        let pull_main_d = [
            -dirs.main_d[0] * tension.right_main_n,
            -dirs.main_d[1] * tension.left_main_n,
        ];
        let pull_capsule_d = dirs.capsule_d * tension.capsule_n;
        assert_balanced(
            "drone translation",
            t,
            accel(Body::Drone) * v.drone_mass_kg,
            eval.external_force_n[1] + pull_main_d[0] + pull_main_d[1] + pull_capsule_d,
            weight,
        );
        let w_d = k0.omega_body[1];
        let moments_d = v.r_lines_on_drone_m[0].cross(&pull_main_d[0])
            + v.r_lines_on_drone_m[1].cross(&pull_main_d[1])
            + v.r_capsule_line_on_drone_m.cross(&pull_capsule_d);
        assert_balanced(
            "drone rotation",
            t,
            v.drone_inertia * omega_dot(Body::Drone) + w_d.cross(&(v.drone_inertia * w_d)),
            eval.external_moment_nm[1] + moments_d,
            weight * 0.01,
        );

        // Capsule and transponder: point masses on their lines.
        assert_balanced(
            "capsule translation",
            t,
            accel(Body::Capsule) * v.capsule.mass_kg,
            eval.external_force_n[2] - Vector3::z() * tension.capsule_n
                + dirs.transponder_cap * tension.transponder_n,
            weight,
        );
        assert_balanced(
            "transponder translation",
            t,
            accel(Body::Transponder) * v.transponder.mass_kg,
            eval.external_force_n[3] - Vector3::z() * tension.transponder_n,
            weight,
        );
        checked += 1;
    }
    assert!(checked >= 20, "only {checked} instants checked");
}

#[test]
fn the_chains_velocities_are_the_derivatives_of_its_positions() {
    let mut m = model(Arc::new(Calm));
    let h = 1e-3;
    let flight = fly(
        &mut m,
        seed_pose(200.0).to_state(),
        7.0,
        h,
        exciting_schedule,
    );
    let v = m.vehicle.clone();
    for k in (100..flight.len() - 1).step_by(300) {
        let (t, x) = flight[k];
        if [2.0, 4.0, 6.0].iter().any(|s| (t - s).abs() < 2.0 * h) {
            continue;
        }
        let u = exciting_schedule(t)
            .saturated(v.main_line_travel_m)
            .main_line_m;
        let (km, k0, kp) = (
            Kinematics::new(&v, &flight[k - 1].1, u),
            Kinematics::new(&v, &x, u),
            Kinematics::new(&v, &flight[k + 1].1, u),
        );
        for body in Body::ALL {
            let i = body as usize;
            let fd = (kp.position_ned_m[i] - km.position_ned_m[i]) / (2.0 * h);
            let analytic = k0.velocity_ned_mps(body);
            assert!(
                (fd - analytic).norm() < 1e-4 * (1.0 + analytic.norm()),
                "{} at t = {t}: d/dt position {fd:?} vs chain velocity {analytic:?}",
                body.name()
            );
        }
    }
}

#[test]
fn lines_keep_their_lengths_over_a_300_s_flight() {
    let mut m = model(Arc::new(
        ConstantWind::from_speed_direction(2.0, 45.0).expect("valid wind"),
    ));
    let v = m.vehicle.clone();
    let schedule = |t: f64| Controls {
        main_line_m: 0.02 * (t / 20.0).sin(),
        brake_right: 0.3 + 0.3 * (t / 13.0).sin(),
        brake_left: 0.3,
    };
    let flight = fly(&mut m, seed_pose(1500.0).to_state(), 300.0, 0.01, schedule);
    let mut worst = [0.0_f64; 3];
    for (t, x) in flight.iter().step_by(10) {
        let k = Kinematics::new(&v, x, schedule(*t).main_line_m);
        let ends = k.line_ends_ned_m(&v);
        // The mean main line runs between the midpoints of the canopy ends and of the drone
        // ends; its length follows the servo (ΔD sideways), the other two are fixed.
        let top = (ends[0].0 + ends[1].0) * 0.5;
        let bottom = (ends[0].1 + ends[1].1) * 0.5;
        let lengths = [
            (top - bottom).norm() - k.line_drop_m.norm(),
            (ends[2].0 - ends[2].1).norm() - v.capsule_line_length_m,
            (ends[3].0 - ends[3].1).norm() - v.transponder_line_length_m,
        ];
        for (w, l) in worst.iter_mut().zip(lengths) {
            *w = w.max(l.abs());
        }
    }
    assert!(
        worst.iter().all(|e| *e < 1e-9),
        "line length errors {worst:?} m"
    );
}

#[test]
fn without_air_every_body_falls_at_g_and_the_lines_go_slack() {
    let vehicle = Vehicle::straplex();
    let g = vehicle.gravity_mps2;
    let mut m = ParafoilModel::new(
        vehicle,
        Environment {
            atmosphere: Arc::new(Vacuum),
            wind: Arc::new(Calm),
            ground_altitude_msl_m: 0.0,
        },
    );
    // Any attitude, any common velocity, no rotation: nothing but gravity acts.
    let mut pose = seed_pose(1000.0);
    pose.canopy_euler_deg = [10.0, -20.0, 30.0];
    pose.canopy_velocity_mps = [5.0, -1.0, 2.0];
    let flight = fly(&mut m, pose.to_state(), 10.0, 0.01, |_| Controls::default());
    for (t, x) in flight.iter().step_by(100) {
        let eval = m.evaluate(*t, x);
        assert!(
            eval.tensions.as_array().iter().all(|f| f.abs() < 1e-9),
            "tensions {:?} at t = {t}",
            eval.tensions
        );
        let k = Kinematics::new(&m.vehicle, x, 0.0);
        let kd = Kinematics::new(&m.vehicle, &(x + eval.derivative * 1e-6), 0.0);
        for body in Body::ALL {
            let a = (kd.velocity_ned_mps(body) - k.velocity_ned_mps(body)) / 1e-6;
            assert!(
                (a - Vector3::new(0.0, 0.0, g)).norm() < 1e-5,
                "{} accelerates at {a:?} at t = {t}",
                body.name()
            );
        }
    }
    // After 10 s of free fall the vertical speed grew by g·t.
    let (_, x_end) = flight.last().copied().unwrap_or_default();
    let k = Kinematics::new(&m.vehicle, &x_end, 0.0);
    let v0 = Kinematics::new(&m.vehicle, &pose.to_state(), 0.0).velocity_ned_mps(Body::Canopy);
    assert!((k.velocity_ned_mps(Body::Canopy).z - v0.z - g * 10.0).abs() < 1e-6);
}

#[test]
fn without_wind_or_control_no_lateral_motion_appears() {
    let mut m = model(Arc::new(Calm));
    let flight = fly(&mut m, seed_pose(1500.0).to_state(), 300.0, 0.01, |_| {
        Controls::default()
    });
    let lateral_states = [
        idx::POSITION + 1,
        idx::CANOPY_EULER,
        idx::CANOPY_EULER + 2,
        idx::CANOPY_VELOCITY + 1,
        idx::CANOPY_RATES,
        idx::CANOPY_RATES + 2,
        idx::DRONE_EULER,
        idx::DRONE_EULER + 2,
        idx::DRONE_RATES,
        idx::DRONE_RATES + 2,
        idx::CAPSULE_ANGLES,
        idx::CAPSULE_RATES,
        idx::TRANSPONDER_ANGLES,
        idx::TRANSPONDER_RATES,
    ];
    let worst = flight
        .iter()
        .flat_map(|(_, x)| lateral_states.iter().map(|&i| x[i].abs()))
        .fold(0.0, f64::max);
    assert!(worst < 1e-9, "lateral state reached {worst}");
    let (_, x_end) = flight.last().copied().unwrap_or_default();
    assert!(x_end[idx::POSITION] > 500.0, "it glided forward");
}

#[test]
fn every_line_is_taut_in_steady_glide() {
    let mut m = model(Arc::new(Calm));
    let flight = fly(&mut m, seed_pose(500.0).to_state(), 40.0, 0.01, |_| {
        Controls::default()
    });
    for (t, x) in flight.iter().filter(|(t, _)| *t > 15.0).step_by(50) {
        let tensions = m.evaluate(*t, x).tensions;
        assert!(tensions.min() > 5.0, "slack line at t = {t}: {tensions:?}");
    }
}
