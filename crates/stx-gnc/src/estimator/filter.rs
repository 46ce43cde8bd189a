//! The filter proper: three angle filters and the navigation EKF, advanced one measurement at a
//! time in timestamp order (the buffering around it lives in the parent module). `Copy`, so
//! the parent can keep a committed copy and replay late measurements onto a clone.
//!
//! The equations are in the parent module's documentation; the comments here say how the code
//! follows them.

use nalgebra::{Matrix2, Matrix3, SMatrix, SVector, Vector2, Vector3};
use stx_dynamics::atmosphere::{Atmosphere, STANDARD_GRAVITY_MPS2, StandardAtmosphere};
use stx_dynamics::rotation::wrap_pi;

use super::angle::AngleFilter;
use super::config::Tuning;
use crate::estimate::Estimate;
use crate::measurement::{AIR_GAS_CONSTANT, AirDataSample, AttitudeSample, GpsFix, Measurement};

/// Number of navigation states.
pub(crate) const N: usize = 13;
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
    /// Sideslip of the air velocity from the drone's measured heading in straight flight, rad
    /// (the AHRS's heading bias included).
    pub const SIDESLIP: usize = 12;
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

/// The drone's x axis in NED for pitch θ and yaw ψ (roll does not move it):
/// `e_x = [cos θ cos ψ, cos θ sin ψ, −sin θ]`.
pub(crate) fn x_axis_ned(pitch: f64, yaw: f64) -> Vector3<f64> {
    let (st, ct) = pitch.sin_cos();
    let (sp, cp) = yaw.sin_cos();
    Vector3::new(ct * cp, ct * sp, -st)
}

/// `∂(e_x·v)/∂θ` and `∂(e_x·v)/∂ψ`: how pitch and heading errors become pitot errors.
fn x_axis_projection_gradient(pitch: f64, yaw: f64, v: &Vector3<f64>) -> (f64, f64) {
    let (st, ct) = pitch.sin_cos();
    let (sp, cp) = yaw.sin_cos();
    let along = cp * v.x + sp * v.y;
    let across = -sp * v.x + cp * v.y;
    (-st * along - ct * v.z, ct * across)
}

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
    fn predict(&mut self, dt_s: f64, t: &Tuning) {
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
        // dense 12×12 products, and this runs at every measurement and estimate.
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

        // Random walks on the air velocity, turn rate, wind, scale and bias, with the air
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

        self.p += q;
    }

    /// The Kalman update for innovation `y` with Jacobian `h` and noise `r`; refused (and the
    /// state left alone) if the innovation's normalised square exceeds `gate_nis` or the
    /// innovation covariance is not positive definite.
    fn update<const M: usize>(
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

/// The filter at one instant: three angle filters and, once started by a GPS fix, the
/// navigation EKF.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct NavFilter {
    /// Instant the state describes, s.
    pub time_s: f64,
    /// Whether any measurement has set the time.
    started: bool,
    /// Roll, pitch, yaw of the drone.
    pub attitude: [AngleFilter; 3],
    /// Navigation state, once a GPS fix (with an attitude) has started it.
    pub nav: Option<Nav>,
    /// Instants of the last GPS fix used, AHRS sample and pitot sample received, s.
    pub last_gps_s: f64,
    pub last_attitude_s: f64,
    pub last_air_data_s: f64,
    /// Consecutive gated GPS position and velocity blocks.
    gated_position_in_row: u32,
    gated_velocity_in_row: u32,
    /// Consecutive pitot samples that read a healthy airspeed along the drone's x axis while
    /// the state put the air beside or behind it.
    contradicting_pitot_in_row: u32,
    /// Whether a static pressure has set the barometric bias.
    baro_started: bool,
    /// The latest AHRS sample, to interpolate the attitude of a pitot sample that falls
    /// between two.
    last_attitude: Option<AttitudeSample>,
    /// Since when the flight has been straight, s (+∞ while turning).
    straight_since_s: f64,
    /// Air density of the latest air-data sample and its 1-σ, kg/m³.
    density: Option<(f64, f64)>,
}

/// Turn-rate uncertainty when the navigation filter starts, rad/s.
const INITIAL_TURN_SIGMA_RAD_S: f64 = 0.5;
/// Extra air-velocity uncertainty over the wind's when the filter starts, m/s.
const INITIAL_AIR_EXTRA_SIGMA_MPS: f64 = 1.0;

