//! The equations of motion `M [Ẋ; F_C] = N` (seed eq. 4.104), solved at every evaluation.
//!
//! Eighteen Newton–Euler equations — canopy 6, drone 6, capsule 3 and transponder 3
//! translational (the hanging bodies' own rotation is neglected, seed §4.4.2) — in eighteen
//! unknowns: the 14 generalized-speed derivatives and the magnitudes of the four line tensions
//! (right and left main line, drone–capsule line, capsule–transponder line). The columns of the
//! mass matrix come from [`kinematics::Kinematics::accelerations`]; the kinematic rows (Euler
//! angle rates, position, servo lags) are evaluated explicitly.
//!
//! Interpretations of the seed, each a documented decision (see the crate's model notes):
//! - the main lines' mean vectors stand for the seed's summed `R_TC/CMC`, `R_TD/TC`, `R_CMD/TD`;
//! - a line pulls along its full 3-D direction (the seed drops the line-frame x component);
//! - apparent mass acts at the canopy CM for a wind that is steady over a step (eq. 4.65);
//! - no Munk moment unless the vehicle file switches it on (`canopy.munk_moment`; the seed's
//!   N4 has none, and its coefficients were tuned without it: MODEL_NOTES.md);
//! - the whole 12-m stack sees the density and wind at the canopy;
//! - the hanging bodies' two angles are read in whichever of two charts keeps them clear of a
//!   pole, and the integrator moves them between charts ([`pendant`]).

pub mod aero;
pub mod kinematics;
mod linear;
pub mod pendant;

use std::sync::Arc;

use nalgebra::{Matrix3, SMatrix, Vector3};

use crate::atmosphere::Atmosphere;
use crate::rotation::euler_rates;
use crate::state::{Controls, N_DOF, StateVector, idx, vec3_at};
use crate::vehicle::Vehicle;
use crate::wind::WindField;

pub use aero::CanopyAir;
pub use kinematics::{Body, Kinematics};

/// The air the vehicle flies through.
#[derive(Clone)]
pub struct Environment {
    /// Density, pressure and temperature over altitude.
    pub atmosphere: Arc<dyn Atmosphere>,
    /// Wind over position and time.
    pub wind: Arc<dyn WindField>,
    /// Altitude of the NED origin above mean sea level, m: the ground is at z = 0.
    pub ground_altitude_msl_m: f64,
}

impl Environment {
    /// Still air of the US Standard Atmosphere over a ground at sea level: what tests and
    /// benchmarks of the model alone fly in.
    pub fn calm() -> Self {
        Self {
            atmosphere: Arc::new(crate::atmosphere::StandardAtmosphere),
            wind: Arc::new(crate::wind::Calm),
            ground_altitude_msl_m: 0.0,
        }
    }
}

impl std::fmt::Debug for Environment {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Environment")
            .field("ground_altitude_msl_m", &self.ground_altitude_msl_m)
            .finish_non_exhaustive()
    }
}

/// Line tensions, N, positive when the line pulls.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Tensions {
    /// Right main line.
    pub right_main_n: f64,
    /// Left main line.
    pub left_main_n: f64,
    /// Drone–capsule line.
    pub capsule_n: f64,
    /// Capsule–transponder line.
    pub transponder_n: f64,
}

impl Tensions {
    /// The four tensions in the order above.
    pub fn as_array(&self) -> [f64; 4] {
        [
            self.right_main_n,
            self.left_main_n,
            self.capsule_n,
            self.transponder_n,
        ]
    }

    /// The smallest of the four, N.
    pub fn min(&self) -> f64 {
        self.as_array().into_iter().fold(f64::INFINITY, f64::min)
    }
}

/// Everything one evaluation of the model yields.
#[derive(Debug, Clone)]
pub struct Evaluation {
    /// Ẋ. Non-finite if the equations could not be solved (the integrator reports it).
    pub derivative: StateVector,
    /// Line tensions solved with it.
    pub tensions: Tensions,
    /// The canopy's air data.
    pub canopy_air: CanopyAir,
    /// Applied external force on each body (weight, aerodynamics, apparent mass's
    /// velocity terms), in its own frame, N: what Newton's law balances with the tensions.
    pub external_force_n: [Vector3<f64>; 4],
    /// Applied external moment about the CM of the canopy and the drone (aerodynamic,
    /// including the aerodynamic force's moment from the pressure centre, and the canopy's
    /// Munk moment when the vehicle has it), own frame, N·m.
    pub external_moment_nm: [Vector3<f64>; 2],
}

