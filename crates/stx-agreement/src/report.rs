//! A whole mission's agreement in figures: for each thing the station shows, the share of the
//! flight it disagreed with the truth and by how much, the landing predictions at set heights
//! against the touchdown, and the landing figures.

use serde::Serialize;
use stx_dynamics::model::Body;
use stx_gnc::mission::FlightStage;
use stx_gnc::stats::percentile;

use crate::compare::{Sample, distance};
use crate::truth::TruthLanding;

/// Heights above the ground at which the predicted landing is held against the touchdown, m.
pub const PREDICTION_HEIGHTS_M: [f64; 3] = [300.0, 100.0, 50.0];

/// A guidance phase is counted as agreeing "around a transition" when the disagreement starts
/// or ends within this long of a change of the drone's phase, s.
pub const NEAR_TRANSITION_S: f64 = 2.0;

/// How often a yes/no agreement held.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Share {
    /// Instants compared.
    pub samples: u64,
    /// Instants the station disagreed.
    pub disagreed: u64,
}

impl Share {
    fn count(&mut self, agrees: bool) {
        self.samples += 1;
        self.disagreed += u64::from(!agrees);
    }

    /// Share of the instants the station agreed, 0…1 (1 with nothing compared).
    pub fn agreed(&self) -> f64 {
        if self.samples == 0 {
            1.0
        } else {
            1.0 - self.disagreed as f64 / self.samples as f64
        }
    }
}

/// A run of consecutive instants of disagreement.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Span {
    /// Mission time it began, s.
    pub from_s: f64,
    /// How long it lasted, s.
    pub duration_s: f64,
    /// It began or ended within [`NEAR_TRANSITION_S`] of a change of the drone's phase.
    pub near_transition: bool,
}

/// The sizes of an error over the instants it was measured.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Spread {
    /// Instants measured.
    pub samples: u64,
    /// Median of the absolute error.
    pub p50: f64,
    /// 95th percentile of the absolute error.
    pub p95: f64,
    /// Largest absolute error.
    pub max: f64,
}

impl Spread {
    /// The spread of `values` (absolute values taken).
    pub fn of(values: impl IntoIterator<Item = f64>) -> Self {
        let mut v: Vec<f64> = values.into_iter().map(f64::abs).collect();
        v.sort_by(f64::total_cmp);
        if v.is_empty() {
            return Self::default();
        }
        Self {
            samples: v.len() as u64,
            p50: percentile(&v, 0.5),
            p95: percentile(&v, 0.95),
            max: v[v.len() - 1],
        }
    }
}

/// The predicted landing at one height against the touchdown.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PredictionAtHeight {
    /// Height of the drone above the ground, m.
    pub height_m: f64,
    /// Mission time the drone passed it, s.
    pub time_s: f64,
    /// The station's planned landing's distance from the drone's touchdown, m.
    pub station_error_m: Option<f64>,
    /// The drone's own prediction's distance from it, m.
    pub onboard_error_m: Option<f64>,
}

/// The landing in figures.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LandingFigures {
    /// Mission time of the first ground contact, s.
    pub time_s: f64,
    /// The body that touched first.
    pub first_body: String,
    /// Under the parafoil (else the round chute).
    pub under_parafoil: bool,
    /// The drone body's distance from the drone's target at the first contact, m.
    pub drone_miss_m: Option<f64>,
    /// The payload capsule's, m.
    pub payload_miss_m: Option<f64>,
    /// The miss the station shows, m.
    pub station_miss_m: Option<f64>,
}

/// One mission's agreement.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MissionReport {
    /// The mission's name.
    pub mission: String,
    /// Its seed.
    pub seed: u64,
    /// The dispersion set it flew.
    pub dispersions: String,
    /// Mission time per station time.
    pub speed: f64,
    /// How the station heard the drone.
    pub delivery: &'static str,
    /// Mission time flown, s.
    pub flight_s: f64,
    /// Of which under the parafoil, s.
    pub parafoil_s: f64,
    /// Landing predictions the station made.
    pub predictions: u64,
    /// The stage shown, over the whole flight.
    pub stage: Share,
    /// The mode the station's guidance flies, over the whole flight.
    pub mode: Share,
    /// The station's guidance phase, under the parafoil.
    pub phase: Share,
    /// The phase's disagreements under the parafoil.
    pub phase_spans: Vec<Span>,
    /// The target, where both have one, m.
    pub target_error_m: Spread,
    /// Instants one had a target and the other none.
    pub target_missing: u64,
    /// The final-approach course while the drone flies a spiral, degrees.
    pub final_course_error_deg: Spread,
    /// Share of the spiral's instants the station's final course was within 5°.
    pub final_course_within_5_deg: Share,
    /// The station's wind estimate against the true wind at the drone, by stage, m/s.
    pub wind_error_mps: Vec<(String, Spread)>,
    /// The station's position against the truth, under the parafoil, m.
    pub position_error_m: Spread,
    /// The replica's learned main-line trim against the drone's, under the parafoil, mm.
    pub trim_error_mm: Spread,
    /// The predicted landing at [`PREDICTION_HEIGHTS_M`].
    pub predictions_at: Vec<PredictionAtHeight>,
    /// The landing; `None` if it did not land.
    pub landing: Option<LandingFigures>,
}

/// What a mission is, for its report.
#[derive(Debug, Clone, PartialEq)]
pub struct MissionName {
    /// The mission.
    pub mission: String,
    /// Its seed.
    pub seed: u64,
    /// The dispersion set.
    pub dispersions: String,
    /// Mission time per station time.
    pub speed: f64,
    /// How the station heard the drone.
    pub delivery: &'static str,
}