impl NavFilter {
    pub const fn new() -> Self {
        Self {
            time_s: 0.0,
            started: false,
            attitude: [AngleFilter::new(); 3],
            nav: None,
            last_gps_s: f64::NEG_INFINITY,
            last_attitude_s: f64::NEG_INFINITY,
            last_air_data_s: f64::NEG_INFINITY,
            gated_position_in_row: 0,
            gated_velocity_in_row: 0,
            contradicting_pitot_in_row: 0,
            baro_started: false,
            last_attitude: None,
            straight_since_s: f64::INFINITY,
            density: None,
        }
    }

    /// Instant of the latest AHRS sample applied, s (−∞ before the first).
    pub fn last_attitude_time_s(&self) -> f64 {
        self.last_attitude.map_or(f64::NEG_INFINITY, |a| a.time_s)
    }

    fn attitude_started(&self) -> bool {
        self.attitude.iter().all(|a| a.started)
    }

    /// Advances everything to `time_s` (never backwards).
    pub fn predict_to(&mut self, time_s: f64, t: &Tuning) {
        if !self.started {
            self.time_s = time_s;
            self.started = true;
            return;
        }
        let dt_s = time_s - self.time_s;
        if dt_s <= 0.0 {
            return;
        }
        if let Some(nav) = &mut self.nav {
            nav.predict(dt_s, t);
        }
        let [roll, pitch, yaw] = &mut self.attitude;
        roll.predict(dt_s, t.q_roll_pitch);
        pitch.predict(dt_s, t.q_roll_pitch);
        yaw.predict(dt_s, t.q_yaw);
        self.time_s = time_s;
    }

    /// Advances to the measurement's instant and feeds it. `next_attitude` is the first AHRS
    /// sample after it, if already received: a pitot sample between two AHRS samples is
    /// projected with the attitude interpolated between them.
    pub fn apply(
        &mut self,
        m: &Measurement,
        next_attitude: Option<&AttitudeSample>,
        t: &Tuning,
    ) -> Outcome {
        self.predict_to(m.time_s(), t);
        let outcome = match m {
            Measurement::Attitude(a) => self.apply_attitude(a, t),
            Measurement::Gps(g) => self.apply_gps(g, t),
            Measurement::AirData(a) => self.apply_air_data(a, next_attitude, t),
        };
        self.heal();
        outcome
    }

    /// Finite but absurd input (positions of 1e300 m, a gap of centuries) can overflow the
    /// arithmetic; a non-finite state would then stay so for ever. Such a part is dropped and
    /// starts again from the next measurement instead.
    fn heal(&mut self) {
        for angle in &mut self.attitude {
            let finite = angle.angle_rad.is_finite()
                && angle.rate_rad_s.is_finite()
                && angle.covariance.iter().all(|v| v.is_finite());
            if !finite {
                *angle = AngleFilter::new();
            }
        }
        let nav_finite = self.nav.as_ref().is_none_or(|nav| {
            nav.x.iter().all(|v| v.is_finite()) && nav.p.iter().all(|v| v.is_finite())
        });
        if !nav_finite || !self.time_s.is_finite() {
            self.nav = None;
        }
        if !self.time_s.is_finite() {
            *self = Self::new();
        }
    }

    fn apply_attitude(&mut self, a: &AttitudeSample, t: &Tuning) -> Outcome {
        self.last_attitude_s = a.time_s;
        self.last_attitude = Some(*a);
        let measured = [a.roll_rad, a.pitch_rad, a.yaw_rad];
        let variances = [t.r_roll_pitch, t.r_roll_pitch, t.r_yaw];
        let mut started = false;
        for k in 0..3 {
            started |= self.attitude[k].update(measured[k], variances[k], t.max_angular_rate_rad_s);
        }
        if started {
            return Outcome::Reset;
        }
        self.sideslip_update(a.time_s, t);
        Outcome::Used
    }

