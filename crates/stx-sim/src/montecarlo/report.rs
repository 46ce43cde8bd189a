//! What a campaign gave: the statistics operators judge it by ([`MonteCarloReport`]) and the
//! worst runs, named so that each can be replayed.

use serde::{Deserialize, Serialize};
use stx_gnc::stats::percentile;

use super::config::MonteCarloConfig;
use super::growth::MissGrowth;
use super::run::{RunConditions, RunResult, SensorsLearned};
use super::zones::ZoneLandings;
use crate::dispersions::Dispersions;

/// A run among the worst of a campaign by its payload's miss (what the campaign's goals are
/// about), enough to replay it (`only_run`).
#[derive(Debug, Clone, Serialize)]
pub struct WorstRun {
    /// Index in the campaign.
    pub index: usize,
    /// The payload's (capsule's) miss distance, m.
    pub payload_miss_m: f64,
    /// The first contact's miss distance (the lowest body, the transponder), m.
    pub miss_m: f64,
    /// The payload's touchdown long (+) or short (−) along the upwind direction, m.
    pub long_short_m: f64,
    /// Right (+) or left (−) of it, m.
    pub left_right_m: f64,
    /// Heading at touchdown minus upwind, degrees.
    pub heading_vs_upwind_deg: f64,
    /// The payload's miss in a word: `long`, `short`, `left` or `right`, whichever component
    /// is larger.
    pub cause: &'static str,
    /// Whether guidance found the target out of reach (its miss is then the wind's and the
    /// stack's, not guidance's).
    pub unreachable: bool,
    /// The phase where its miss grew (payload misses of [`GROWTH_MISS_M`](super::GROWTH_MISS_M) or more).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub miss_grew: Option<MissGrowth>,
    /// Its conditions.
    pub conditions: RunConditions,
}

/// A miss in a word: the larger of its along-wind (`long` / `short`) and cross-wind (`right` /
/// `left`) components.
pub fn miss_in_a_word(long_short_m: f64, left_right_m: f64) -> &'static str {
    match (
        long_short_m.abs() >= left_right_m.abs(),
        long_short_m >= 0.0,
        left_right_m >= 0.0,
    ) {
        (true, true, _) => "long",
        (true, false, _) => "short",
        (false, _, true) => "right",
        (false, _, false) => "left",
    }
}

/// Median, 95th percentile, maximum and mean of a sample.
#[derive(Debug, Clone, Copy, Serialize, Default)]
pub struct Stats {
    /// Median.
    pub median: f64,
    /// 95th percentile (nearest rank).
    pub p95: f64,
    /// Largest.
    pub max: f64,
    /// Mean.
    pub mean: f64,
}

impl Stats {
    /// Statistics of `values` (NaN-free; infinities rank last).
    pub fn of(values: &[f64]) -> Self {
        if values.is_empty() {
            return Self::default();
        }
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        Self {
            median: if sorted.len() % 2 == 1 {
                sorted[sorted.len() / 2]
            } else {
                0.5 * (sorted[sorted.len() / 2 - 1] + sorted[sorted.len() / 2])
            },
            p95: percentile(&sorted, 0.95),
            max: sorted[sorted.len() - 1],
            mean: sorted.iter().sum::<f64>() / sorted.len() as f64,
        }
    }
}

/// What defines a campaign: every shard of it must agree on all of this.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CampaignHeader {
    /// Runs in the whole campaign.
    pub campaign_runs: usize,
    /// Campaign seed.
    pub seed: u64,
    /// Largest mean wind, m/s.
    pub wind_max_mps: f64,
    /// Release height above the target, m.
    pub altitude_m: f64,
    /// Release points within this distance of the target, m.
    pub release_radius_m: f64,
    /// Whether guidance flared.
    pub flare: bool,
    /// The dispersion set every run drew from.
    pub dispersions: Dispersions,
    /// The keep-out zones guidance kept out of, by name (none: flown without).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub keep_out_zones: Vec<String>,
    /// Whether guidance knew the zones (false: they only counted the landings).
    #[serde(default = "yes")]
    pub keep_out_guided: bool,
    /// Whether guidance was given a ground anemometer's surface wind.
    #[serde(default)]
    pub anemometer: bool,
    /// The vehicle file every run flew (the truth, dispersions drawn around it); absent: the
    /// shipped STRAPLEX stack.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vehicle: Option<String>,
    /// The vehicle file whose trimmed steady glide guidance planned with; absent: the table
    /// guidance ships with (the shipped stack's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub guidance_vehicle: Option<String>,
}

fn yes() -> bool {
    true
}

