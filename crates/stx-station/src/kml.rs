//! The KML feed for Google Earth: a network link that refreshes, and the live document with
//! the track, the vehicle, the target, the planned pattern and the predicted touchdowns.

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

fn placemark(out: &mut String, name: &str, lat: f64, lon: f64, alt: f64) {
    let _ = writeln!(
        out,
        "<Placemark><name>{}</name><Point><altitudeMode>absolute</altitudeMode>\
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
        placemark(&mut out, "vehicle", e.lat_deg, e.lon_deg, e.alt_msl_m);
    }
    if let Some(g) = &state.guidance {
        if let Some(t) = &g.target {
            placemark(
                &mut out,
                "landing target",
                t.lat_deg,
                t.lon_deg,
                t.alt_msl_m,
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
        placemark(
            &mut out,
            "predicted landing (plan)",
            p.planned.lat_deg,
            p.planned.lon_deg,
            0.0,
        );
        placemark(
            &mut out,
            "predicted landing (uncontrolled)",
            p.uncontrolled.lat_deg,
            p.uncontrolled.lon_deg,
            0.0,
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
