//! What the map draws and the operators are warned of: the contours of the probability grid
//! (marching squares, the `contour` crate) as polygons in local (north, east) metres, and the
//! keep-out zones each contour's region overlaps.

use serde::{Deserialize, Serialize};

use super::grid::ProbabilityGrid;
use crate::keep_out::KeepOutZones;

/// One polygon of a contour: its boundary and holes, (north, east), m, closing point repeated.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct FootprintPolygon {
    /// Outer boundary, (north, east) m.
    pub exterior_ne_m: Vec<[f64; 2]>,
    /// Holes (ground inside the boundary reached less often), (north, east) m.
    pub holes_ne_m: Vec<Vec<[f64; 2]>>,
}

/// The ground reached with at least `level` probability.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct FootprintContour {
    /// Probability level, 0…1 (0.5 and 0.95 by default).
    pub level: f64,
    /// The region's polygons (usually one).
    pub polygons: Vec<FootprintPolygon>,
}

/// A keep-out zone overlapped by a footprint's region.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct ZoneHit {
    /// The zone's name.
    pub name: String,
    /// The highest contour level whose region overlaps it, 0…1.
    pub level: f64,
}

/// The contours of `grid` at each of `levels` (cells at or above the level inside).
pub(crate) fn contours(grid: &ProbabilityGrid, levels: &[f64]) -> Vec<FootprintContour> {
    // The crate puts value (x, y) at the square (x…x+1, y…y+1), so its coordinates are shifted
    // half a cell to put each cell's value at its centre; x runs east, y north.
    let half = 0.5 * grid.cell_size_m;
    let builder = contour::ContourBuilder::new(grid.cols, grid.rows, true)
        .x_origin(grid.origin_ne_m[1] - half)
        .y_origin(grid.origin_ne_m[0] - half)
        .x_step(grid.cell_size_m)
        .y_step(grid.cell_size_m);
    match builder.contours(&grid.probability, levels) {
        Ok(found) => found
            .into_iter()
            .map(|c| FootprintContour {
                level: c.threshold(),
                polygons: c
                    .geometry()
                    .0
                    .iter()
                    .map(|p| FootprintPolygon {
                        exterior_ne_m: p.exterior().0.iter().map(|c| [c.y, c.x]).collect(),
                        holes_ne_m: p
                            .interiors()
                            .iter()
                            .map(|h| h.0.iter().map(|c| [c.y, c.x]).collect())
                            .collect(),
                    })
                    .collect(),
            })
            .collect(),
        // Only a grid whose size disagrees with its values fails, which `count` never makes.
        Err(_) => Vec::new(),
    }
}

/// The zones of `zones` the region at or above each of `levels` overlaps, each named once
/// with the highest such level. A zone overlaps when a reached cell's centre lies in it or one
/// of its vertices lies in a reached cell (so a zone smaller than a cell is not missed).
pub(crate) fn zone_hits(
    grid: &ProbabilityGrid,
    zones: &KeepOutZones,
    levels: &[f64],
) -> Vec<ZoneHit> {
    let mut hits = Vec::new();
    for zone in &zones.zones {
        let peak = zone_peak(grid, zone);
        if let Some(level) = levels
            .iter()
            .copied()
            .filter(|&l| peak >= l)
            .reduce(f64::max)
        {
            match hits.iter_mut().find(|h: &&mut ZoneHit| h.name == zone.name) {
                Some(hit) => hit.level = hit.level.max(level),
                None => hits.push(ZoneHit {
                    name: zone.name.clone(),
                    level,
                }),
            }
        }
    }
    hits
}

/// The highest probability of a cell overlapping `zone`.
fn zone_peak(grid: &ProbabilityGrid, zone: &crate::keep_out::KeepOutZone) -> f64 {
    let vertices = zone.rings_ne_m.iter().flatten();
    let mut peak = vertices
        .clone()
        .map(|&v| grid.probability_at(v))
        .fold(0.0, f64::max);
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for v in vertices {
        for k in 0..2 {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    }
    let range = |k: usize, len: usize| {
        let first = ((lo[k] - grid.origin_ne_m[k]) / grid.cell_size_m)
            .ceil()
            .max(0.0);
        let last = ((hi[k] - grid.origin_ne_m[k]) / grid.cell_size_m)
            .floor()
            .min(len as f64 - 1.0);
        (last >= first).then_some(first as usize..=last as usize)
    };
    if let (Some(rows), Some(cols)) = (range(0, grid.rows), range(1, grid.cols)) {
        for row in rows {
            for col in cols.clone() {
                let p = grid.probability[row * grid.cols + col];
                if p > peak && zone.contains(grid.cell_centre(row, col)) {
                    peak = p;
                }
            }
        }
    }
    peak
}
