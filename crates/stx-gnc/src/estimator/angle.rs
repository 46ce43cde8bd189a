//! A two-state Kalman filter for one attitude angle and its rate, fed by the AHRS's angle
//! alone (the drone reports no gyro rates).
//!
//! Model: the rate is a random walk driven by white angular acceleration of spectral density
//! `q` (rad²/s³), the angle integrates the rate:
//!
//! ```text
//! [θ; ω]ₖ₊₁ = [1 Δt; 0 1]·[θ; ω]ₖ,   Q = q·[Δt³/3  Δt²/2; Δt²/2  Δt]
//! z = θ + v,  v ~ N(0, r)
//! ```
//!
//! Angles live on a circle: the innovation is wrapped to (−π, π] and the angle is wrapped after
//! every step, so a heading passing ±180° is one small step, not a 360° jump. Wrapping makes
//! the rate ambiguous by multiples of 2π/Δt (a filter sampled at 4 Hz cannot tell 0 from
//! 25 rad/s), so the rate is held within a physical limit: without it, a burst of swinging can
//! leave the filter locked onto an alias, flipping the angle by 180° at every sample.
//!
//! There is no innovation gate: the AHRS is the only source of attitude, and a drone swinging
//! under the canopy really does jump by tens of degrees between samples.

use nalgebra::{Matrix2, Vector2};
use stx_types::rotation::wrap_pi;

/// One angle and its rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct AngleFilter {
    /// The angle, rad in (−π, π].
    pub angle_rad: f64,
    /// Its rate, rad/s.
    pub rate_rad_s: f64,
    /// Covariance of `[angle, rate]`.
    pub covariance: Matrix2<f64>,
    /// Whether a measurement has started the filter.
    pub started: bool,
}

/// Rate uncertainty when the filter starts, rad/s: the parafoil turns at up to about 1 rad/s
/// and the drone swings faster.
const INITIAL_RATE_SIGMA_RAD_S: f64 = 1.5;

impl AngleFilter {
    /// A filter that has seen nothing.
    pub const fn new() -> Self {
        Self {
            angle_rad: 0.0,
            rate_rad_s: 0.0,
            covariance: Matrix2::new(0.0, 0.0, 0.0, 0.0),
            started: false,
        }
    }

    /// Advances by `dt_s` (≥ 0) with angular-acceleration density `q` (rad²/s³).
    pub fn predict(&mut self, dt_s: f64, q: f64) {
        if !self.started || dt_s <= 0.0 {
            return;
        }
        self.angle_rad = wrap_pi(self.angle_rad + self.rate_rad_s * dt_s);
        let f = Matrix2::new(1.0, dt_s, 0.0, 1.0);
        let dt2 = dt_s * dt_s;
        let noise = Matrix2::new(dt2 * dt_s / 3.0, dt2 / 2.0, dt2 / 2.0, dt_s) * q;
        self.covariance = f * self.covariance * f.transpose() + noise;
    }

    /// Restarts at `measured_rad` with variance `r` and an unknown rate.
    fn reset(&mut self, measured_rad: f64, r: f64) {
        self.angle_rad = wrap_pi(measured_rad);
        self.rate_rad_s = 0.0;
        self.covariance = Matrix2::new(r, 0.0, 0.0, INITIAL_RATE_SIGMA_RAD_S.powi(2));
        self.started = true;
    }

    /// Feeds a measured angle with variance `r` (rad²), keeping the rate within
    /// `max_rate_rad_s`. Returns true if this measurement started the filter.
    pub fn update(&mut self, measured_rad: f64, r: f64, max_rate_rad_s: f64) -> bool {
        if !self.started {
            self.reset(measured_rad, r);
            return true;
        }
        let innovation = wrap_pi(measured_rad - self.angle_rad);
        let p = self.covariance;
        let s = p[(0, 0)] + r;
        let gain = Vector2::new(p[(0, 0)], p[(1, 0)]) / s;
        self.angle_rad = wrap_pi(self.angle_rad + gain.x * innovation);
        self.rate_rad_s =
            (self.rate_rad_s + gain.y * innovation).clamp(-max_rate_rad_s, max_rate_rad_s);
        // (I − K H) P with H = [1 0], symmetrised against rounding.
        let updated = p - gain * Vector2::new(p[(0, 0)], p[(0, 1)]).transpose();
        self.covariance = (updated + updated.transpose()) * 0.5;
        false
    }

    /// 1-σ of the angle, rad (∞ before the first measurement).
    pub fn angle_sigma_rad(&self) -> f64 {
        if self.started {
            self.covariance[(0, 0)].max(0.0).sqrt()
        } else {
            f64::INFINITY
        }
    }

    /// 1-σ of the rate, rad/s (∞ before the first measurement).
    pub fn rate_sigma_rad_s(&self) -> f64 {
        if self.started {
            self.covariance[(1, 1)].max(0.0).sqrt()
        } else {
            f64::INFINITY
        }
    }

    /// Variance of the angle, rad² (0 before the first measurement: callers check `started`).
    pub fn angle_variance(&self) -> f64 {
        self.covariance[(0, 0)].max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn follows_a_constant_rate_through_the_wrap_and_learns_the_rate() {
        let mut f = AngleFilter::new();
        let rate = 0.8;
        let dt = 0.25;
        // Start at 170°, turning right: crosses +180° → −180° after 0.22 s.
        let start = 170f64.to_radians();
        let r = 1e-4;
        for k in 0..80 {
            let t = k as f64 * dt;
            if k > 0 {
                f.predict(dt, 1.0);
            }
            f.update(wrap_pi(start + rate * t), r, 3.0);
            let truth = wrap_pi(start + rate * t);
            if k > 8 {
                assert!(
                    wrap_pi(f.angle_rad - truth).abs() < 0.02,
                    "step {k}: {} vs {truth}",
                    f.angle_rad
                );
                assert!((f.rate_rad_s - rate).abs() < 0.05, "rate {}", f.rate_rad_s);
            }
            assert!(f.angle_rad > -PI && f.angle_rad <= PI);
        }
    }

    #[test]
    fn a_noisy_swing_does_not_lock_the_rate_onto_an_alias() {
        // A heading that jumps by nearly ±180° between samples looks, to a wrapped filter,
        // like a rate of about ±12.6 rad/s; the limit keeps the rate physical and the filter
        // returns to the true heading once the jumps stop.
        let mut f = AngleFilter::new();
        let r = 1e-3;
        for k in 0..40 {
            f.predict(0.25, 4.0);
            let jump = if k % 2 == 0 { 3.0 } else { -0.1 };
            f.update(jump, r, 3.0);
            assert!(f.rate_rad_s.abs() <= 3.0);
        }
        for _ in 0..40 {
            f.predict(0.25, 4.0);
            f.update(1.0, r, 3.0);
        }
        assert!((f.angle_rad - 1.0).abs() < 0.01, "angle {}", f.angle_rad);
        assert!(f.rate_rad_s.abs() < 0.05, "rate {}", f.rate_rad_s);
    }
}
