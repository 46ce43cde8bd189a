//! A recording for tools that do not read MCAP: one CSV per channel ([`csv`]: columns are the
//! messages' JSON fields, flattened, with units from the channels' JSON Schemas) and the
//! flight's track as KML (Google Earth) or GPX (phones, GIS) ([`track`]), KML through the one
//! KML writer of stx ([`kml`], which the station's live feed uses too).
//!
//! CSV and the two XML formats are written by hand: each is a few lines of text whose only
//! subtleties are quoting a CSV field (handled and tested here) and escaping XML text (by
//! `quick_xml::escape::escape`, everywhere stx writes XML), where a writer library would add
//! a dependency for less than it saves.

pub mod csv;
pub mod kml;
pub mod track;

use thiserror::Error;

use crate::ReadError;

/// Why an export failed.
#[derive(Debug, Error)]
pub enum ExportError {
    /// The recording could not be read.
    #[error(transparent)]
    Read(#[from] ReadError),
    /// An output could not be written.
    #[error("{path}: {source}")]
    Write {
        /// The file or directory.
        path: String,
        /// What went wrong.
        #[source]
        source: std::io::Error,
    },
    /// The recording has no positions to draw a track from.
    #[error("the recording has no foxglove.LocationFix channel with positions")]
    NoTrack,
}

/// UTC ISO 8601 of a time in ns since the Unix epoch (`2026-11-24T10:00:00.250Z`).
pub fn utc(ns: u64) -> String {
    let t = time::OffsetDateTime::UNIX_EPOCH + time::Duration::nanoseconds(ns as i64);
    format!(
        "{:04}-{:02}-{:02}T{:02}:{:02}:{:02}.{:03}Z",
        t.year(),
        u8::from(t.month()),
        t.day(),
        t.hour(),
        t.minute(),
        t.second(),
        t.millisecond()
    )
}

#[cfg(test)]
mod tests {
    #[test]
    fn utc_times_are_iso_8601_with_milliseconds() {
        assert_eq!(super::utc(0), "1970-01-01T00:00:00.000Z");
        assert_eq!(
            super::utc(1_795_576_246_253_000_000),
            "2026-11-25T03:10:46.253Z"
        );
    }
}
