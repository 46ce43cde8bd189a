//! The KML feed for Google Earth: a network link that refreshes, and the live document with
//! the track, the vehicle, the target, the planned pattern and the predicted touchdowns.
//!
//! Altitudes: the track, the vehicle and the target are where they are (`absolute`, MSL).
//! Predicted touchdowns have no altitude of their own worth drawing (the station's predictor
//! lands on the site's ground level, which is not the terrain under the point):
//! they are `clampToGround`, on Google Earth's terrain wherever they fall.
//!
//! Written through stx-record's KML writer (`stx_record::export::kml`), the one of stx.

use stx_record::export::kml::{AltitudeMode, Coordinate, Kml};

use crate::messages::StateMsg;
use crate::messages::TrackPoint;

/// The network link Google Earth opens: it reloads `live_url` every `refresh_s` seconds.
pub fn network_link(name: &str, live_url: &str, refresh_s: f64) -> String {
    stx_record::export::kml::network_link(name, live_url, refresh_s)
}

/// A point of the document (altitude MSL, or 0 for a point on the ground).
fn coordinate(lat_deg: f64, lon_deg: f64, alt_m: f64) -> Coordinate {
    Coordinate {
        lat_deg,
        lon_deg,
        alt_m,
    }
}

/// The live document.
pub fn live(name: &str, track: &[TrackPoint], state: &StateMsg) -> String {
    let mut doc = Kml::document(name);
    let air = AltitudeMode::Absolute;
    let ground = AltitudeMode::ClampToGround;
    if track.len() >= 2 {
        let points = track
            .iter()
            .map(|p| coordinate(p.lat_deg, p.lon_deg, p.alt_msl_m));
        doc.line("track", points, air);
    }
    if let Some(e) = &state.estimate {
        doc.point(
            "vehicle",
            None,
            coordinate(e.lat_deg, e.lon_deg, e.alt_msl_m),
            air,
        );
    }
    if let Some(g) = &state.guidance {
        if let Some(t) = &g.target {
            let at = coordinate(t.lat_deg, t.lon_deg, t.alt_msl_m);
            doc.point("landing target", None, at, air);
        }
        if let Some(p) = &g.pattern {
            let corners = p.corners.iter().chain(p.corners.first());
            doc.line(
                "spiral pattern",
                corners.map(|c| coordinate(c[0], c[1], 0.0)),
                ground,
            );
        }
    }
    if let Some(p) = &state.prediction {
        if let Some(planned) = &p.planned {
            let at = coordinate(planned.lat_deg, planned.lon_deg, 0.0);
            doc.point("predicted landing (station, plan)", None, at, ground);
        }
        let u = &p.uncontrolled;
        let at = coordinate(u.lat_deg, u.lon_deg, 0.0);
        doc.point(
            "predicted landing (station, uncontrolled)",
            None,
            at,
            ground,
        );
    }
    if let Some(p) = state
        .vehicle
        .as_ref()
        .and_then(|v| v.predicted_landing.as_ref())
    {
        let at = coordinate(p.lat_deg, p.lon_deg, 0.0);
        doc.point("predicted landing (drone's own)", None, at, ground);
    }
    doc.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_escaped_and_the_link_points_at_the_live_feed() {
        let doc = network_link("A & B <ground>", "/kml/live?token=a&b", 2.0);
        assert!(doc.contains("A &amp; B &lt;ground&gt;"));
        assert!(doc.contains("/kml/live?token=a&amp;b"));
        assert!(doc.contains("<refreshInterval>2</refreshInterval>"));
    }
}