impl CampaignHeader {
    /// The header of `config`'s campaign.
    pub fn of(config: &MonteCarloConfig) -> Self {
        Self {
            campaign_runs: config.runs,
            seed: config.seed,
            wind_max_mps: config.wind_max_mps,
            altitude_m: config.altitude_m,
            release_radius_m: config.release_radius_m,
            flare: config.flare,
            dispersions: config.dispersions.clone(),
            keep_out_zones: config
                .keep_out
                .zones
                .iter()
                .map(|z| z.name.clone())
                .collect(),
            keep_out_guided: config.keep_out_guided,
            anemometer: config.anemometer,
            vehicle: config.vehicle_name.clone(),
            guidance_vehicle: config.guidance_vehicle_name.clone(),
        }
    }
}

/// The campaign's result (printed by `stx montecarlo --json`).
#[derive(Debug, Clone, Serialize)]
pub struct MonteCarloReport {
    /// What was flown.
    #[serde(flatten)]
    pub campaign: CampaignHeader,
    /// Runs in this report (flown or failed).
    pub runs: usize,
    /// Distance from the target at the first ground contact (the lowest body, usually the
    /// transponder), m. Failed runs count as misses beyond any landing: with any, the maximum
    /// is infinite (`null` in JSON) and the percentiles rank them last.
    pub miss_m: Stats,
    /// Distance from the target to the capsule's (the payload's) touchdown, m; failed runs
    /// count as [`Self::miss_m`] says.
    pub payload_miss_m: Stats,
    /// The capsule's vertical speed at its touchdown, m/s.
    pub payload_touchdown_vertical_speed_mps: Stats,
    /// Share of touchdowns with the heading within 30° of upwind (runs in calm air, where no
    /// upwind exists, count as into the wind).
    pub into_wind_fraction: f64,
    /// The same share with calm runs judged like the others, against the instantaneous wind
    /// (gusts included) where they touched down.
    pub into_wind_fraction_strict: f64,
    /// The share among the runs not in calm air alone (the goal's figure), against the
    /// instantaneous wind (gusts included) where they touched down.
    pub into_wind_fraction_non_calm: f64,
    /// The share among the runs not in calm air within 30° of the surface wind: the mean wind
    /// at the touchdown (gusts left out), as a windsock or weather report gives it.
    pub into_surface_wind_fraction_non_calm: f64,
    /// Runs that touched down in calm air (mean wind below [`CALM_WIND_MPS`]).
    pub calm_runs: usize,
    /// Vertical speed at touchdown, m/s.
    pub touchdown_vertical_speed_mps: Stats,
    /// RMS of the wind-estimate error from 30 s after release, over all runs, m/s.
    pub wind_estimate_rmse_mps: f64,
    /// Per-run wind-estimate RMS errors, m/s.
    pub wind_estimate_rmse_per_run_mps: Stats,
    /// The estimator's AHRS heading bias at touchdown less the truth, size of, over the runs
    /// flown with sensors, degrees.
    pub heading_bias_error_deg: Stats,
    /// The estimator's pitot scale at touchdown less the truth, size of, over the same runs.
    pub pitot_scale_error: Stats,
    /// The payload's miss over the runs guidance found the target within reach (failed runs
    /// count among them, as [`Self::miss_m`] says), m.
    pub reachable_payload_miss_m: Stats,
    /// The payload's miss over the runs guidance found the target out of reach, m.
    pub unreachable_payload_miss_m: Stats,
    /// Runs in which guidance found the target out of reach.
    pub unreachable_runs: usize,
    /// Over those runs, the distance from the best reachable point guidance first announced
    /// to the touchdown, m.
    pub unreachable_from_best_m: Stats,
    /// The same from the best reachable point announced last, m.
    pub unreachable_from_last_best_m: Stats,
    /// Of those runs, the ones that found the target within reach again and flew for it.
    pub unreachable_back_in_reach_runs: usize,
    /// Over those runs, the payload's touchdown from the point guidance chose last: the best
    /// reachable point announced last, or the target for a run back within reach, m.
    pub unreachable_payload_from_last_aim_m: Stats,
    /// Capsules landed in keep-out zones, overall and by wind (campaigns with zones only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub keep_out: Option<ZoneLandings>,
    /// Runs that failed to fly (integration error, time-out, a refused draw), with their index
    /// and reason.
    pub failed_runs: Vec<(usize, String)>,
    /// Wall-clock time, s.
    pub wall_time_s: f64,
    /// The runs with the largest misses, worst first (at most [`WORST_RUNS`]).
    pub worst: Vec<WorstRun>,
    /// Every run.
    pub results: Vec<RunResult>,
}

