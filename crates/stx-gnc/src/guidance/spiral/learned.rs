//! What guidance learns in flight of how this stack glides: its horizontal airspeed and sink
//! rate against the polar it was given, so that every plan (reach, pattern, final) is made
//! with the glide the real canopy flies, not the model's.
//!
//! A real canopy differs from any model by 10–30 % in its coefficients; a 20 % smaller lift
//! slope turns a 1.7 m landing into 19 m when guidance plans with the model's polar. Two scale
//! factors are learned, one on the polar's horizontal airspeed and one on its sink rate (the
//! shape of the polar over the brake is kept), from straight flight with the brakes held:
//! airspeed as the estimator's ground velocity less its wind, sink as its sink rate. Measured
//! this way the airspeed carries the wind estimate's error along the track, which is what
//! planning over the ground needs: flown into the wind, speed over the ground is then what
//! the learned airspeed less the estimated wind predicts.

use crate::estimate::Estimate;
use crate::performance::{BRAKE_POINTS, GlidePerformance};

/// Time constant of the learned scales once settled, s: long against gusts, short against a
/// descent of several minutes.
const LEARN_TIME_S: f64 = 30.0;
/// The brakes must have been held this long for a sample to count, s (servo and canopy
/// transients take about 2 s).
const BRAKE_SETTLE_S: f64 = 4.0;
/// A brake change smaller than this counts as held.
const BRAKE_HELD: f64 = 0.02;
/// Heading rate above which the flight is a turn, not a glide, rad/s.
const MAX_TURN_RAD_S: f64 = 0.1;
/// Sink rate below which nothing is learned (a flare, a thermal), m/s.
const MIN_SINK_MPS: f64 = 1.0;
/// Samples whose ratio to the polar is outside these bounds are not learned from.
const SCALE_LIMITS: [f64; 2] = [0.6, 1.6];

/// The learned scales and what learning them needs to remember.
#[derive(Debug, Clone, Copy)]
pub struct LearnedGlide {
    /// Horizontal airspeed flown over the polar's.
    pub airspeed_scale: f64,
    /// Sink rate flown over the polar's.
    pub sink_scale: f64,
    /// Seconds of straight, steady flight learned from.
    pub learned_s: f64,
    last_time_s: Option<f64>,
    held_brake: f64,
    held_since_s: f64,
}

impl Default for LearnedGlide {
    fn default() -> Self {
        Self {
            airspeed_scale: 1.0,
            sink_scale: 1.0,
            learned_s: 0.0,
            last_time_s: None,
            held_brake: f64::NAN,
            held_since_s: 0.0,
        }
    }
}

impl LearnedGlide {
    /// Learns from `est`, the brakes having been at `brake` (symmetric part) since the last
    /// update, in air of `density` kg/m³, against the polar `perf`.
    pub fn update(&mut self, perf: &GlidePerformance, est: &Estimate, brake: f64, density: f64) {
        let now = est.time_s;
        let dt = match self.last_time_s.replace(now) {
            Some(t) => (now - t).max(0.0),
            None => 0.0,
        };
        // A NaN brake (none held yet) counts as a change.
        let held = (brake - self.held_brake).abs() < BRAKE_HELD;
        if !held {
            self.held_brake = brake;
            self.held_since_s = now;
        }
        let steady = now - self.held_since_s >= BRAKE_SETTLE_S
            && est.heading_rate_rad_s.abs() < MAX_TURN_RAD_S
            && est.sink_rate_mps > MIN_SINK_MPS
            && est.gps_ok
            && dt > 0.0;
        if !steady {
            return;
        }
        let air = est.velocity_ned_mps - est.wind_ned_mps;
        let airspeed = air.x.hypot(air.y);
        let polar_airspeed = perf.horizontal_airspeed(brake, density);
        let polar_sink = perf.sink_rate(brake, 0.0, density);
        if !(airspeed.is_finite() && polar_airspeed > 0.1 && polar_sink > 0.1) {
            return;
        }
        let [lo, hi] = SCALE_LIMITS;
        let (airspeed_ratio, sink_ratio) =
            (airspeed / polar_airspeed, est.sink_rate_mps / polar_sink);
        // A sample no canopy of this kind could fly is a wrong estimate (a wind estimate far
        // off, a GPS jump), not something to learn.
        if !((lo..=hi).contains(&airspeed_ratio) && (lo..=hi).contains(&sink_ratio)) {
            return;
        }
        // A plain average at first, then a moving one.
        let gain = dt / (self.learned_s + dt).min(LEARN_TIME_S);
        self.airspeed_scale += gain * (airspeed_ratio - self.airspeed_scale);
        self.sink_scale += gain * (sink_ratio - self.sink_scale);
        self.learned_s += dt;
    }

