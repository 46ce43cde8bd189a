//! The flight's track from a recording's positions (`foxglove.LocationFix`; the drone's GPS,
//! `/vehicle/gps`, when there is one, else the first such channel), as KML 2.2 (a line at
//! its absolute altitude with start and end placemarks, for Google Earth) or GPX 1.1 (a
//! track of timed points with elevation, for phones and GIS tools).

use std::io::{Read, Seek};

use super::{ExportError, utc};
use crate::Recording;
use crate::foxglove::{LOCATION_FIX, LocationFix};

/// One point of the track.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackPoint {
    /// Log time, ns since the Unix epoch.
    pub time_ns: u64,
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Longitude, degrees.
    pub lon_deg: f64,
    /// Altitude, m.
    pub alt_m: f64,
}

/// The preferred positions channel.
pub const PREFERRED_TOPIC: &str = "/vehicle/gps";

/// The track of `recording`: its topic and points in time order (fixes that are no position,
/// [`LocationFix::is_position`], left out: out of range, or at 0°, 0° without a fix).
pub fn track<R: Read + Seek>(
    recording: &mut Recording<R>,
) -> Result<(String, Vec<TrackPoint>), ExportError> {
    let fixes: Vec<&str> = recording
        .channels()
        .iter()
        .filter(|c| c.schema_name == LOCATION_FIX && c.message_count > 0)
        .map(|c| &*c.topic)
        .collect();
    let topic = fixes
        .iter()
        .find(|t| **t == PREFERRED_TOPIC)
        .or_else(|| fixes.first())
        .map(|t| t.to_string())
        .ok_or(ExportError::NoTrack)?;
    let mut points = Vec::new();
    for message in recording.messages()? {
        let message = message?;
        if *message.topic != *topic {
            continue;
        }
        if let Ok(f) = serde_json::from_slice::<LocationFix>(&message.data)
            && f.is_position()
        {
            points.push(TrackPoint {
                time_ns: message.log_time,
                lat_deg: f.latitude,
                lon_deg: f.longitude,
                alt_m: f.altitude,
            });
        }
    }
    if points.is_empty() {
        return Err(ExportError::NoTrack);
    }
    Ok((topic, points))
}

/// XML text with `&`, `<`, `>`, `"` and `'` escaped.
pub fn xml_escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

/// The track as a KML 2.2 document named `name`.
pub fn kml(name: &str, points: &[TrackPoint]) -> String {
    let name = xml_escape(name);
    let coordinates: Vec<String> = points
        .iter()
        .map(|p| format!("{:.7},{:.7},{:.1}", p.lon_deg, p.lat_deg, p.alt_m))
        .collect();
    let placemark = |label: &str, p: &TrackPoint| {
        format!(
            "    <Placemark><name>{label}</name><TimeStamp><when>{}</when></TimeStamp><Point><altitudeMode>absolute</altitudeMode><coordinates>{:.7},{:.7},{:.1}</coordinates></Point></Placemark>\n",
            utc(p.time_ns),
            p.lon_deg,
            p.lat_deg,
            p.alt_m
        )
    };
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    out.push_str("<kml xmlns=\"http://www.opengis.net/kml/2.2\">\n  <Document>\n");
    out.push_str(&format!("    <name>{name}</name>\n"));
    out.push_str("    <Placemark><name>track</name><LineString><altitudeMode>absolute</altitudeMode><coordinates>");
    out.push_str(&coordinates.join(" "));
    out.push_str("</coordinates></LineString></Placemark>\n");
    if let (Some(first), Some(last)) = (points.first(), points.last()) {
        out.push_str(&placemark("start", first));
        out.push_str(&placemark("end", last));
    }
    out.push_str("  </Document>\n</kml>\n");
    out
}

/// The track as a GPX 1.1 document named `name`.
pub fn gpx(name: &str, points: &[TrackPoint]) -> String {
    let name = xml_escape(name);
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    out.push_str(
        "<gpx version=\"1.1\" creator=\"stx\" xmlns=\"http://www.topografix.com/GPX/1/1\">\n",
    );
    out.push_str(&format!("  <trk><name>{name}</name><trkseg>\n"));
    for p in points {
        out.push_str(&format!(
            "    <trkpt lat=\"{:.7}\" lon=\"{:.7}\"><ele>{:.1}</ele><time>{}</time></trkpt>\n",
            p.lat_deg,
            p.lon_deg,
            p.alt_m,
            utc(p.time_ns)
        ));
    }
    out.push_str("  </trkseg></trk>\n</gpx>\n");
    out
}
