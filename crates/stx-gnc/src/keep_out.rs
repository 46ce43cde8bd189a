//! Keep-out zones read from GeoJSON (RFC 7946) polygons into the mission's local frame.
//!
//! The zones themselves and their plane geometry (whether a point lies in one, whether a leg
//! crosses one) are [`KeepOutZone`] and [`KeepOutZones`] of `stx_types::keep_out`, re-exported
//! here: the link carries zones as a fence and needs them without this reader. The `geojson`
//! crate parses and checks the text's structure; what it leaves to its users (rings closed,
//! long enough and not crossing themselves, coordinates finite and on the globe) is checked
//! here, and a bad file is refused with the feature and the rule it breaks.

use geojson::{GeoJson, GeometryValue, PolygonType};
use thiserror::Error;

use crate::geo::LocalFrame;
use stx_types::keep_out::ring_crosses_itself;
pub use stx_types::keep_out::{KeepOutZone, KeepOutZones};

/// Why a keep-out file was refused.
#[derive(Debug, Error, PartialEq)]
pub enum KeepOutError {
    /// Not GeoJSON.
    #[error("keep-out zones are not GeoJSON: {0}")]
    Parse(String),
    /// A feature whose geometry is not an area.
    #[error("keep-out feature {feature}: a {found} is not an area (Polygon or MultiPolygon)")]
    NotAnArea {
        /// Index of the feature in the file.
        feature: usize,
        /// The geometry's type.
        found: String,
    },
    /// A ring that is not a closed polygon boundary.
    #[error("keep-out feature {feature}: ring {ring} {reason}")]
    Ring {
        /// Index of the feature in the file.
        feature: usize,
        /// Index of the ring in its polygon (0 the boundary, then holes).
        ring: usize,
        /// The rule broken.
        reason: &'static str,
    },
    /// A position off the globe or not a number.
    #[error(
        "keep-out feature {feature}: position [{lon}, {lat}] is not a longitude in −180…180° and a latitude in −90…90°"
    )]
    Position {
        /// Index of the feature in the file.
        feature: usize,
        /// Longitude given, degrees.
        lon: f64,
        /// Latitude given, degrees.
        lat: f64,
    },
}

/// Reads a GeoJSON FeatureCollection, Feature or bare geometry of Polygons and MultiPolygons,
/// placing it in `frame`.
pub fn from_geojson(text: &str, frame: &LocalFrame) -> Result<KeepOutZones, KeepOutError> {
    let parsed: GeoJson = text
        .parse()
        .map_err(|e: geojson::Error| KeepOutError::Parse(e.to_string()))?;
    let features: Vec<(Option<String>, Option<geojson::Geometry>)> = match parsed {
        GeoJson::FeatureCollection(fc) => fc
            .features
            .into_iter()
            .map(|f| (name_of(&f), f.geometry))
            .collect(),
        GeoJson::Feature(f) => vec![(name_of(&f), f.geometry)],
        GeoJson::Geometry(g) => vec![(None, Some(g))],
    };
    let mut zones = Vec::new();
    for (feature, (name, geometry)) in features.into_iter().enumerate() {
        let name = name.unwrap_or_else(|| format!("zone {feature}"));
        let polygons = match geometry.map(|g| g.value) {
            Some(GeometryValue::Polygon { coordinates }) => vec![coordinates],
            Some(GeometryValue::MultiPolygon { coordinates }) => coordinates,
            Some(other) => {
                return Err(KeepOutError::NotAnArea {
                    feature,
                    found: other.type_name().to_string(),
                });
            }
            None => {
                return Err(KeepOutError::NotAnArea {
                    feature,
                    found: "feature without geometry".into(),
                });
            }
        };
        for polygon in polygons {
            zones.push(KeepOutZone {
                name: name.clone(),
                rings_ne_m: flatten(&polygon, frame, feature)?,
            });
        }
    }
    Ok(KeepOutZones { zones })
}

fn name_of(feature: &geojson::Feature) -> Option<String> {
    feature
        .properties
        .as_ref()?
        .get("name")?
        .as_str()
        .map(str::to_string)
}

/// The polygon's rings in the local plane, each checked and its closing point dropped.
fn flatten(
    polygon: &PolygonType,
    frame: &LocalFrame,
    feature: usize,
) -> Result<Vec<Vec<[f64; 2]>>, KeepOutError> {
    if polygon.is_empty() {
        return Err(KeepOutError::Ring {
            feature,
            ring: 0,
            reason: "is missing: a polygon needs its boundary",
        });
    }
    polygon
        .iter()
        .enumerate()
        .map(|(ring, positions)| {
            let bad = |reason| KeepOutError::Ring {
                feature,
                ring,
                reason,
            };
            if positions.len() < 4 {
                return Err(bad(
                    "has fewer than 4 positions (a triangle and its closing point)",
                ));
            }
            let mut points = Vec::with_capacity(positions.len());
            for position in positions {
                let &[lon, lat, ..] = position.as_slice() else {
                    return Err(bad("has a position with fewer than 2 numbers"));
                };
                if !(lon.is_finite() && lat.is_finite()) || lon.abs() > 180.0 || lat.abs() > 90.0 {
                    return Err(KeepOutError::Position { feature, lon, lat });
                }
                let ned = frame.to_ned(lat, lon, frame.alt_msl_m);
                points.push([ned.x, ned.y]);
            }
            if positions.first().map(|p| p.as_slice()) != positions.last().map(|p| p.as_slice()) {
                return Err(bad(
                    "is not closed (its last position must repeat its first)",
                ));
            }
            points.pop();
            if ring_crosses_itself(&points) {
                return Err(bad(
                    "crosses itself (two of its edges meet): it bounds no single area",
                ));
            }
            Ok(points)
        })
        .collect()
}

#[cfg(test)]
mod tests;
