//! The mission's local frame: North-East-Down metres from an origin on the ground (the launch
//! site, or the landing field), and its link to latitude, longitude and altitude, which is what
//! the GPS and MAVLink speak.
//!
//! A tangent plane with the WGS-84 radii of curvature at the origin: over the tens of
//! kilometres a STRAPLEX descent drifts, its horizontal error is centimetres. Altitude is kept
//! as height above the origin's ground (`−down`), not as a curved-Earth height.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

const WGS84_A_M: f64 = 6_378_137.0;
const WGS84_E2: f64 = 6.694_379_990_14e-3;

/// Origin of the local frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LocalFrame {
    /// Latitude of the origin, degrees north.
    pub lat_deg: f64,
    /// Longitude of the origin, degrees east.
    pub lon_deg: f64,
    /// Ground altitude at the origin above mean sea level, m.
    pub alt_msl_m: f64,
}

impl LocalFrame {
    /// Meridional and prime-vertical radii of curvature at the origin, m.
    fn radii_m(&self) -> (f64, f64) {
        let s = self.lat_deg.to_radians().sin();
        let w = (1.0 - WGS84_E2 * s * s).sqrt();
        (WGS84_A_M * (1.0 - WGS84_E2) / (w * w * w), WGS84_A_M / w)
    }

    /// Local NED position of a geodetic point, m.
    pub fn to_ned(&self, lat_deg: f64, lon_deg: f64, alt_msl_m: f64) -> Vector3<f64> {
        let (meridian, prime) = self.radii_m();
        let mut dlon = lon_deg - self.lon_deg;
        if dlon > 180.0 {
            dlon -= 360.0;
        } else if dlon < -180.0 {
            dlon += 360.0;
        }
        Vector3::new(
            (lat_deg - self.lat_deg).to_radians() * meridian,
            dlon.to_radians() * prime * self.lat_deg.to_radians().cos(),
            -(alt_msl_m - self.alt_msl_m),
        )
    }

    /// Geodetic position `(lat_deg, lon_deg, alt_msl_m)` of a local NED point.
    pub fn to_geodetic(&self, ned_m: &Vector3<f64>) -> (f64, f64, f64) {
        let (meridian, prime) = self.radii_m();
        let lat = self.lat_deg + (ned_m.x / meridian).to_degrees();
        let mut lon =
            self.lon_deg + (ned_m.y / (prime * self.lat_deg.to_radians().cos())).to_degrees();
        if lon > 180.0 {
            lon -= 360.0;
        } else if lon <= -180.0 {
            lon += 360.0;
        }
        (lat, lon, self.alt_msl_m - ned_m.z)
    }
}

/// Whether coordinates can be a vehicle's position: finite, within ±90° and ±180°, and not
/// exactly 0°, 0° (the placeholder of a GNSS report without a fix, or of an autopilot's
/// estimate before it has an origin: no launch site is there).
pub fn is_position(lat_deg: f64, lon_deg: f64) -> bool {
    lat_deg.abs() <= 90.0 && lon_deg.abs() <= 180.0 && !(lat_deg == 0.0 && lon_deg == 0.0)
}

impl Default for LocalFrame {
    /// Évora aerodrome, Portugal, the usual STRAPLEX launch site (about 38.53° N, 7.89° W,
    /// 245 m).
    fn default() -> Self {
        Self {
            lat_deg: 38.5333,
            lon_deg: -7.8889,
            alt_msl_m: 245.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_and_has_the_right_scale() {
        let frame = LocalFrame::default();
        let p = Vector3::new(1234.5, -6789.0, -321.0);
        let (lat, lon, alt) = frame.to_geodetic(&p);
        let back = frame.to_ned(lat, lon, alt);
        assert!((back - p).norm() < 1e-6, "{back:?}");
        // One degree of latitude is about 111 km.
        let north = frame.to_ned(frame.lat_deg + 1.0, frame.lon_deg, frame.alt_msl_m);
        assert!((north.x - 111_000.0).abs() < 500.0, "{north:?}");
        assert!((alt - (245.0 + 321.0)).abs() < 1e-9);
    }

    #[test]
    fn longitude_wraps_at_the_antimeridian() {
        let frame = LocalFrame {
            lat_deg: 0.0,
            lon_deg: 179.9,
            alt_msl_m: 0.0,
        };
        let east = frame.to_ned(0.0, -179.9, 0.0);
        assert!((east.y - 22_264.0).abs() < 20.0, "{east:?}");
        let (_, lon, _) = frame.to_geodetic(&east);
        assert!((lon + 179.9).abs() < 1e-9);
    }
}