    /// In straight flight the drone weathervanes: the horizontal air velocity lies along its
    /// heading, give or take its swing and a slowly varying offset `β₀` (which also takes up the
    /// AHRS's heading bias). That pseudo-measurement,
    /// `0 = e_y·a_h − |a_h|·β₀` with `e_y = [−sin ψ, cos ψ]`, gives the cross-wind from a
    /// single heading. Turns (and the swing after them) break it, so it is used only after the
    /// flight has been straight for a while; `β₀` itself is learnt from the wind found in turns.
    fn sideslip_update(&mut self, time_s: f64, t: &Tuning) {
        let Some(mut nav) = self.nav else {
            return;
        };
        let yaw = &self.attitude[2];
        let straight = nav.x[ix::TURN].abs() < t.straight_turn_rate_rad_s
            && yaw.rate_rad_s.abs() < t.straight_yaw_rate_rad_s;
        if !straight {
            self.straight_since_s = f64::INFINITY;
            return;
        }
        self.straight_since_s = self.straight_since_s.min(time_s);
        if time_s - self.straight_since_s < t.straight_settle_s {
            return;
        }
        let air_h = Vector2::new(nav.x[ix::AIR], nav.x[ix::AIR + 1]);
        let speed_h = air_h.norm();
        if speed_h < t.pitot_min_airspeed_mps.max(MIN_SPEED_FOR_DIRECTION_MPS) {
            return;
        }
        let (s, c) = yaw.angle_rad.sin_cos();
        let e_y = Vector2::new(-s, c);
        let beta = nav.x[ix::SIDESLIP];
        let predicted = e_y.dot(&air_h) - speed_h * beta;
        let mut h = SMatrix::<f64, 1, N>::zeros();
        let d_air = e_y - air_h * (beta / speed_h);
        h[(0, ix::AIR)] = d_air.x;
        h[(0, ix::AIR + 1)] = d_air.y;
        h[(0, ix::SIDESLIP)] = -speed_h;
        // The swing, and the heading's own uncertainty (∂(e_y·a)/∂ψ = −e_x·a).
        let along = Vector2::new(c, s).dot(&air_h);
        let variance = (speed_h * t.straight_sideslip_sigma_rad).powi(2)
            + along * along * yaw.angle_variance();
        let y = SMatrix::<f64, 1, 1>::new(-predicted);
        nav.update(
            &y,
            &h,
            &SMatrix::<f64, 1, 1>::new(variance),
            Some(t.gate_nis[0]),
        );
        self.nav = Some(nav);
    }

    /// GPS noise: position variances (horizontal, vertical) and speed variance, floored.
    fn gps_variances(g: &GpsFix, t: &Tuning) -> (f64, f64, f64) {
        (
            g.horizontal_accuracy_m.max(t.gps_min_horizontal_m).powi(2),
            g.vertical_accuracy_m.max(t.gps_min_vertical_m).powi(2),
            g.speed_accuracy_mps.max(t.gps_min_speed_mps).powi(2),
        )
    }

    /// Starts (or restarts) the navigation state from a fix, with the wind prior given.
    fn start_nav(
        &mut self,
        g: &GpsFix,
        wind: Vector2<f64>,
        wind_variance: f64,
        scale: (f64, f64),
        t: &Tuning,
    ) {
        let (h_var, v_var, s_var) = Self::gps_variances(g, t);
        let mut x = StateVec::zeros();
        let mut p = Covariance::zeros();
        for k in 0..3 {
            x[ix::POSITION + k] = g.position_ned_m[k];
            p[(ix::POSITION + k, ix::POSITION + k)] = if k < 2 { h_var } else { v_var };
        }
        // Air velocity from the ground velocity and the wind prior, both uncertain by the
        // wind's spread until the velocity update below ties them together.
        let air = g.velocity_ned_mps - Vector3::new(wind.x, wind.y, 0.0);
        for k in 0..3 {
            x[ix::AIR + k] = air[k];
            let spread = if k < 2 { wind_variance } else { 0.0 };
            p[(ix::AIR + k, ix::AIR + k)] = spread + INITIAL_AIR_EXTRA_SIGMA_MPS.powi(2);
        }
        p[(ix::TURN, ix::TURN)] = INITIAL_TURN_SIGMA_RAD_S.powi(2);
        p[(ix::WIND_DOWN, ix::WIND_DOWN)] = t.vertical_wind_variance;
        for k in 0..2 {
            x[ix::WIND + k] = wind[k];
            p[(ix::WIND + k, ix::WIND + k)] = wind_variance;
        }
        x[ix::SCALE] = scale.0;
        p[(ix::SCALE, ix::SCALE)] = scale.1;
        p[(ix::BARO, ix::BARO)] = t.initial_baro_variance;
        p[(ix::SIDESLIP, ix::SIDESLIP)] = t.initial_sideslip_variance;
        let mut nav = Nav { x, p };
        Self::velocity_update(&mut nav, g, s_var, None);
        self.nav = Some(nav);
        self.baro_started = false;
        self.gated_position_in_row = 0;
        self.gated_velocity_in_row = 0;
    }

