//! The point-mass stages' models (see the parent module): the balloon's ascent rate and the
//! stack's drag under its round chute (shared with the flight-path planner, so they live in
//! `stx_gnc::flight_path`), and the swing of the drone under either.

use std::f64::consts::TAU;

use nalgebra::Vector3;
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
pub use stx_gnc::flight_path::{Balloon, RoundChute};

/// The drone's swing under the balloon or the round chute (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Swing {
    /// Pendulum period, s.
    pub period_s: f64,
    /// Roll amplitude, rad.
    pub roll_rad: f64,
    /// Pitch amplitude, rad.
    pub pitch_rad: f64,
    /// Spin of the flight train, rad/s (sign: direction).
    pub spin_rad_s: f64,
    /// Yaw wobble amplitude, rad, at 2.5 pendulum periods.
    pub wobble_rad: f64,
    /// Phases of roll, pitch and wobble, rad.
    pub phases_rad: [f64; 3],
    /// Yaw at time zero, rad.
    pub yaw0_rad: f64,
}

impl Swing {
    /// The swing of a flight train of `length_m` with roll amplitude `amplitude_deg`, spinning
    /// at `spin_deg_s`, phases drawn from `rng`.
    pub(super) fn new(
        length_m: f64,
        amplitude_deg: f64,
        spin_deg_s: f64,
        rng: &mut ChaCha8Rng,
    ) -> Self {
        let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
        Self {
            period_s: TAU * (length_m / 9.80665).sqrt(),
            roll_rad: amplitude_deg.to_radians(),
            pitch_rad: 0.7 * amplitude_deg.to_radians(),
            spin_rad_s: sign * spin_deg_s.to_radians(),
            wobble_rad: 2.0 * amplitude_deg.to_radians(),
            phases_rad: [
                rng.random::<f64>() * TAU,
                rng.random::<f64>() * TAU,
                rng.random::<f64>() * TAU,
            ],
            yaw0_rad: rng.random::<f64>() * TAU,
        }
    }

    /// Roll, pitch, yaw (yaw unwrapped) and their rates at `time_s`.
    pub fn attitude(&self, time_s: f64) -> (Vector3<f64>, Vector3<f64>) {
        let w = TAU / self.period_s;
        // Pitch swings at a slightly different frequency: the train is not a planar pendulum.
        let wp = 1.13 * w;
        let ww = w / 2.5;
        let [pr, pp, pw] = self.phases_rad;
        let euler = Vector3::new(
            self.roll_rad * (w * time_s + pr).sin(),
            self.pitch_rad * (wp * time_s + pp).sin(),
            self.yaw0_rad + self.spin_rad_s * time_s + self.wobble_rad * (ww * time_s + pw).sin(),
        );
        let rates = Vector3::new(
            self.roll_rad * w * (w * time_s + pr).cos(),
            self.pitch_rad * wp * (wp * time_s + pp).cos(),
            self.spin_rad_s + self.wobble_rad * ww * (ww * time_s + pw).cos(),
        );
        (euler, rates)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn the_swing_rates_are_the_derivatives_of_its_angles() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let s = Swing::new(15.0, 2.0, 3.0, &mut rng);
        let (a0, r) = s.attitude(10.0);
        let (a1, _) = s.attitude(10.0 + 1e-6);
        let numeric = (a1 - a0) / 1e-6;
        assert!((numeric - r).norm() < 1e-5, "{numeric:?} {r:?}");
        assert!((s.period_s - 7.77).abs() < 0.05);
    }
}
