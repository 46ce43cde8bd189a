//! Where a run's miss grew: the guidance phase over which the landing guidance expected moved
//! furthest from the target.
//!
//! From 30 s after release, and at every phase change after, the run keeps guidance and its
//! estimate as they were. Once the run
//! has landed, and only if it missed by [`GROWTH_MISS_M`] or more (the runs a report names
//! among its worst; the others are not worth the predictions), the landing predictor flies
//! each kept guidance from its estimate to the ground in fast time — what the station's
//! planned prediction showed at that moment. Phase `k` is judged by how much the expected
//! miss grew from its start to the next phase's start; the last phase ends on the payload's
//! real touchdown. The phase with the largest growth is where the error grew: the estimate or
//! the polar went wrong there (the prediction moves when guidance learns it), or the flight
//! itself did not follow the plan (gusts, a turn flown wide).

use serde::{Deserialize, Serialize};
use stx_dynamics::atmosphere::StandardAtmosphere;
use stx_gnc::estimate::Estimate;
use stx_gnc::guidance::Guidance;
use stx_gnc::mission::GuidancePhase;
use stx_gnc::predict::{PredictorConfig, planned_touchdown_ne_m};

/// Runs that missed by less than this are not accounted for, m.
pub const GROWTH_MISS_M: f64 = 15.0;
/// Nothing is kept before this long after release, s: the estimator's wind starts at zero
/// and converges over the first seconds (the wind-estimate error is judged from here too), and
/// a prediction on that wind says nothing about guidance.
const FIRST_KEPT_S: f64 = 30.0;

/// The phase where a run's miss grew.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MissGrowth {
    /// The phase.
    pub phase: GuidancePhase,
    /// How much the expected miss grew over it, m.
    pub grew_m: f64,
    /// Height of the drone above the target's ground when it began, m.
    pub from_height_m: f64,
}

/// Guidance and its estimate at each phase change of one run.
#[derive(Debug, Clone, Default)]
pub(super) struct PhaseSnapshots {
    kept: Vec<(GuidancePhase, Estimate, Guidance)>,
}

impl PhaseSnapshots {
    /// Keeps `guidance` and `est` if the phase changed since the last one kept (the first
    /// [`FIRST_KEPT_S`] after release, whatever the phase).
    pub(super) fn observe(&mut self, guidance: &Guidance, est: Option<&Estimate>) {
        let phase = guidance.phase();
        let changed = self.kept.last().is_none_or(|(p, _, _)| *p != phase);
        if let Some(est) = est
            && changed
            && est.time_s >= FIRST_KEPT_S
            && !matches!(phase, GuidancePhase::Idle | GuidancePhase::Landed)
        {
            self.kept.push((phase, *est, guidance.clone()));
        }
    }

    /// The phase where the miss grew most, for a payload that touched down at `payload_ne`
    /// (north, east of the target at the origin, m) with a miss of `miss_m`; `None` for a miss
    /// under [`GROWTH_MISS_M`] or no phase kept.
    pub(super) fn where_miss_grew(
        &self,
        payload_ne: [f64; 2],
        miss_m: f64,
        ground_altitude_msl_m: f64,
    ) -> Option<MissGrowth> {
        if miss_m < GROWTH_MISS_M || self.kept.is_empty() {
            return None;
        }
        let config = PredictorConfig {
            step_s: 0.25,
            ..PredictorConfig::default()
        };
        let mut expected: Vec<f64> = self
            .kept
            .iter()
            .map(|(_, est, guidance)| {
                let ne = planned_touchdown_ne_m(
                    est,
                    guidance,
                    &guidance.learned_performance(),
                    &StandardAtmosphere,
                    ground_altitude_msl_m,
                    &config,
                );
                ne[0].hypot(ne[1])
            })
            .collect();
        expected.push(payload_ne[0].hypot(payload_ne[1]));
        self.kept
            .iter()
            .zip(expected.windows(2))
            .map(|((phase, est, _), pair)| MissGrowth {
                phase: *phase,
                grew_m: pair[1] - pair[0],
                from_height_m: est.height_m(),
            })
            .max_by(|a, b| a.grew_m.total_cmp(&b.grew_m))
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;
    use stx_gnc::guidance::GuidanceConfig;
    use stx_gnc::pointmass::PointMass;

    use super::*;

    /// Guidance left uncontrolled (neutral servos: the prediction is the straight glide) and
    /// the estimate of a stack `height` m up at `north` m heading north in still air, at
    /// `time_s`.
    fn kept_at(north: f64, height: f64, time_s: f64) -> (Estimate, Guidance) {
        let est = PointMass::new(time_s, Vector3::new(north, 0.0, -height), 0.0)
            .estimate(&Vector3::zeros());
        (est, Guidance::new(GuidanceConfig::default()))
    }

    /// Where the straight glide from `kept_at(north, height, …)` ends, m north.
    fn glide_end(north: f64, height: f64) -> f64 {
        let (est, guidance) = kept_at(north, height, 40.0);
        planned_touchdown_ne_m(
            &est,
            &guidance,
            &guidance.learned_performance(),
            &StandardAtmosphere,
            0.0,
            &PredictorConfig {
                step_s: 0.25,
                ..PredictorConfig::default()
            },
        )[0]
    }

    #[test]
    fn the_phase_whose_expected_landing_moved_away_is_where_the_miss_grew() {
        // The pattern ends with a landing expected on the target; on the final it is expected
        // 40 m beyond, and the payload comes down 45 m beyond: the miss grew on the pattern's
        // last leg (by 40 m), not on the final (by 5 m).
        let glide = glide_end(0.0, 150.0);
        assert!(glide > 100.0, "{glide}");
        let on_target = kept_at(-glide, 150.0, 40.0);
        let beyond = kept_at(40.0 - glide, 150.0, 60.0);
        let snapshots = PhaseSnapshots {
            kept: vec![
                (GuidancePhase::Branch2, on_target.0, on_target.1.clone()),
                (GuidancePhase::FinalApproach, beyond.0, beyond.1),
            ],
        };
        let grew = snapshots
            .where_miss_grew([45.0, 0.0], 45.0, 0.0)
            .expect("a miss over the threshold");
        assert_eq!(grew.phase, GuidancePhase::Branch2);
        assert!((grew.grew_m - 40.0).abs() < 1.0, "{grew:?}");
        assert!((grew.from_height_m - 150.0).abs() < 1e-9);
        // Landed 30 m beyond instead: it came back on the final, still the leg's growth.
        let back = snapshots.where_miss_grew([30.0, 0.0], 30.0, 0.0);
        assert_eq!(back.map(|g| g.phase), Some(GuidancePhase::Branch2));
        // Expected on the target at every phase change, landed 20 m off: the final.
        let steady = PhaseSnapshots {
            kept: vec![
                (GuidancePhase::Branch2, on_target.0, on_target.1.clone()),
                (GuidancePhase::FinalApproach, on_target.0, on_target.1),
            ],
        };
        let late = steady
            .where_miss_grew([0.0, 20.0], 20.0, 0.0)
            .expect("grew");
        assert_eq!(late.phase, GuidancePhase::FinalApproach);
        // A miss under the threshold is not accounted for.
        assert_eq!(steady.where_miss_grew([0.0, 10.0], 10.0, 0.0), None);
    }
}
