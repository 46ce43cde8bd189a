//! The wind the spiral plans with: the estimator's, low-passed once the estimator trusts it,
//! and whether it has been trusted long enough for energy decisions.

use serde::{Deserialize, Serialize};

use crate::estimate::Estimate;

/// Wind uncertainty (1-σ per component) below which guidance trusts the wind for its energy
/// decisions, m/s.
const WIND_KNOWN_SIGMA_MPS: f64 = 0.6;
/// Time the wind uncertainty must have stayed small before energy decisions use it, s.
const WIND_SETTLE_S: f64 = 10.0;

/// The planning wind's memory between updates.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct PlanningWind {
    /// The low-passed wind (north, east), m/s, while the estimator trusts its wind.
    filtered_ne_mps: Option<[f64; 2]>,
    /// Time of the last update, s.
    last_time_s: Option<f64>,
    /// Since when the estimator's wind uncertainty has been small, s.
    known_since_s: Option<f64>,
}

/// The wind at one update.
#[derive(Debug, Clone, Copy)]
pub(super) struct WindNow {
    /// The estimator's wind as it is (north, east), m/s.
    pub(super) measured_ne_mps: [f64; 2],
    /// The wind guidance plans with (north, east), m/s.
    pub(super) ne_mps: [f64; 2],
    /// Its speed, m/s.
    pub(super) speed_mps: f64,
    /// Whether it has been certain for long enough to decide on.
    pub(super) known: bool,
}

impl PlanningWind {
    /// Takes in the estimate's wind; `filter_s` is the low-pass time constant, s.
    pub(super) fn update(&mut self, est: &Estimate, filter_s: f64) -> WindNow {
        // Wind used for planning: low-passed so the pattern does not twitch with gusts, but only
        // once the estimator trusts its wind. Before, its wind starts near zero and swings by
        // metres per second as it converges; a filter started there lagged the truth for many
        // time constants, and in a strong wind the reach check then saw a wind too weak to
        // call the target out of reach until the pattern had committed to it (issue 3 audit:
        // 8–10 m/s winds missed by up to 1.2 km unflagged). So the raw estimate is followed
        // until its uncertainty is small, and the filter starts from the estimate then.
        let measured = [est.wind_ned_mps.x, est.wind_ned_mps.y];
        let sigma_ok = est.wind_sigma_mps.x.max(est.wind_sigma_mps.y) < WIND_KNOWN_SIGMA_MPS;
        let dt = self
            .last_time_s
            .map(|t| (est.time_s - t).clamp(0.0, 5.0))
            .unwrap_or(0.0);
        self.last_time_s = Some(est.time_s);
        let wind = match self.filtered_ne_mps {
            Some(w) if sigma_ok => {
                let k = dt / (filter_s + dt);
                [
                    w[0] + k * (measured[0] - w[0]),
                    w[1] + k * (measured[1] - w[1]),
                ]
            }
            _ => measured,
        };
        self.filtered_ne_mps = sigma_ok.then_some(wind);

        // Energy decisions wait until the wind is known: the estimator's first seconds can be
        // metres per second off, and a pattern abandoned on a wrong wind is not recovered.
        // ... and have stayed good for a while: the estimator's first converged seconds still
        // carry metres per second of error that its uncertainty does not show, and a pattern
        // committed to a wrong wind's axis is flown across the real one.
        self.known_since_s = match (sigma_ok, self.known_since_s) {
            (false, _) => None,
            (true, None) => Some(est.time_s),
            (true, since) => since,
        };
        let known = self
            .known_since_s
            .is_some_and(|since| est.time_s - since >= WIND_SETTLE_S);
        WindNow {
            measured_ne_mps: measured,
            ne_mps: wind,
            speed_mps: wind[0].hypot(wind[1]),
            known,
        }
    }
}

/// A wind measured at the ground by the target (a surface anemometer the station reads, or a
/// value the operator typed), uplinked to guidance.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SurfaceWind {
    /// The wind (north, east; the air's velocity, not where it comes from), m/s: the
    /// anemometer's mean over its averaging time.
    pub ne_mps: [f64; 2],
    /// When it was measured, on guidance's clock (the estimate's time), s.
    pub time_s: f64,
}

/// A surface wind older than this is not used, s: the low-level wind changes in minutes.
pub(super) const SURFACE_WIND_MAX_AGE_S: f64 = 120.0;
/// Below this height of the lowest body the surface wind starts to count in the planning
/// wind, m: about where the final is turned onto.
const SURFACE_WIND_FROM_M: f64 = 250.0;
/// At and below this height it counts half, m: what the rest of the descent flies through is
/// then about the mean of the wind here (the estimator's) and at the ground (the
/// anemometer's), for a wind that changes evenly with height.
const SURFACE_WIND_HALF_M: f64 = 100.0;

