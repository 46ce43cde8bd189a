//! The turn rate the pattern's corners are planned with: the rate the control gains in force
//! actually turn the parafoil at, found by flying a point mass through a corner.

use nalgebra::Vector3;
use stx_types::controls::Controls;

use crate::control::{self, ControlGains, TurnLatch};
use crate::performance::GlidePerformance;
use crate::pointmass::{Conditions, PointMass};

/// Average turn rate of a 90° course change flown by the course law with `gains` on the
/// point-mass parafoil `perf` (still air, the 4 Hz control period), rad/s: 90° over the
/// time to cover 90 % of the change from straight flight.
///
/// The seed planned corners at a fixed rate; with the gains `stx tune` produced the vehicle
/// turns at about two thirds of the 20°/s once assumed, and corners planned for 20°/s were
/// started late, overshooting every branch and misplacing the final approach.
pub fn corner_turn_rate_rad_s(gains: &ControlGains, perf: &GlidePerformance) -> f64 {
    const CONTROL_PERIOD_S: f64 = 0.25;
    const STEPS_PER_PERIOD: usize = 5;
    const LONGEST_S: f64 = 60.0;
    let quarter = std::f64::consts::FRAC_PI_2;
    let air = Conditions::nominal(Vector3::zeros(), perf.reference_density_kg_per_m3);
    let mut mass = PointMass::new(0.0, Vector3::zeros(), 0.0);
    while mass.time_s < LONGEST_S {
        let main_line_m = control::course(
            gains,
            &mut TurnLatch::default(),
            mass.heading_rad,
            mass.turn_rate_rad_s,
            quarter,
        );
        let controls = Controls {
            main_line_m,
            ..Controls::default()
        };
        for _ in 0..STEPS_PER_PERIOD {
            mass.step(
                perf,
                &controls,
                &air,
                CONTROL_PERIOD_S / STEPS_PER_PERIOD as f64,
            );
            if mass.heading_rad >= 0.9 * quarter {
                return quarter / mass.time_s;
            }
        }
    }
    quarter / LONGEST_S
}

/// The corner turn rate in use, with the gains and turn model it was computed for: computing
/// it flies a point mass, so it is kept until either changes by more than [`RATE_STEP`].
/// Only the turn model matters (the heading of the point mass does not depend on its glide),
/// so the glide learned at every update does not cost a new flight.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct CornerRate(Option<(ControlGains, [f64; 3], f64)>);

/// Relative change of the (learned) maximum turn rate for which the corner rate is computed
/// again.
const RATE_STEP: f64 = 0.01;

impl CornerRate {
    /// The rate to plan the corners with, rad/s: `set_rad_s` if the operator set one (> 0),
    /// else the rate `gains` turn at on `perf`.
    pub(super) fn planned(
        &mut self,
        set_rad_s: f64,
        gains: &ControlGains,
        perf: &GlidePerformance,
    ) -> f64 {
        if set_rad_s > 0.0 {
            return set_rad_s;
        }
        let key = [
            perf.max_turn_rate_rad_s,
            perf.turn_main_line_scale_m,
            perf.turn_time_constant_s,
        ];
        match self.0 {
            Some((g, k, rate))
                if g == *gains
                    && k[1..] == key[1..]
                    && (k[0] - key[0]).abs() <= RATE_STEP * k[0].abs() =>
            {
                rate
            }
            _ => {
                let rate = corner_turn_rate_rad_s(gains, perf);
                self.0 = Some((*gains, key, rate));
                rate
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guidance::spiral::{Spiral, SpiralStatus};
    use crate::guidance::{GuidanceConfig, Plan};
    use crate::mission::GuidancePhase;

    fn status_after_one_update(config: &GuidanceConfig) -> SpiralStatus {
        let mut spiral = Spiral::new();
        spiral.force_phase(GuidancePhase::Approximation);
        let plan = Plan {
            target_ned_m: Vector3::zeros(),
            ..Plan::default()
        };
        let est = PointMass::new(0.0, Vector3::new(300.0, 0.0, -500.0), 0.0)
            .estimate(&Vector3::new(1.0, 0.0, 0.0));
        spiral.update(config, &plan, &est, 1.2);
        *spiral.status()
    }

    /// Regression: corners were planned at a fixed 20°/s, the rate of the hand-set gains,
    /// while the tuned gains in use turn at about 13°/s; every corner was started late.
    #[test]
    fn corners_are_planned_at_the_rate_the_gains_turn() {
        let perf = GlidePerformance::default();
        let tuned = corner_turn_rate_rad_s(&ControlGains::default(), &perf);
        assert!(
            (11.0..15.0).contains(&tuned.to_degrees()),
            "tuned gains turn at {:.1}°/s",
            tuned.to_degrees()
        );
        let hand_set = ControlGains {
            hk1_m_per_rad: 0.012,
            hk2_m_s_per_rad: 0.012,
            ..ControlGains::default()
        };
        let fast = corner_turn_rate_rad_s(&hand_set, &perf);
        assert!(
            (18.0..23.0).contains(&fast.to_degrees()),
            "hand-set gains turn at {:.1}°/s",
            fast.to_degrees()
        );

        // Planning uses the rate of the gains in force, and the turn distance follows it.
        let mut config = GuidanceConfig::default();
        let status = status_after_one_update(&config);
        assert!((status.planned_turn_rate_rad_s - tuned).abs() < 1e-12);
        let v0 = perf.horizontal_airspeed(0.0, 1.2);
        assert!((status.turn_distance_m - v0 / tuned).abs() < 1e-9);
        config.gains = hand_set;
        let status_fast = status_after_one_update(&config);
        assert!((status_fast.planned_turn_rate_rad_s - fast).abs() < 1e-12);
        assert!(status_fast.turn_distance_m < status.turn_distance_m);
        // A rate set by the operator overrides it.
        config.spiral.planned_turn_rate_rad_s = 0.5;
        assert_eq!(
            status_after_one_update(&config).planned_turn_rate_rad_s,
            0.5
        );
    }
}
