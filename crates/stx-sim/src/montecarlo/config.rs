//! [`MonteCarloConfig`]: what a campaign flies.

use serde::Serialize;
use stx_gnc::guidance::GuidanceConfig;

/// What to run.
#[derive(Debug, Clone, Serialize)]
pub struct MonteCarloConfig {
    /// Number of runs.
    pub runs: usize,
    /// Seed of the whole campaign.
    pub seed: u64,
    /// Largest mean wind speed drawn, m/s.
    pub wind_max_mps: f64,
    /// Release height above the target, m.
    pub altitude_m: f64,
    /// Release points are drawn uniformly within this distance of the target, m.
    pub release_radius_m: f64,
    /// Whether guidance flares (a campaign without it measures what the flare is worth).
    pub flare: bool,
    /// Worker threads.
    pub threads: usize,
    /// Fly only this run (by index), keeping its phase events and track: replays one run of a
    /// campaign exactly, since its conditions depend only on the seed and the index.
    pub only_run: Option<usize>,
    /// Guidance settings.
    #[serde(skip)]
    pub guidance: GuidanceConfig,
}

impl Default for MonteCarloConfig {
    fn default() -> Self {
        Self {
            runs: 100,
            seed: 1,
            wind_max_mps: 4.0,
            altitude_m: 600.0,
            release_radius_m: 400.0,
            flare: true,
            threads: 2,
            only_run: None,
            guidance: GuidanceConfig::default(),
        }
    }
}