    /// The polar `perf` with the learned scales: horizontal airspeed and sink rate scaled at
    /// every brake setting.
    pub fn performance(&self, perf: &GlidePerformance) -> GlidePerformance {
        if self.learned_s == 0.0 {
            return *perf;
        }
        let (airspeed_scale, sink_scale) = (self.airspeed_scale, self.sink_scale);
        let mut learned = *perf;
        for k in 0..BRAKE_POINTS {
            let (v, s) = (perf.airspeed_mps[k], perf.sink_rate_mps[k]);
            let horizontal = (v * v - s * s).max(0.0).sqrt() * airspeed_scale;
            let sink = s * sink_scale;
            learned.airspeed_mps[k] = horizontal.hypot(sink);
            learned.sink_rate_mps[k] = sink;
        }
        learned
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;

    use super::*;
    use crate::pointmass::{Conditions, PointMass};
    use stx_dynamics::state::Controls;

    /// A point mass sinking `sink_scale` times the polar's flown for `seconds` with the brakes
    /// at `brake` (turning if `turning`) in a 3 m/s wind; what was learned.
    fn learn(sink_scale: f64, brake: f64, turning: bool, seconds: usize) -> LearnedGlide {
        let perf = GlidePerformance::default();
        let wind = Vector3::new(-3.0, 1.0, 0.0);
        let air = Conditions {
            sink_scale,
            ..Conditions::nominal(wind, perf.reference_density_kg_per_m3)
        };
        let mut stack = PointMass::new(0.0, Vector3::new(0.0, 0.0, -800.0), 0.3);
        let controls = Controls {
            main_line_m: if turning { 0.02 } else { 0.0 },
            brake_right: brake,
            brake_left: brake,
        };
        let mut learned = LearnedGlide::default();
        for _ in 0..seconds * 4 {
            for _ in 0..5 {
                stack.step(&perf, &controls, &air, 0.05);
            }
            let est = stack.estimate(&wind);
            learned.update(&perf, &est, brake, air.density_kg_per_m3);
        }
        learned
    }

    #[test]
    fn a_stack_that_sinks_faster_than_its_polar_is_learned_in_straight_flight() {
        let nominal = learn(1.0, 0.0, false, 60);
        assert!((nominal.sink_scale - 1.0).abs() < 0.01, "{nominal:?}");
        assert!((nominal.airspeed_scale - 1.0).abs() < 0.01, "{nominal:?}");
        let heavy = learn(1.2, 0.4, false, 60);
        assert!((heavy.sink_scale - 1.2).abs() < 0.01, "{heavy:?}");
        let perf = GlidePerformance::default();
        let rho = perf.reference_density_kg_per_m3;
        let learned = heavy.performance(&perf);
        let planned = learned.sink_rate(0.4, 0.0, rho) / perf.sink_rate(0.4, 0.0, rho);
        assert!((planned - heavy.sink_scale).abs() < 1e-9, "{planned}");
        let planned = learned.horizontal_airspeed(0.0, rho) / perf.horizontal_airspeed(0.0, rho);
        assert!((planned - heavy.airspeed_scale).abs() < 1e-9, "{planned}");
    }

    #[test]
    fn nothing_is_learned_in_turns_or_before_the_brakes_settle() {
        let turning = learn(1.2, 0.0, true, 60);
        assert_eq!(turning.learned_s, 0.0, "{turning:?}");
        let brief = learn(1.2, 0.0, false, 3);
        assert_eq!(brief.learned_s, 0.0, "{brief:?}");
        let perf = GlidePerformance::default();
        assert_eq!(brief.performance(&perf), perf);
    }
}
