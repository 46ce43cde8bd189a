//! Landings in keep-out zones: with zones given to a campaign, guidance flies every run with
//! them as hard constraints and each run records the zone its capsule came down in; the
//! report counts those landings overall and by wind, so "how often does the payload land in
//! the pond next to the target" has a measured answer at each wind.
//!
//! The capsule (the payload) is the body that matters: it is what lands in the water. Failed
//! runs did not land anywhere and are counted apart, not as landings outside every zone.

use serde::{Deserialize, Serialize};

use super::run::RunResult;

/// Width of the wind bins of [`ZoneLandings::by_wind`], m/s.
pub const WIND_BIN_MPS: f64 = 2.0;

/// Capsule landings among some runs, and those in a zone.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ZoneCount {
    /// Lowest mean wind of the bin, m/s (inclusive).
    pub wind_from_mps: f64,
    /// Highest mean wind of the bin, m/s (exclusive).
    pub wind_to_mps: f64,
    /// Runs that landed.
    pub landings: usize,
    /// Of those, capsules down in a zone.
    pub in_zone: usize,
}

/// A run whose capsule landed in a zone.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ZoneLanding {
    /// Its index in the campaign (`--replay INDEX` flies it again).
    pub index: usize,
    /// The zone's name.
    pub zone: String,
    /// The run's mean wind, m/s.
    pub wind_mps: f64,
    /// The capsule's touchdown, north and east of the target, m.
    pub payload_ne_m: [f64; 2],
}

/// The campaign's landings in keep-out zones.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ZoneLandings {
    /// The zones flown with, by name.
    pub zones: Vec<String>,
    /// Whether guidance knew them (false: they only counted the landings).
    pub guided: bool,
    /// Runs that landed (failed runs are not landings).
    pub landings: usize,
    /// Capsules down in a zone.
    pub in_zone: usize,
    /// Runs that failed to fly (not counted above).
    pub failed: usize,
    /// The same by mean wind, in bins of [`WIND_BIN_MPS`] from calm up to the campaign's
    /// largest wind.
    pub by_wind: Vec<ZoneCount>,
    /// Every landing in a zone, by index.
    pub runs: Vec<ZoneLanding>,
}

impl ZoneLandings {
    /// The zone landings of `results` of a campaign flown with `zones` up to `wind_max_mps`.
    pub fn of(
        zones: &[String],
        guided: bool,
        results: &[RunResult],
        failed: usize,
        wind_max_mps: f64,
    ) -> Self {
        let bins = ((wind_max_mps / WIND_BIN_MPS).ceil() as usize).max(1);
        let mut by_wind: Vec<ZoneCount> = (0..bins)
            .map(|k| ZoneCount {
                wind_from_mps: k as f64 * WIND_BIN_MPS,
                wind_to_mps: (k + 1) as f64 * WIND_BIN_MPS,
                landings: 0,
                in_zone: 0,
            })
            .collect();
        let mut runs = Vec::new();
        for r in results {
            let wind = r.conditions.wind_speed_mps;
            let bin = ((wind / WIND_BIN_MPS) as usize).min(bins - 1);
            by_wind[bin].landings += 1;
            if let Some(zone) = &r.payload_zone {
                by_wind[bin].in_zone += 1;
                runs.push(ZoneLanding {
                    index: r.index,
                    zone: zone.clone(),
                    wind_mps: wind,
                    payload_ne_m: r.payload_touchdown_ne_m,
                });
            }
        }
        runs.sort_by_key(|l| l.index);
        Self {
            zones: zones.to_vec(),
            guided,
            landings: results.len(),
            in_zone: runs.len(),
            failed,
            by_wind,
            runs,
        }
    }
}
