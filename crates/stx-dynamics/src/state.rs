//! The 31-state vector of seed eq. 4.14 and the three control inputs.
//!
//! The layout is fixed because the analysis tools (linearisation, the seed's published
//! matrices) index it: see [`idx`]. [`Pose`] gives it names for people writing initial
//! conditions; the model itself reads the vector directly.

use nalgebra::{SVector, Vector3};
use serde::{Deserialize, Serialize};

// The controls are the onboard guidance's output too, so they live with the shared types.
pub use stx_types::controls::Controls;

/// Number of states.
pub const N_STATES: usize = 31;
/// Number of degrees of freedom (generalized speeds).
pub const N_DOF: usize = 14;
/// The state vector.
pub type StateVector = SVector<f64, N_STATES>;

/// Indices into [`StateVector`] (seed eq. 4.14).
pub mod idx {
    /// Canopy CM position `x, y, z`, inertial NED, m.
    pub const POSITION: usize = 0;
    /// Canopy Euler angles `φ, θ, ψ` relative to the inertial frame, rad.
    pub const CANOPY_EULER: usize = 3;
    /// Canopy CM velocity `u, v, w` relative to the inertial frame, canopy frame, m/s.
    pub const CANOPY_VELOCITY: usize = 6;
    /// Canopy angular velocity `p, q, r`, canopy frame, rad/s.
    pub const CANOPY_RATES: usize = 9;
    /// Pitch of the line frame relative to the canopy `θ_L/C`, rad.
    pub const LINE_PITCH: usize = 12;
    /// Its rate `q_L/C`, rad/s.
    pub const LINE_PITCH_RATE: usize = 13;
    /// Drone Euler angles relative to the line frame, rad.
    pub const DRONE_EULER: usize = 14;
    /// Drone angular velocity relative to the line frame, drone frame, rad/s.
    pub const DRONE_RATES: usize = 17;
    /// Capsule roll and pitch relative to the drone, rad. A roll within π of 2π means the
    /// pair is read from the drone's axes turned 90° about z, away from the seed chart's pole
    /// (`model::pendant`).
    pub const CAPSULE_ANGLES: usize = 20;
    /// Capsule relative rates `p, q` (x and y of its relative angular velocity, capsule frame).
    pub const CAPSULE_RATES: usize = 22;
    /// Transponder roll and pitch relative to the capsule, rad, in either chart as for the
    /// capsule.
    pub const TRANSPONDER_ANGLES: usize = 24;
    /// Transponder relative rates `p, q`, transponder frame, rad/s.
    pub const TRANSPONDER_RATES: usize = 26;
    /// Differential main-line displacement ΔL, m.
    pub const MAIN_LINE: usize = 28;
    /// Right brake servo position, normalised 0…1.
    pub const BRAKE_RIGHT: usize = 29;
    /// Left brake servo position, normalised 0…1.
    pub const BRAKE_LEFT: usize = 30;

    /// State indices of the 14 generalized speeds, in the order the model solves for their
    /// derivatives.
    pub const SPEEDS: [usize; super::N_DOF] = [6, 7, 8, 9, 10, 11, 13, 17, 18, 19, 22, 23, 26, 27];

    /// Short names of every state, for tables and CSV headers.
    pub const NAMES: [&str; super::N_STATES] = [
        "x",
        "y",
        "z",
        "phi_c",
        "theta_c",
        "psi_c",
        "u_c",
        "v_c",
        "w_c",
        "p_c",
        "q_c",
        "r_c",
        "theta_l",
        "q_l",
        "phi_d",
        "theta_d",
        "psi_d",
        "p_d",
        "q_d",
        "r_d",
        "phi_cap",
        "theta_cap",
        "p_cap",
        "q_cap",
        "phi_t",
        "theta_t",
        "p_t",
        "q_t",
        "delta_l",
        "servo_r",
        "servo_l",
    ];

