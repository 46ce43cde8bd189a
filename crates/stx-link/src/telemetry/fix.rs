//! When a GNSS report is a position: the one rule every consumer of positions follows (the
//! station's estimator, track, landing and ascent winds; the recording's `foxglove.LocationFix`;
//! the tlog importer; replay and the flight-log reader).
//!
//! A receiver without a fix still sends GPS_RAW_INT (and an autopilot GLOBAL_POSITION_INT
//! before its estimator has an origin), with zeros where the coordinates go: ArduPilot's, and
//! our simulated drone's during a GPS outage. Taken as positions, those zeros put the vehicle at
//! 0° N 0° E, in the Gulf of Guinea, and a map or a Foxglove panel draws the track from there.
//! So a report is a position only with a fix of at least two dimensions (GPS_FIX_TYPE ≥ 2) and
//! coordinates that are finite, within range and not exactly 0°, 0° (no launch site is there;
//! a real fix near it is never exactly on it at 1e-7° resolution).

use super::gps_solution::GpsSolution;
use super::navigation::{GlobalPosition, GpsFix, GpsRaw};
// The coordinates' half of the rule is shared with readers of recorded positions that have no
// link (the flight-log reader), so it lives with the local frame.
pub use stx_types::geo::is_position;

impl GpsFix {
    /// At least a 2-D fix (GPS_FIX_TYPE ≥ 2): the receiver knows where it is.
    pub fn has_position(self) -> bool {
        !matches!(self, Self::NoGps | Self::NoFix)
    }

    /// A 3-D fix or better (GPS_FIX_TYPE ≥ 3): its altitude too.
    pub fn is_3d(self) -> bool {
        !matches!(self, Self::NoGps | Self::NoFix | Self::Fix2d)
    }
}

/// Whether a receiver's report with fix type `fix` at `lat_deg`, `lon_deg` is a position.
pub fn has_position_fix(fix: GpsFix, lat_deg: f64, lon_deg: f64) -> bool {
    fix.has_position() && is_position(lat_deg, lon_deg)
}

impl GpsRaw {
    /// Whether this report is a position ([`has_position_fix`]).
    pub fn has_position_fix(&self) -> bool {
        has_position_fix(self.fix, self.lat_deg, self.lon_deg)
    }

    /// A position with its altitude: a 3-D fix or better, as an estimator needs.
    pub fn has_3d_fix(&self) -> bool {
        self.has_position_fix() && self.fix.is_3d()
    }
}

impl GpsSolution {
    /// Whether this solution is a position ([`has_position_fix`]).
    pub fn has_position_fix(&self) -> bool {
        has_position_fix(self.fix, self.lat_deg, self.lon_deg)
    }

    /// A position with its altitude: a 3-D fix or better, as an estimator needs.
    pub fn has_3d_fix(&self) -> bool {
        self.has_position_fix() && self.fix.is_3d()
    }
}

impl GlobalPosition {
    /// Whether the drone's estimate is a position: GLOBAL_POSITION_INT has no fix type, and
    /// an autopilot sends 0°, 0° until its estimator has an origin ([`is_position`]).
    pub fn has_position(&self) -> bool {
        is_position(self.lat_deg, self.lon_deg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gps(fix: GpsFix, lat_deg: f64, lon_deg: f64) -> GpsRaw {
        GpsRaw {
            time_usec: 0,
            fix,
            lat_deg,
            lon_deg,
            alt_msl_m: 245.0,
            ground_speed_mps: None,
            course_deg: None,
            satellites: Some(9),
            h_acc_m: None,
            v_acc_m: None,
        }
    }

    #[test]
    fn a_position_needs_a_2d_fix_and_coordinates_other_than_zero_zero() {
        use GpsFix::*;
        for fix in [NoGps, NoFix] {
            assert!(!gps(fix, 38.5, -7.9).has_position_fix(), "{fix:?}");
        }
        for fix in [Fix2d, Fix3d, Dgps, RtkFloat, RtkFixed, Static, Ppp] {
            assert!(gps(fix, 38.5, -7.9).has_position_fix(), "{fix:?}");
            assert!(!gps(fix, 0.0, 0.0).has_position_fix(), "{fix:?} at 0, 0");
            // One coordinate at zero is a real place (the equator, Greenwich).
            assert!(gps(fix, 0.0, -7.9).has_position_fix(), "{fix:?}");
            assert!(gps(fix, 38.5, 0.0).has_position_fix(), "{fix:?}");
        }
        assert!(!gps(Fix2d, 38.5, -7.9).has_3d_fix());
        assert!(gps(Fix3d, 38.5, -7.9).has_3d_fix());
        assert!(!gps(Fix3d, 0.0, 0.0).has_3d_fix());
        assert!(!gps(Fix3d, f64::NAN, -7.9).has_position_fix());
        assert!(!gps(Fix3d, 91.0, -7.9).has_position_fix());
        assert!(!gps(Fix3d, 38.5, 180.5).has_position_fix());
    }

    #[test]
    fn the_drones_estimate_at_zero_zero_is_no_position() {
        let super::super::Telemetry::Position(flying) = crate::fixtures::telemetry_sample(1) else {
            panic!("the fixture's second message is a GLOBAL_POSITION_INT");
        };
        let at = |lat_deg, lon_deg| GlobalPosition {
            lat_deg,
            lon_deg,
            ..flying
        };
        assert!(!at(0.0, 0.0).has_position());
        assert!(at(38.5, -7.9).has_position());
    }
}
