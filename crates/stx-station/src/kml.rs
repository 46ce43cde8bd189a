//! The KML feed for Google Earth: a network link that refreshes, and the live document with
//! the track, the vehicle, the target, the planned pattern and the predicted touchdowns.
//!
//! Altitudes: the track, the vehicle and the target are where they are (`absolute`, MSL).
//! Predicted touchdowns have no altitude of their own worth drawing (the station's predictor
//! lands on the site's ground level, which is not the terrain under the point):
//! they are `clampToGround`, on Google Earth's terrain wherever they fall.

use std::fmt::Write;

use crate::messages::StateMsg;
use crate::messages::TrackPoint;

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The network link Google Earth opens: it reloads `live_url` every `refresh_s` seconds.
pub fn network_link(name: &str, live_url: &str, refresh_s: f64) -> String {
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<kml xmlns="http://www.opengis.net/kml/2.2">
<NetworkLink>
  <name>{}</name>
  <Link>
    <href>{}</href>
    <refreshMode>onInterval</refreshMode>
    <refreshInterval>{refresh_s}</refreshInterval>
  </Link>
</NetworkLink>
</kml>
"#,
        escape(name),
        escape(live_url)
    )
}

/// A point in the air (MSL) or on the ground wherever it falls.
#[derive(Debug, Clone, Copy)]
enum Height {
    Msl(f64),
    Ground,
}

fn placemark(out: &mut String, name: &str, lat: f64, lon: f64, height: Height) {
    let (mode, alt) = match height {
        Height::Msl(alt) => ("absolute", alt),
        Height::Ground => ("clampToGround", 0.0),
    };
    let _ = writeln!(
        out,
        "<Placemark><name>{}</name><Point><altitudeMode>{mode}</altitudeMode>\
         <coordinates>{lon:.7},{lat:.7},{alt:.1}</coordinates></Point></Placemark>",
        escape(name)
    );
}

/// The live document.
pub fn live(name: &str, track: &[TrackPoint], state: &StateMsg) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<kml xmlns=\"http://www.opengis.net/kml/2.2\">\n<Document><name>{}</name>",
        escape(name)
    );
    if track.len() >= 2 {
        out.push_str(
            "<Placemark><name>track</name><LineString><altitudeMode>absolute</altitudeMode><coordinates>\n",
        );
        for p in track {
            let _ = writeln!(out, "{:.7},{:.7},{:.1}", p.lon_deg, p.lat_deg, p.alt_msl_m);
        }
        out.push_str("</coordinates></LineString></Placemark>\n");
    }
    if let Some(e) = &state.estimate {
        placemark(
            &mut out,
            "vehicle",
            e.lat_deg,
            e.lon_deg,
            Height::Msl(e.alt_msl_m),
        );
    }
    if let Some(g) = &state.guidance {
        if let Some(t) = &g.target {
            placemark(
                &mut out,
                "landing target",
                t.lat_deg,
                t.lon_deg,
                Height::Msl(t.alt_msl_m),
            );
        }
        if let Some(p) = &g.pattern {
            out.push_str(
                "<Placemark><name>spiral pattern</name><LineString><tessellate>1</tessellate><coordinates>\n",
            );
            for c in p.corners.iter().chain(p.corners.first()) {
                let _ = writeln!(out, "{:.7},{:.7},0", c[1], c[0]);
            }
            out.push_str("</coordinates></LineString></Placemark>\n");
        }
    }
    if let Some(p) = &state.prediction {
        if let Some(planned) = &p.planned {
            placemark(
                &mut out,
                "predicted landing (station, plan)",
                planned.lat_deg,
                planned.lon_deg,
                Height::Ground,
            );
        }
        placemark(
            &mut out,
            "predicted landing (station, uncontrolled)",
            p.uncontrolled.lat_deg,
            p.uncontrolled.lon_deg,
            Height::Ground,
        );
    }
    if let Some(p) = state
        .vehicle
        .as_ref()
        .and_then(|v| v.predicted_landing.as_ref())
    {
        placemark(
            &mut out,
            "predicted landing (drone's own)",
            p.lat_deg,
            p.lon_deg,
            Height::Ground,
        );
    }
    out.push_str("</Document>\n</kml>\n");
    out
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