    /// The states whose sign the left–right mirror flips: lateral position, roll and yaw of
    /// every body, sideslip velocity, roll and yaw rates, and the differential main line. A
    /// flight without wind, main line or differential brake keeps them at zero; the mirror
    /// also swaps the two brake servos.
    pub const LATERAL: [usize; 15] = [
        POSITION + 1,
        CANOPY_EULER,
        CANOPY_EULER + 2,
        CANOPY_VELOCITY + 1,
        CANOPY_RATES,
        CANOPY_RATES + 2,
        DRONE_EULER,
        DRONE_EULER + 2,
        DRONE_RATES,
        DRONE_RATES + 2,
        CAPSULE_ANGLES,
        CAPSULE_RATES,
        TRANSPONDER_ANGLES,
        TRANSPONDER_RATES,
        MAIN_LINE,
    ];
}

/// Initial conditions with names, in the units people write them in. Angles in degrees.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Pose {
    /// Canopy CM position, inertial NED, m (z is down: 100 m up is z = −100).
    pub position_ned_m: [f64; 3],
    /// Canopy roll, pitch, yaw, degrees.
    pub canopy_euler_deg: [f64; 3],
    /// Canopy CM velocity in the canopy frame (u forward, v right, w down), m/s.
    pub canopy_velocity_mps: [f64; 3],
    /// Canopy body rates p, q, r, degrees/s.
    pub canopy_rates_deg_s: [f64; 3],
    /// Line pitch relative to the canopy, degrees.
    pub line_pitch_deg: f64,
    /// Drone roll, pitch, yaw relative to the line frame, degrees.
    pub drone_euler_deg: [f64; 3],
    /// Capsule roll and pitch relative to the drone, degrees.
    pub capsule_angles_deg: [f64; 2],
    /// Transponder roll and pitch relative to the capsule, degrees.
    pub transponder_angles_deg: [f64; 2],
    /// Servo positions: ΔL (m), right brake, left brake (0…1).
    pub servos: [f64; 3],
}

impl Pose {
    /// The seed's initial conditions for uncontrolled flight (§4.6), `altitude_m` up: the canopy
    /// pitched 6.5° and flying 3.3 m/s with 1 m/s down its axis, the lines 9° behind it and the
    /// hanging bodies at their §4.6 angles, servos neutral.
    pub fn seed_release(altitude_m: f64) -> Self {
        Self {
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

    /// The state vector for this pose, every relative rate zero except the canopy's.
    pub fn to_state(&self) -> StateVector {
        let mut x = StateVector::zeros();
        let set3 = |x: &mut StateVector, at: usize, v: [f64; 3], scale: f64| {
            for (i, c) in v.iter().enumerate() {
                x[at + i] = c * scale;
            }
        };
        let rad = std::f64::consts::PI / 180.0;
        set3(&mut x, idx::POSITION, self.position_ned_m, 1.0);
        set3(&mut x, idx::CANOPY_EULER, self.canopy_euler_deg, rad);
        set3(&mut x, idx::CANOPY_VELOCITY, self.canopy_velocity_mps, 1.0);
        set3(&mut x, idx::CANOPY_RATES, self.canopy_rates_deg_s, rad);
        x[idx::LINE_PITCH] = self.line_pitch_deg * rad;
        set3(&mut x, idx::DRONE_EULER, self.drone_euler_deg, rad);
        x[idx::CAPSULE_ANGLES] = self.capsule_angles_deg[0] * rad;
        x[idx::CAPSULE_ANGLES + 1] = self.capsule_angles_deg[1] * rad;
        x[idx::TRANSPONDER_ANGLES] = self.transponder_angles_deg[0] * rad;
        x[idx::TRANSPONDER_ANGLES + 1] = self.transponder_angles_deg[1] * rad;
        set3(&mut x, idx::MAIN_LINE, self.servos, 1.0);
        x
    }
}

/// A three-vector out of the state at `at`.
pub fn vec3_at(x: &StateVector, at: usize) -> Vector3<f64> {
    Vector3::new(x[at], x[at + 1], x[at + 2])
}
