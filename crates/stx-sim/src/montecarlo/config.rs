//! [`MonteCarloConfig`]: what a campaign flies.

use serde::Serialize;
use stx_dynamics::vehicle::Vehicle;
use stx_gnc::guidance::GuidanceConfig;
use stx_gnc::keep_out::KeepOutZones;

use crate::dispersions::Dispersions;
use crate::sensors::SensorConfig;

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
    /// Fly only this shard of the campaign's runs.
    pub shard: Option<Shard>,
    /// How each run's world differs from the one guidance assumes (every run draws its own).
    pub dispersions: Dispersions,
    /// The sensors' settings before dispersion.
    #[serde(skip)]
    pub sensors: SensorConfig,
    /// The stack every run flies (the truth), before its dispersions are drawn around it.
    #[serde(skip)]
    pub vehicle: Vehicle,
    /// Where [`Self::vehicle`] came from (a vehicle file, as the report names it); `None`: the
    /// shipped STRAPLEX stack.
    pub vehicle_name: Option<String>,
    /// Guidance settings.
    #[serde(skip)]
    pub guidance: GuidanceConfig,
    /// The vehicle file whose steady glide `guidance.performance` was trimmed from, as the
    /// report names it; `None`: guidance plans with the table it was given (by default the
    /// shipped stack's). Only a name: setting it does not change the table.
    pub guidance_vehicle_name: Option<String>,
    /// Keep-out zones in the target's frame (`LocalFrame::default()`): guidance keeps out of
    /// them, and the report counts the capsules that land in one.
    #[serde(skip)]
    pub keep_out: KeepOutZones,
    /// Whether guidance is given [`Self::keep_out`] (false: the zones only count the landings
    /// in them, to measure what keeping out of them is worth).
    pub keep_out_guided: bool,
    /// Whether a ground anemometer by the target ([`crate::anemometer`], its default settings)
    /// reports the surface wind to guidance.
    pub anemometer: bool,
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
            shard: None,
            dispersions: Dispersions::nominal(),
            sensors: SensorConfig::default(),
            vehicle: Vehicle::straplex(),
            vehicle_name: None,
            guidance: GuidanceConfig::default(),
            guidance_vehicle_name: None,
            keep_out: KeepOutZones::default(),
            keep_out_guided: true,
            anemometer: false,
        }
    }
}

/// Shard `index` (1-based) of `count`: the runs whose index is `index − 1` modulo `count`, so
/// that every shard gets easy and hard runs alike.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
pub struct Shard {
    /// Which shard, 1…count.
    pub index: usize,
    /// How many shards.
    pub count: usize,
}

impl Shard {
    /// Parses `K/N` (1 ≤ K ≤ N).
    pub fn parse(text: &str) -> Result<Self, String> {
        let bad = || format!("shard `{text}` is not K/N with 1 ≤ K ≤ N");
        let (k, n) = text.split_once('/').ok_or_else(bad)?;
        let (index, count) = (
            k.trim().parse::<usize>().map_err(|_| bad())?,
            n.trim().parse::<usize>().map_err(|_| bad())?,
        );
        if index == 0 || index > count {
            return Err(bad());
        }
        Ok(Self { index, count })
    }

    /// Whether run `run` belongs to this shard.
    pub fn owns(&self, run: usize) -> bool {
        run % self.count == self.index - 1
    }
}

impl MonteCarloConfig {
    /// The run indices this configuration flies, in order.
    pub fn indices(&self) -> Vec<usize> {
        match self.only_run {
            Some(only) => vec![only],
            None => (0..self.runs)
                .filter(|i| self.shard.is_none_or(|s| s.owns(*i)))
                .collect(),
        }
    }
}
