//! The straight-flight pseudo-measurement: a weathervaning drone's air velocity lies along its
//! true heading, give or take its swing and a slowly varying sideslip offset, which gives the
//! cross-wind from a single heading once the flight has been straight for a while.

use nalgebra::{SMatrix, Vector2};

use super::angle::AngleFilter;
use super::config::Tuning;
use super::ekf::{MIN_SPEED_FOR_DIRECTION_MPS, N, Nav, ix};

/// Since when the flight has been straight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct StraightFlight {
    /// s; +∞ while turning.
    since_s: f64,
}

impl StraightFlight {
    pub(super) const fn new() -> Self {
        Self {
            since_s: f64::INFINITY,
        }
    }

    /// In straight flight the drone weathervanes: the horizontal air velocity lies along its
    /// true heading `ψ − δψ` (the AHRS's heading less its bias), give or take its swing and a
    /// slowly varying offset `β₀`. That pseudo-measurement,
    /// `0 = e_y·a_h − |a_h|·β₀` with `e_y = [−sin(ψ − δψ), cos(ψ − δψ)]`, gives the cross-wind
    /// from a single heading. Turns (and the swing after them) break it, so it is used only
    /// after the flight has been straight for a while.
    ///
    /// It sees `β₀` and `δψ` only as their difference (`∂/∂δψ = e_x·a_h ≈ |a_h| = −∂/∂β₀`):
    /// in straight flight the GPS learns where the air comes from relative to the AHRS's
    /// heading, not how much of that is the magnetometer and how much the drone's trim. The
    /// bias alone is learnt through the pitot in the swing and in turns (`pitot.rs`); the
    /// split in between follows the two priors, a tight one on `β₀` (the simulated drone's
    /// straight-flight sideslip is within a degree or so of zero) and a wide one on the bias.
    pub(super) fn update(&mut self, nav: &mut Nav, yaw: &AngleFilter, time_s: f64, t: &Tuning) {
        let straight = nav.x[ix::TURN].abs() < t.straight_turn_rate_rad_s
            && yaw.rate_rad_s.abs() < t.straight_yaw_rate_rad_s;
        if !straight {
            self.since_s = f64::INFINITY;
            return;
        }
        self.since_s = self.since_s.min(time_s);
        if time_s - self.since_s < t.straight_settle_s {
            return;
        }
        let air_h = Vector2::new(nav.x[ix::AIR], nav.x[ix::AIR + 1]);
        let speed_h = air_h.norm();
        if speed_h < t.pitot_min_airspeed_mps.max(MIN_SPEED_FOR_DIRECTION_MPS) {
            return;
        }
        let (s, c) = (yaw.angle_rad - nav.x[ix::HEADING_BIAS]).sin_cos();
        let e_y = Vector2::new(-s, c);
        let beta = nav.x[ix::SIDESLIP];
        let predicted = e_y.dot(&air_h) - speed_h * beta;
        let mut h = SMatrix::<f64, 1, N>::zeros();
        let d_air = e_y - air_h * (beta / speed_h);
        h[(0, ix::AIR)] = d_air.x;
        h[(0, ix::AIR + 1)] = d_air.y;
        h[(0, ix::SIDESLIP)] = -speed_h;
        // The swing, and the heading's own uncertainty (∂(e_y·a)/∂ψ = −e_x·a, so
        // ∂(e_y·a)/∂δψ = e_x·a).
        let along = Vector2::new(c, s).dot(&air_h);
        h[(0, ix::HEADING_BIAS)] = along;
        let variance = (speed_h * t.straight_sideslip_sigma_rad).powi(2)
            + along * along * yaw.angle_variance();
        let y = SMatrix::<f64, 1, 1>::new(-predicted);
        nav.update(
            &y,
            &h,
            &SMatrix::<f64, 1, 1>::new(variance),
            Some(t.gate_nis[0]),
        );
    }
}