    /// GPS velocity: `z = v_air + [w_N, w_E, 0]`.
    fn velocity_update(nav: &mut Nav, g: &GpsFix, speed_variance: f64, gate: Option<f64>) -> bool {
        let y = g.velocity_ned_mps - (nav.air_ned() + nav.wind_ned());
        let mut h = SMatrix::<f64, 3, N>::zeros();
        for k in 0..3 {
            h[(k, ix::AIR + k)] = 1.0;
        }
        h[(0, ix::WIND)] = 1.0;
        h[(1, ix::WIND + 1)] = 1.0;
        h[(2, ix::WIND_DOWN)] = 1.0;
        nav.update(&y, &h, &(Matrix3::identity() * speed_variance), gate)
    }

    fn apply_gps(&mut self, g: &GpsFix, t: &Tuning) -> Outcome {
        if !self.attitude_started() {
            return Outcome::Unused;
        }
        let Some(mut nav) = self.nav else {
            self.start_nav(
                g,
                Vector2::zeros(),
                t.initial_wind_variance,
                (1.0, t.initial_scale_variance),
                t,
            );
            self.last_gps_s = g.time_s;
            return Outcome::Reset;
        };
        let (h_var, v_var, s_var) = Self::gps_variances(g, t);
        let mut outcome = Outcome::Used;

        let y = g.position_ned_m - nav.x.fixed_rows::<3>(ix::POSITION);
        let mut h = SMatrix::<f64, 3, N>::zeros();
        h.fixed_view_mut::<3, 3>(0, ix::POSITION)
            .copy_from(&Matrix3::identity());
        let r = Matrix3::from_diagonal(&Vector3::new(h_var, h_var, v_var));
        if nav.update(&y, &h, &r, Some(t.gate_nis[2])) {
            self.gated_position_in_row = 0;
        } else {
            self.gated_position_in_row += 1;
            outcome = Outcome::Gated;
            if self.gated_position_in_row >= t.reset_after_rejections {
                // The fixes agree with each other but not with the state: believe them.
                for k in 0..3 {
                    nav.x[ix::POSITION + k] = g.position_ned_m[k];
                    for j in 0..N {
                        nav.p[(ix::POSITION + k, j)] = 0.0;
                        nav.p[(j, ix::POSITION + k)] = 0.0;
                    }
                    nav.p[(ix::POSITION + k, ix::POSITION + k)] = r[(k, k)];
                }
                self.gated_position_in_row = 0;
                outcome = Outcome::Reset;
            }
        }

        if Self::velocity_update(&mut nav, g, s_var, Some(t.gate_nis[2])) {
            self.gated_velocity_in_row = 0;
        } else {
            self.gated_velocity_in_row += 1;
            outcome = Outcome::Gated;
            if self.gated_velocity_in_row >= t.reset_after_rejections {
                // Keep the wind as a prior but let the fix set the velocities.
                let wind = Vector2::new(nav.x[ix::WIND], nav.x[ix::WIND + 1]);
                let scale = (nav.x[ix::SCALE], nav.p[(ix::SCALE, ix::SCALE)]);
                self.start_nav(g, wind, t.initial_wind_variance, scale, t);
                self.last_gps_s = g.time_s;
                return Outcome::Reset;
            }
        }
        if outcome != Outcome::Gated {
            self.last_gps_s = g.time_s;
        }
        self.nav = Some(nav);
        outcome
    }

    fn apply_air_data(
        &mut self,
        a: &AirDataSample,
        next_attitude: Option<&AttitudeSample>,
        t: &Tuning,
    ) -> Outcome {
        self.last_air_data_s = a.time_s;
        // ρ = p/(R·T): relative errors add in quadrature.
        let density = a.density_kg_per_m3();
        let relative = (t.static_pressure_noise_pa / a.static_pressure_pa)
            .hypot(t.temperature_sigma_k / a.temperature_k);
        self.density = Some((density, density * relative));
        if !self.attitude_started() {
            return Outcome::Unused;
        }
        let Some(mut nav) = self.nav else {
            return Outcome::Unused;
        };
        let baro = self.baro_update(&mut nav, a, t);
        let pitot = self.pitot_update(&mut nav, a, next_attitude, t);
        self.nav = Some(nav);
        match (baro, pitot) {
            (Outcome::Gated, _) | (_, Outcome::Gated) => Outcome::Gated,
            (Outcome::Used, _) | (_, Outcome::Used) => Outcome::Used,
            (Outcome::Reset, _) => Outcome::Reset,
            _ => Outcome::Unused,
        }
    }