impl MissionReport {
    /// The figures of a flight's `samples` (in time order), its landing and the station's
    /// miss.
    pub fn new(
        name: MissionName,
        samples: &[Sample],
        landing: Option<TruthLanding>,
        station_miss_m: Option<f64>,
        predictions: u64,
    ) -> Self {
        let mut stage = Share::default();
        let mut mode = Share::default();
        let mut phase = Share::default();
        let mut within_5 = Share::default();
        let mut target_missing = 0;
        for s in samples {
            stage.count(s.stage_agrees());
            mode.count(s.mode_agrees());
            if s.under_parafoil() {
                phase.count(s.phase_agrees());
            }
            target_missing += u64::from(s.target_missing);
            if s.spiral_flying() {
                within_5.count(s.final_course_error_deg.is_some_and(|e| e.abs() <= 5.0));
            }
        }
        let parafoil: Vec<&Sample> = samples.iter().filter(|s| s.under_parafoil()).collect();
        let wind = [
            FlightStage::Ascent,
            FlightStage::RoundChute,
            FlightStage::Parafoil,
        ]
        .iter()
        .map(|&st| {
            (
                crate::compare::snake(st),
                Spread::of(
                    samples
                        .iter()
                        .filter(|s| s.truth.stage == st)
                        .filter_map(|s| s.wind_error_mps),
                ),
            )
        })
        .collect();
        let touchdown = landing.map(|l| l.body_ne_m(Body::Drone));
        let predictions_at = PREDICTION_HEIGHTS_M
            .iter()
            .filter_map(|&h| {
                let s = parafoil.iter().find(|s| s.truth.height_m() <= h)?;
                let error = |p: Option<[f64; 2]>| Some(distance(p?, touchdown?));
                Some(PredictionAtHeight {
                    height_m: h,
                    time_s: s.truth.time_s,
                    station_error_m: error(s.planned_ne_m),
                    onboard_error_m: error(s.truth.onboard_prediction_ne_m),
                })
            })
            .collect();
        let target = samples.last().and_then(|s| s.truth.target_ne_m);
        let landing = landing.map(|l| LandingFigures {
            time_s: l.time_s,
            first_body: format!("{:?}", l.first_body).to_lowercase(),
            under_parafoil: l.under_parafoil,
            drone_miss_m: target.map(|t| distance(l.body_ne_m(Body::Drone), t)),
            payload_miss_m: target.map(|t| distance(l.body_ne_m(Body::Capsule), t)),
            station_miss_m,
        });
        Self {
            mission: name.mission,
            seed: name.seed,
            dispersions: name.dispersions,
            speed: name.speed,
            delivery: name.delivery,
            flight_s: samples.last().map_or(0.0, |s| s.truth.time_s),
            // From the first sample under the parafoil to the last: the samples' spacing is not
            // even (the pair steps the drone at its own rate).
            parafoil_s: match (parafoil.first(), parafoil.last()) {
                (Some(a), Some(b)) => b.truth.time_s - a.truth.time_s,
                _ => 0.0,
            },
            predictions,
            stage,
            mode,
            phase,
            phase_spans: phase_spans(&parafoil),
            target_error_m: Spread::of(samples.iter().filter_map(|s| s.target_error_m)),
            target_missing,
            final_course_error_deg: Spread::of(
                samples
                    .iter()
                    .filter(|s| s.spiral_flying())
                    .filter_map(|s| s.final_course_error_deg),
            ),
            final_course_within_5_deg: within_5,
            wind_error_mps: wind,
            position_error_m: Spread::of(parafoil.iter().filter_map(|s| s.position_error_m)),
            trim_error_mm: Spread::of(
                parafoil
                    .iter()
                    .filter_map(|s| s.trim_error_m.map(|e| 1000.0 * e.abs())),
            ),
            predictions_at,
            landing,
        }
    }

    /// The longest phase disagreement, s.
    pub fn longest_phase_span_s(&self) -> f64 {
        self.phase_spans
            .iter()
            .map(|s| s.duration_s)
            .fold(0.0, f64::max)
    }
}

/// The runs of phase disagreement among `samples` (under the parafoil, in time order).
fn phase_spans(samples: &[&Sample]) -> Vec<Span> {
    let changes: Vec<f64> = samples
        .windows(2)
        .filter(|w| w[0].truth.phase != w[1].truth.phase)
        .map(|w| w[1].truth.time_s)
        .collect();
    let near = |t: f64| changes.iter().any(|c| (c - t).abs() <= NEAR_TRANSITION_S);
    let mut spans = Vec::new();
    let mut start: Option<(f64, usize)> = None;
    for (i, s) in samples.iter().enumerate() {
        match (s.phase_agrees(), start) {
            (false, None) => start = Some((s.truth.time_s, i)),
            (true, Some((from_s, _))) => {
                let to_s = s.truth.time_s;
                spans.push(Span {
                    from_s,
                    duration_s: to_s - from_s,
                    near_transition: near(from_s) || near(to_s),
                });
                start = None;
            }
            _ => {}
        }
    }
    if let (Some((from_s, _)), Some(last)) = (start, samples.last()) {
        let to_s = last.truth.time_s;
        spans.push(Span {
            from_s,
            duration_s: to_s - from_s,
            near_transition: near(from_s) || near(to_s),
        });
    }
    spans
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spreads_are_of_absolute_values() {
        let s = Spread::of([-3.0, 1.0, 2.0]);
        assert_eq!((s.p50, s.max, s.samples), (2.0, 3.0, 3));
    }

    #[test]
    fn a_share_counts_disagreements() {
        let mut s = Share::default();
        for agrees in [true, true, false, true] {
            s.count(agrees);
        }
        assert_eq!(s.disagreed, 1);
        assert!((s.agreed() - 0.75).abs() < 1e-12);
    }
}
