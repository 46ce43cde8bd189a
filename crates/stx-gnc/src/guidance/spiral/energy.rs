//! The spiral's energy sums: planning speeds over the ground, the height a turn costs, the
//! height needed to turn base and glide in (the seed's H3), and the height a loop takes.

use super::config::SpiralConfig;
use crate::performance::GlidePerformance;

/// Speeds, rates and losses planned with at one update.
#[derive(Debug, Clone, Copy)]
pub(super) struct Energy {
    /// Measured wind along the pattern's axis (downwind positive: the final's headwind), m/s.
    pub(super) wind_along_mps: f64,
    /// The same with the planning margin added (more headwind than measured), m/s.
    pub(super) wind_along_planned_mps: f64,
    /// Horizontal airspeed with the brakes released, m/s.
    pub(super) v0: f64,
    /// Sink rate with the brakes released, m/s.
    pub(super) s0: f64,
    /// Sink rate with the brakes at their trim, m/s.
    st: f64,
    /// Turn rate the corners are planned with, rad/s.
    pub(super) turn_rate_rad_s: f64,
    /// Height a 90° corner costs beyond straight flight, m.
    turn_loss: f64,
    /// Ground speeds downwind, upwind (brakes released, and at trim) and across, m/s.
    g_down: f64,
    g_up0: f64,
    g_up_t: f64,
    pub(super) g_cross: f64,
    /// Distance before a corner at which the next branch is started (the turn radius), m.
    pub(super) turn_distance: f64,
    hang_height_m: f64,
    final_margin_m: f64,
    min_final_m: f64,
}

impl Energy {
    /// The sums for a wind of `wind_along_mps` along the axis, air of `density` kg/m³, the
    /// brakes' trim `brake_trim` and corners at `turn_rate_rad_s`.
    pub(super) fn plan(
        sc: &SpiralConfig,
        perf: &GlidePerformance,
        brake_trim: f64,
        density: f64,
        wind_along_mps: f64,
        turn_rate_rad_s: f64,
    ) -> Self {
        let w_along_measured = wind_along_mps;
        // Plan for a little more headwind than measured: arriving high is corrected by the
        // brakes, arriving low only by releasing them, which buys much less.
        let w_along = w_along_measured
            + sc.wind_margin_fraction * w_along_measured.abs()
            + sc.wind_margin_mps;
        let r = turn_rate_rad_s;
        let v0 = perf.horizontal_airspeed(0.0, density);
        let vt = perf.horizontal_airspeed(brake_trim, density);
        let s0 = perf.sink_rate(0.0, 0.0, density);
        let st = perf.sink_rate(brake_trim, 0.0, density);
        let turn_loss = std::f64::consts::FRAC_PI_2 / r * perf.sink_rate(0.0, r, density)
            - std::f64::consts::FRAC_PI_2 / r * s0;
        Self {
            wind_along_mps,
            wind_along_planned_mps: w_along,
            v0,
            s0,
            st,
            turn_rate_rad_s,
            turn_loss,
            g_down: v0 + w_along,
            g_up0: (v0 - w_along).max(0.3),
            g_up_t: (vt - w_along).max(0.3),
            g_cross: (v0 * v0 - w_along * w_along).max(0.09).sqrt(),
            turn_distance: perf.turn_radius_m(r, 0.0, density),
            hang_height_m: sc.hang_height_m,
            final_margin_m: sc.final_margin_m,
            min_final_m: sc.min_final_m,
        }
    }

    /// Height needed to turn base at `x_base` (m downwind of the target) from a downwind leg
    /// `lateral` m off the final line, and glide in, m.
    pub(super) fn needed_from(&self, x_base: f64, lateral: f64) -> f64 {
        self.hang_height_m
            + self.s0 * lateral.abs() / self.g_cross
            + self.st * x_base.max(0.0) / self.g_up_t
            + 2.0 * self.turn_loss
            + self.final_margin_m
    }

    /// Height needed to go for the final from (x, y) with no more pattern, m: downwind to the
    /// shortest final if upwind of it, across to the final line, then the final glide.
    pub(super) fn needed_direct(&self, x: f64, y: f64) -> f64 {
        let x_entry = x.max(self.min_final_m);
        self.needed_from(x_entry, y) + self.s0 * (x_entry - x) / self.g_down
    }

    /// Height one loop of a pattern `2ax` × `2ay` takes, m.
    pub(super) fn loop_loss(&self, ax: f64, ay: f64) -> f64 {
        self.s0 * (2.0 * ay / self.g_cross * 2.0 + 2.0 * ax / self.g_up0 + 2.0 * ax / self.g_down)
            + 4.0 * self.turn_loss
    }
}
