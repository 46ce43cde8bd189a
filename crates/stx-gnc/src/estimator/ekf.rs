//! The navigation EKF proper: the layout of its fourteen states, the process model that
//! carries them through a turn (with `F·P·Fᵀ` by row operations), and the Kalman update with its
//! innovation gate. The measurements that feed it have a file each (`gps.rs`, `pitot.rs`,
//! `baro.rs`, `sideslip.rs`); the parent module's documentation has the equations.

use nalgebra::{Matrix2, SMatrix, SVector, Vector2, Vector3};

use super::config::Tuning;

/// Number of navigation states.
pub(crate) const N: usize = 14;
pub(crate) type StateVec = SVector<f64, N>;
pub(crate) type Covariance = SMatrix<f64, N, N>;

/// Where each state sits in the navigation state vector.
pub(crate) mod ix {
    /// Position, NED, m (3).
    pub const POSITION: usize = 0;
    /// Velocity relative to the air, NED, m/s (3).
    pub const AIR: usize = 3;
    /// Turn rate of the horizontal air velocity about the down axis, rad/s.
    pub const TURN: usize = 6;
    /// Horizontal wind, north and east, m/s (2).
    pub const WIND: usize = 7;
    /// Vertical wind (down), m/s.
    pub const WIND_DOWN: usize = 9;
    /// Pitot scale factor, dimensionless.
    pub const SCALE: usize = 10;
    /// Barometric bias, natural log of pressure.
    pub const BARO: usize = 11;
    /// Sideslip of the air velocity from the drone's true heading in straight flight, rad.
    pub const SIDESLIP: usize = 12;
    /// The AHRS's heading bias: its yaw minus the drone's true yaw, rad.
    pub const HEADING_BIAS: usize = 13;
}

/// What became of one measurement.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Outcome {
    /// Used by the filter.
    Used,
    /// (Part of) it failed the innovation gate.
    Gated,
    /// It (re)started a filter.
    Reset,
    /// Nothing could use it (filter not started yet, pitot below its minimum airspeed).
    Unused,
}

/// Below this horizontal air speed the air velocity's direction, and the pitot's reading, mean
/// too little to use, m/s (and it keeps divisions by the speed away from zero).
pub(crate) const MIN_SPEED_FOR_DIRECTION_MPS: f64 = 1.0;

/// A horizontal rotation by `angle` about the down axis (positive: north towards east).
fn rotation(angle: f64) -> Matrix2<f64> {
    let (s, c) = angle.sin_cos();
    Matrix2::new(c, -s, s, c)
}

/// `G = ∫₀^Δt R(ω·τ) dτ` and `∂G/∂ω`: the displacement of a velocity that turns at the
/// constant rate `ω` over `Δt`, so dead reckoning through a turn follows the arc.
fn integrated_rotation(omega: f64, dt_s: f64) -> (Matrix2<f64>, Matrix2<f64>) {
    let theta = omega * dt_s;
    let (int_cos, int_sin, d_cos, d_sin) = if theta.abs() < 1e-4 {
        // Series in θ: ∫cos = Δt(1 − θ²/6), ∫sin = Δt·θ/2 (1 − θ²/12), and their ω-derivatives.
        let dt2 = dt_s * dt_s;
        (
            dt_s * (1.0 - theta * theta / 6.0),
            0.5 * dt_s * theta * (1.0 - theta * theta / 12.0),
            -omega * dt2 * dt_s / 3.0,
            0.5 * dt2 * (1.0 - theta * theta / 4.0),
        )
    } else {
        let (s, c) = theta.sin_cos();
        let w2 = omega * omega;
        (
            s / omega,
            (1.0 - c) / omega,
            (theta * c - s) / w2,
            (theta * s - 1.0 + c) / w2,
        )
    };
    (
        Matrix2::new(int_cos, -int_sin, int_sin, int_cos),
        Matrix2::new(d_cos, -d_sin, d_sin, d_cos),
    )
}

/// The non-identity blocks of the state transition `F` over one step.
struct Transition {
    /// `∂p_h/∂v_air,h = ∫R dτ`.
    g: Matrix2<f64>,
    /// `∂p_h/∂ω`.
    dg_air: Vector2<f64>,
    /// `∂v_air,h/∂v_air,h = R(ωΔt)`.
    turn: Matrix2<f64>,
    /// `∂v_air,h/∂ω`.
    d_turn: Vector2<f64>,
    dt_s: f64,
    /// `∂w_D⁺/∂w_D`.
    vertical_decay: f64,
}