/// The STRAPLEX multibody model: vehicle, environment and held control inputs.
#[derive(Debug, Clone)]
pub struct ParafoilModel {
    /// The vehicle flown.
    pub vehicle: Vehicle,
    /// The air it flies in.
    pub environment: Environment,
    controls: Controls,
    evaluations: u64,
}

/// First row of each body's equations, in the order of the unknowns' derivation.
mod row {
    pub const CANOPY_FORCE: usize = 0;
    pub const CANOPY_MOMENT: usize = 3;
    pub const DRONE_FORCE: usize = 6;
    pub const DRONE_MOMENT: usize = 9;
    pub const CAPSULE_FORCE: usize = 12;
    pub const TRANSPONDER_FORCE: usize = 15;
}

/// Unknowns after the 14 generalized-speed derivatives: the tension magnitudes.
///
/// The main lines enter as their mean tension and half their difference (`T_R = mean + half`,
/// `T_L = mean − half`), not as `T_R` and `T_L`. Their columns are then sums and differences of
/// the two lines' mirrored coefficients, whose lateral (or longitudinal) parts cancel exactly in
/// floating point, so a mirror-symmetric state yields exactly zero lateral derivatives. Solved
/// for `T_R`, `T_L` directly, rounding made the two differ by an ulp; that seed grew into
/// lateral motion of a stack flying without wind or control (MODEL_NOTES.md, "Symmetry").
mod unknown {
    pub const MAIN_MEAN: usize = 14;
    pub const MAIN_HALF_DIFFERENCE: usize = 15;
    pub const CAPSULE_LINE: usize = 16;
    pub const TRANSPONDER_LINE: usize = 17;
}

/// Where each equation row and each unknown sit in the array handed to the solver.
///
/// Eliminating from the bottom of the stack up (transponder, capsule, drone, canopy) keeps the
/// elimination inside each body's few equations: a body couples to the one above it only
/// through the tension of the line it hangs from, so most multipliers are zero and skipped.
/// Rows: transponder, capsule, drone, canopy. Unknowns: transponder ṗ, q̇, T_T; capsule ṗ,
/// q̇, T_CAP; q̇_L, drone rates, main lines; canopy.
const ROW_POSITION: [usize; 18] = [12, 13, 14, 15, 16, 17, 6, 7, 8, 9, 10, 11, 3, 4, 5, 0, 1, 2];
const UNKNOWN_POSITION: [usize; 18] =
    [12, 13, 14, 15, 16, 17, 6, 7, 8, 9, 3, 4, 0, 1, 10, 11, 5, 2];

/// Ends of the bodies' blocks in the permuted order: transponder, capsule, drone, canopy.
const BLOCK_ENDS: [usize; 4] = [3, 6, 12, 18];

/// The 18 equations `M z = N`, stored already permuted for [`linear::solve`].
struct Equations {
    a: [[f64; 18]; 18],
    b: [f64; 18],
}

impl Default for Equations {
    fn default() -> Self {
        Self {
            a: [[0.0; 18]; 18],
            b: [0.0; 18],
        }
    }
}

impl Equations {
    /// Rows `first..first + 3`, columns of the 14 speed derivatives.
    fn set_rows(&mut self, first: usize, block: &SMatrix<f64, 3, N_DOF>) {
        for k in 0..3 {
            let row = &mut self.a[ROW_POSITION[first + k]];
            for j in 0..N_DOF {
                row[UNKNOWN_POSITION[j]] = block[(k, j)];
            }
        }
    }

    /// Adds a 3×3 block at rows `first..`, unknowns `column..`.
    fn add_block(&mut self, first: usize, column: usize, block: &Matrix3<f64>) {
        for k in 0..3 {
            for j in 0..3 {
                self.a[ROW_POSITION[first + k]][UNKNOWN_POSITION[column + j]] += block[(k, j)];
            }
        }
    }

