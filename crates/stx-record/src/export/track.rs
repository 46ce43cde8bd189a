//! The flight's track from a recording's positions (`foxglove.LocationFix`; the drone's GPS,
//! `/vehicle/gps`, when there is one, else the first such channel), as KML 2.2 (a line at
//! its absolute altitude with start and end placemarks, for Google Earth) or GPX 1.1 (a
//! track of timed points with elevation, for phones and GIS tools).

use std::io::{Read, Seek};

use quick_xml::escape::escape;

use super::kml::{AltitudeMode, Coordinate, Kml};
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

/// The track as a KML 2.2 document named `name`: a line at its absolute altitude, with
/// placemarks at the start and the end.
pub fn kml(name: &str, points: &[TrackPoint]) -> String {
    let at = |p: &TrackPoint| Coordinate {
        lat_deg: p.lat_deg,
        lon_deg: p.lon_deg,
        alt_m: p.alt_m,
    };
    let mut doc = Kml::document(name);
    doc.line("track", points.iter().map(at), AltitudeMode::Absolute);
    if let (Some(first), Some(last)) = (points.first(), points.last()) {
        for (label, p) in [("start", first), ("end", last)] {
            doc.point(label, Some(&utc(p.time_ns)), at(p), AltitudeMode::Absolute);
        }
    }
    doc.finish()
}

/// The track as a GPX 1.1 document named `name`.
pub fn gpx(name: &str, points: &[TrackPoint]) -> String {
    let name = escape(name);
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