impl Transition {
    /// `F·M`: only the rows of the position, the horizontal air velocity and the vertical wind
    /// change.
    fn apply_rows(&self, m: &Covariance) -> Covariance {
        let mut out = *m;
        let row = |i: usize| m.row(i);
        let (air_n, air_e, turn) = (row(ix::AIR), row(ix::AIR + 1), row(ix::TURN));
        for k in 0..2 {
            let mut r = row(ix::POSITION + k).into_owned();
            r += air_n * self.g[(k, 0)] + air_e * self.g[(k, 1)] + turn * self.dg_air[k];
            r += row(ix::WIND + k) * self.dt_s;
            out.set_row(ix::POSITION + k, &r);
            let v = air_n * self.turn[(k, 0)] + air_e * self.turn[(k, 1)] + turn * self.d_turn[k];
            out.set_row(ix::AIR + k, &v);
        }
        let down = row(ix::POSITION + 2) + (row(ix::AIR + 2) + row(ix::WIND_DOWN)) * self.dt_s;
        out.set_row(ix::POSITION + 2, &down);
        out.set_row(ix::WIND_DOWN, &(row(ix::WIND_DOWN) * self.vertical_decay));
        out
    }
}

/// The navigation EKF's state and covariance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Nav {
    pub x: StateVec,
    pub p: Covariance,
}

impl Nav {
    /// Velocity relative to the air, NED, m/s.
    pub fn air_ned(&self) -> Vector3<f64> {
        self.x.fixed_rows::<3>(ix::AIR).into_owned()
    }

    /// Wind as a NED vector, m/s.
    pub fn wind_ned(&self) -> Vector3<f64> {
        Vector3::new(
            self.x[ix::WIND],
            self.x[ix::WIND + 1],
            self.x[ix::WIND_DOWN],
        )
    }

    /// Advances by `dt_s`: the horizontal air velocity turns at the turn-rate state, the
    /// position follows the arc plus the wind.
    pub fn predict(&mut self, dt_s: f64, t: &Tuning) {
        let omega = self.x[ix::TURN];
        let air_h = Vector2::new(self.x[ix::AIR], self.x[ix::AIR + 1]);
        let turn = rotation(omega * dt_s);
        let (g, dg_domega) = integrated_rotation(omega, dt_s);
        let wind_h = Vector2::new(self.x[ix::WIND], self.x[ix::WIND + 1]);

        let displacement_h = g * air_h + wind_h * dt_s;
        let new_air_h = turn * air_h;
        self.x[ix::POSITION] += displacement_h.x;
        self.x[ix::POSITION + 1] += displacement_h.y;
        self.x[ix::POSITION + 2] += (self.x[ix::AIR + 2] + self.x[ix::WIND_DOWN]) * dt_s;
        let vertical_decay = (-dt_s / t.vertical_wind_correlation_s).exp();
        self.x[ix::WIND_DOWN] *= vertical_decay;
        self.x[ix::AIR] = new_air_h.x;
        self.x[ix::AIR + 1] = new_air_h.y;

        // F = I except for the blocks below; F·P·Fᵀ by row operations costs a tenth of two
        // dense 14×14 products, and this runs at every measurement and estimate.
        // ∂(R(ωΔt)·v)/∂ω = Δt·R(ωΔt + π/2)·v.
        let d_turn = rotation(omega * dt_s + std::f64::consts::FRAC_PI_2) * air_h * dt_s;
        let transition = Transition {
            g,
            dg_air: dg_domega * air_h,
            turn,
            d_turn,
            dt_s,
            vertical_decay,
        };
        let fp = transition.apply_rows(&self.p);
        self.p = transition.apply_rows(&fp.transpose());

        // Random walks on the air velocity, turn rate, wind, scale and biases, with the air
        // velocity's and the wind's carried into position (Δt²/2 and Δt³/3 terms).
        let mut q = Covariance::zeros();
        let dt2 = dt_s * dt_s;
        let dt3 = dt2 * dt_s;
        for (k, density) in [
            (0, t.q_air_horizontal),
            (1, t.q_air_horizontal),
            (2, t.q_air_vertical),
        ] {
            q[(ix::AIR + k, ix::AIR + k)] = density * dt_s;
            q[(ix::POSITION + k, ix::AIR + k)] = density * dt2 / 2.0;
            q[(ix::AIR + k, ix::POSITION + k)] = density * dt2 / 2.0;
            q[(ix::POSITION + k, ix::POSITION + k)] = density * dt3 / 3.0 + t.q_position * dt_s;
        }
        for k in 0..2 {
            q[(ix::WIND + k, ix::WIND + k)] = t.q_wind * dt_s;
            q[(ix::POSITION + k, ix::WIND + k)] = t.q_wind * dt2 / 2.0;
            q[(ix::WIND + k, ix::POSITION + k)] = t.q_wind * dt2 / 2.0;
            q[(ix::POSITION + k, ix::POSITION + k)] += t.q_wind * dt3 / 3.0;
        }
        q[(ix::TURN, ix::TURN)] = t.q_turn * dt_s;
        q[(ix::WIND_DOWN, ix::WIND_DOWN)] =
            t.vertical_wind_variance * (1.0 - vertical_decay * vertical_decay);
        q[(ix::SCALE, ix::SCALE)] = t.q_scale * dt_s;
        q[(ix::BARO, ix::BARO)] = t.q_baro * dt_s;
        q[(ix::SIDESLIP, ix::SIDESLIP)] = t.q_sideslip * dt_s;
        q[(ix::HEADING_BIAS, ix::HEADING_BIAS)] = t.q_heading_bias * dt_s;

        self.p += q;
    }

