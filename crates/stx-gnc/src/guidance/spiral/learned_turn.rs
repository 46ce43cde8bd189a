//! What guidance learns in flight of how this stack turns: the turn rate a main-line command
//! gives, against the rate the polar's turn model says, so that corners are planned at the
//! rate the real canopy turns.
//!
//! The polar's turn rate is `max · tanh(main line / scale)`; a canopy whose moment
//! derivatives differ by 20 % turns about that much faster or slower for the same command,
//! and corners planned at the wrong rate start early or late. One factor on the turn rate
//! is learned by least squares between the heading rate measured and the rate the polar
//! predicts for the commands sent, both through the same servo and turn lags: the corners
//! and the course changes of the pattern give it samples every loop. Commands that hardly
//! turn are not used (there the heading rate is mostly the estimator's noise and the air's).

use crate::estimate::Estimate;
use crate::performance::GlidePerformance;

/// Time constant of forgetting, s: several corners.
const LEARN_TIME_S: f64 = 60.0;
/// Servo rate constant the commands pass through, 1/s (the seed's K = 5).
const SERVO_RATE_PER_S: f64 = 5.0;
/// Predicted turn rates below this are not learned from, rad/s (≈ 3°/s).
const MIN_TURN_RAD_S: f64 = 0.05;
/// Samples whose ratio to the prediction is outside these bounds are not learned from, and
/// the learned factor stays within them.
const SCALE_LIMITS: [f64; 2] = [0.5, 2.0];
/// Weight of the prior "as the polar says", in seconds of turning at 0.2 rad/s.
const PRIOR_S: f64 = 1.0;
const PRIOR_RATE_RAD_S: f64 = 0.2;

/// The learned turn-rate factor and the predicted rate it is learned against.
#[derive(Debug, Clone, Copy, Default)]
pub struct LearnedTurn {
    /// Forgotten sums of weight × predicted², weight × predicted × measured.
    sums: [f64; 2],
    /// Forgotten sums of weight and weight × measured², for the scatter about the fit.
    scatter: [f64; 2],
    /// The main line the servo is at in the prediction, m.
    servo_m: f64,
    /// The turn rate the polar predicts now, rad/s.
    predicted_rad_s: f64,
    /// Seconds of turning learned from.
    pub learned_s: f64,
    last_time_s: Option<f64>,
}

impl LearnedTurn {
    /// Learns from `est`, the main line having been commanded to `main_line_m` since the last
    /// update, against the polar `perf`.
    pub fn update(&mut self, perf: &GlidePerformance, est: &Estimate, main_line_m: f64) {
        let now = est.time_s;
        let dt = match self.last_time_s.replace(now) {
            Some(t) => (now - t).max(0.0),
            None => return,
        };
        if dt == 0.0 || !main_line_m.is_finite() {
            return;
        }
        // The prediction through the servo and the canopy's turn lag over the period, in
        // steps short against both.
        let steps = (dt / 0.05).ceil().max(1.0);
        let h = dt / steps;
        let servo = 1.0 - (-SERVO_RATE_PER_S * h).exp();
        let turn = 1.0 - (-h / perf.turn_time_constant_s.max(1e-3)).exp();
        for _ in 0..steps as usize {
            self.servo_m += (main_line_m - self.servo_m) * servo;
            self.predicted_rad_s += (perf.turn_rate(self.servo_m) - self.predicted_rad_s) * turn;
        }
        let (predicted, measured) = (self.predicted_rad_s, est.heading_rate_rad_s);
        if predicted.abs() < MIN_TURN_RAD_S || !measured.is_finite() {
            return;
        }
        let ratio = measured / predicted;
        if !(SCALE_LIMITS[0]..=SCALE_LIMITS[1]).contains(&ratio) {
            return;
        }
        let keep = (-dt / LEARN_TIME_S).exp();
        self.sums = [
            keep * self.sums[0] + dt * predicted * predicted,
            keep * self.sums[1] + dt * predicted * measured,
        ];
        self.scatter = [
            keep * self.scatter[0] + dt,
            keep * self.scatter[1] + dt * measured * measured,
        ];
        self.learned_s += dt;
    }

    /// The turn rate flown over the polar's.
    pub fn scale(&self) -> f64 {
        let prior = PRIOR_S * PRIOR_RATE_RAD_S * PRIOR_RATE_RAD_S;
        ((self.sums[1] + prior) / (self.sums[0] + prior)).clamp(SCALE_LIMITS[0], SCALE_LIMITS[1])
    }

    /// 1-σ of [`scale`](Self::scale): the residual of the fit over the independent samples
    /// behind it (errors correlated over `CORRELATION_S`, as the glide's). `None` before any.
    pub fn sigma(&self) -> Option<f64> {
        let [weight, measured2] = self.scatter;
        let [predicted2, cross] = self.sums;
        if weight <= 0.0 || predicted2 <= 0.0 {
            return None;
        }
        let k = cross / predicted2;
        // Σw·(m − k·p)², per unit weight: the residual turn rate's variance, (rad/s)².
        let residual = ((measured2 - 2.0 * k * cross + k * k * predicted2) / weight).max(0.0);
        let independent = (weight / super::learned::CORRELATION_S).max(1.0);
        Some((residual / (predicted2 / weight * independent)).sqrt())
    }

