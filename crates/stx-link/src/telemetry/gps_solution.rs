//! The GPS receiver's whole solution (GPS_INPUT): position, the NED velocity with its vertical
//! component, and the receiver's own accuracies, as floats.
//!
//! GPS_RAW_INT, which every ground station reads, has no vertical velocity and no speed
//! accuracy, so a station running its own estimator on it must borrow the vertical velocity
//! from the drone's estimate (GLOBAL_POSITION_INT) — which is not a measurement, and which
//! after the drone restarts its estimator (as it does when the parafoil deploys) is missing or
//! wrong for seconds. The station's estimate then parted from the drone's by 0.3 m/s of
//! airspeed for the rest of the flight. GPS_INPUT is the common dialect's message for a raw
//! receiver solution ("not the global position estimate of the system") and carries all of it;
//! autopilots take it as an input, and here the drone sends it beside GPS_RAW_INT so that the
//! station's estimator sees what the onboard one sees. Fields the receiver does not give are
//! marked in `ignore_flags` and read back as `None`.

use mavlink::dialects::common::{self as mc, MavMessage};
use serde::{Deserialize, Serialize};

use super::navigation::GpsFix;
use super::units::{deg_to_e7, e7_to_deg};

/// The receiver's solution.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct GpsSolution {
    /// When the receiver measured it, µs since the drone's boot.
    pub time_usec: u64,
    /// Fix type.
    pub fix: GpsFix,
    /// Latitude, degrees WGS84 (wire: degE7).
    pub lat_deg: f64,
    /// Longitude, degrees WGS84 (wire: degE7).
    pub lon_deg: f64,
    /// Altitude above mean sea level, m (wire: f32).
    pub alt_msl_m: f64,
    /// Velocity north, east, down, m/s (wire: f32); `None` if the receiver gives none.
    pub velocity_ned_mps: Option<[f64; 3]>,
    /// 1-σ speed accuracy, m/s.
    pub speed_accuracy_mps: Option<f64>,
    /// 1-σ horizontal position accuracy, m.
    pub horizontal_accuracy_m: Option<f64>,
    /// 1-σ vertical position accuracy, m.
    pub vertical_accuracy_m: Option<f64>,
    /// Satellites used, `None` if unknown (wire 255).
    pub satellites: Option<u8>,
}

/// A known, finite value as f32, or the field marked ignored.
fn field(
    v: Option<f64>,
    flag: mc::GpsInputIgnoreFlags,
    ignored: &mut mc::GpsInputIgnoreFlags,
) -> f32 {
    match v {
        Some(v) if v.is_finite() => v as f32,
        _ => {
            *ignored |= flag;
            0.0
        }
    }
}

/// A field not marked ignored, and finite.
fn read(v: f32, flag: mc::GpsInputIgnoreFlags, ignored: mc::GpsInputIgnoreFlags) -> Option<f64> {
    (!ignored.contains(flag) && v.is_finite()).then_some(f64::from(v))
}

impl GpsSolution {
    /// The GPS_INPUT carrying it.
    pub(super) fn to_mavlink(self) -> MavMessage {
        use mc::GpsInputIgnoreFlags as F;
        let mut ignored = F::GPS_INPUT_IGNORE_FLAG_HDOP | F::GPS_INPUT_IGNORE_FLAG_VDOP;
        let v = self.velocity_ned_mps;
        let velocity_known = v.is_some_and(|v| v.iter().all(|c| c.is_finite()));
        if !velocity_known {
            ignored |= F::GPS_INPUT_IGNORE_FLAG_VEL_HORIZ | F::GPS_INPUT_IGNORE_FLAG_VEL_VERT;
        }
        let [vn, ve, vd] = match v {
            Some(v) if velocity_known => v.map(|c| c as f32),
            _ => [0.0; 3],
        };
        MavMessage::GPS_INPUT(mc::GPS_INPUT_DATA {
            time_usec: self.time_usec,
            time_week_ms: 0,
            lat: deg_to_e7(self.lat_deg),
            lon: deg_to_e7(self.lon_deg),
            alt: self.alt_msl_m as f32,
            hdop: 0.0,
            vdop: 0.0,
            vn,
            ve,
            vd,
            speed_accuracy: field(
                self.speed_accuracy_mps,
                F::GPS_INPUT_IGNORE_FLAG_SPEED_ACCURACY,
                &mut ignored,
            ),
            horiz_accuracy: field(
                self.horizontal_accuracy_m,
                F::GPS_INPUT_IGNORE_FLAG_HORIZONTAL_ACCURACY,
                &mut ignored,
            ),
            vert_accuracy: field(
                self.vertical_accuracy_m,
                F::GPS_INPUT_IGNORE_FLAG_VERTICAL_ACCURACY,
                &mut ignored,
            ),
            ignore_flags: ignored,
            time_week: 0,
            gps_id: 0,
            fix_type: self.fix.to_mav(),
            satellites_visible: self.satellites.map_or(u8::MAX, |s| s.min(254)),
            yaw: 0,
        })
    }