    /// One unknown's coefficients in rows `first..first + 3`.
    fn set_column(&mut self, first: usize, column: usize, values: &Vector3<f64>) {
        for k in 0..3 {
            self.a[ROW_POSITION[first + k]][UNKNOWN_POSITION[column]] = values[k];
        }
    }

    /// The main lines' coefficients in rows `first..first + 3`, given per unit of the right
    /// and of the left line's tension: the mean tension's column is their sum, the half
    /// difference's their difference (see [`unknown`]).
    fn set_main_line_columns(&mut self, first: usize, right: &Vector3<f64>, left: &Vector3<f64>) {
        self.set_column(first, unknown::MAIN_MEAN, &(right + left));
        self.set_column(first, unknown::MAIN_HALF_DIFFERENCE, &(right - left));
    }

    /// Right-hand side of rows `first..first + 3`.
    fn set_rhs(&mut self, first: usize, values: &Vector3<f64>) {
        for k in 0..3 {
            self.b[ROW_POSITION[first + k]] = values[k];
        }
    }

    /// The unknowns in their natural order, NaN if the system is singular.
    fn solve(&mut self) -> [f64; 18] {
        if linear::solve_blocked_in_place(&mut self.a, &mut self.b, &BLOCK_ENDS) {
            std::array::from_fn(|j| self.b[UNKNOWN_POSITION[j]])
        } else {
            [f64::NAN; 18]
        }
    }
}

impl ParafoilModel {
    /// A model with neutral controls.
    pub fn new(vehicle: Vehicle, environment: Environment) -> Self {
        Self {
            vehicle,
            environment,
            controls: Controls::default(),
            evaluations: 0,
        }
    }

    /// Holds new servo commands (saturated to the servos' range) from now on.
    pub fn set_controls(&mut self, controls: Controls) {
        self.controls = controls.saturated(self.vehicle.main_line_travel_m);
    }

    /// The servo commands held.
    pub fn controls(&self) -> Controls {
        self.controls
    }

    /// Derivative evaluations so far.
    pub fn evaluations(&self) -> u64 {
        self.evaluations
    }

    /// Ẋ at `time_s`, counted.
    pub fn derivative(&mut self, time_s: f64, x: &StateVector) -> StateVector {
        self.evaluations += 1;
        self.evaluate(time_s, x).derivative
    }