    /// The polar `perf` with the learned turn rate.
    pub fn performance(&self, perf: &GlidePerformance) -> GlidePerformance {
        GlidePerformance {
            max_turn_rate_rad_s: perf.max_turn_rate_rad_s * self.scale(),
            ..*perf
        }
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;

    use super::*;
    use crate::control::{self, ControlGains};
    use crate::pointmass::{Conditions, PointMass};
    use std::f64::consts::FRAC_PI_2;
    use stx_types::controls::Controls;
    use stx_types::rotation::wrap_pi;

    /// A point mass whose turn rate is `factor` times its polar's, steered through 90° course
    /// changes by the course law for `seconds` (or flown straight); what was learned.
    fn learn(factor: f64, seconds: usize, turning: bool) -> LearnedTurn {
        fly(factor, seconds, turning, false).0
    }

    /// The same flight, the gains scheduled by the turn rate learned if `scheduled`; what was
    /// learned and the rise time (to 90 %) of the last course change, s.
    fn fly(factor: f64, seconds: usize, turning: bool, scheduled: bool) -> (LearnedTurn, f64) {
        let polar = GlidePerformance::default();
        let flown = GlidePerformance {
            max_turn_rate_rad_s: polar.max_turn_rate_rad_s * factor,
            ..polar
        };
        let gains = ControlGains::default();
        let wind = Vector3::new(-2.0, 1.0, 0.0);
        let air = Conditions::nominal(wind, polar.reference_density_kg_per_m3);
        let mut stack = PointMass::new(0.0, Vector3::new(0.0, 0.0, -800.0), 0.0);
        let mut learned = LearnedTurn::default();
        let mut command = 0.0;
        let mut rise_s = None;
        for k in 0..seconds * 4 {
            for _ in 0..5 {
                stack.step(
                    &flown,
                    &Controls {
                        main_line_m: command,
                        ..Controls::default()
                    },
                    &air,
                    0.05,
                );
            }
            let est = stack.estimate(&wind);
            learned.update(&polar, &est, command);
            // A new course every 20 s, a quarter turn on.
            let wanted = if turning {
                std::f64::consts::FRAC_PI_2 * (k / 80) as f64
            } else {
                0.0
            };
            // Each change is a quarter turn to the right: the time to 90 % of it.
            if k % 80 == 0 {
                rise_s = None;
            }
            if rise_s.is_none() && wrap_pi(est.heading_rad - wanted) > -0.1 * FRAC_PI_2 {
                rise_s = Some((k % 80) as f64 * 0.25);
            }
            let flown_gains = if scheduled {
                gains.for_turn_scale(learned.scale())
            } else {
                gains
            };
            command = control::course(
                &flown_gains,
                &mut control::TurnLatch::default(),
                est.heading_rad,
                est.heading_rate_rad_s,
                wanted,
            );
        }
        (learned, rise_s.unwrap_or(f64::INFINITY))
    }

    #[test]
    fn a_canopy_that_turns_faster_or_slower_than_its_polar_is_learned_in_the_corners() {
        for factor in [0.75, 1.0, 1.3] {
            let learned = learn(factor, 120, true);
            assert!(learned.learned_s > 10.0, "{learned:?}");
            assert!(
                (learned.scale() - factor).abs() < 0.05 * factor,
                "{factor}: learned {:.3}",
                learned.scale()
            );
            let perf = GlidePerformance::default();
            let planned = learned.performance(&perf).turn_rate(0.005) / perf.turn_rate(0.005);
            assert!((planned - learned.scale()).abs() < 1e-9);
            // The model turns as the polar says bar the factor: the fit's residual, and so
            // its 1-σ, is small.
            let sigma = learned.sigma().expect("learned");
            assert!(sigma < 0.02 * factor, "{factor}: σ {sigma:.4}");
        }
    }

    #[test]
    fn gains_scheduled_by_the_learned_turn_rate_turn_a_quick_canopy_like_the_nominal_one() {
        let (_, nominal) = fly(1.0, 120, true, false);
        let (learned, quick) = fly(1.6, 120, true, false);
        let (_, scheduled) = fly(1.6, 120, true, true);
        assert!((learned.scale() - 1.6).abs() < 0.1, "{}", learned.scale());
        // 60 % more turn authority under the same gains is a different loop (here a quicker
        // one); the scheduled gains give back the loop they were tuned for.
        assert!(quick < nominal - 0.5, "{quick} s against {nominal} s");
        assert!(
            (scheduled - nominal).abs() < 0.3 * (nominal - quick),
            "scheduled {scheduled} s, nominal {nominal} s, unscheduled {quick} s"
        );
    }

    #[test]
    fn straight_flight_teaches_nothing_about_turning() {
        let learned = learn(1.3, 60, false);
        assert_eq!(learned.learned_s, 0.0, "{learned:?}");
        assert_eq!(learned.scale(), 1.0);
        assert_eq!(learned.sigma(), None);
    }
}
