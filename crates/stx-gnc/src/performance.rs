//! What guidance and the landing predictor assume about how the parafoil flies: airspeed and
//! sink rate against brake and density, and how fast it turns for a main-line command. A
//! point-mass summary of the 14-DOF model, measured from it (the values below are checked
//! against the model by `crates/stx-sim/tests/sim/performance_matches_model.rs`).
//!
//! The steady glide is a table over the brake setting because it is far from linear in it:
//! the first fifth of brake costs as much airspeed as the last two fifths, and in a headwind
//! close to the airspeed a straight line between the ends mispredicts the glide over the ground
//! by 10 %.

use serde::{Deserialize, Serialize};

/// Number of brake settings in the steady-glide table.
pub const BRAKE_POINTS: usize = 6;

/// Steady flight of the parafoil, reduced to a few numbers.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GlidePerformance {
    /// Air density the speeds below are given at, kg/m³.
    pub reference_density_kg_per_m3: f64,
    /// Symmetric brake settings the table below is given at, 0…1, increasing.
    pub brake_points: [f64; BRAKE_POINTS],
    /// Steady true airspeed at each brake setting, m/s.
    pub airspeed_mps: [f64; BRAKE_POINTS],
    /// Steady sink rate at each brake setting, m/s.
    pub sink_rate_mps: [f64; BRAKE_POINTS],
    /// Steady turn rate with the main line fully over, rad/s.
    pub max_turn_rate_rad_s: f64,
    /// Main-line command that gives tanh(1) ≈ 76 % of the maximum turn rate, m.
    pub turn_main_line_scale_m: f64,
    /// Time constant of the turn rate's response to the main line, s.
    pub turn_time_constant_s: f64,
    /// Extra sink in a steady turn per (rad/s)² of turn rate, m/s per (rad/s)².
    pub turn_sink_mps_per_rad2_s2: f64,
}

impl Default for GlidePerformance {
    /// The STRAPLEX stack as the 14-DOF model flies it 100 m above sea level (steady glides
    /// measured with `stx sim`; pinned by the test named in the module doc).
    fn default() -> Self {
        Self {
            reference_density_kg_per_m3: 1.2133,
            brake_points: [0.0, 0.2, 0.4, 0.6, 0.8, 1.0],
            airspeed_mps: [6.703, 6.253, 5.919, 5.654, 5.436, 5.251],
            sink_rate_mps: [2.948, 2.815, 2.735, 2.679, 2.636, 2.602],
            max_turn_rate_rad_s: 0.85,
            turn_main_line_scale_m: 0.011,
            turn_time_constant_s: 1.5,
            turn_sink_mps_per_rad2_s2: 5.3,
        }
    }
}

impl GlidePerformance {
    fn density_scale(&self, density_kg_per_m3: f64) -> f64 {
        // Same lift coefficient in thinner air needs V ∝ 1/√ρ; sink scales alike.
        (self.reference_density_kg_per_m3 / density_kg_per_m3.max(1e-6)).sqrt()
    }

    /// A table value at `brake`, interpolated linearly and held beyond the table's ends.
    fn at_brake(&self, table: &[f64; BRAKE_POINTS], brake: f64) -> f64 {
        let points = &self.brake_points;
        // NaN, and anything at or below the first point, read the first entry.
        if brake.is_nan() || brake <= points[0] {
            return table[0];
        }
        for k in 1..BRAKE_POINTS {
            if brake <= points[k] {
                let f = (brake - points[k - 1]) / (points[k] - points[k - 1]);
                return table[k - 1] + f * (table[k] - table[k - 1]);
            }
        }
        table[BRAKE_POINTS - 1]
    }

    /// True airspeed at symmetric brake `brake` (0…1) and density, m/s.
    pub fn airspeed(&self, brake: f64, density_kg_per_m3: f64) -> f64 {
        self.at_brake(&self.airspeed_mps, brake) * self.density_scale(density_kg_per_m3)
    }

    /// Sink rate at symmetric brake, turn rate and density, m/s.
    pub fn sink_rate(&self, brake: f64, turn_rate_rad_s: f64, density_kg_per_m3: f64) -> f64 {
        let straight = self.at_brake(&self.sink_rate_mps, brake);
        (straight + self.turn_sink_mps_per_rad2_s2 * turn_rate_rad_s * turn_rate_rad_s)
            * self.density_scale(density_kg_per_m3)
    }

    /// Horizontal airspeed in straight flight, m/s.
    pub fn horizontal_airspeed(&self, brake: f64, density_kg_per_m3: f64) -> f64 {
        let v = self.airspeed(brake, density_kg_per_m3);
        let s = self.sink_rate(brake, 0.0, density_kg_per_m3);
        (v * v - s * s).max(0.0).sqrt()
    }

    /// Glide over the ground (distance per height) flying straight into a headwind
    /// `headwind_mps` at symmetric brake `brake`; negative when blown backwards.
    pub fn ground_glide(&self, brake: f64, headwind_mps: f64, density_kg_per_m3: f64) -> f64 {
        self.course_glide(brake, headwind_mps, 0.0, density_kg_per_m3)
    }

    /// Glide over the ground along a course with `headwind_mps` along it and `crosswind_mps`
    /// across it: the canopy crabs into the crosswind, so only the rest of its airspeed
    /// carries it along the course (none when the crosswind is as strong as the airspeed).
    pub fn course_glide(
        &self,
        brake: f64,
        headwind_mps: f64,
        crosswind_mps: f64,
        density_kg_per_m3: f64,
    ) -> f64 {
        let airspeed = self.horizontal_airspeed(brake, density_kg_per_m3);
        let along = (airspeed * airspeed - crosswind_mps * crosswind_mps)
            .max(0.0)
            .sqrt();
        (along - headwind_mps) / self.sink_rate(brake, 0.0, density_kg_per_m3)
    }