    /// Barometric altitude: `ln p_s = ln p_std(h₀ − p_D) + b`.
    fn baro_update(&mut self, nav: &mut Nav, a: &AirDataSample, t: &Tuning) -> Outcome {
        let altitude_msl_m = t.ground_altitude_msl_m - nav.x[ix::POSITION + 2];
        let standard = StandardAtmosphere.air_at(altitude_msl_m);
        if !(standard.pressure_pa > 0.0 && standard.temperature_k > 0.0) {
            return Outcome::Unused;
        }
        let measured = a.static_pressure_pa.ln();
        let mut h = SMatrix::<f64, 1, N>::zeros();
        // d ln p / d(altitude) = −g/(R·T), and altitude = h₀ − p_D.
        h[(0, ix::POSITION + 2)] =
            STANDARD_GRAVITY_MPS2 / (AIR_GAS_CONSTANT * standard.temperature_k);
        h[(0, ix::BARO)] = 1.0;
        let r =
            SMatrix::<f64, 1, 1>::new((t.static_pressure_noise_pa / a.static_pressure_pa).powi(2));
        if !self.baro_started {
            // First reading: the bias takes up the whole difference, uncorrelated before the
            // update ties it to the altitude's uncertainty.
            nav.x[ix::BARO] = measured - standard.pressure_pa.ln();
            for j in 0..N {
                nav.p[(ix::BARO, j)] = 0.0;
                nav.p[(j, ix::BARO)] = 0.0;
            }
            nav.p[(ix::BARO, ix::BARO)] = t.initial_baro_variance;
            nav.update(&SMatrix::<f64, 1, 1>::zeros(), &h, &r, None);
            self.baro_started = true;
            return Outcome::Reset;
        }
        let y = SMatrix::<f64, 1, 1>::new(measured - standard.pressure_pa.ln() - nav.x[ix::BARO]);
        if nav.update(&y, &h, &r, Some(t.gate_nis[0])) {
            Outcome::Used
        } else {
            Outcome::Gated
        }
    }

    /// Pitch and heading at `time_s` with their variances: the AHRS's own if sampled at that
    /// instant, else interpolated between the AHRS samples around it when both are known (the
    /// drone swings too fast for the angle filters' extrapolation), else the angle filters'.
    fn attitude_at(
        &self,
        time_s: f64,
        next: Option<&AttitudeSample>,
        t: &Tuning,
    ) -> (f64, f64, f64, f64) {
        let [_, pitch, yaw] = &self.attitude;
        let filtered = (
            pitch.angle_rad,
            pitch.angle_variance(),
            yaw.angle_rad,
            yaw.angle_variance(),
        );
        let Some(before) = self.last_attitude else {
            return filtered;
        };
        if before.time_s == time_s {
            // Sampled together (the drone's 4 Hz loop): the AHRS's own angles.
            return (before.pitch_rad, t.r_roll_pitch, before.yaw_rad, t.r_yaw);
        }
        let Some(after) = next else {
            return filtered;
        };
        let span_s = after.time_s - before.time_s;
        if !(before.time_s <= time_s && time_s <= after.time_s && span_s <= MAX_INTERPOLATION_S) {
            return filtered;
        }
        let f = if span_s > 0.0 {
            (time_s - before.time_s) / span_s
        } else {
            0.0
        };
        let d_pitch = after.pitch_rad - before.pitch_rad;
        let d_yaw = wrap_pi(after.yaw_rad - before.yaw_rad);
        // The swing between the samples is not a straight line: allow for the chord's error.
        let bow = 0.5 * f.min(1.0 - f);
        (
            before.pitch_rad + f * d_pitch,
            t.r_roll_pitch + (bow * d_pitch).powi(2),
            wrap_pi(before.yaw_rad + f * d_yaw),
            t.r_yaw + (bow * d_yaw).powi(2),
        )
    }

