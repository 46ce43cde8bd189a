//! The live reachable footprint: the ground the stack can still reach from where it is, with
//! the probability of reaching each point given what is uncertain (issue 15 item 1), and the
//! keep-out zones that ground overlaps (item 2). The station refreshes it every few seconds
//! during the descent and the map draws its 50 % and 95 % contours.
//!
//! # Model
//!
//! Through the air mass the parafoil flies at its airspeed `v` and sinks at `s`, whatever its
//! heading; over the ground it also drifts with the wind. Flying one heading at brake `b` from
//! height `h` it covers `R_b = ∫ v_b/s_b dz` through the air while the air carries it
//! `W_b = ∫ w(z)/s_b dz`; any other heading covers the same distance through the air, so the
//! touchdowns at that brake fill the circle of radius `R_b` about the start plus `W_b`, and
//! its inside is reached by spending the surplus in turns (as the spiral guidance does). Braking
//! lowers both speeds: a longer descent drifts further, so in strong wind the discs of the
//! brake settings differ and the reachable ground is their union (one disc per entry of the
//! glide table; a brake changed in flight mixes them, which their union approximates). The
//! reach is the point-mass's ([`crate::pointmass`]) in closed form, layer by layer through the
//! wind field and the atmosphere's density, and it costs microseconds per draw.
//!
//! Guidance ends every landing with a final approach into the wind from about 150 m up
//! (`GNC_NOTES.md`: "the 156 m a final needs"), so the footprint does too: the descent is
//! split at `reserve_height_m`. Above it the vehicle may fly anywhere within its still-air
//! reach of the drifting air mass (less `edge_margin_m` for the turns towards the point and
//! onto the final); below it, it flies straight into the wind along the final, at any brake
//! between released and full, and lands on the point. So the reachable points are the discs of
//! final starts moved upwind by the final's run through the air and downwind by its drift:
//! a point downwind costs the final's run twice (out past it and back), a point upwind none.
//! In calm air (under 0.5 m/s over the final) the final may point anywhere and the disc keeps
//! its whole still-air reach. The reserve and margin are settings, checked against the 14-DOF
//! model with guidance in the loop (`crates/stx-sim/tests/sim/footprint_against_full_model.rs`).
//!
//! # Uncertainty
//!
//! Each of `draws` draws disperses the start position (the estimate's σ), the wind by a
//! constant offset over the whole descent (the estimate's σ and `extra_wind_sigma_mps` in
//! quadrature: a bias, the part of the wind error that does not average out on the way down),
//! and the airspeed and sink rate by the configured fractions. A cell's probability is the
//! fraction of draws reaching its centre, and the contours at 50 % and 95 % are traced through
//! the grid by marching squares.
//!
//! Pure: the caller passes the estimate, the wind field below (a profile measured on the ascent,
//! or none for the estimate's own wind everywhere), the atmosphere and a seeded RNG.

mod config;
mod grid;
mod outline;
mod reach;
#[cfg(test)]
mod tests;

use rand::Rng;
use stx_types::atmosphere::Atmosphere;
use stx_types::wind::WindField;
use thiserror::Error;

pub use config::{FootprintConfig, FootprintConfigError, ValidFootprintConfig};
pub use grid::ProbabilityGrid;
pub use outline::{FootprintContour, FootprintPolygon, ZoneHit};
// The pre-flight plan outlines its steered region with the same counter and contours.
pub(crate) use outline::contours;
pub(crate) use reach::Disc;

use crate::estimate::Estimate;
use crate::keep_out::KeepOutZones;
use crate::performance::GlidePerformance;

/// The probability levels whose contours a footprint traces, ascending.
pub const LEVELS: [f64; 2] = [0.5, 0.95];

/// What one footprint is computed from.
#[derive(Clone, Copy)]
pub struct FootprintInput<'a> {
    /// The navigation estimate: position, height, wind and their σ.
    pub estimate: &'a Estimate,
    /// How the parafoil flies (the learned performance when the caller has one).
    pub performance: &'a GlidePerformance,
    /// The wind at the heights below (NED, origin on the ground), e.g. the profile measured on
    /// the ascent; `None` uses the estimate's wind at every height.
    pub wind_below: Option<&'a dyn WindField>,
    /// The air's density over altitude.
    pub atmosphere: &'a dyn Atmosphere,
    /// Altitude of the ground (the NED origin) above mean sea level, m.
    pub ground_altitude_msl_m: f64,
}

