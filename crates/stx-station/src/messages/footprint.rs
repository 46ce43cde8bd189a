//! The reachable footprint as the dashboard draws it (issue 15 item 1): the 50 % and 95 %
//! regions of ground the stack can still reach, as latitude/longitude rings.

use schemars::JsonSchema;
use serde::Serialize;

/// The latest reachable footprint.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct FootprintView {
    /// Mission clock when it was computed, s: the map shows it as the time of the refresh.
    pub computed_s: f64,
    /// Seconds since it was computed.
    pub age_s: f64,
    /// Old (no refresh for several periods): show it as stale.
    pub stale: bool,
    /// Height it was computed from, m above the ground.
    pub height_m: f64,
    /// Number of dispersed draws its probabilities are fractions of.
    pub draws: u32,
    /// The regions, by ascending probability level (0.5, then 0.95).
    pub contours: Vec<FootprintContourView>,
    /// The keep-out zones the regions overlap: ground the stack could land on and must not.
    pub zone_hits: Vec<FootprintZoneHit>,
}

/// A keep-out zone inside the reachable ground.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct FootprintZoneHit {
    /// The zone's name.
    pub zone: String,
    /// The highest probability level whose region overlaps it, 0…1 (0.5 or 0.95).
    pub level: f64,
}

/// The ground reached with at least `level` probability.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct FootprintContourView {
    /// Probability level, 0…1.
    pub level: f64,
    /// Polygons, each its outer ring then its holes; a ring is `[lat_deg, lon_deg]` points.
    pub polygons: Vec<Vec<Vec<[f64; 2]>>>,
}
