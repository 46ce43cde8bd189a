//! One instant: what the station publishes (its `state`, the message every page draws from)
//! against the truth. Positions are compared in the drone's frame (north, east of its launch
//! site, m): the station's latitudes and longitudes are converted with the mission's site.

use nalgebra::Vector3;
use stx_gnc::geo::LocalFrame;
use stx_gnc::mission::{FlightMode, FlightStage, GuidancePhase};
use stx_station::messages::StateMsg;

use crate::truth::TruthSample;

/// Snake-case name of a mission enum as the `state` message spells it.
pub fn snake<T: serde::Serialize + std::fmt::Debug>(v: T) -> String {
    serde_json::to_value(&v)
        .ok()
        .and_then(|j| j.as_str().map(String::from))
        .unwrap_or_else(|| format!("{v:?}"))
}

/// The station's picture against the truth at one instant.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    /// The truth.
    pub truth: TruthSample,
    /// The stage the station shows, as it spells it (`None`: none shown).
    pub stage: Option<String>,
    /// The mode of the station's guidance.
    pub mode: Option<String>,
    /// The station's guidance phase.
    pub phase: Option<String>,
    /// How far the station's target is from the drone's, m; `None` when either has none.
    pub target_error_m: Option<f64>,
    /// The drone has a target and the station shows none (or the reverse).
    pub target_missing: bool,
    /// The station's final-approach course minus the drone's, degrees in −180…180, while the
    /// drone flies a spiral and the station shows a pattern.
    pub final_course_error_deg: Option<f64>,
    /// While the drone flies a spiral, the station shows no pattern.
    pub final_course_missing: bool,
    /// The replica's learned main-line trim minus the drone's, m (see
    /// [`Sample::with_replica_trim`]); `None` before it is set.
    pub trim_error_m: Option<f64>,
    /// The station's planned landing (north, east), m.
    pub planned_ne_m: Option<[f64; 2]>,
    /// Seconds the station's planned landing says are left.
    pub planned_time_to_land_s: Option<f64>,
    /// The station's wind estimate minus the true wind at the drone, horizontal, m/s.
    pub wind_error_mps: Option<f64>,
    /// The station's estimated position minus the truth, horizontal, m.
    pub position_error_m: Option<f64>,
}

impl Sample {
    /// `state` against `truth`, positions through `site`.
    pub fn compare(state: &StateMsg, truth: TruthSample, site: &LocalFrame) -> Self {
        let ne = |lat: f64, lon: f64| {
            let p = site.to_ned(lat, lon, site.alt_msl_m);
            [p.x, p.y]
        };
        let guidance = state.guidance.as_ref();
        let station_target = guidance
            .and_then(|g| g.target.as_ref())
            .map(|t| ne(t.lat_deg, t.lon_deg));
        let target_error_m = match (station_target, truth.target_ne_m) {
            (Some(s), Some(t)) => Some(distance(s, t)),
            _ => None,
        };
        let pattern = guidance.and_then(|g| g.pattern.as_ref());
        let final_course_error_deg = match (pattern, truth.final_course_rad) {
            (Some(p), Some(t)) => Some(angle_deg(p.final_course_deg - t.to_degrees())),
            _ => None,
        };
        let planned = state.prediction.as_ref().and_then(|p| p.planned.as_ref());
        let estimate = state.estimate.as_ref();
        Self {
            stage: state.mission.stage.clone(),
            mode: guidance.map(|g| g.mode.clone()),
            phase: guidance.map(|g| g.phase.clone()),
            target_error_m,
            target_missing: station_target.is_some() != truth.target_ne_m.is_some(),
            final_course_error_deg,
            final_course_missing: truth.final_course_rad.is_some() && pattern.is_none(),
            trim_error_m: None,
            planned_ne_m: planned.map(|p| ne(p.lat_deg, p.lon_deg)),
            planned_time_to_land_s: planned.map(|p| p.time_to_land_s),
            wind_error_mps: estimate.map(|e| {
                (e.wind_ned_mps[0] - truth.wind_ned_mps.x)
                    .hypot(e.wind_ned_mps[1] - truth.wind_ned_mps.y)
            }),
            position_error_m: estimate.map(|e| {
                let p: Vector3<f64> = site.to_ned(e.lat_deg, e.lon_deg, e.alt_msl_m);
                (p.x - truth.position_ned_m.x).hypot(p.y - truth.position_ned_m.y)
            }),
            truth,
        }
    }

    /// With the replica's learned main-line trim, `trim_m`. The station does not publish it,
    /// but everything the replica plans and predicts flies with it: a replica updated at other
    /// instants than the drone's guidance learns another trim, and its predicted landing drifts
    /// from the drone's without any phase or course disagreeing.
    pub fn with_replica_trim(mut self, trim_m: f64) -> Self {
        self.trim_error_m = Some(trim_m - self.truth.trim_m);
        self
    }

    /// The station shows the drone's stage.
    pub fn stage_agrees(&self) -> bool {
        self.stage.as_deref() == Some(snake(self.truth.stage).as_str())
    }

    /// The station's guidance flies the drone's mode.
    pub fn mode_agrees(&self) -> bool {
        self.mode.as_deref() == Some(snake(self.truth.mode).as_str())
    }

    /// The station's guidance phase is the drone's.
    pub fn phase_agrees(&self) -> bool {
        self.phase.as_deref() == Some(snake(self.truth.phase).as_str())
    }

    /// The drone flies under its parafoil (steered or not).
    pub fn under_parafoil(&self) -> bool {
        self.truth.stage == FlightStage::Parafoil
    }

    /// The drone flies a spiral landing under its parafoil, before the ground.
    pub fn spiral_flying(&self) -> bool {
        self.under_parafoil()
            && self.truth.mode == FlightMode::SpiralLanding
            && self.truth.phase != GuidancePhase::Landed
    }
}

/// Distance between two (north, east) points, m.
pub fn distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// An angle difference brought into −180…180, degrees.
pub fn angle_deg(d: f64) -> f64 {
    (d + 180.0).rem_euclid(360.0) - 180.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angle_differences_wrap_to_the_short_way() {
        assert!((angle_deg(359.0 - 1.0) - -2.0).abs() < 1e-9);
        assert!((angle_deg(1.0 - 359.0) - 2.0).abs() < 1e-9);
        assert!((angle_deg(90.0) - 90.0).abs() < 1e-9);
    }

    #[test]
    fn enums_are_spelled_as_the_state_message_spells_them() {
        assert_eq!(snake(GuidancePhase::FinalApproach), "final_approach");
        assert_eq!(snake(FlightStage::RoundChute), "round_chute");
        assert_eq!(snake(FlightMode::SpiralLanding), "spiral_landing");
    }
}