    /// The Kalman update for innovation `y` with Jacobian `h` and noise `r`; refused (and the
    /// state left alone) if the innovation's normalised square exceeds `gate_nis` or the
    /// innovation covariance is not positive definite.
    pub fn update<const M: usize>(
        &mut self,
        y: &SVector<f64, M>,
        h: &SMatrix<f64, M, N>,
        r: &SMatrix<f64, M, M>,
        gate_nis: Option<f64>,
    ) -> bool {
        let ph_t = self.p * h.transpose();
        let s = h * ph_t + r;
        let Some(chol) = s.cholesky() else {
            return false;
        };
        let s_inv_y = chol.solve(y);
        let nis = y.dot(&s_inv_y);
        // A NaN NIS (which finite inputs should never give) fails the gate too.
        let passes = |gate: f64| nis.partial_cmp(&gate).is_some_and(|o| o.is_le());
        if gate_nis.is_some_and(|gate| !passes(gate)) {
            return false;
        }
        // K = P Hᵀ S⁻¹, computed as (S⁻¹ H P)ᵀ since S and P are symmetric.
        let gain = chol.solve(&ph_t.transpose()).transpose();
        self.x += gain * y;
        self.p -= gain * ph_t.transpose();
        self.p = (self.p + self.p.transpose()) * 0.5;
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integrated_rotation_and_its_derivative_match_numerical_ones() {
        let dt = 0.25;
        for omega in [-1.2, -3e-5, 0.0, 2e-5, 0.6] {
            let (g, dg) = integrated_rotation(omega, dt);
            let steps = 20_000;
            let h = dt / steps as f64;
            let sum: Matrix2<f64> = (0..steps)
                .map(|i| rotation(omega * (i as f64 + 0.5) * h) * h)
                .sum();
            assert!((g - sum).abs().max() < 1e-9, "G at ω = {omega}");
            let e = 1e-3;
            let numeric = (integrated_rotation(omega + e, dt).0
                - integrated_rotation(omega - e, dt).0)
                / (2.0 * e);
            assert!((dg - numeric).abs().max() < 1e-7, "∂G/∂ω at ω = {omega}");
        }
    }

    /// A tuning with every process noise zero, so `P⁺ = F P Fᵀ` exactly.
    fn noiseless() -> Tuning {
        let mut t = Tuning::new(&crate::estimator::EstimatorConfig::default());
        t.q_air_horizontal = 0.0;
        t.q_air_vertical = 0.0;
        t.q_turn = 0.0;
        t.q_wind = 0.0;
        t.q_position = 0.0;
        t.q_scale = 0.0;
        t.q_baro = 0.0;
        t.q_sideslip = 0.0;
        t.q_heading_bias = 0.0;
        t.vertical_wind_variance = 0.0;
        t
    }

    #[test]
    fn covariance_propagation_is_the_jacobian_of_the_state_propagation() {
        let t = noiseless();
        let x = StateVec::from_column_slice(&[
            10.0, -20.0, -500.0, 6.0, -3.0, 4.5, 0.7, -2.0, 3.0, 0.4, 0.97, 0.01, 0.05, -0.08,
        ]);
        // A full, symmetric positive-definite covariance.
        let a = Covariance::from_fn(|i, j| ((i * 7 + j * 3) % 11) as f64 * 0.1 - 0.5);
        let p = a * a.transpose() + Covariance::identity();
        let dt = 0.25;
        let mut nav = Nav { x, p };
        nav.predict(dt, &t);

        // Finite-difference Jacobian of the state propagation.
        let propagate = |x: StateVec| {
            let mut n = Nav {
                x,
                p: Covariance::identity(),
            };
            n.predict(dt, &t);
            n.x
        };
        let mut f = Covariance::zeros();
        for j in 0..N {
            let h = 1e-6;
            let mut plus = x;
            let mut minus = x;
            plus[j] += h;
            minus[j] -= h;
            f.set_column(j, &((propagate(plus) - propagate(minus)) / (2.0 * h)));
        }
        let expected = f * p * f.transpose();
        let worst = (nav.p - expected).abs().max();
        assert!(worst < 1e-5, "largest difference {worst}");
    }
}
