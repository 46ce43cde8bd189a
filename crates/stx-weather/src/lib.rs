//! Forecast and measured winds for the pre-flight planner and the station's forecast: a GFS
//! GRIB2 file (or several) as a 4-D wind field, and a radiosonde sounding, each read down to
//! the wind-versus-altitude profile the planner flies through.
//!
//! Why a crate of its own: decoding GRIB2 and parsing soundings is file handling the onboard
//! guidance (`stx-gnc`) must not carry, and both `stx plan` and the station read the same
//! files. It depends on no other stx crate; its callers turn a [`WindLevel`] list into their
//! forecast rows.
//!
//! How the parts fit:
//! - [`gfs`] reads GRIB2 bytes (NOAA's `pgrb2` 0.25° or 0.5°, whole or a subset cut by the
//!   NOMADS filter: a latitude/longitude box, chosen levels and hours) with the `grib` crate
//!   into a [`GfsField`]: `UGRD`, `VGRD` and `HGT` on isobaric levels over (forecast time,
//!   pressure level, latitude, longitude). Anything else in the file is skipped; a missing
//!   variable, level or hour is refused, naming it.
//! - [`GfsField::profile`] interpolates it at a place and time: bilinear in latitude and
//!   longitude on each level, linear in time between the two forecast hours around it, and the
//!   level's geopotential height turned into geometric height ([`geometric_height_m`]). The
//!   result is one [`WindLevel`] per pressure level, lowest first; between levels the planner
//!   interpolates in height, as it does any forecast.
//! - [`sounding`] reads a radiosonde ascent as the University of Wyoming prints it
//!   (`TEXT:LIST`: PRES HGHT TEMP … DRCT SKNT …) into the same levels.
//! - [`decode`] is the plain decoding underneath (every message's values with their
//!   latitudes and longitudes), kept public so tests hold it against ecCodes' on any file.
//!
//! Units: heights in metres above mean sea level, winds in m/s with the north and east
//! components of where the air goes (GRIB's `VGRD` and `UGRD` on a latitude/longitude grid),
//! pressures in Pa, times as UTC instants.

pub mod decode;
pub mod gfs;
mod height;
pub mod sounding;

pub use gfs::{GfsError, GfsField};
pub use height::{EARTH_RADIUS_M, geometric_height_m};
pub use sounding::{Sounding, SoundingError};
pub use time::{OffsetDateTime, UtcOffset};

/// The wind at one height, from a forecast level or a sounding's line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindLevel {
    /// Geometric height above mean sea level, m.
    pub alt_msl_m: f64,
    /// Northward component of the air's velocity, m/s (GRIB's `VGRD`).
    pub north_mps: f64,
    /// Eastward component of the air's velocity, m/s (GRIB's `UGRD`).
    pub east_mps: f64,
    /// The level's pressure, Pa, where the source gives it.
    pub pressure_pa: Option<f64>,
}

impl WindLevel {
    /// Horizontal wind speed, m/s.
    pub fn speed_mps(&self) -> f64 {
        self.north_mps.hypot(self.east_mps)
    }

    /// Direction the wind blows from, degrees clockwise from true north in [0, 360).
    pub fn from_deg(&self) -> f64 {
        (-self.east_mps)
            .atan2(-self.north_mps)
            .to_degrees()
            .rem_euclid(360.0)
    }
}

/// An RFC 3339 time (`2026-11-30T06:00:00Z`), as `stx plan --launch-time` and the station
/// config give it.
pub fn parse_time(text: &str) -> Result<OffsetDateTime, time::error::Parse> {
    OffsetDateTime::parse(text, &time::format_description::well_known::Rfc3339)
}

/// `time` as RFC 3339, for messages.
pub fn format_time(time: OffsetDateTime) -> String {
    time.format(&time::format_description::well_known::Rfc3339)
        .unwrap_or_else(|_| time.to_string())
}
