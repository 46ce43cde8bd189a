//! What guidance learns in flight of how this stack glides: its horizontal airspeed and sink
//! rate against the polar it was given, and how the brakes change them, so that every plan
//! (reach, pattern, final) is made with the glide the real canopy flies, not the model's.
//!
//! A real canopy differs from any model by 10–30 % in its coefficients (more in its brake
//! terms); a 20 % smaller lift slope turns a 1.7 m landing into 19 m when guidance plans with
//! the model's polar. Two scale factors are learned, one on the polar's horizontal airspeed
//! and one on its sink rate, each linear in the brake ([`BrakeScale`]): from straight flight
//! with the brakes held, airspeed as the estimator's ground velocity less its wind, sink as
//! its sink rate. Measured this way the airspeed carries the wind estimate's error along the
//! track, which is what planning over the ground needs: flown into the wind, speed over the
//! ground is then what the learned airspeed less the estimated wind predicts.

use serde::{Deserialize, Serialize};

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
/// Samples whose ratio to the polar is outside these bounds are not learned from, and the
/// learned scales stay within them. Wide enough for the canopies a realistic dispersion draws
/// (lift slope 1-σ 20 %): with [0.6, 1.6] a canopy of half the lift slope (seed 12 runs 698
/// and 793, `--dispersions realistic`) flew outside them all the way down, learned nothing and
/// landed 64–81 m short of a reachable target, in a keep-out zone.
const SCALE_LIMITS: [f64; 2] = [0.4, 2.5];
/// Weight of the prior "as the polar says" (scale 1), in seconds of samples: small, so that
/// the first samples count, but enough to hold the scales before any.
const PRIOR_S: f64 = 0.5;
/// Seconds over which the samples' errors are correlated (the gusts and the wind estimate's
/// wander): a moving sum of `n` seconds holds about `n / CORRELATION_S` independent samples,
/// which the learned scales' 1-σ counts.
pub(crate) const CORRELATION_S: f64 = 4.0;
/// Weight of the prior "the brakes do what the polar says" (no slope of the scale over the
/// brake), in seconds of samples per unit brake squared: a slope is learned only from
/// samples at brake settings well apart, not from the scatter at one setting.
const PRIOR_SLOPE_S: f64 = 0.3;

/// A scale factor linear in the brake, `a + b·(brake − c)` about the samples' mean brake `c`,
/// fitted by least squares to the samples with exponential forgetting, about the prior
/// `a = 1, b = 0`. Flown at one brake setting (most of a flight) it learns `a` there and
/// applies it at every setting; flown at two, it also learns how the brakes differ from the
/// polar. (About the mean brake the two are fitted apart: the slope's prior does not hold
/// back the level learned.)
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct BrakeScale {
    /// Forgotten sums of weight, weight × brake, weight × brake².
    moments: [f64; 3],
    /// Forgotten sums of weight × ratio and weight × brake × ratio.
    rhs: [f64; 2],
    /// Forgotten sum of weight × ratio², for the scatter about the level.
    square: f64,
}

impl BrakeScale {
    /// Adds a sample `ratio` at `brake` of weight `dt`, the earlier ones forgotten by `keep`.
    fn add(&mut self, brake: f64, ratio: f64, dt: f64, keep: f64) {
        let [m0, m1, m2] = self.moments;
        self.moments = [
            keep * m0 + dt,
            keep * m1 + dt * brake,
            keep * m2 + dt * brake * brake,
        ];
        self.rhs = [
            keep * self.rhs[0] + dt * ratio,
            keep * self.rhs[1] + dt * brake * ratio,
        ];
        self.square = keep * self.square + dt * ratio * ratio;
    }

    /// 1-σ of the level learned (at the mean brake flown): the samples' scatter about it over
    /// the square root of the independent samples behind it. `None` before any sample.
    fn sigma(&self) -> Option<f64> {
        let m0 = self.moments[0];
        if m0 <= 0.0 {
            return None;
        }
        let mean = self.rhs[0] / m0;
        let variance = (self.square / m0 - mean * mean).max(0.0);
        Some((variance / (m0 / CORRELATION_S).max(1.0)).sqrt())
    }

    /// The scale at `brake`.
    fn at(&self, brake: f64) -> f64 {
        let [m0, m1, m2] = self.moments;
        let [r0, r1] = self.rhs;
        let mean_brake = if m0 > 0.0 { m1 / m0 } else { 0.0 };
        let level = (r0 + PRIOR_S) / (m0 + PRIOR_S);
        let spread = (m2 - mean_brake * m1).max(0.0);
        let slope = (r1 - mean_brake * r0) / (spread + PRIOR_SLOPE_S);
        (level + slope * (brake - mean_brake)).clamp(SCALE_LIMITS[0], SCALE_LIMITS[1])
    }
}