    /// Pitot: indicated airspeed `z = k·(e_x·v_air)`, the air along the drone's x axis from
    /// the AHRS's pitch and heading; their uncertainty is added to the noise.
    fn pitot_update(
        &mut self,
        nav: &mut Nav,
        a: &AirDataSample,
        next_attitude: Option<&AttitudeSample>,
        t: &Tuning,
    ) -> Outcome {
        let measured = a.indicated_airspeed_mps();
        let (pitch, pitch_variance, yaw, yaw_variance) =
            self.attitude_at(a.time_s, next_attitude, t);
        let air = nav.air_ned();
        let e_x = x_axis_ned(pitch, yaw);
        let along_x = e_x.dot(&air);
        let scale = nav.x[ix::SCALE];
        let floor = t.pitot_min_airspeed_mps.max(MIN_SPEED_FOR_DIRECTION_MPS);
        if measured < floor {
            return Outcome::Unused;
        }
        if scale * along_x < floor {
            // The pitot reads the air coming from ahead, the state has it from beside or
            // behind. A swinging drone does that for a moment; for seconds on end it means the
            // state has turned its air velocity (and so the wind) the wrong way — a solution
            // that every other measurement also fits (the GPS sees only their sum, and the
            // straight-flight sideslip is zero for a reversed air velocity too), so nothing
            // else would ever correct it. Monte Carlo seed 4 run 157 flew on a wind 19 m/s
            // off, seed 3 run 354 on one 7 m/s off. After as many contradictions in a row as
            // GPS rejections that restart the filter, the air velocity is restarted along the
            // drone's x axis at the pitot's speed, the ground velocity kept.
            self.contradicting_pitot_in_row += 1;
            if self.contradicting_pitot_in_row < t.reset_after_rejections {
                return Outcome::Unused;
            }
            self.contradicting_pitot_in_row = 0;
            let ground = air + nav.wind_ned();
            let speed = measured / scale.max(0.1);
            let horizontal = (speed * speed - air.z * air.z).max(0.0).sqrt();
            let (sin_yaw, cos_yaw) = yaw.sin_cos();
            let new_air = Vector2::new(horizontal * cos_yaw, horizontal * sin_yaw);
            for k in 0..2 {
                nav.x[ix::AIR + k] = new_air[k];
                nav.x[ix::WIND + k] = ground[k] - new_air[k];
            }
            for i in [ix::AIR, ix::AIR + 1, ix::WIND, ix::WIND + 1] {
                for j in 0..N {
                    nav.p[(i, j)] = 0.0;
                    nav.p[(j, i)] = 0.0;
                }
            }
            for k in 0..2 {
                // The drone's heading is only the stack's give or take its swing: the new air
                // velocity, and so the wind, is uncertain by that much, and tied together
                // through the ground velocity they sum to.
                let variance = t.initial_wind_variance.min((0.5 * horizontal).powi(2));
                nav.p[(ix::AIR + k, ix::AIR + k)] = variance;
                nav.p[(ix::WIND + k, ix::WIND + k)] = variance;
                nav.p[(ix::AIR + k, ix::WIND + k)] = -variance;
                nav.p[(ix::WIND + k, ix::AIR + k)] = -variance;
            }
            return Outcome::Reset;
        }
        self.contradicting_pitot_in_row = 0;
        let density = a.density_kg_per_m3();
        let (d_pitch, d_yaw) = x_axis_projection_gradient(pitch, yaw, &air);
        // σ_u = σ_Δp / (ρ·u) from u = √(2Δp/ρ), plus the attitude's share and a floor.
        let variance = (t.differential_pressure_noise_pa / (density * measured)).powi(2)
            + (scale * d_pitch).powi(2) * pitch_variance
            + (scale * d_yaw).powi(2) * yaw_variance
            + t.pitot_floor_variance;
        let mut h = SMatrix::<f64, 1, N>::zeros();
        for k in 0..3 {
            h[(0, ix::AIR + k)] = scale * e_x[k];
        }
        h[(0, ix::SCALE)] = along_x;
        let y = SMatrix::<f64, 1, 1>::new(measured - scale * along_x);
        if nav.update(
            &y,
            &h,
            &SMatrix::<f64, 1, 1>::new(variance),
            Some(t.gate_nis[0]),
        ) {
            Outcome::Used
        } else {
            Outcome::Gated
        }
    }

    /// The estimate at `now_s`: this state predicted forward (never backward) and read out.
    /// A non-finite `now_s` reads the state out as it is, at its own instant.
    pub fn estimate(&self, now_s: f64, t: &Tuning, timeouts: &Timeouts) -> Estimate {
        if !now_s.is_finite() {
            return self.read_out(self.time_s, timeouts);
        }
        let mut f = *self;
        if now_s > f.time_s {
            f.predict_to(now_s, t);
        }
        f.read_out(now_s, timeouts)
    }

