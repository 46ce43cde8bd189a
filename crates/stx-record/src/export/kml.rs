//! The one KML 2.2 writer of stx: documents of named placemarks (a point, or a line of
//! points) and the network link Google Earth refreshes. A recording's track export
//! ([`super::track::kml`]) and the station's live Google Earth feed (stx-station) both write
//! through it, with every name escaped the same way (`quick_xml::escape::escape`).
//!
//! Ours rather than a KML crate's: the few elements Google Earth needs are a handful of
//! format strings, and the KML crates bring a geometry model stx does not use.

use std::fmt::Write as _;

use quick_xml::escape::escape;

/// Where a placemark's altitudes count from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AltitudeMode {
    /// Above mean sea level, as given.
    Absolute,
    /// On Google Earth's terrain wherever it falls (a line follows the ground).
    ClampToGround,
}

impl AltitudeMode {
    fn name(self) -> &'static str {
        match self {
            Self::Absolute => "absolute",
            Self::ClampToGround => "clampToGround",
        }
    }
}

/// A point of a placemark: longitude and latitude, degrees, altitude, m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coordinate {
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Longitude, degrees.
    pub lon_deg: f64,
    /// Altitude, m (MSL for [`AltitudeMode::Absolute`]; ignored on the ground).
    pub alt_m: f64,
}

impl Coordinate {
    fn write(&self, out: &mut String) {
        let _ = write!(
            out,
            "{:.7},{:.7},{:.1}",
            self.lon_deg, self.lat_deg, self.alt_m
        );
    }
}

const HEADER: &str =
    "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<kml xmlns=\"http://www.opengis.net/kml/2.2\">\n";

/// A KML document being written: [`Kml::document`], placemarks, then [`Kml::finish`].
#[derive(Debug, Clone)]
pub struct Kml(String);

impl Kml {
    /// A document named `name`.
    pub fn document(name: &str) -> Self {
        Self(format!("{HEADER}<Document><name>{}</name>\n", escape(name)))
    }

    /// A point placemark named `name`, at the instant `when` (ISO 8601 UTC) if given.
    pub fn point(&mut self, name: &str, when: Option<&str>, at: Coordinate, mode: AltitudeMode) {
        let out = &mut self.0;
        let _ = write!(out, "<Placemark><name>{}</name>", escape(name));
        if let Some(when) = when {
            let _ = write!(out, "<TimeStamp><when>{}</when></TimeStamp>", escape(when));
        }
        let _ = write!(
            out,
            "<Point><altitudeMode>{}</altitudeMode><coordinates>",
            mode.name()
        );
        at.write(out);
        out.push_str("</coordinates></Point></Placemark>\n");
    }

    /// A line placemark named `name` through `points`, in order.
    pub fn line(
        &mut self,
        name: &str,
        points: impl IntoIterator<Item = Coordinate>,
        mode: AltitudeMode,
    ) {
        let out = &mut self.0;
        let _ = write!(out, "<Placemark><name>{}</name><LineString>", escape(name));
        if mode == AltitudeMode::ClampToGround {
            out.push_str("<tessellate>1</tessellate>");
        }
        let _ = writeln!(
            out,
            "<altitudeMode>{}</altitudeMode><coordinates>",
            mode.name()
        );
        for p in points {
            p.write(out);
            out.push('\n');
        }
        out.push_str("</coordinates></LineString></Placemark>\n");
    }

    /// The document's text.
    pub fn finish(mut self) -> String {
        self.0.push_str("</Document>\n</kml>\n");
        self.0
    }
}

/// The network link Google Earth opens: it reloads `href` every `refresh_s` seconds.
pub fn network_link(name: &str, href: &str, refresh_s: f64) -> String {
    format!(
        "{HEADER}<NetworkLink>\n  <name>{}</name>\n  <Link>\n    <href>{}</href>\n    \
         <refreshMode>onInterval</refreshMode>\n    <refreshInterval>{refresh_s}</refreshInterval>\n  \
         </Link>\n</NetworkLink>\n</kml>\n",
        escape(name),
        escape(href)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_links_are_escaped_quotes_included() {
        let doc = network_link("A & B <ground> \"x\"", "/kml/live?token=a&b", 2.0);
        assert!(
            doc.contains("A &amp; B &lt;ground&gt; &quot;x&quot;"),
            "{doc}"
        );
        assert!(doc.contains("/kml/live?token=a&amp;b"));
        assert!(doc.contains("<refreshInterval>2</refreshInterval>"));
        let mut kml = Kml::document("it's");
        let at = Coordinate {
            lat_deg: 1.0,
            lon_deg: 2.0,
            alt_m: 3.0,
        };
        kml.point(
            "p",
            Some("2026-01-01T00:00:00.000Z"),
            at,
            AltitudeMode::Absolute,
        );
        kml.line("l", [at, at], AltitudeMode::ClampToGround);
        let doc = kml.finish();
        assert!(doc.contains("<name>it&apos;s</name>"), "{doc}");
        assert!(doc.contains("<coordinates>2.0000000,1.0000000,3.0</coordinates>"));
        assert!(doc.contains("<tessellate>1</tessellate><altitudeMode>clampToGround"));
        assert!(doc.ends_with("</Document>\n</kml>\n"));
    }
}
