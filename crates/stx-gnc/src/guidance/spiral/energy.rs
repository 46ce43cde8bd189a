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
    /// Horizontal airspeed with the brakes at their trim, m/s.
    vt: f64,
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
            vt,
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

    /// Ground speed flying straight towards `(dx, dy)` (wind frame) with the brakes released
    /// in a wind of `w` m/s along the axis, m/s.
    fn ground_speed_towards(&self, dx: f64, dy: f64, w: f64) -> f64 {
        let d = dx.hypot(dy);
        // The air velocity plus the wind lies along the way: g² − 2g(w·d) + w² = v0².
        let along = if d < 1e-9 { 0.0 } else { w * dx / d };
        (along + (along * along - w * w + self.v0 * self.v0).max(0.0).sqrt()).max(0.3)
    }

    /// Height needed to fly straight from (x, y) to the final line at `join_x` (m downwind
    /// of the target) and glide in from there, with `extra_headwind_mps` more wind than
    /// planned, m.
    pub(super) fn needed_via(&self, x: f64, y: f64, join_x: f64, extra_headwind_mps: f64) -> f64 {
        let w = self.wind_along_planned_mps + extra_headwind_mps;
        let (dx, dy) = (join_x - x, -y);
        self.hang_height_m
            + self.s0 * dx.hypot(dy) / self.ground_speed_towards(dx, dy, w)
            + self.st * join_x.max(0.0) / (self.vt - w).max(0.3)
            + 2.0 * self.turn_loss
            + self.final_margin_m
    }

    /// Where a base leg from (x, y) should meet the final line, m downwind of the target,
    /// with `height` m of height: straight across (`x`) if the height covers it even with
    /// `extra_headwind_mps` more wind than planned; else the longest final it covers flown
    /// to diagonally, or, if none, the one needing least.
    ///
    /// Into a strong headwind a base leg straight across gains nothing upwind while the
    /// height goes, and the final's glide over the ground, airspeed less headwind, is most
    /// sensitive to the wind's error: 4 m/s against a 6 m/s airspeed, across and then up a
    /// 290 m final took about 100 m more height than the diagonal to a short final, and the
    /// final fell 33 m short (seed 2, run 131).
    pub(super) fn base_join_x(&self, x: f64, y: f64, height: f64, extra_headwind_mps: f64) -> f64 {
        const STEPS: usize = 40;
        let shortest = self.min_final_m.min(x);
        let mut cheapest = (x, f64::INFINITY);
        for k in 0..=STEPS {
            let join_x = x - (x - shortest) * k as f64 / STEPS as f64;
            let needed = self.needed_via(x, y, join_x, extra_headwind_mps);
            if needed <= height {
                return join_x;
            }
            if needed < cheapest.1 {
                cheapest = (join_x, needed);
            }
        }
        cheapest.0
    }

    /// Height one loop of a pattern `2ax` × `2ay` takes, m.
    pub(super) fn loop_loss(&self, ax: f64, ay: f64) -> f64 {
        self.s0 * (2.0 * ay / self.g_cross * 2.0 + 2.0 * ax / self.g_up0 + 2.0 * ax / self.g_down)
            + 4.0 * self.turn_loss
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sums of the default canopy at sea level into a 4 m/s headwind on the final.
    fn into_a_strong_headwind() -> Energy {
        let perf = GlidePerformance::default();
        Energy::plan(
            &SpiralConfig::default(),
            &perf,
            0.5,
            perf.reference_density_kg_per_m3,
            4.0,
            0.3,
        )
    }

    #[test]
    fn a_base_leg_goes_straight_across_when_its_height_covers_the_whole_final() {
        let e = into_a_strong_headwind();
        let (x, y) = (250.0, 60.0);
        let across = e.needed_via(x, y, x, WIND_MARGIN);
        assert_eq!(e.base_join_x(x, y, across + 1.0, WIND_MARGIN), x);
    }

    #[test]
    fn a_base_leg_too_low_for_the_whole_final_joins_a_shorter_one_diagonally() {
        let e = into_a_strong_headwind();
        let (x, y) = (250.0, 60.0);
        let across = e.needed_via(x, y, x, WIND_MARGIN);
        // Into the wind the diagonal to a short final costs less height than across and up.
        let shortest = e.needed_via(x, y, e.min_final_m, WIND_MARGIN);
        assert!(shortest < across - 10.0, "{shortest} vs {across}");
        let height = 0.5 * (shortest + across);
        let join = e.base_join_x(x, y, height, WIND_MARGIN);
        assert!(join < x && join >= e.min_final_m, "{join}");
        // The longest final the height reaches: its need is within the height, and a final
        // a step (5 m) longer would need more.
        assert!(e.needed_via(x, y, join, WIND_MARGIN) <= height);
        assert!(e.needed_via(x, y, join + 6.0, WIND_MARGIN) > height);
        // With no final in reach the cheapest is taken.
        let lowest = e.base_join_x(x, y, 0.0, WIND_MARGIN);
        let cheapest = e.needed_via(x, y, lowest, WIND_MARGIN);
        assert!(cheapest <= shortest + 1e-9 && cheapest <= across);
    }

    #[test]
    fn a_stronger_headwind_than_planned_needs_more_height_for_the_same_final() {
        let e = into_a_strong_headwind();
        assert!(e.needed_via(250.0, 60.0, 150.0, 0.3) > e.needed_via(250.0, 60.0, 150.0, 0.0));
    }

    const WIND_MARGIN: f64 = 0.3;
}