impl MonteCarloReport {
    /// The statistics of `results` and `failed_runs` (sorted by index) of `campaign`.
    pub fn assemble(
        campaign: CampaignHeader,
        results: Vec<RunResult>,
        failed_runs: Vec<(usize, String)>,
        wall_time_s: f64,
    ) -> Self {
        // A miss statistic ranks failed runs beyond every landing; other statistics are of
        // the landings alone.
        let miss = |f: fn(&RunResult) -> f64| {
            let values: Vec<f64> = results
                .iter()
                .map(f)
                .chain(failed_runs.iter().map(|_| f64::INFINITY))
                .collect();
            Stats::of(&values)
        };
        let of_landings =
            |f: fn(&RunResult) -> f64| Stats::of(&results.iter().map(f).collect::<Vec<_>>());
        let wind_errors: Vec<f64> = results.iter().map(|r| r.wind_estimate_rmse_mps).collect();
        let pooled = if results.is_empty() {
            0.0
        } else {
            (wind_errors.iter().map(|e| e * e).sum::<f64>() / wind_errors.len() as f64).sqrt()
        };
        let learned = |f: fn(&SensorsLearned) -> f64| {
            let values: Vec<f64> = results
                .iter()
                .filter_map(|r| r.sensors_learned.as_ref().map(|s| f(s).abs()))
                .collect();
            Stats::of(&values)
        };
        let mut by_miss: Vec<&RunResult> = results.iter().collect();
        by_miss.sort_by(|a, b| {
            b.payload_miss_m
                .total_cmp(&a.payload_miss_m)
                .then(a.index.cmp(&b.index))
        });
        let worst = by_miss
            .iter()
            .take(WORST_RUNS)
            .map(|r| WorstRun {
                index: r.index,
                payload_miss_m: r.payload_miss_m,
                miss_m: r.miss_m,
                long_short_m: r.payload_long_short_m,
                left_right_m: r.payload_left_right_m,
                heading_vs_upwind_deg: r.heading_vs_upwind_deg,
                cause: miss_in_a_word(r.payload_long_short_m, r.payload_left_right_m),
                unreachable: r.unreachable,
                miss_grew: r.miss_grew,
                conditions: r.conditions.clone(),
            })
            .collect();
        let announced = |f: fn(&RunResult) -> Option<f64>| {
            Stats::of(&results.iter().filter_map(f).collect::<Vec<_>>())
        };
        let keep_out = (!campaign.keep_out_zones.is_empty()).then(|| {
            ZoneLandings::of(
                &campaign.keep_out_zones,
                campaign.keep_out_guided,
                &results,
                failed_runs.len(),
                campaign.wind_max_mps,
            )
        });
        Self {
            keep_out,
            campaign,
            runs: results.len() + failed_runs.len(),
            miss_m: miss(|r| r.miss_m),
            payload_miss_m: miss(|r| r.payload_miss_m),
            payload_touchdown_vertical_speed_mps: of_landings(|r| {
                r.payload_touchdown_vertical_speed_mps
            }),
            into_wind_fraction: into_wind_fraction(&results, true),
            into_wind_fraction_strict: into_wind_fraction(&results, false),
            into_wind_fraction_non_calm: share(results.iter().filter(|r| !r.calm), |r| {
                r.heading_vs_upwind_deg.abs() <= INTO_WIND_DEG
            }),
            into_surface_wind_fraction_non_calm: share(results.iter().filter(|r| !r.calm), |r| {
                r.heading_vs_surface_wind_deg.abs() <= INTO_WIND_DEG
            }),
            calm_runs: results.iter().filter(|r| r.calm).count(),
            touchdown_vertical_speed_mps: of_landings(|r| r.touchdown_vertical_speed_mps),
            wind_estimate_rmse_mps: pooled,
            wind_estimate_rmse_per_run_mps: Stats::of(&wind_errors),
            heading_bias_error_deg: learned(|s| s.heading_bias_error_deg()),
            pitot_scale_error: learned(|s| s.pitot_scale_error()),
            reachable_payload_miss_m: Stats::of(
                &results
                    .iter()
                    .filter(|r| !r.unreachable)
                    .map(|r| r.payload_miss_m)
                    .chain(failed_runs.iter().map(|_| f64::INFINITY))
                    .collect::<Vec<_>>(),
            ),
            unreachable_payload_miss_m: Stats::of(
                &results
                    .iter()
                    .filter(|r| r.unreachable)
                    .map(|r| r.payload_miss_m)
                    .collect::<Vec<_>>(),
            ),
            unreachable_runs: results.iter().filter(|r| r.unreachable).count(),
            unreachable_from_best_m: announced(|r| r.from_best_reachable_m),
            unreachable_from_last_best_m: announced(|r| r.from_last_best_reachable_m),
            unreachable_back_in_reach_runs: results.iter().filter(|r| r.back_in_reach).count(),
            unreachable_payload_from_last_aim_m: announced(|r| r.payload_from_last_aim_m),
            failed_runs,
            wall_time_s,
            worst,
            results,
        }
    }
}

