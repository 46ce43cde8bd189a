//! The probability grid: square cells over local (north, east), each counting the draws whose
//! reachable discs cover its centre.
//!
//! A draw marks its discs row by row as runs of columns; the runs of the draw's discs are
//! merged (a cell counts once per draw however many brake settings reach it) and added to a
//! difference array, so a draw costs the rows its discs span, not the cells they cover.

use nalgebra::Vector2;

use super::reach::Disc;

/// Counts of reaching draws over a grid of square cells.
#[derive(Debug, Clone, PartialEq)]
pub struct ProbabilityGrid {
    /// Centre of cell (row 0, column 0), (north, east), m.
    pub origin_ne_m: [f64; 2],
    /// Side of a cell, m.
    pub cell_size_m: f64,
    /// Number of rows (north).
    pub rows: usize,
    /// Number of columns (east).
    pub cols: usize,
    /// Fraction of draws reaching each cell, row-major (row = north index).
    pub probability: Vec<f64>,
}

impl ProbabilityGrid {
    /// The south-west and north-east corners of the box holding every disc (north, east), m;
    /// infinite with no disc.
    pub(crate) fn bounds(discs: &[Disc]) -> (Vector2<f64>, Vector2<f64>) {
        let (mut lo, mut hi) = (
            Vector2::repeat(f64::INFINITY),
            Vector2::repeat(f64::NEG_INFINITY),
        );
        for d in discs {
            let r = Vector2::repeat(d.radius_m);
            lo = lo.inf(&(d.centre_ne_m - r));
            hi = hi.sup(&(d.centre_ne_m + r));
        }
        (lo, hi)
    }

    /// Rows and columns a grid needs to hold every disc with a cell of empty margin around.
    pub(crate) fn extent(discs: &[Disc], cell_size_m: f64) -> ([f64; 2], usize, usize) {
        let (lo, hi) = Self::bounds(discs);
        let origin = [lo.x - cell_size_m, lo.y - cell_size_m];
        let cells = |span: f64| (span / cell_size_m).ceil() as usize + 3;
        (origin, cells(hi.x - lo.x), cells(hi.y - lo.y))
    }

    /// Counts the draws (each a slice of discs) covering each cell.
    pub(crate) fn count<'a>(
        origin_ne_m: [f64; 2],
        cell_size_m: f64,
        rows: usize,
        cols: usize,
        draws: impl ExactSizeIterator<Item = &'a [Disc]>,
    ) -> Self {
        let n = draws.len().max(1);
        // One extra column per row holds the end of runs reaching the last column.
        let mut diff = vec![0i32; rows * (cols + 1)];
        let mut runs: Vec<(usize, usize, usize)> = Vec::new();
        for discs in draws {
            runs.clear();
            for d in discs {
                push_runs(d, origin_ne_m, cell_size_m, rows, cols, &mut runs);
            }
            runs.sort_unstable();
            let mut current: Option<(usize, usize, usize)> = None;
            for &(row, start, end) in runs.iter() {
                current = match current {
                    Some((r, s, e)) if r == row && start <= e + 1 => Some((r, s, e.max(end))),
                    Some(done) => {
                        mark(&mut diff, cols, done);
                        Some((row, start, end))
                    }
                    None => Some((row, start, end)),
                };
            }
            if let Some(done) = current {
                mark(&mut diff, cols, done);
            }
        }
        let mut probability = vec![0.0; rows * cols];
        for row in 0..rows {
            let mut running = 0i32;
            for col in 0..cols {
                running += diff[row * (cols + 1) + col];
                probability[row * cols + col] = f64::from(running) / n as f64;
            }
        }
        Self {
            origin_ne_m,
            cell_size_m,
            rows,
            cols,
            probability,
        }
    }

    /// Centre of cell (`row`, `col`), (north, east), m.
    pub fn cell_centre(&self, row: usize, col: usize) -> [f64; 2] {
        [
            self.origin_ne_m[0] + row as f64 * self.cell_size_m,
            self.origin_ne_m[1] + col as f64 * self.cell_size_m,
        ]
    }

    /// Fraction of draws reaching the cell holding `p_ne_m` (north, east, m); 0 off the grid.
    pub fn probability_at(&self, p_ne_m: [f64; 2]) -> f64 {
        let index = |v: f64, origin: f64, len: usize| {
            let i = ((v - origin) / self.cell_size_m).round();
            (i >= 0.0 && i < len as f64).then_some(i as usize)
        };
        match (
            index(p_ne_m[0], self.origin_ne_m[0], self.rows),
            index(p_ne_m[1], self.origin_ne_m[1], self.cols),
        ) {
            (Some(row), Some(col)) => self.probability[row * self.cols + col],
            _ => 0.0,
        }
    }

    /// Area of the cells reached with at least `level` probability, m².
    pub fn area_at_least(&self, level: f64) -> f64 {
        let n = self.probability.iter().filter(|&&p| p >= level).count();
        n as f64 * self.cell_size_m * self.cell_size_m
    }
}

/// The runs of columns whose cell centres lie in disc `d`, one per row it spans.
fn push_runs(
    d: &Disc,
    origin: [f64; 2],
    cell: f64,
    rows: usize,
    cols: usize,
    runs: &mut Vec<(usize, usize, usize)>,
) {
    let (cn, ce, r) = (d.centre_ne_m.x, d.centre_ne_m.y, d.radius_m);
    let first = ((cn - r - origin[0]) / cell).ceil().max(0.0) as usize;
    let last = ((cn + r - origin[0]) / cell).floor();
    if last < 0.0 {
        return;
    }
    let last = (last as usize).min(rows.saturating_sub(1));
    for row in first..=last {
        let y = origin[0] + row as f64 * cell - cn;
        let half = (r * r - y * y).max(0.0).sqrt();
        let start = ((ce - half - origin[1]) / cell).ceil().max(0.0);
        let end = ((ce + half - origin[1]) / cell).floor();
        if end < start || end < 0.0 || start >= cols as f64 {
            continue;
        }
        let end = (end as usize).min(cols.saturating_sub(1));
        runs.push((row, start as usize, end));
    }
}

fn mark(diff: &mut [i32], cols: usize, (row, start, end): (usize, usize, usize)) {
    diff[row * (cols + 1) + start] += 1;
    diff[row * (cols + 1) + end + 1] -= 1;
}