    /// The symmetric brake that makes the ground glide into `headwind_mps` equal
    /// `wanted_glide`, clamped to 0…1 (0 when even released brakes glide too short, 1 when even
    /// full brakes glide too far).
    pub fn brake_for_ground_glide(
        &self,
        wanted_glide: f64,
        headwind_mps: f64,
        density_kg_per_m3: f64,
    ) -> f64 {
        self.brake_for_course_glide(wanted_glide, headwind_mps, 0.0, density_kg_per_m3)
    }

    /// [`Self::brake_for_ground_glide`] along a course with a crosswind as well. The glide
    /// falls monotonically with brake (less airspeed, more sink, and a larger share of the
    /// airspeed spent crabbing), so a bisection is exact to its tolerance.
    pub fn brake_for_course_glide(
        &self,
        wanted_glide: f64,
        headwind_mps: f64,
        crosswind_mps: f64,
        density_kg_per_m3: f64,
    ) -> f64 {
        let glide = |b: f64| self.course_glide(b, headwind_mps, crosswind_mps, density_kg_per_m3);
        if wanted_glide >= glide(0.0) {
            return 0.0;
        }
        if wanted_glide <= glide(1.0) {
            return 1.0;
        }
        let (mut low, mut high) = (0.0, 1.0);
        for _ in 0..30 {
            let mid = 0.5 * (low + high);
            if glide(mid) > wanted_glide {
                low = mid;
            } else {
                high = mid;
            }
        }
        0.5 * (low + high)
    }

    /// Steady turn rate for a main-line command, rad/s (positive right).
    pub fn turn_rate(&self, main_line_m: f64) -> f64 {
        self.max_turn_rate_rad_s * (main_line_m / self.turn_main_line_scale_m).tanh()
    }

    /// Radius of a turn at the given rate in straight-flight airspeed, m.
    pub fn turn_radius_m(&self, turn_rate_rad_s: f64, brake: f64, density_kg_per_m3: f64) -> f64 {
        self.horizontal_airspeed(brake, density_kg_per_m3) / turn_rate_rad_s.abs().max(1e-3)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_crosswind_takes_the_airspeed_the_crab_needs_from_the_glide_along_the_course() {
        let perf = GlidePerformance::default();
        let rho = perf.reference_density_kg_per_m3;
        let va = perf.horizontal_airspeed(0.0, rho);
        let sink = perf.sink_rate(0.0, 0.0, rho);
        // 3-4-5: a crosswind of 0.6 of the airspeed leaves 0.8 of it along the course.
        let glide = perf.course_glide(0.0, 1.0, 0.6 * va, rho);
        assert!((glide - (0.8 * va - 1.0) / sink).abs() < 1e-12, "{glide}");
        assert_eq!(
            perf.course_glide(0.3, 2.0, 0.0, rho),
            perf.ground_glide(0.3, 2.0, rho)
        );
        // A crosswind as strong as the airspeed: nothing along the course.
        assert!((perf.course_glide(0.0, 0.0, 2.0 * va, rho)).abs() < 1e-12);
        // The same glide wanted across a crosswind needs less brake.
        let wanted = 0.6 * perf.ground_glide(0.0, 2.0, rho);
        let straight = perf.brake_for_ground_glide(wanted, 2.0, rho);
        let crossed = perf.brake_for_course_glide(wanted, 2.0, 3.0, rho);
        assert!(crossed < straight - 0.05, "{crossed} against {straight}");
        let achieved = perf.course_glide(crossed, 2.0, 3.0, rho);
        assert!(
            (achieved - wanted).abs() < 1e-6,
            "{achieved} against {wanted}"
        );
    }

    #[test]
    fn brakes_slow_and_steepen_and_thin_air_speeds_up() {
        let p = GlidePerformance::default();
        let glide = |b: f64| p.horizontal_airspeed(b, 1.225) / p.sink_rate(b, 0.0, 1.225);
        assert!(glide(1.0) < glide(0.5) && glide(0.5) < glide(0.0));
        assert!((glide(0.0) - 2.04).abs() < 0.03, "{}", glide(0.0));
        assert!((p.airspeed(0.3, 1.2133) - 0.5 * (6.253 + 5.919)).abs() < 1e-12);
        assert_eq!(p.airspeed(-1.0, 1.2133), 6.703);
        assert_eq!(p.airspeed(2.0, 1.2133), 5.251);
        assert!(p.airspeed(0.0, 0.3) > 1.9 * p.airspeed(0.0, 1.225));
        assert!(p.sink_rate(0.0, 0.5, 1.225) > p.sink_rate(0.0, 0.0, 1.225));
        assert!(p.turn_rate(1.0).abs() <= p.max_turn_rate_rad_s);
        // The brake that gives a glide between the extremes reproduces it.
        for headwind in [0.0, 2.0, 4.0] {
            let wanted =
                0.5 * (p.ground_glide(0.0, headwind, 1.1) + p.ground_glide(1.0, headwind, 1.1));
            let b = p.brake_for_ground_glide(wanted, headwind, 1.1);
            assert!((p.ground_glide(b, headwind, 1.1) - wanted).abs() < 1e-6);
            assert_eq!(p.brake_for_ground_glide(100.0, headwind, 1.1), 0.0);
            assert_eq!(p.brake_for_ground_glide(-100.0, headwind, 1.1), 1.0);
        }
        assert!(p.turn_rate(-0.005) < 0.0);
    }
}
