//! A campaign over many machines: each flies a [`Shard`](super::Shard) of the runs and writes a
//! [`CampaignPart`]; [`merge`] checks the parts belong to one campaign and cover it exactly, and
//! assembles the report one machine would have given (only the wall time differs: the merged
//! report's is the sum over the parts, the CPU time the campaign took).

use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::config::Shard;
use super::report::{CampaignHeader, MonteCarloReport};
use super::run::RunResult;

/// One shard's runs, as `stx montecarlo --shard K/N --out FILE` writes them.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CampaignPart {
    /// The campaign.
    pub campaign: CampaignHeader,
    /// Which shard.
    pub shard: Shard,
    /// Its runs that landed.
    pub results: Vec<RunResult>,
    /// Its runs that failed, with why.
    pub failed_runs: Vec<(usize, String)>,
    /// Wall time of the shard, s.
    pub wall_time_s: f64,
}

impl CampaignPart {
    /// The part of a report flown with `shard`.
    pub fn of(report: MonteCarloReport, shard: Shard) -> Self {
        Self {
            campaign: report.campaign,
            shard,
            results: report.results,
            failed_runs: report.failed_runs,
            wall_time_s: report.wall_time_s,
        }
    }
}

/// Why parts could not be merged.
#[derive(Debug, Error, PartialEq)]
pub enum MergeError {
    /// Nothing to merge.
    #[error("no parts to merge")]
    Empty,
    /// A part is of another campaign.
    #[error(
        "part {part} is of another campaign (seed, runs, winds, release or dispersions differ)"
    )]
    OtherCampaign {
        /// Its position among the parts given, from 1.
        part: usize,
    },
    /// Shards are missing or given twice.
    #[error("shards of {count} given: {given:?}; each of 1…{count} must be given once")]
    Coverage {
        /// How many shards the campaign was split into.
        count: usize,
        /// The shard numbers given, sorted.
        given: Vec<usize>,
    },
    /// A run is in the wrong shard or missing: a part was edited or truncated.
    #[error("run {run} is missing or does not belong where it was found")]
    Runs {
        /// The first run that is wrong.
        run: usize,
    },
}

/// Merges the parts of one campaign into its report.
pub fn merge(parts: Vec<CampaignPart>) -> Result<MonteCarloReport, MergeError> {
    let first = parts.first().ok_or(MergeError::Empty)?;
    let campaign = first.campaign.clone();
    let count = first.shard.count;
    for (k, p) in parts.iter().enumerate() {
        if p.campaign != campaign {
            return Err(MergeError::OtherCampaign { part: k + 1 });
        }
    }
    let mut given: Vec<usize> = parts
        .iter()
        .map(|p| {
            if p.shard.count == count {
                p.shard.index
            } else {
                0
            }
        })
        .collect();
    given.sort_unstable();
    if given != (1..=count).collect::<Vec<_>>() {
        return Err(MergeError::Coverage { count, given });
    }
    let mut results = Vec::new();
    let mut failed_runs = Vec::new();
    let mut wall_time_s = 0.0;
    for p in parts {
        let shard = p.shard;
        if let Some(r) = p.results.iter().find(|r| !shard.owns(r.index)) {
            return Err(MergeError::Runs { run: r.index });
        }
        if let Some((run, _)) = p.failed_runs.iter().find(|(i, _)| !shard.owns(*i)) {
            return Err(MergeError::Runs { run: *run });
        }
        results.extend(p.results);
        failed_runs.extend(p.failed_runs);
        wall_time_s += p.wall_time_s;
    }
    results.sort_by_key(|r| r.index);
    failed_runs.sort_by_key(|(i, _)| *i);
    let mut flown: Vec<usize> = results
        .iter()
        .map(|r| r.index)
        .chain(failed_runs.iter().map(|(i, _)| *i))
        .collect();
    flown.sort_unstable();
    if let Some(run) = (0..campaign.campaign_runs).find(|i| flown.get(*i) != Some(i)) {
        return Err(MergeError::Runs { run });
    }
    if flown.len() != campaign.campaign_runs {
        return Err(MergeError::Runs {
            run: campaign.campaign_runs,
        });
    }
    Ok(MonteCarloReport::assemble(
        campaign,
        results,
        failed_runs,
        wall_time_s,
    ))
}