    fn read_out(&self, now_s: f64, timeouts: &Timeouts) -> Estimate {
        let [roll, pitch, yaw] = &self.attitude;
        let unknown = Vector3::repeat(f64::INFINITY);
        let gps_age_s = now_s - self.last_gps_s;
        let mut e = Estimate {
            time_s: now_s,
            position_ned_m: Vector3::zeros(),
            position_sigma_m: unknown,
            velocity_ned_mps: Vector3::zeros(),
            velocity_sigma_mps: unknown,
            heading_rad: yaw.angle_rad,
            heading_sigma_rad: yaw.angle_sigma_rad(),
            heading_rate_rad_s: yaw.rate_rad_s,
            heading_rate_sigma_rad_s: yaw.rate_sigma_rad_s(),
            drone_yaw_rad: yaw.angle_rad,
            drone_yaw_rate_rad_s: yaw.rate_rad_s,
            course_rad: 0.0,
            course_sigma_rad: f64::INFINITY,
            roll_rad: roll.angle_rad,
            pitch_rad: pitch.angle_rad,
            airspeed_mps: 0.0,
            airspeed_sigma_mps: f64::INFINITY,
            sink_rate_mps: 0.0,
            sink_rate_sigma_mps: f64::INFINITY,
            glide_ratio_air: 0.0,
            glide_ratio_air_sigma: f64::INFINITY,
            glide_ratio_ground: 0.0,
            glide_ratio_ground_sigma: f64::INFINITY,
            air_density_kg_per_m3: self.density.map_or(0.0, |d| d.0),
            air_density_sigma_kg_per_m3: self.density.map_or(f64::INFINITY, |d| d.1),
            wind_ned_mps: Vector3::zeros(),
            wind_sigma_mps: Vector3::new(f64::INFINITY, f64::INFINITY, 0.0),
            gps_ok: self.nav.is_some() && gps_age_s <= timeouts.gps_s,
            gps_age_s,
            attitude_ok: now_s - self.last_attitude_s <= timeouts.attitude_s,
            air_data_ok: now_s - self.last_air_data_s <= timeouts.air_data_s,
        };
        let Some(nav) = &self.nav else {
            return e;
        };
        let air = nav.air_ned();
        let velocity = air + nav.wind_ned();
        // Velocity covariance over (air, wind).
        let mut j = SMatrix::<f64, 3, N>::zeros();
        for k in 0..3 {
            j[(k, ix::AIR + k)] = 1.0;
        }
        j[(0, ix::WIND)] = 1.0;
        j[(1, ix::WIND + 1)] = 1.0;
        j[(2, ix::WIND_DOWN)] = 1.0;
        let velocity_cov = j * nav.p * j.transpose();

        let sigma = |variance: f64| variance.max(0.0).sqrt();
        e.position_ned_m = nav.x.fixed_rows::<3>(ix::POSITION).into_owned();
        e.position_sigma_m = Vector3::from_fn(|k, _| sigma(nav.p[(k, k)]));
        e.velocity_ned_mps = velocity;
        e.velocity_sigma_mps = Vector3::from_fn(|k, _| sigma(velocity_cov[(k, k)]));

        let ground_speed = velocity.x.hypot(velocity.y);
        e.course_rad = wrap_pi(velocity.y.atan2(velocity.x));
        e.course_sigma_rad = if ground_speed > 1e-3 {
            // Gradient of atan2(v_E, v_N) is [−v_E, v_N]/|v|².
            let g = Vector2::new(-velocity.y, velocity.x) / (ground_speed * ground_speed);
            let cov = velocity_cov.fixed_view::<2, 2>(0, 0);
            sigma((g.transpose() * cov * g)[(0, 0)]).min(std::f64::consts::PI)
        } else {
            std::f64::consts::PI
        };

        let airspeed = air.norm();
        let air_cov = nav.p.fixed_view::<3, 3>(ix::AIR, ix::AIR);
        e.airspeed_mps = airspeed;
        e.airspeed_sigma_mps = if airspeed > 1e-6 {
            let n = air / airspeed;
            sigma((n.transpose() * air_cov * n)[(0, 0)])
        } else {
            sigma(air_cov.trace())
        };
        e.sink_rate_mps = velocity.z;
        e.sink_rate_sigma_mps = e.velocity_sigma_mps.z;
        // Through the air mass with the air-relative sink; over the ground with the height
        // lost (they differ by the vertical wind).
        let glide = |distance_rate: f64, sink: f64| {
            if sink > MIN_SINK_FOR_GLIDE_MPS {
                distance_rate / sink
            } else {
                f64::INFINITY
            }
        };
        e.glide_ratio_air = glide(air.x.hypot(air.y), air.z);
        e.glide_ratio_ground = glide(ground_speed, velocity.z);
        e.glide_ratio_air_sigma = glide_sigma(&air, &air_cov.into_owned());
        e.glide_ratio_ground_sigma = glide_sigma(&velocity, &velocity_cov);
        // The vehicle's heading is where the stack flies through the air, not where the
        // swinging drone points: the direction of the horizontal air velocity, turning at ω.
        // Guidance steers on it; the drone's own yaw stays in the angle filters.
        let horizontal_air = air.x.hypot(air.y);
        if horizontal_air > 0.5 {
            e.heading_rad = wrap_pi(air.y.atan2(air.x));
            let g = Vector2::new(-air.y, air.x) / (horizontal_air * horizontal_air);
            let cov = air_cov.fixed_view::<2, 2>(0, 0);
            e.heading_sigma_rad =
                sigma((g.transpose() * cov * g)[(0, 0)]).min(std::f64::consts::PI);
            e.heading_rate_rad_s = nav.x[ix::TURN];
            e.heading_rate_sigma_rad_s = sigma(nav.p[(ix::TURN, ix::TURN)]);
        }
        e.wind_ned_mps = Vector3::new(nav.x[ix::WIND], nav.x[ix::WIND + 1], 0.0);
        e.wind_sigma_mps = Vector3::new(
            sigma(nav.p[(ix::WIND, ix::WIND)]),
            sigma(nav.p[(ix::WIND + 1, ix::WIND + 1)]),
            0.0,
        );
        e
    }
}