/// The brake settings [`LearnedPolar`] shows the scales at.
const SHOWN_AT: [f64; 3] = [0.0, 0.5, 1.0];

/// What has been learned of the glide and the turn, at three brake settings: what the
/// operator and the Monte Carlo report are shown.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LearnedPolar {
    /// The brake settings shown, 0…1.
    pub brake: [f64; 3],
    /// Horizontal airspeed flown over the polar's at each.
    pub airspeed_scale: [f64; 3],
    /// Sink rate flown over the polar's at each.
    pub sink_scale: [f64; 3],
    /// 1-σ of the airspeed and sink scales at the mean brake flown (their scatter over the
    /// independent samples behind them); `None` before anything was learned.
    pub airspeed_sigma: Option<f64>,
    /// See `airspeed_sigma`.
    pub sink_sigma: Option<f64>,
    /// Seconds of straight, settled flight the glide was learned from, s.
    pub learned_s: f64,
    /// Turn rate flown over the rate the polar's turn model gives for the same commands.
    pub turn_scale: f64,
    /// 1-σ of the turn factor; `None` before any turn was learned from.
    pub turn_sigma: Option<f64>,
    /// Seconds of turning the turn rate was learned from, s.
    pub turn_learned_s: f64,
}

/// The learned scales and what learning them needs to remember.
#[derive(Debug, Clone, Copy)]
pub struct LearnedGlide {
    /// Horizontal airspeed flown over the polar's.
    airspeed: BrakeScale,
    /// Sink rate flown over the polar's.
    sink: BrakeScale,
    /// Seconds of straight, steady flight learned from.
    pub learned_s: f64,
    last_time_s: Option<f64>,
    held_brake: f64,
    held_since_s: f64,
}

