//! The region steering reaches, from the samples' reach discs ([`ReachDisc`]): the ground that
//! the discs of enough samples cover, outlined as one polygon for the map.
//!
//! Each point's share is the fraction of discs covering it, counted on a grid of square cells
//! ([`REGION_CELLS`] across the discs' extent, so a plan of any size costs the same) by the
//! footprint's own counter, and the outline is the footprint's marching-squares contour.
//!
//! The level is relative to the best point's share, not a fixed probability: before launch the
//! wind over a two-hour flight moves the air mass further than the parafoil glides (a 1-σ of
//! 20 km against a 5-km glide from the station's defaults), so no point is reached by half the
//! samples and a 50 % region would be empty. The region holds the ground reached by at least
//! `share_of_best` times the best point's share; with every sample alike (no spread) the best
//! share is 1 and the region at ½ is the glide disc itself. Both shares are reported, so the
//! page says what the region stands for.

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};

use super::ReachDisc;
use crate::footprint::{Disc, ProbabilityGrid, contours};

/// Cells across the larger side of the discs' extent.
pub const REGION_CELLS: f64 = 160.0;

/// The ground steering reaches in enough of the samples.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct SteeredRegion {
    /// Fraction of the samples that reach each point of the region, at least, 0…1.
    pub probability: f64,
    /// Fraction of the samples that reach the best-reached point, 0…1: the best a target can do.
    pub best_probability: f64,
    /// Outline (north, east), m, its first point repeated at the end; the largest piece if the
    /// region falls apart (samples in separate clusters); empty if no sample reaches anywhere.
    pub outline_ne_m: Vec<[f64; 2]>,
}

/// The region the discs of at least `share_of_best` times the best point's share of `discs`
/// cover (see the module doc); `share_of_best` in (0, 1].
pub(crate) fn steered_region(discs: &[ReachDisc], share_of_best: f64) -> SteeredRegion {
    let empty = SteeredRegion {
        probability: 0.0,
        best_probability: 0.0,
        outline_ne_m: Vec::new(),
    };
    let discs: Vec<Disc> = discs
        .iter()
        .map(|d| Disc {
            centre_ne_m: Vector2::from(d.centre_ne_m),
            radius_m: d.radius_m,
        })
        .collect();
    let (lo, hi) = ProbabilityGrid::bounds(&discs);
    let span = (hi - lo).max();
    if !(span.is_finite() && span > 0.0) {
        return empty;
    }
    let cell = span / REGION_CELLS;
    let (origin, rows, cols) = ProbabilityGrid::extent(&discs, cell);
    let grid = ProbabilityGrid::count(
        origin,
        cell,
        rows,
        cols,
        discs.iter().map(std::slice::from_ref),
    );
    let best = grid.probability.iter().copied().fold(0.0, f64::max);
    if best <= 0.0 {
        return empty;
    }
    let level = share_of_best * best;
    let outline = contours(&grid, &[level])
        .into_iter()
        .flat_map(|c| c.polygons)
        .map(|p| p.exterior_ne_m)
        .max_by(|a, b| area(a).total_cmp(&area(b)))
        .unwrap_or_default();
    SteeredRegion {
        probability: level,
        best_probability: best,
        outline_ne_m: outline,
    }
}

/// Area enclosed by `ring` (either orientation), m².
fn area(ring: &[[f64; 2]]) -> f64 {
    let twice: f64 = ring
        .iter()
        .zip(ring.iter().cycle().skip(1))
        .map(|(a, b)| a[0] * b[1] - b[0] * a[1])
        .sum();
    0.5 * twice.abs()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fraction of `discs` covering `p`, counted exactly.
    fn share(discs: &[ReachDisc], p: [f64; 2]) -> f64 {
        discs.iter().filter(|d| d.contains(p)).count() as f64 / discs.len() as f64
    }

    #[test]
    fn discs_spread_wider_than_they_reach_still_give_a_region_with_area() {
        // A pre-flight plan from the pad: the samples' air masses spread over 40 km, each
        // glide reaches 5 km, so no point is reached by half of them (the old outline, drawn
        // from the mean centre, was that centre 72 times).
        let discs: Vec<ReachDisc> = (0..400)
            .map(|i| ReachDisc {
                centre_ne_m: [
                    f64::from(i % 20) * 2000.0 - 19_000.0,
                    f64::from(i / 20) * 2000.0 - 19_000.0,
                ],
                radius_m: 5000.0,
            })
            .collect();
        let region = steered_region(&discs, 0.5);
        let outline = &region.outline_ne_m;
        let mut distinct: Vec<[f64; 2]> = Vec::new();
        for q in outline {
            if !distinct
                .iter()
                .any(|d| (d[0] - q[0]).hypot(d[1] - q[1]) < 1.0)
            {
                distinct.push(*q);
            }
        }
        assert!(distinct.len() >= 3, "{} distinct vertices", distinct.len());
        // About 20 discs of 400 reach any one point of the middle.
        assert!(
            (0.03..0.08).contains(&region.best_probability),
            "{region:?}"
        );
        assert!((region.probability - 0.5 * region.best_probability).abs() < 1e-12);
        // The middle of the spread is inside and reached that often; the region spans most
        // of the 38-km square of centres, and a point 5 km beyond its corner is out.
        assert!(share(&discs, [0.0, 0.0]) >= region.probability);
        let a = area(outline);
        assert!(a > 25.0e3 * 25.0e3 && a < 48.0e3 * 48.0e3, "{a} m²");
        let inside = |p: [f64; 2]| {
            let mut odd = false;
            for (a, b) in outline.iter().zip(outline.iter().cycle().skip(1)) {
                if (a[1] > p[1]) != (b[1] > p[1])
                    && p[0] < a[0] + (b[0] - a[0]) * (p[1] - a[1]) / (b[1] - a[1])
                {
                    odd = !odd;
                }
            }
            odd
        };
        assert!(inside([0.0, 0.0]) && inside([12_000.0, -12_000.0]));
        assert!(!inside([24_000.0, 24_000.0]));
        assert!(share(&discs, [24_000.0, 24_000.0]) < region.probability);
    }

    #[test]
    fn alike_samples_give_their_glide_disc_at_one_half() {
        let disc = ReachDisc {
            centre_ne_m: [3000.0, -1000.0],
            radius_m: 4000.0,
        };
        let region = steered_region(&[disc; 30], 0.5);
        assert_eq!((region.probability, region.best_probability), (0.5, 1.0));
        let cell = 8000.0 / REGION_CELLS;
        for q in &region.outline_ne_m {
            let r = (q[0] - 3000.0).hypot(q[1] + 1000.0);
            assert!((r - 4000.0).abs() <= cell, "{q:?} at {r} m");
        }
        assert!(region.outline_ne_m.len() > 100);
    }

    #[test]
    fn no_reach_gives_no_region() {
        let disc = ReachDisc {
            centre_ne_m: [0.0, 0.0],
            radius_m: 0.0,
        };
        assert!(steered_region(&[disc; 3], 0.5).outline_ne_m.is_empty());
    }
}
