//! Which way to turn when the way to go is nearly behind: chosen once, held through the turn.
//!
//! The laws wrap an angle error to (−π, π], so near ±180° the shorter way flips with the
//! smallest change of the measured course. The drone hangs below the canopy and twists the
//! moment the main line moves, and flying into a headwind the estimated course over the
//! ground follows its heading: a full command one way swings the course estimate by 30–50°
//! within one 0.25 s control period. Near ±180° that flips the error's sign, the next
//! command goes the other way, and the loop chatters at 2 Hz with the canopy not turning at
//! all (seed 11, run 169 with lower heading gains: a reversal onto the downwind leg never
//! flown, 76 s upwind to the ground, 232 m off). A latch takes the side of the error when
//! it first exceeds [`LATCH_RAD`] and keeps the error on that side, unwrapped, until less
//! than [`RELEASE_RAD`] is left: the reversal is flown one way. The side belongs to the
//! direction wanted when it was taken: when the wanted direction moves by more than
//! [`RETARGET_RAD`] (a new plan, a new phase), the side is chosen anew, so a turn is never
//! flown the long way round to a target that is no longer behind.

use std::f64::consts::PI;

use stx_types::rotation::wrap_pi;

/// An error larger than this (150°) takes a side.
pub const LATCH_RAD: f64 = 5.0 * PI / 6.0;
/// The side is kept until the error is smaller than this (90°).
pub const RELEASE_RAD: f64 = PI / 2.0;
/// A wanted direction that moved by more than this (30°) since the side was taken releases it.
pub const RETARGET_RAD: f64 = PI / 6.0;

/// The turn's side, held from when its error first exceeded [`LATCH_RAD`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TurnLatch {
    /// The side (`true`: the error is kept positive) and the wanted direction it was taken
    /// for, rad.
    held: Option<(bool, f64)>,
}

impl TurnLatch {
    /// The error to act on when flying `actual_rad` towards `wanted_rad`: their difference
    /// wrapped to (−π, π], or, while a side is held, on that side (up to ±2π).
    pub fn resolve(&mut self, actual_rad: f64, wanted_rad: f64) -> f64 {
        let e = wrap_pi(actual_rad - wanted_rad);
        if !e.is_finite() || e.abs() < RELEASE_RAD {
            self.held = None;
            return e;
        }
        if let Some((_, for_rad)) = self.held
            && wrap_pi(wanted_rad - for_rad).abs() > RETARGET_RAD
        {
            self.held = None;
        }
        if self.held.is_none() && e.abs() > LATCH_RAD {
            self.held = Some((e > 0.0, wanted_rad));
        }
        match self.held {
            Some((true, _)) if e < 0.0 => e + 2.0 * PI,
            Some((false, _)) if e > 0.0 => e - 2.0 * PI,
            _ => e,
        }
    }

    /// Whether a side is held.
    #[cfg(test)]
    fn is_latched(&self) -> bool {
        self.held.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn deg(d: f64) -> f64 {
        d.to_radians()
    }

    #[test]
    fn small_errors_are_only_wrapped() {
        let mut latch = TurnLatch::default();
        assert!((latch.resolve(deg(370.0), 0.0) - deg(10.0)).abs() < 1e-12);
        assert!((latch.resolve(deg(-140.0), 0.0) - deg(-140.0)).abs() < 1e-12);
        assert!(!latch.is_latched());
    }

    #[test]
    fn a_reversal_keeps_its_side_while_the_measured_course_jitters_across_180_degrees() {
        let mut latch = TurnLatch::default();
        // The first large error is +170°: turn so as to reduce it, and keep doing so when
        // the estimate swings 30° past ±180°.
        assert!((latch.resolve(deg(170.0), 0.0) - deg(170.0)).abs() < 1e-12);
        for jitter in [-200.0, 160.0, -175.0, 185.0, 150.0] {
            let e = latch.resolve(deg(jitter), 0.0);
            assert!(e > 0.0, "{jitter}° resolved to {:.1}°", e.to_degrees());
            assert!((wrap_pi(e) - wrap_pi(deg(jitter))).abs() < 1e-9);
        }
        // The wanted direction moves by 80°: the error of −100° to it is flown the short way,
        // not 260° round on the side held for the old one.
        let mut moved = latch;
        assert!((moved.resolve(deg(-20.0), deg(80.0)) - deg(-100.0)).abs() < 1e-9);
        // Released once the turn has brought the error under 90°; a new reversal picks anew.
        assert!((latch.resolve(deg(80.0), 0.0) - deg(80.0)).abs() < 1e-12);
        assert!(!latch.is_latched());
        assert!(latch.resolve(deg(-179.0), 0.0) < 0.0);
        assert!(latch.resolve(deg(179.0), 0.0) < 0.0);
    }

    /// A course reversal flown by the course law at 4 Hz on a stack whose course estimate
    /// jumps against the command (the drone's twist, 4°/mm as measured in seed 11 run 169),
    /// turning at the polar's rate with its lags. Returns how far from the wanted course the
    /// stack is after 40 s, degrees (30 s with the higher heading gains before 2026-11-28:
    /// today's turn more gently and end the reversal 11° off at 30 s, 8° at 40 s).
    fn reversal(latched: bool) -> f64 {
        use crate::control::{ControlGains, course};
        let gains = ControlGains::default();
        let (dt, period) = (0.05, 5);
        let twist_rad_per_m = 4f64.to_radians() * 1000.0;
        let (mut chi, mut rate, mut servo, mut command) = (0.0f64, 0.0, 0.0, 0.0);
        let mut latch = TurnLatch::default();
        let mut last_measured: Option<f64> = None;
        for step in 0..800 {
            let measured = chi - twist_rad_per_m * servo;
            if step % period == 0 {
                let measured_rate = last_measured
                    .map(|m| wrap_pi(measured - m) / (dt * period as f64))
                    .unwrap_or(0.0);
                last_measured = Some(measured);
                if !latched {
                    latch = TurnLatch::default();
                }
                command = course(&gains, &mut latch, measured, measured_rate, PI);
            }
            servo += (command - servo) * (5.0 * dt).min(1.0);
            let steady = 0.85 * (servo / 0.011f64).tanh();
            rate += (steady - rate) * dt / 1.5;
            chi += rate * dt;
        }
        wrap_pi(chi - PI).abs().to_degrees()
    }

    #[test]
    fn a_reversal_with_a_course_estimate_that_jumps_against_the_command_is_flown_through() {
        let off = reversal(true);
        assert!(
            off < 10.0,
            "latched: {off:.1}° from the wanted course after 40 s"
        );
        // Wrapped alone, the same loop chatters near ±180° and barely turns.
        let unlatched = reversal(false);
        assert!(
            unlatched > 120.0,
            "wrapped alone: {unlatched:.0}° off after 40 s"
        );
    }
}
