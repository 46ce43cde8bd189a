//! stx-weather from outside: GRIB2 decoding and the wind field held against ecCodes (committed
//! readings, and ecCodes run live), bad and corrupt files, and Wyoming soundings.

mod common;
mod corrupt;
mod eccodes_fixtures;
mod eccodes_peer;
mod gfs_field;
mod sounding;
