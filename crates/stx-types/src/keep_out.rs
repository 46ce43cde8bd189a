//! Keep-out zones: the places the payload must not land on (water, a border, forest, roads,
//! people), as polygons in the mission's local frame, and the plane geometry asked of them:
//! whether a point lies in one and whether a straight leg crosses one.
//!
//! A zone is a few hundred metres to a few kilometres across, so its rings are flattened once
//! into the local north–east plane of [`LocalFrame`] (the error of that flat-Earth step is
//! centimetres at these sizes) and every later question is plane geometry: the even–odd rule
//! for inside (holes in a polygon are outside its zone), segment intersection for a leg.
//!
//! Zones reach a mission two ways: read from a GeoJSON file (`stx_gnc::keep_out`, which
//! refuses among others a ring that [`ring_crosses_itself`]) and received as a MAVLink fence
//! (`stx-link`'s plan protocol, which needs these types and not the file reader).

use crate::geo::LocalFrame;

/// One zone: a polygon in the local frame.
#[derive(Debug, Clone, PartialEq)]
pub struct KeepOutZone {
    /// Its name: a GeoJSON feature's `name` property, else `zone N` (N its index in the file).
    pub name: String,
    /// Rings as (north, east) in metres, closing point dropped: the boundary first, then holes.
    pub rings_ne_m: Vec<Vec<[f64; 2]>>,
}

impl KeepOutZone {
    /// Whether `p` (north, east, m) lies in the zone (not in one of its holes).
    pub fn contains(&self, p: [f64; 2]) -> bool {
        // Even–odd over every ring: a point in a hole crosses the boundary and the hole.
        self.rings_ne_m
            .iter()
            .filter(|ring| ring_contains(ring, p))
            .count()
            % 2
            == 1
    }

    /// The boundary's vertices (closing point dropped) as latitude, longitude in degrees, in
    /// `frame` (for the fence sent to the drone, which has no holes).
    pub fn boundary_lat_lon(&self, frame: &LocalFrame) -> Vec<[f64; 2]> {
        self.rings_ne_m.first().map_or_else(Vec::new, |ring| {
            ring.iter()
                .map(|ne| {
                    let (lat, lon, _) =
                        frame.to_geodetic(&nalgebra::Vector3::new(ne[0], ne[1], 0.0));
                    [lat, lon]
                })
                .collect()
        })
    }

    /// Whether the straight leg from `a` to `b` (north, east, m) enters the zone: an end in
    /// it, or an edge crossed.
    pub fn crossed_by(&self, a: [f64; 2], b: [f64; 2]) -> bool {
        self.contains(a)
            || self.contains(b)
            || self
                .rings_ne_m
                .iter()
                .flat_map(|ring| edges(ring))
                .any(|(c, d)| segments_cross(a, b, c, d))
    }
}

/// The zones of one mission.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct KeepOutZones {
    /// The zones, in the file's order (a MultiPolygon gives one zone per polygon).
    pub zones: Vec<KeepOutZone>,
}

impl KeepOutZones {
    /// The first zone `p` (north, east, m) lies in.
    pub fn zone_at(&self, p: [f64; 2]) -> Option<&KeepOutZone> {
        self.zones.iter().find(|z| z.contains(p))
    }

    /// The first zone the straight leg from `a` to `b` enters.
    pub fn crossed_by(&self, a: [f64; 2], b: [f64; 2]) -> Option<&KeepOutZone> {
        self.zones.iter().find(|z| z.crossed_by(a, b))
    }
}

/// A ring's edges, the closing one included.
fn edges(ring: &[[f64; 2]]) -> impl Iterator<Item = ([f64; 2], [f64; 2])> + '_ {
    ring.iter()
        .zip(ring.iter().cycle().skip(1))
        .map(|(a, b)| (*a, *b))
}

/// Even–odd ray cast towards +east.
fn ring_contains(ring: &[[f64; 2]], p: [f64; 2]) -> bool {
    let mut inside = false;
    for (a, b) in edges(ring) {
        if (a[0] > p[0]) != (b[0] > p[0]) {
            let east = a[1] + (p[0] - a[0]) / (b[0] - a[0]) * (b[1] - a[1]);
            if p[1] < east {
                inside = !inside;
            }
        }
    }
    inside
}

/// Whether two edges of an open ring (closing point dropped) that share no corner meet.
/// Inside-or-out by the even–odd rule is then no longer what the operator drew (a bow tie's middle, a loop pulled through),
/// so such a ring is refused. Repeated consecutive points (some GIS exports have them) are
/// skipped first: their zero-length edge would touch its neighbours' neighbours. The check is
/// quadratic in the corners, which a zone drawn or traced by hand keeps in the hundreds.
pub fn ring_crosses_itself(ring: &[[f64; 2]]) -> bool {
    let mut corners: Vec<[f64; 2]> = Vec::with_capacity(ring.len());
    for p in ring {
        if corners.last() != Some(p) {
            corners.push(*p);
        }
    }
    while corners.len() > 1 && corners.first() == corners.last() {
        corners.pop();
    }
    let n = corners.len();
    (0..n).any(|i| {
        // Edge i and its neighbours share a corner; the last edge neighbours the first.
        let last = if i == 0 { n.saturating_sub(1) } else { n };
        (i + 2..last).any(|j| {
            segments_cross(
                corners[i],
                corners[(i + 1) % n],
                corners[j],
                corners[(j + 1) % n],
            )
        })
    })
}

/// Whether segments `ab` and `cd` cross or touch.
fn segments_cross(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let cross = |o: [f64; 2], p: [f64; 2], q: [f64; 2]| {
        (p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0])
    };
    let (d1, d2) = (cross(c, d, a), cross(c, d, b));
    let (d3, d4) = (cross(a, b, c), cross(a, b, d));
    // Collinear segments (all four zero) would pass the sign tests even when apart; an
    // overlap along an edge is caught by the ends' `contains` instead.
    d1 * d2 <= 0.0 && d3 * d4 <= 0.0 && !(d1 == 0.0 && d2 == 0.0 && d3 == 0.0 && d4 == 0.0)
}

#[cfg(test)]
mod tests;