/// Largest angle between heading and upwind at touchdown that counts as into the wind, degrees.
pub const INTO_WIND_DEG: f64 = 30.0;

/// Share of `results` that touched down into the wind (within [`INTO_WIND_DEG`] of upwind);
/// with `calm_counts`, runs in calm air count as into the wind whatever their heading.
pub fn into_wind_fraction(results: &[RunResult], calm_counts: bool) -> f64 {
    share(results.iter(), |r| {
        (calm_counts && r.calm) || r.heading_vs_upwind_deg.abs() <= INTO_WIND_DEG
    })
}

/// Share of `runs` for which `holds`; 0 of none.
fn share<'a>(runs: impl Iterator<Item = &'a RunResult>, holds: impl Fn(&RunResult) -> bool) -> f64 {
    let (mut n, mut yes) = (0usize, 0usize);
    for r in runs {
        n += 1;
        yes += usize::from(holds(r));
    }
    if n == 0 { 0.0 } else { yes as f64 / n as f64 }
}

/// How many of the worst runs a report names.
pub const WORST_RUNS: usize = 5;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::montecarlo::run::conditions;

    fn landed(heading_vs_upwind_deg: f64, calm: bool) -> RunResult {
        RunResult {
            index: 0,
            conditions: conditions(&MonteCarloConfig::default(), 0),
            vehicle_draw: Default::default(),
            wind_shape: crate::dispersions::WindShape::draw(
                &Dispersions::nominal(),
                &mut <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(0),
            ),
            miss_m: 1.0,
            heading_vs_upwind_deg,
            heading_vs_surface_wind_deg: heading_vs_upwind_deg,
            calm,
            touchdown_vertical_speed_mps: 2.5,
            payload_miss_m: 1.0,
            miss_grew: None,
            learned: None,
            payload_touchdown_vertical_speed_mps: 2.0,
            payload_touchdown_ne_m: [1.0, 0.0],
            payload_zone: None,
            payload_after_first_contact_s: 2.0,
            wind_estimate_rmse_mps: 0.2,
            sensors_learned: None,
            unreachable: false,
            best_reachable_ne_m: None,
            from_best_reachable_m: None,
            last_best_reachable_ne_m: None,
            from_last_best_reachable_m: None,
            back_in_reach: false,
            payload_from_last_aim_m: None,
            flight_time_s: 200.0,
            long_short_m: 0.0,
            left_right_m: 0.0,
            payload_long_short_m: 0.0,
            payload_left_right_m: 0.0,
            events: Vec::new(),
            track: Vec::new(),
        }
    }

    #[test]
    fn zone_landings_are_counted_by_wind_with_failed_runs_apart() {
        let run = |index: usize, wind: f64, zone: Option<&str>| {
            let mut r = landed(0.0, false);
            r.index = index;
            r.conditions.wind_speed_mps = wind;
            r.payload_zone = zone.map(str::to_string);
            r
        };
        let results = vec![
            run(3, 0.5, None),
            run(1, 1.9, Some("Pond")),
            run(2, 2.0, None),
            run(4, 5.5, Some("Road")),
        ];
        let mut header = CampaignHeader::of(&MonteCarloConfig {
            wind_max_mps: 6.0,
            ..MonteCarloConfig::default()
        });
        header.keep_out_zones = vec!["Pond".into(), "Road".into()];
        let report = MonteCarloReport::assemble(header, results, vec![(0, "x".into())], 1.0);
        let z = report.keep_out.expect("zones counted");
        assert_eq!((z.landings, z.in_zone, z.failed), (4, 2, 1));
        let bins: Vec<(f64, usize, usize)> = z
            .by_wind
            .iter()
            .map(|b| (b.wind_from_mps, b.landings, b.in_zone))
            .collect();
        assert_eq!(bins, vec![(0.0, 2, 1), (2.0, 1, 0), (4.0, 1, 1)]);
        let named: Vec<(usize, &str)> = z.runs.iter().map(|l| (l.index, l.zone.as_str())).collect();
        assert_eq!(named, vec![(1, "Pond"), (4, "Road")]);
        // Without zones, no count at all.
        let plain = CampaignHeader::of(&MonteCarloConfig::default());
        assert!(
            MonteCarloReport::assemble(plain, vec![], vec![], 0.0)
                .keep_out
                .is_none()
        );
    }

    #[test]
    fn reachable_and_unreachable_runs_are_reported_apart_and_each_worst_run_named() {
        // The first contact (the transponder) lands elsewhere, in the reverse order of misses
        // and on the other side: the worst runs are the payload's, named by its touchdown.
        let run = |index, miss: f64, unreachable, long_short_m: f64, left_right_m: f64| RunResult {
            index,
            miss_m: 50.0 - miss,
            payload_miss_m: miss,
            unreachable,
            long_short_m: -long_short_m,
            left_right_m: -left_right_m,
            payload_long_short_m: long_short_m,
            payload_left_right_m: left_right_m,
            ..landed(0.0, false)
        };
        let report = MonteCarloReport::assemble(
            CampaignHeader::of(&MonteCarloConfig::default()),
            vec![
                run(0, 4.0, false, 3.0, -2.0),
                run(1, 6.0, false, -1.0, 5.9),
                run(2, 40.0, true, -39.0, 8.0),
                run(3, 8.0, false, 2.0, -7.7),
            ],
            Vec::new(),
            0.0,
        );
        assert_eq!(report.reachable_payload_miss_m.median, 6.0);
        assert_eq!(report.reachable_payload_miss_m.max, 8.0);
        assert_eq!(report.unreachable_payload_miss_m.max, 40.0);
        let named: Vec<_> = report
            .worst
            .iter()
            .map(|w| (w.index, w.cause, w.unreachable))
            .collect();
        assert_eq!(
            named,
            vec![
                (2, "short", true),
                (3, "left", false),
                (1, "right", false),
                (0, "long", false)
            ]
        );
    }

    #[test]
    fn into_the_wind_means_within_30_degrees_of_upwind_on_either_side() {
        let runs = [
            landed(29.0, false),
            landed(-30.0, false),
            landed(31.0, false),
            landed(-179.0, false),
        ];
        assert_eq!(into_wind_fraction(&runs, true), 0.5);
        assert_eq!(into_wind_fraction(&runs, false), 0.5);
    }

    #[test]
    fn the_surface_wind_share_judges_the_non_calm_runs_against_the_mean_wind_not_the_gust() {
        // Into a gust but 40° off the mean wind, and the other way round; calm runs left out.
        let run = |gust: f64, mean: f64, calm: bool| RunResult {
            heading_vs_surface_wind_deg: mean,
            ..landed(gust, calm)
        };
        let runs = vec![
            run(10.0, 40.0, false),
            run(40.0, 10.0, false),
            run(5.0, 5.0, false),
            run(170.0, 170.0, true),
        ];
        let report = MonteCarloReport::assemble(
            CampaignHeader::of(&MonteCarloConfig::default()),
            runs,
            Vec::new(),
            0.0,
        );
        assert_eq!(report.into_surface_wind_fraction_non_calm, 2.0 / 3.0);
        assert_eq!(report.into_wind_fraction_non_calm, 2.0 / 3.0);
        let gusty_only = [run(10.0, 40.0, false), run(5.0, 5.0, false)];
        assert_eq!(
            share(gusty_only.iter(), |r| r.heading_vs_surface_wind_deg.abs()
                <= INTO_WIND_DEG),
            0.5
        );
        assert_eq!(share([].iter(), |_| true), 0.0);
    }

    #[test]
    fn a_calm_touchdown_counts_as_into_the_wind_whatever_its_heading_except_when_strict() {
        let runs = [landed(150.0, true), landed(150.0, false)];
        assert_eq!(into_wind_fraction(&runs, true), 0.5);
        assert_eq!(into_wind_fraction(&runs, false), 0.0);
        assert_eq!(into_wind_fraction(&[], true), 0.0);
    }
}

#[cfg(test)]
mod failed_run_tests {
    use super::*;

    #[test]
    fn failed_runs_count_as_the_worst_misses() {
        // Four landings and one failure: the failure ranks last.
        let mut values = vec![1.0, 2.0, 3.0, 4.0];
        values.push(f64::INFINITY);
        let s = Stats::of(&values);
        assert_eq!(s.median, 3.0);
        assert!(s.p95.is_infinite() && s.max.is_infinite());
        let report = MonteCarloReport::assemble(
            CampaignHeader::of(&MonteCarloConfig::default()),
            Vec::new(),
            vec![(3, "still flying".into())],
            0.0,
        );
        assert_eq!(report.runs, 1);
        assert!(report.miss_m.median.is_infinite());
        assert!(report.reachable_payload_miss_m.median.is_infinite());
    }
}
