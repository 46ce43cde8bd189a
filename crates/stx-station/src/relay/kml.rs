//! The relay's Google Earth document: the public track, the payload, the predicted landing
//! and the target, as the station's feed draws them (`crate::kml`), from the public state.

use stx_record::export::kml::{AltitudeMode, Coordinate, Kml};

use super::public::{PublicStateMsg, PublicTrackPoint};

/// The live document.
pub fn public_live(
    name: &str,
    track: &[PublicTrackPoint],
    state: Option<&PublicStateMsg>,
) -> String {
    let at = |lat_deg, lon_deg, alt_m| Coordinate {
        lat_deg,
        lon_deg,
        alt_m,
    };
    let mut doc = Kml::document(name);
    if track.len() >= 2 {
        let points = track.iter().map(|p| at(p.lat_deg, p.lon_deg, p.alt_msl_m));
        doc.line("track", points, AltitudeMode::Absolute);
    }
    if let Some(s) = state {
        if let Some(p) = &s.position {
            let here = at(p.lat_deg, p.lon_deg, p.alt_msl_m);
            doc.point("payload", None, here, AltitudeMode::Absolute);
        }
        for (what, p) in [
            ("predicted landing", s.landing),
            ("landing target", s.target),
        ] {
            if let Some(p) = p {
                let ground = at(p.lat_deg, p.lon_deg, 0.0);
                doc.point(what, None, ground, AltitudeMode::ClampToGround);
            }
        }
    }
    doc.finish()
}