    /// Solves the equations of motion at one state.
    pub fn evaluate(&self, time_s: f64, x: &StateVector) -> Evaluation {
        let v = &self.vehicle;
        let u = self.controls;
        let kin = Kinematics::new(v, x, u.main_line_m);
        // The command is held over a step, so the servo's acceleration is −K·ΔL̇.
        let main_line_accel = -v.servo_rate_per_s.x * kin.main_line_rate_mps;
        let acc = kin.accelerations(v, x, main_line_accel);

        // The stack is 12 m tall: density and wind are taken at the canopy for every body
        // (0.1 % of density and a few cm/s of shear apart at most), one look-up each.
        let p_canopy = kin.position_ned_m[0];
        let density = self
            .environment
            .atmosphere
            .air_at(self.environment.ground_altitude_msl_m - p_canopy.z)
            .density_kg_per_m3;
        let rho = [density; 4];
        let wind_ned = self.environment.wind.wind_ned_mps(time_s, &p_canopy);
        let wind_body: [Vector3<f64>; 4] = std::array::from_fn(|i| kin.t_i_body[i] * wind_ned);
        let wind_canopy = wind_body[0];
        let v_rel: [Vector3<f64>; 4] =
            std::array::from_fn(|i| kin.velocity_body_mps[i] - wind_body[i]);
        let g_ned = Vector3::new(0.0, 0.0, v.gravity_mps2);
        let weight = |i: usize, m: f64| kin.t_i_body[i] * g_ned * m;

        let [omega_c, omega_d, _, _] = kin.omega_body;
        let (canopy_wrench, canopy_air) = aero::canopy(
            v,
            rho[0],
            &v_rel[0],
            &omega_c,
            x[idx::BRAKE_RIGHT],
            x[idx::BRAKE_LEFT],
        );
        let drone_wrench = aero::drone(v, rho[1], &v_rel[1], &omega_d);

        // Apparent mass and inertia (Lissaman & Brown), scaled by the canopy's density.
        let m_app = Matrix3::from_diagonal(&(v.apparent.mass_per_density_m3 * rho[0]));
        let i_app = Matrix3::from_diagonal(&(v.apparent.inertia_per_density_m5 * rho[0]));
        let canopy_inertia = v.canopy_inertia + i_app;
        // Kirchhoff's moment of the air carried along: the rate of the apparent angular
        // momentum about the moving canopy CM lacks `V_rel × (M_app·V_rel)`, which turns a
        // body with unequal apparent masses broadside to the flow (nose-up at a glide).
        let munk_moment = if v.config.canopy.munk_moment {
            -v_rel[0].cross(&(m_app * v_rel[0]))
        } else {
            Vector3::zeros()
        };
        let canopy_moment = canopy_wrench.moment_nm + munk_moment;

        let e_main_c = kin.main_line_dir.map(|e| kin.t_c_l.transpose() * e);
        let e_main_d = kin.main_line_dir.map(|e| kin.t_l_d * e);
        // Capsule line: from the drone towards the capsule, i.e. the capsule frame's z axis.
        let e_cap_d = kin.t_d_cap.transpose() * Vector3::z();
        let e_t_cap = kin.t_cap_t.transpose() * Vector3::z();

        let mut eq = Equations::default();
        let mut external = [Vector3::zeros(); 4];

        // Canopy translation, canopy frame: its mass and the apparent mass on V̇.
        external[0] = weight(0, v.canopy_mass_kg) + canopy_wrench.force_n
            - m_app * omega_c.cross(&wind_canopy)
            - omega_c.cross(&(m_app * v_rel[0]));
        let a_c = &acc.linear[0];
        eq.set_rows(row::CANOPY_FORCE, &(a_c.jac * v.canopy_mass_kg));
        eq.add_block(row::CANOPY_FORCE, kinematics::nu::CANOPY_VELOCITY, &m_app);
        eq.set_main_line_columns(row::CANOPY_FORCE, &(-e_main_c[0]), &(-e_main_c[1]));
        eq.set_rhs(
            row::CANOPY_FORCE,
            &(external[0] - a_c.bias * v.canopy_mass_kg),
        );

        // Canopy rotation about its CM, canopy frame.
        let alpha_c = &acc.angular[0];
        eq.set_rows(row::CANOPY_MOMENT, &(canopy_inertia * alpha_c.jac));
        eq.set_main_line_columns(
            row::CANOPY_MOMENT,
            &(-v.r_lines_on_canopy_m[0].cross(&e_main_c[0])),
            &(-v.r_lines_on_canopy_m[1].cross(&e_main_c[1])),
        );
        eq.set_rhs(
            row::CANOPY_MOMENT,
            &(canopy_moment
                - omega_c.cross(&(canopy_inertia * omega_c))
                - canopy_inertia * alpha_c.bias),
        );

        // Drone translation and rotation, drone frame.
        external[1] = weight(1, v.drone_mass_kg) + drone_wrench.force_n;
        let a_d = &acc.linear[1];
        eq.set_rows(row::DRONE_FORCE, &(a_d.jac * v.drone_mass_kg));
        eq.set_main_line_columns(row::DRONE_FORCE, &e_main_d[0], &e_main_d[1]);
        eq.set_column(row::DRONE_FORCE, unknown::CAPSULE_LINE, &(-e_cap_d));
        eq.set_rhs(
            row::DRONE_FORCE,
            &(external[1] - a_d.bias * v.drone_mass_kg),
        );
        let alpha_d = &acc.angular[1];
        eq.set_rows(row::DRONE_MOMENT, &(v.drone_inertia * alpha_d.jac));
        eq.set_main_line_columns(
            row::DRONE_MOMENT,
            &v.r_lines_on_drone_m[0].cross(&e_main_d[0]),
            &v.r_lines_on_drone_m[1].cross(&e_main_d[1]),
        );
        eq.set_column(
            row::DRONE_MOMENT,
            unknown::CAPSULE_LINE,
            &(-v.r_capsule_line_on_drone_m.cross(&e_cap_d)),
        );
        eq.set_rhs(
            row::DRONE_MOMENT,
            &(drone_wrench.moment_nm
                - omega_d.cross(&(v.drone_inertia * omega_d))
                - v.drone_inertia * alpha_d.bias),
        );

        // Capsule translation, capsule frame.
        let cap = &v.capsule;
        external[2] = weight(2, cap.mass_kg) + aero::drag(rho[2], cap.drag_area_m2, &v_rel[2]);
        let a_cap = &acc.linear[2];
        eq.set_rows(row::CAPSULE_FORCE, &(a_cap.jac * cap.mass_kg));
        eq.set_column(row::CAPSULE_FORCE, unknown::CAPSULE_LINE, &Vector3::z());
        eq.set_column(row::CAPSULE_FORCE, unknown::TRANSPONDER_LINE, &(-e_t_cap));
        eq.set_rhs(
            row::CAPSULE_FORCE,
            &(external[2] - a_cap.bias * cap.mass_kg),
        );

        // Transponder translation, transponder frame.
        let tr = &v.transponder;
        external[3] = weight(3, tr.mass_kg) + aero::drag(rho[3], tr.drag_area_m2, &v_rel[3]);
        let a_t = &acc.linear[3];
        eq.set_rows(row::TRANSPONDER_FORCE, &(a_t.jac * tr.mass_kg));
        eq.set_column(
            row::TRANSPONDER_FORCE,
            unknown::TRANSPONDER_LINE,
            &Vector3::z(),
        );
        eq.set_rhs(
            row::TRANSPONDER_FORCE,
            &(external[3] - a_t.bias * tr.mass_kg),
        );

        let solution = eq.solve();

        let mut dx = StateVector::zeros();
        let t_i_c = &kin.t_i_c;
        dx.fixed_rows_mut::<3>(idx::POSITION)
            .copy_from(&(t_i_c.transpose() * vec3_at(x, idx::CANOPY_VELOCITY)));
        dx.fixed_rows_mut::<3>(idx::CANOPY_EULER)
            .copy_from(&euler_rates(
                &vec3_at(x, idx::CANOPY_EULER),
                &vec3_at(x, idx::CANOPY_RATES),
            ));
        dx[idx::LINE_PITCH] = x[idx::LINE_PITCH_RATE];
        dx.fixed_rows_mut::<3>(idx::DRONE_EULER)
            .copy_from(&euler_rates(
                &vec3_at(x, idx::DRONE_EULER),
                &vec3_at(x, idx::DRONE_RATES),
            ));
        for (angles, rates) in [
            (idx::CAPSULE_ANGLES, idx::CAPSULE_RATES),
            (idx::TRANSPONDER_ANGLES, idx::TRANSPONDER_RATES),
        ] {
            // p = φ̇, q = cos φ · θ̇ (see kinematics::pendant_rel_rate).
            dx[angles] = x[rates];
            dx[angles + 1] = x[rates + 1] / x[angles].cos();
        }
        for (k, &state) in idx::SPEEDS.iter().enumerate() {
            dx[state] = solution[k];
        }
        dx[idx::MAIN_LINE] = kin.main_line_rate_mps;
        dx[idx::BRAKE_RIGHT] = v.servo_rate_per_s.y * (u.brake_right - x[idx::BRAKE_RIGHT]);
        dx[idx::BRAKE_LEFT] = v.servo_rate_per_s.z * (u.brake_left - x[idx::BRAKE_LEFT]);

        Evaluation {
            derivative: dx,
            tensions: Tensions {
                right_main_n: solution[unknown::MAIN_MEAN]
                    + solution[unknown::MAIN_HALF_DIFFERENCE],
                left_main_n: solution[unknown::MAIN_MEAN] - solution[unknown::MAIN_HALF_DIFFERENCE],
                capsule_n: solution[unknown::CAPSULE_LINE],
                transponder_n: solution[unknown::TRANSPONDER_LINE],
            },
            canopy_air,
            external_force_n: external,
            external_moment_nm: [canopy_moment, drone_wrench.moment_nm],
        }
    }
}

impl crate::integrate::OdeSystem<{ crate::state::N_STATES }> for ParafoilModel {
    fn derivative(&mut self, time_s: f64, state: &StateVector) -> StateVector {
        ParafoilModel::derivative(self, time_s, state)
    }

    fn rechart(&self, state: &StateVector) -> Option<StateVector> {
        pendant::rechart(state)
    }
}