    /// What a GPS_INPUT carries.
    pub(super) fn from_mavlink(g: &mc::GPS_INPUT_DATA) -> Self {
        use mc::GpsInputIgnoreFlags as F;
        let ignored = g.ignore_flags;
        let horizontal = !ignored.contains(F::GPS_INPUT_IGNORE_FLAG_VEL_HORIZ);
        let vertical = !ignored.contains(F::GPS_INPUT_IGNORE_FLAG_VEL_VERT);
        let v = [g.vn, g.ve, g.vd].map(f64::from);
        Self {
            time_usec: g.time_usec,
            fix: GpsFix::from_mav(g.fix_type),
            lat_deg: e7_to_deg(g.lat),
            lon_deg: e7_to_deg(g.lon),
            alt_msl_m: f64::from(g.alt),
            velocity_ned_mps: (horizontal && vertical && v.iter().all(|c| c.is_finite()))
                .then_some(v),
            speed_accuracy_mps: read(
                g.speed_accuracy,
                F::GPS_INPUT_IGNORE_FLAG_SPEED_ACCURACY,
                ignored,
            ),
            horizontal_accuracy_m: read(
                g.horiz_accuracy,
                F::GPS_INPUT_IGNORE_FLAG_HORIZONTAL_ACCURACY,
                ignored,
            ),
            vertical_accuracy_m: read(
                g.vert_accuracy,
                F::GPS_INPUT_IGNORE_FLAG_VERTICAL_ACCURACY,
                ignored,
            ),
            satellites: (g.satellites_visible != u8::MAX).then_some(g.satellites_visible),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::telemetry::Telemetry;

    fn solution() -> GpsSolution {
        GpsSolution {
            time_usec: 791_250_000,
            fix: GpsFix::Fix3d,
            lat_deg: 38.536_003_1,
            lon_deg: -7.860_254_4,
            alt_msl_m: 1_245.5,
            velocity_ned_mps: Some([-1.25, 7.5, 4.125]),
            speed_accuracy_mps: Some(0.15),
            horizontal_accuracy_m: Some(2.5),
            vertical_accuracy_m: Some(3.2),
            satellites: Some(12),
        }
    }

    #[test]
    fn a_solution_survives_the_wire_within_its_quantisation() {
        let s = solution();
        let back = Telemetry::from_mavlink(&Telemetry::GpsSolution(s).to_mavlink());
        let Some(Telemetry::GpsSolution(b)) = back else {
            panic!("GPS_INPUT read back as {back:?}");
        };
        assert_eq!(b.time_usec, s.time_usec);
        assert_eq!(b.fix, GpsFix::Fix3d);
        assert!((b.lat_deg - s.lat_deg).abs() < 1e-7 && (b.lon_deg - s.lon_deg).abs() < 1e-7);
        assert!((b.alt_msl_m - s.alt_msl_m).abs() < 1e-3);
        let (v, bv) = (
            s.velocity_ned_mps.unwrap(),
            b.velocity_ned_mps.expect("velocity"),
        );
        for k in 0..3 {
            assert!((v[k] - bv[k]).abs() < 1e-6, "component {k}");
        }
        assert!((b.speed_accuracy_mps.expect("speed accuracy") - 0.15).abs() < 1e-6);
        assert_eq!(b.satellites, Some(12));
    }

    #[test]
    fn what_the_receiver_does_not_give_reads_back_as_unknown() {
        let s = GpsSolution {
            velocity_ned_mps: None,
            speed_accuracy_mps: None,
            vertical_accuracy_m: Some(f64::NAN),
            satellites: None,
            ..solution()
        };
        let Some(Telemetry::GpsSolution(b)) =
            Telemetry::from_mavlink(&Telemetry::GpsSolution(s).to_mavlink())
        else {
            panic!("not a solution");
        };
        assert_eq!(b.velocity_ned_mps, None);
        assert_eq!(b.speed_accuracy_mps, None);
        assert_eq!(b.vertical_accuracy_m, None);
        assert_eq!(b.horizontal_accuracy_m, Some(2.5));
        assert_eq!(b.satellites, None);
    }
}
