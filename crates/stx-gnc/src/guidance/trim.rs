//! The main line's trim, learned in flight: the command that flies straight.
//!
//! A servo's zero, the rigging of the two main lines and a canopy built a little asymmetric
//! all make the stack turn with the main line at zero; the course and localizer laws then fly
//! with a standing error (their gains are proportional), the pattern's legs drift and the final
//! lands off its line. Campaigns with realistic dispersions showed it is the largest single
//! cause of misses (a 2 mm 1-σ main-line offset, 7 % of the travel: median payload miss 12 m
//! with it, 8 m without). The trim is learned as the offset that makes the turn rate the
//! performance model predicts for the commands sent match the turn rate measured, in
//! near-straight flight only (where the model's slope is known best), and taken off every
//! guided command.

use crate::estimate::Estimate;
use crate::performance::GlidePerformance;

/// Time constant of the learned trim, s: long against gusts and turns' transients.
const LEARN_TIME_S: f64 = 30.0;
/// The trim is learned only while the command (with the trim) stays within this share of
/// the performance model's main-line scale, where turn rate is nearly linear in it.
const LINEAR_SHARE: f64 = 0.5;
/// Largest trim learned, m (a third of the servo's travel).
const MAX_TRIM_M: f64 = 0.01;

/// The learned trim and the turn rate the model expects from the commands sent.
#[derive(Debug, Clone, Copy, Default)]
pub struct MainLineTrim {
    /// The main-line offset the stack flies with, m: the command that flies straight is its
    /// negative.
    pub offset_m: f64,
    /// Seconds learned from.
    pub learned_s: f64,
    expected_rate_rad_s: f64,
    last_time_s: Option<f64>,
}

impl MainLineTrim {
    /// Learns from `est`, the main line having been commanded `sent_m` (trim included) since
    /// the last update.
    pub fn update(&mut self, perf: &GlidePerformance, est: &Estimate, sent_m: f64) {
        let now = est.time_s;
        let Some(last_s) = self.last_time_s.replace(now) else {
            // Whatever was flown before (nothing, or commands this trim never saw) the
            // stack turns at the rate measured now; the model's rate relaxes from there.
            if est.heading_rate_rad_s.is_finite() {
                self.expected_rate_rad_s = est.heading_rate_rad_s;
            }
            return;
        };
        let dt = now - last_s;
        if dt <= 0.0 {
            return;
        }
        let effective = sent_m + self.offset_m;
        let scale = perf.turn_main_line_scale_m;
        // The turn rate follows the command with the model's time constant.
        let steady = perf.turn_rate(effective);
        let k = (dt / perf.turn_time_constant_s.max(dt)).min(1.0);
        self.expected_rate_rad_s += k * (steady - self.expected_rate_rad_s);
        if effective.abs() > LINEAR_SHARE * scale || !est.attitude_ok {
            return;
        }
        let slope = perf.max_turn_rate_rad_s / scale * (1.0 - (effective / scale).tanh().powi(2));
        if slope.is_nan() || slope <= 1e-6 || !est.heading_rate_rad_s.is_finite() {
            return;
        }
        let error_m = (est.heading_rate_rad_s - self.expected_rate_rad_s) / slope;
        let gain = dt / (self.learned_s + dt).clamp(LEARN_TIME_S / 3.0, LEARN_TIME_S);
        self.offset_m = (self.offset_m + gain * error_m).clamp(-MAX_TRIM_M, MAX_TRIM_M);
        self.learned_s += dt;
    }

    /// Commands this trim did not see are being flown (manual or hands-off flight): it learns
    /// again from the next guided update on, with its expected turn rate taken from the rate
    /// measured then. Learning across such a gap compared a manual turn with the model's rate
    /// for the last guided command and pinned the trim at its limit (a rehearsal's final
    /// approach flown 30° off its line with the law's command cancelled by the trim).
    pub fn interrupt(&mut self) {
        self.last_time_s = None;
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;
    use stx_types::controls::Controls;

    use super::*;
    use crate::pointmass::{Conditions, PointMass};

    /// A point mass whose main line is offset by `offset_m`, its course held by a proportional
    /// law on the heading rate with the learned trim taken off; the trim learned after
    /// `seconds`, and the mean turn rate of the last 10 s.
    fn fly(offset_m: f64, seconds: usize) -> (MainLineTrim, f64) {
        let perf = GlidePerformance::default();
        let wind = Vector3::zeros();
        let air = Conditions::nominal(wind, perf.reference_density_kg_per_m3);
        let mut stack = PointMass::new(0.0, Vector3::new(0.0, 0.0, -2000.0), 0.0);
        let mut trim = MainLineTrim::default();
        let mut rates = Vec::new();
        for _ in 0..seconds * 4 {
            let est = stack.estimate(&wind);
            // Wants to fly straight: command against the measured turn rate.
            let wanted = -0.004 * est.heading_rate_rad_s;
            let sent = wanted - trim.offset_m;
            trim.update(&perf, &est, sent);
            let controls = Controls {
                main_line_m: sent + offset_m,
                ..Controls::default()
            };
            for _ in 0..5 {
                stack.step(&perf, &controls, &air, 0.05);
            }
            rates.push(est.heading_rate_rad_s);
        }
        let tail = &rates[rates.len() - 40..];
        (trim, tail.iter().sum::<f64>() / tail.len() as f64)
    }

    #[test]
    fn a_main_line_offset_is_learned_and_flown_out() {
        let (trim, rate) = fly(0.002, 120);
        assert!((trim.offset_m - 0.002).abs() < 2e-4, "{trim:?}");
        assert!(rate.abs() < 0.01, "still turning at {rate} rad/s");
        let (trim, _) = fly(0.0, 60);
        assert!(trim.offset_m.abs() < 1e-4, "{trim:?}");
    }

    /// Straight guided flight, 5 s of a hard manual turn the trim does not see, and guided
    /// straight flight again: nothing of the manual turn is learned as trim.
    #[test]
    fn a_manual_turn_between_guided_updates_is_not_learned_as_trim() {
        let perf = GlidePerformance::default();
        let wind = Vector3::zeros();
        let air = Conditions::nominal(wind, perf.reference_density_kg_per_m3);
        let mut stack = PointMass::new(0.0, Vector3::new(0.0, 0.0, -2000.0), 0.0);
        let mut trim = MainLineTrim::default();
        let mut largest = 0.0_f64;
        for k in 0..4 * 60 {
            let est = stack.estimate(&wind);
            let manual = (30 * 4..35 * 4).contains(&k);
            let sent = if manual {
                trim.interrupt();
                -0.012
            } else {
                let sent = -0.004 * est.heading_rate_rad_s - trim.offset_m;
                trim.update(&perf, &est, sent);
                sent
            };
            let controls = Controls {
                main_line_m: sent,
                ..Controls::default()
            };
            for _ in 0..5 {
                stack.step(&perf, &controls, &air, 0.05);
            }
            largest = largest.max(trim.offset_m.abs());
        }
        // Learning across the gap put 2.4 mm here.
        assert!(largest < 5e-4, "trim reached {largest} m");
    }
}
