//! GPS fixes: they start the navigation EKF (with a wind prior), update its position and its
//! ground velocity, and re-start it after repeated rejections, when the fixes agree with each
//! other but not with the state.

use nalgebra::{Matrix3, SMatrix, Vector2, Vector3};

use super::config::Tuning;
use super::ekf::{Covariance, N, Nav, Outcome, StateVec, ix};
use crate::measurement::GpsFix;

/// Turn-rate uncertainty when the navigation filter starts, rad/s.
const INITIAL_TURN_SIGMA_RAD_S: f64 = 0.5;
/// Extra air-velocity uncertainty over the wind's when the filter starts, m/s.
const INITIAL_AIR_EXTRA_SIGMA_MPS: f64 = 1.0;

/// Consecutive gated GPS position and velocity blocks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct GpsGate {
    position_in_row: u32,
    velocity_in_row: u32,
}

/// The sensor calibration a (re)started state takes over: the pitot scale and the AHRS
/// heading bias, each as (value, variance). A restart after rejected fixes is about the air
/// velocity and the wind; what was learnt of the sensors still holds.
#[derive(Debug, Clone, Copy)]
struct Calibration {
    scale: (f64, f64),
    heading_bias: (f64, f64),
}

/// What a fix did: the navigation state after it, and whether it (re)started that state.
pub(super) struct GpsStep {
    pub(super) nav: Nav,
    pub(super) outcome: Outcome,
    /// The state was started afresh (the first fix, or after repeated rejections).
    pub(super) restarted: bool,
}

/// GPS noise: position variances (horizontal, vertical) and speed variance, floored.
fn gps_variances(g: &GpsFix, t: &Tuning) -> (f64, f64, f64) {
    (
        g.horizontal_accuracy_m.max(t.gps_min_horizontal_m).powi(2),
        g.vertical_accuracy_m.max(t.gps_min_vertical_m).powi(2),
        g.speed_accuracy_mps.max(t.gps_min_speed_mps).powi(2),
    )
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

impl GpsGate {
    pub(super) const fn new() -> Self {
        Self {
            position_in_row: 0,
            velocity_in_row: 0,
        }
    }

    /// Starts (or restarts) the navigation state from a fix, with the wind prior given.
    fn start(
        &mut self,
        g: &GpsFix,
        wind: Vector2<f64>,
        wind_variance: f64,
        calibration: Calibration,
        t: &Tuning,
    ) -> Nav {
        let (h_var, v_var, s_var) = gps_variances(g, t);
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
        (x[ix::SCALE], p[(ix::SCALE, ix::SCALE)]) = calibration.scale;
        (x[ix::HEADING_BIAS], p[(ix::HEADING_BIAS, ix::HEADING_BIAS)]) = calibration.heading_bias;
        p[(ix::BARO, ix::BARO)] = t.initial_baro_variance;
        p[(ix::SIDESLIP, ix::SIDESLIP)] = t.initial_sideslip_variance;
        let mut nav = Nav { x, p };
        velocity_update(&mut nav, g, s_var, None);
        self.position_in_row = 0;
        self.velocity_in_row = 0;
        nav
    }

    /// Feeds the fix `g` to the navigation state `nav`, starting it if there is none.
    pub(super) fn apply(&mut self, nav: Option<Nav>, g: &GpsFix, t: &Tuning) -> GpsStep {
        let Some(mut nav) = nav else {
            let nav = self.start(
                g,
                Vector2::zeros(),
                t.initial_wind_variance,
                Calibration {
                    scale: (t.initial_scale, t.initial_scale_variance),
                    heading_bias: (t.initial_heading_bias_rad, t.initial_heading_bias_variance),
                },
                t,
            );
            return GpsStep {
                nav,
                outcome: Outcome::Reset,
                restarted: true,
            };
        };
        let (h_var, v_var, s_var) = gps_variances(g, t);
        let mut outcome = Outcome::Used;

        let y = g.position_ned_m - nav.x.fixed_rows::<3>(ix::POSITION);
        let mut h = SMatrix::<f64, 3, N>::zeros();
        h.fixed_view_mut::<3, 3>(0, ix::POSITION)
            .copy_from(&Matrix3::identity());
        let r = Matrix3::from_diagonal(&Vector3::new(h_var, h_var, v_var));
        if nav.update(&y, &h, &r, Some(t.gate_nis[2])) {
            self.position_in_row = 0;
        } else {
            self.position_in_row += 1;
            outcome = Outcome::Gated;
            if self.position_in_row >= t.reset_after_rejections {
                // The fixes agree with each other but not with the state: believe them.
                for k in 0..3 {
                    nav.x[ix::POSITION + k] = g.position_ned_m[k];
                    for j in 0..N {
                        nav.p[(ix::POSITION + k, j)] = 0.0;
                        nav.p[(j, ix::POSITION + k)] = 0.0;
                    }
                    nav.p[(ix::POSITION + k, ix::POSITION + k)] = r[(k, k)];
                }
                self.position_in_row = 0;
                outcome = Outcome::Reset;
            }
        }

        if velocity_update(&mut nav, g, s_var, Some(t.gate_nis[2])) {
            self.velocity_in_row = 0;
        } else {
            self.velocity_in_row += 1;
            outcome = Outcome::Gated;
            if self.velocity_in_row >= t.reset_after_rejections {
                // Keep the wind as a prior but let the fix set the velocities.
                let wind = Vector2::new(nav.x[ix::WIND], nav.x[ix::WIND + 1]);
                let kept = |i: usize| (nav.x[i], nav.p[(i, i)]);
                let calibration = Calibration {
                    scale: kept(ix::SCALE),
                    heading_bias: kept(ix::HEADING_BIAS),
                };
                let nav = self.start(g, wind, t.initial_wind_variance, calibration, t);
                return GpsStep {
                    nav,
                    outcome: Outcome::Reset,
                    restarted: true,
                };
            }
        }
        GpsStep {
            nav,
            outcome,
            restarted: false,
        }
    }
}
