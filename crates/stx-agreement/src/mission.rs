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

/// One mission to fly.
#[derive(Debug, Clone)]
pub struct MissionSpec {
    /// The mission (its seed included).
    pub mission: MissionConfig,
    /// The dispersion set's name and contents; `None`: the nominal vehicle and sensors.
    pub dispersions: Option<(String, Dispersions)>,
    /// Mission time per station time.
    pub speed: f64,
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
    loop {
        pair.step()?;
        if let Some(state) = pair.state() {
            samples.push(Sample::compare(state, TruthSample::of(pair.drone()), &site));
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
        },
        &samples,
        landing,
        station_miss_m,
        pair.predictions(),
    ))
}