impl Default for LearnedGlide {
    fn default() -> Self {
        Self {
            airspeed: BrakeScale::default(),
            sink: BrakeScale::default(),
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
        let keep = (-dt / LEARN_TIME_S).exp();
        self.airspeed.add(brake, airspeed_ratio, dt, keep);
        self.sink.add(brake, sink_ratio, dt, keep);
        self.learned_s += dt;
    }

    /// The scales learned, at [`SHOWN_AT`]; the turn's fields are left for the turn learner
    /// to fill.
    pub fn polar(&self) -> LearnedPolar {
        LearnedPolar {
            brake: SHOWN_AT,
            airspeed_scale: SHOWN_AT.map(|b| self.airspeed.at(b)),
            sink_scale: SHOWN_AT.map(|b| self.sink.at(b)),
            airspeed_sigma: self.airspeed.sigma(),
            sink_sigma: self.sink.sigma(),
            learned_s: self.learned_s,
            turn_scale: 1.0,
            turn_sigma: None,
            turn_learned_s: 0.0,
        }
    }

    /// Horizontal airspeed flown over the polar's at `brake`.
    #[cfg(test)]
    fn airspeed_scale(&self, brake: f64) -> f64 {
        self.airspeed.at(brake)
    }

    /// Sink rate flown over the polar's at `brake`.
    #[cfg(test)]
    fn sink_scale(&self, brake: f64) -> f64 {
        self.sink.at(brake)
    }

    /// The polar `perf` with the learned scales: horizontal airspeed and sink rate scaled at
    /// every brake setting by the scale learned for it.
    pub fn performance(&self, perf: &GlidePerformance) -> GlidePerformance {
        if self.learned_s == 0.0 {
            return *perf;
        }
        let mut learned = *perf;
        for k in 0..BRAKE_POINTS {
            let brake = perf.brake_points[k];
            let (airspeed_scale, sink_scale) = (self.airspeed.at(brake), self.sink.at(brake));
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
    use stx_types::controls::Controls;

    /// A point mass flying legs of (sink scale against the polar, brake, seconds), turning
    /// if `turning`, in a 3 m/s wind; what was learned.
    fn learn_legs(legs: &[(f64, f64, usize)], turning: bool) -> LearnedGlide {
        let perf = GlidePerformance::default();
        let wind = Vector3::new(-3.0, 1.0, 0.0);
        let mut stack = PointMass::new(0.0, Vector3::new(0.0, 0.0, -800.0), 0.3);
        let mut learned = LearnedGlide::default();
        for &(sink_scale, brake, seconds) in legs {
            let air = Conditions {
                sink_scale,
                ..Conditions::nominal(wind, perf.reference_density_kg_per_m3)
            };
            let controls = Controls {
                main_line_m: if turning { 0.02 } else { 0.0 },
                brake_right: brake,
                brake_left: brake,
            };
            for _ in 0..seconds * 4 {
                for _ in 0..5 {
                    stack.step(&perf, &controls, &air, 0.05);
                }
                let est = stack.estimate(&wind);
                learned.update(&perf, &est, brake, air.density_kg_per_m3);
            }
        }
        learned
    }

    fn learn(sink_scale: f64, brake: f64, turning: bool, seconds: usize) -> LearnedGlide {
        learn_legs(&[(sink_scale, brake, seconds)], turning)
    }

    #[test]
    fn a_stack_that_sinks_faster_than_its_polar_is_learned_in_straight_flight() {
        let nominal = learn(1.0, 0.0, false, 60);
        assert!((nominal.sink_scale(0.0) - 1.0).abs() < 0.01, "{nominal:?}");
        assert!(
            (nominal.airspeed_scale(0.0) - 1.0).abs() < 0.01,
            "{nominal:?}"
        );
        let heavy = learn(1.2, 0.4, false, 60);
        assert!((heavy.sink_scale(0.4) - 1.2).abs() < 0.01, "{heavy:?}");
        // Learned at one brake setting, the others are assumed to scale alike.
        assert!((heavy.sink_scale(0.0) - 1.2).abs() < 0.02, "{heavy:?}");
        let perf = GlidePerformance::default();
        let rho = perf.reference_density_kg_per_m3;
        let learned = heavy.performance(&perf);
        let planned = learned.sink_rate(0.4, 0.0, rho) / perf.sink_rate(0.4, 0.0, rho);
        assert!((planned - heavy.sink_scale(0.4)).abs() < 1e-9, "{planned}");
        let planned = learned.horizontal_airspeed(0.0, rho) / perf.horizontal_airspeed(0.0, rho);
        assert!(
            (planned - heavy.airspeed_scale(0.0)).abs() < 1e-9,
            "{planned}"
        );
    }

    #[test]
    fn a_canopy_far_from_its_polar_is_learned_too() {
        for sink_scale in [0.5, 1.8, 2.2] {
            let learned = learn(sink_scale, 0.0, false, 60);
            assert!(
                (learned.sink_scale(0.0) - sink_scale).abs() < 0.03 * sink_scale,
                "{sink_scale}: {learned:?}"
            );
        }
    }

    #[test]
    fn brakes_that_sink_more_than_the_polar_says_are_learned_from_two_settings() {
        // The polar is right with the brakes released, and 30 % short of the sink at 0.6.
        let learned = learn_legs(&[(1.0, 0.0, 40), (1.3, 0.6, 40)], false);
        assert!((learned.sink_scale(0.0) - 1.0).abs() < 0.05, "{learned:?}");
        assert!((learned.sink_scale(0.6) - 1.3).abs() < 0.03, "{learned:?}");
        // Between and beyond, the line through them.
        assert!((learned.sink_scale(0.3) - 1.15).abs() < 0.04, "{learned:?}");
        let perf = GlidePerformance::default();
        let rho = perf.reference_density_kg_per_m3;
        let planned = learned.performance(&perf).sink_rate(0.6, 0.0, rho);
        assert!((planned / perf.sink_rate(0.6, 0.0, rho) - learned.sink_scale(0.6)).abs() < 1e-9);
        // What the operator is shown: the same line at released, half and full brakes.
        let shown = learned.polar();
        assert_eq!(shown.brake, [0.0, 0.5, 1.0]);
        for k in 0..3 {
            assert_eq!(shown.sink_scale[k], learned.sink_scale(shown.brake[k]));
        }
        assert!(shown.sink_scale[2] > shown.sink_scale[1] && shown.sink_scale[1] > 1.2);
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

    #[test]
    fn the_learned_scales_carry_their_uncertainty_from_the_samples_scatter() {
        // Before anything is learned there is no figure to doubt.
        assert_eq!(learn(1.2, 0.0, true, 30).polar().sink_sigma, None);
        // A steady canopy: samples that agree, a scale known to a fraction of a per cent.
        let steady = learn(1.1, 0.0, false, 64).polar();
        let steady_sigma = steady.sink_sigma.expect("learned");
        assert!(steady_sigma < 0.005, "{steady:?}");
        // Sinking 15 % more and less in turn (a gusty day, one brake setting): the same level
        // learned, but known only to the scatter over the ~16 independent samples behind it,
        // about 0.15 / 4.
        let legs: Vec<_> = (0..8)
            .map(|k| (if k % 2 == 0 { 1.15 } else { 0.85 }, 0.0, 8))
            .collect();
        let gusty = learn_legs(&legs, false).polar();
        let sigma = gusty.sink_sigma.expect("learned");
        assert!((gusty.sink_scale[0] - 1.0).abs() < 0.05, "{gusty:?}");
        assert!((0.02..0.08).contains(&sigma), "{gusty:?}");
        assert!(gusty.airspeed_sigma.is_some());
    }
}