/// 1-σ of the glide ratio `g = |v_h|/v_D` of velocity `v` with covariance `cov`, to first
/// order: `∂g/∂v = [v_N/(|v_h| v_D), v_E/(|v_h| v_D), −|v_h|/v_D²]`. Infinite where the ratio is.
fn glide_sigma(v: &Vector3<f64>, cov: &Matrix3<f64>) -> f64 {
    let horizontal = v.x.hypot(v.y);
    let sink = v.z;
    if sink <= MIN_SINK_FOR_GLIDE_MPS {
        return f64::INFINITY;
    }
    let j = if horizontal > 1e-9 {
        Vector3::new(
            v.x / (horizontal * sink),
            v.y / (horizontal * sink),
            -horizontal / (sink * sink),
        )
    } else {
        Vector3::new(0.0, 0.0, 0.0)
    };
    (j.transpose() * cov * j)[(0, 0)].max(0.0).sqrt()
}

/// Below this sink rate a glide ratio means nothing and is reported as infinite, m/s.
const MIN_SINK_FOR_GLIDE_MPS: f64 = 0.05;

/// Longest gap between two AHRS samples across which a pitot sample's attitude is
/// interpolated, s; beyond it the angle filters' estimate is used.
pub(crate) const MAX_INTERPOLATION_S: f64 = 1.0;

/// Below this horizontal air speed the air velocity's direction, and the pitot's reading, mean
/// too little to use, m/s (and it keeps divisions by the speed away from zero).
const MIN_SPEED_FOR_DIRECTION_MPS: f64 = 1.0;

/// The status timeouts, s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Timeouts {
    pub gps_s: f64,
    pub attitude_s: f64,
    pub air_data_s: f64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use stx_dynamics::rotation::t_from_euler;

    #[test]
    fn the_x_axis_is_the_first_row_of_the_models_euler_matrix() {
        let (roll, pitch, yaw) = (0.3, -0.5, 2.9);
        let model = t_from_euler(&Vector3::new(roll, pitch, yaw));
        let row = model.row(0).transpose();
        assert!((x_axis_ned(pitch, yaw) - row).norm() < 1e-12);
    }

    #[test]
    fn projection_gradient_matches_finite_differences() {
        let v = Vector3::new(-6.0, 3.0, 2.5);
        let (pitch, yaw) = (-0.4, 3.0);
        let (d_pitch, d_yaw) = x_axis_projection_gradient(pitch, yaw, &v);
        let h = 1e-6;
        let f = |p: f64, y: f64| x_axis_ned(p, y).dot(&v);
        assert!((d_pitch - (f(pitch + h, yaw) - f(pitch - h, yaw)) / (2.0 * h)).abs() < 1e-6);
        assert!((d_yaw - (f(pitch, yaw + h) - f(pitch, yaw - h)) / (2.0 * h)).abs() < 1e-6);
    }

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
        t.vertical_wind_variance = 0.0;
        t
    }

    #[test]
    fn covariance_propagation_is_the_jacobian_of_the_state_propagation() {
        let t = noiseless();
        let x = StateVec::from_column_slice(&[
            10.0, -20.0, -500.0, 6.0, -3.0, 4.5, 0.7, -2.0, 3.0, 0.4, 0.97, 0.01, 0.05,
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