impl WindNow {
    /// The planning wind with `surface` mixed in for the rest of the descent from a lowest
    /// body `lowest_body_height` m up, at `now_s`: nothing above [`SURFACE_WIND_FROM_M`], half
    /// at [`SURFACE_WIND_HALF_M`] and below; a stale surface wind is left out. The
    /// estimator's own wind (`measured_ne_mps`, which the reach check uses) is kept.
    pub(super) fn toward_surface(
        self,
        surface: Option<&SurfaceWind>,
        lowest_body_height: f64,
        now_s: f64,
    ) -> Self {
        let Some(surface) = surface.filter(|s| {
            let age = now_s - s.time_s;
            (-1.0..=SURFACE_WIND_MAX_AGE_S).contains(&age) && s.ne_mps.iter().all(|v| v.is_finite())
        }) else {
            return self;
        };
        let share = 0.5
            * ((SURFACE_WIND_FROM_M - lowest_body_height)
                / (SURFACE_WIND_FROM_M - SURFACE_WIND_HALF_M))
                .clamp(0.0, 1.0);
        let ne = [0, 1].map(|k| self.ne_mps[k] + share * (surface.ne_mps[k] - self.ne_mps[k]));
        Self {
            ne_mps: ne,
            speed_mps: ne[0].hypot(ne[1]),
            ..self
        }
    }
}

/// Direction a horizontal wind (north, east; the air's velocity) blows from, degrees 0…360.
pub(super) fn wind_from_deg(wind_ne: [f64; 2]) -> f64 {
    (-wind_ne[1])
        .atan2(-wind_ne[0])
        .to_degrees()
        .rem_euclid(360.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guidance::spiral::Spiral;
    use crate::guidance::{GuidanceConfig, Plan};
    use crate::mission::GuidancePhase;
    use crate::pointmass::PointMass;
    use nalgebra::Vector3;

    #[test]
    fn the_surface_wind_counts_below_the_pattern_and_half_near_the_ground() {
        let aloft = WindNow {
            measured_ne_mps: [-3.0, 0.0],
            ne_mps: [-3.0, 0.0],
            speed_mps: 3.0,
            known: true,
        };
        let ground = SurfaceWind {
            ne_mps: [-1.0, 0.0],
            time_s: 100.0,
        };
        let at = |height: f64, now: f64| aloft.toward_surface(Some(&ground), height, now);
        assert_eq!(at(400.0, 110.0).ne_mps, aloft.ne_mps);
        assert!((at(175.0, 110.0).ne_mps[0] + 2.5).abs() < 1e-9);
        assert!((at(50.0, 110.0).ne_mps[0] + 2.0).abs() < 1e-9);
        assert!((at(50.0, 110.0).speed_mps - 2.0).abs() < 1e-9);
        // The reach check keeps the estimator's wind; a stale surface wind is not used.
        assert_eq!(at(50.0, 110.0).measured_ne_mps, aloft.measured_ne_mps);
        assert_eq!(
            at(50.0, 100.0 + SURFACE_WIND_MAX_AGE_S + 1.0).ne_mps,
            aloft.ne_mps
        );
        assert_eq!(aloft.toward_surface(None, 50.0, 110.0).ne_mps, aloft.ne_mps);
    }

    /// Regression (Monte Carlo seed 2, run 730): eight seconds after release the estimator's
    /// wind was 4 m/s off with a small uncertainty; guidance committed to a downwind leg on
    /// that wind's axis at once, flew it across the real wind and landed 64 m short.
    #[test]
    fn energy_decisions_wait_until_the_wind_estimate_has_settled() {
        let config = GuidanceConfig::default();
        let plan = Plan {
            target_ned_m: Vector3::zeros(),
            ..Plan::default()
        };
        let mut spiral = Spiral::new();
        spiral.force_phase(GuidancePhase::Approximation);
        // Low and far: short of height, whatever the wind.
        let wind = Vector3::new(-2.0, -3.0, 0.0);
        let mut first_change = None;
        for k in 0..80 {
            let t = 0.25 * k as f64;
            let mut est =
                PointMass::new(t, Vector3::new(250.0, 150.0, -120.0), 2.0).estimate(&wind);
            est.wind_sigma_mps = Vector3::new(0.3, 0.3, 0.3);
            let (_, change) = spiral.update(&config, &plan, &est, 1.2);
            if change.is_some() && first_change.is_none() {
                first_change = Some(t);
            }
        }
        let t = first_change.expect("guidance decides once the wind has settled");
        assert!(
            (WIND_SETTLE_S..WIND_SETTLE_S + 0.5).contains(&t),
            "first decision at {t} s"
        );
    }
}