/// Why no footprint could be computed from an estimate.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum FootprintError {
    /// A quantity of the estimate is not finite (e.g. the wind σ before it converged).
    #[error("estimate's {quantity} is not finite: no footprint")]
    NotFinite {
        /// Which quantity.
        quantity: &'static str,
    },
    /// The vehicle is at or below touchdown height.
    #[error("height {height_m:.1} m is at or below touchdown ({touchdown_m:.1} m): no footprint")]
    OnGround {
        /// Height of the estimate, m.
        height_m: f64,
        /// Height of touchdown (the hang height), m.
        touchdown_m: f64,
    },
    /// The ground is too large for the cell size and the cell budget.
    #[error(
        "footprint needs {cells} cells, more than max_cells = {max_cells}: coarsen cell_size_m"
    )]
    TooManyCells {
        /// Cells needed.
        cells: usize,
        /// The budget.
        max_cells: usize,
    },
}

/// The reachable ground at one instant.
#[derive(Debug, Clone, PartialEq)]
pub struct Footprint {
    /// Instant of the estimate it starts from, s on the mission clock.
    pub time_s: f64,
    /// Height it starts from, m.
    pub height_m: f64,
    /// Number of draws the probabilities are fractions of.
    pub draws: usize,
    /// Centre of the undispersed vehicle's reach at released brakes (final included),
    /// (north, east) m: where it lands flying no further than its final needs.
    pub drift_point_ne_m: [f64; 2],
    /// Radius of that reach, m.
    pub nominal_radius_m: f64,
    /// Probability of reaching each cell.
    pub grid: ProbabilityGrid,
    /// The regions at [`LEVELS`], in that order.
    pub contours: Vec<FootprintContour>,
}

impl Footprint {
    /// Fraction of draws reaching `p_ne_m` (north, east, m).
    pub fn probability_at(&self, p_ne_m: [f64; 2]) -> f64 {
        self.grid.probability_at(p_ne_m)
    }

    /// The keep-out zones its 50 % and 95 % regions overlap, each with the highest level.
    pub fn zone_hits(&self, zones: &KeepOutZones) -> Vec<ZoneHit> {
        outline::zone_hits(&self.grid, zones, &LEVELS)
    }
}

/// Computes the footprint from `input` with `config`, drawing the dispersions from `rng`.
pub fn footprint(
    input: &FootprintInput,
    config: &ValidFootprintConfig,
    rng: &mut (impl Rng + ?Sized),
) -> Result<Footprint, FootprintError> {
    let config = config.get();
    check_finite(input)?;
    let height = input.estimate.height_m();
    if height <= config.hang_height_m {
        return Err(FootprintError::OnGround {
            height_m: height,
            touchdown_m: config.hang_height_m,
        });
    }
    let columns = reach::columns(input, config);
    let finite = |l: &reach::Leg| {
        l.time_s.is_finite() && l.air_m.is_finite() && l.drift_ne_m.iter().all(|v| v.is_finite())
    };
    if !columns.iter().all(|c| finite(&c.above) && finite(&c.last)) {
        return Err(FootprintError::NotFinite {
            quantity: "wind or air below",
        });
    }
    let discs: Vec<[reach::Disc; reach::DISCS]> = (0..config.draws)
        .map(|_| {
            let d = reach::draw(input, config, rng);
            reach::discs(&columns, &d, config.edge_margin_m)
        })
        .collect();
    let (origin, rows, cols) = ProbabilityGrid::extent(discs.as_flattened(), config.cell_size_m);
    let cells = rows.saturating_mul(cols);
    if cells > config.max_cells {
        return Err(FootprintError::TooManyCells {
            cells,
            max_cells: config.max_cells,
        });
    }
    let grid = ProbabilityGrid::count(
        origin,
        config.cell_size_m,
        rows,
        cols,
        discs.iter().map(|d| d.as_slice()),
    );
    let nominal = reach::discs(&columns, &reach::nominal(input), config.edge_margin_m)[0];
    Ok(Footprint {
        time_s: input.estimate.time_s,
        height_m: height,
        draws: config.draws,
        drift_point_ne_m: [nominal.centre_ne_m.x, nominal.centre_ne_m.y],
        nominal_radius_m: nominal.radius_m,
        contours: outline::contours(&grid, &LEVELS),
        grid,
    })
}

fn check_finite(input: &FootprintInput) -> Result<(), FootprintError> {
    let est = input.estimate;
    let quantities = [
        ("position", est.position_ned_m.iter().all(|v| v.is_finite())),
        (
            "position σ",
            est.position_sigma_m.iter().all(|v| v.is_finite()),
        ),
        ("wind", est.wind_ned_mps.iter().all(|v| v.is_finite())),
        ("wind σ", est.wind_sigma_mps.iter().all(|v| v.is_finite())),
        ("ground altitude", input.ground_altitude_msl_m.is_finite()),
    ];
    match quantities.into_iter().find(|(_, ok)| !ok) {
        Some((quantity, _)) => Err(FootprintError::NotFinite { quantity }),
        None => Ok(()),
    }
}
