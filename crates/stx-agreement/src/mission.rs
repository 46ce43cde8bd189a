//! One whole mission, pad to landing, with the station beside the drone: the pair flown step by
//! step, the station's state held against the truth at every control period, and the figures.

use stx_sim::dispersions::Dispersions;
use stx_sim::drone::MissionConfig;
use stx_station::config::StationConfig;

use crate::compare::Sample;
use crate::pair::{Pair, PairError};
use crate::report::{MissionName, MissionReport};
use crate::truth::{TruthLanding, TruthSample};

/// Mission time flown on after the landing, s: the station hears of it and settles.
const AFTER_LANDING_S: f64 = 10.0;

/// How the station hears the drone.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Delivery {
    /// Each control period's telemetry as it is sent, one `state` after each.
    EachPeriod,
    /// In bursts of one, three and two control periods in turn: a station loaded by its pages
    /// and predictions reads several periods' telemetry at once, as it did live at 20×.
    Bursts,
}

impl Delivery {
    /// Control periods in the burst that ends at step `n`.
    fn periods(self, n: usize) -> usize {
        match self {
            Self::EachPeriod => 1,
            Self::Bursts => [1, 3, 2][n % 3],
        }
    }

    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::EachPeriod => "each period",
            Self::Bursts => "bursts of 1-3 periods",
        }
    }
}

/// One mission to fly.
#[derive(Debug, Clone)]
pub struct MissionSpec {
    /// The mission (its seed included).
    pub mission: MissionConfig,
    /// The dispersion set's name and contents; `None`: the nominal vehicle and sensors.
    pub dispersions: Option<(String, Dispersions)>,
    /// Mission time per station time.
    pub speed: f64,
    /// How the station hears the drone.
    pub delivery: Delivery,
    /// The station's configuration.
    pub station: StationConfig,
    /// The station's keep-out zones: file name and GeoJSON text.
    pub keep_out: Option<(String, String)>,
}

/// Flies `spec` from the pad to the landing and reports the station's agreement with the truth.
pub fn fly(spec: &MissionSpec) -> Result<MissionReport, PairError> {
    let mut pair = Pair::new(
        &spec.mission,
        spec.dispersions.as_ref().map(|(_, d)| d),
        spec.station.clone(),
        spec.keep_out
            .as_ref()
            .map(|(file, text)| (file.as_str(), text.clone())),
        spec.speed,
    )?;
    let site = spec.mission.site;
    let mut samples = Vec::new();
    let mut landed_at: Option<f64> = None;
    for burst in 0.. {
        for _ in 1..spec.delivery.periods(burst) {
            pair.step_unheard()?;
        }
        pair.step()?;
        if let Some(state) = pair.state() {
            let trim_m = pair.core().replica().learned_trim_m();
            samples.push(
                Sample::compare(state, TruthSample::of(pair.drone()), &site)
                    .with_replica_trim(trim_m),
            );
        }
        if pair.landed() {
            let at = *landed_at.get_or_insert(pair.mission_s());
            if pair.mission_s() - at >= AFTER_LANDING_S {
                break;
            }
        }
    }
    let landing = TruthLanding::of(pair.drone());
    let station_miss_m = pair
        .state()
        .and_then(|s| s.mission.landing.as_ref())
        .and_then(|l| l.miss_m);
    Ok(MissionReport::new(
        MissionName {
            mission: spec.mission.name.clone(),
            seed: spec.mission.seed,
            dispersions: spec
                .dispersions
                .as_ref()
                .map_or_else(|| "none".to_string(), |(n, _)| n.clone()),
            speed: spec.speed,
            delivery: spec.delivery.name(),
        },
        &samples,
        landing,
        station_miss_m,
        pair.predictions(),
    ))
}
