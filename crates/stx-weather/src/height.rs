//! Geopotential height (what GFS' `HGT` and a sounding's `HGHT` give, in geopotential metres)
//! to geometric height above mean sea level.
//!
//! Gravity is taken as g₀ scaled by the inverse square of the distance from the Earth's centre
//! over a sphere of radius R, so that Z = R·h/(R + h) and h = R·Z/(R − Z). R is the IUGG mean
//! Earth radius; the WMO's latitude-dependent formula differs from it by under 0.3 % of the
//! difference h − Z (a few metres at 35 km), well inside what a forecast's winds vary over.

/// The mean Earth radius R used for the conversion, m (IUGG R₁).
pub const EARTH_RADIUS_M: f64 = 6_371_008.8;

/// Geometric height above mean sea level, m, of a geopotential height `z_gpm` in geopotential
/// metres: h = R·Z/(R − Z).
pub fn geometric_height_m(z_gpm: f64) -> f64 {
    EARTH_RADIUS_M * z_gpm / (EARTH_RADIUS_M - z_gpm)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_conversion_inverts_z_equals_r_h_over_r_plus_h() {
        for h in [0.0, 1000.0, 11_000.0, 35_000.0, 55_000.0] {
            let z = EARTH_RADIUS_M * h / (EARTH_RADIUS_M + h);
            assert!((geometric_height_m(z) - h).abs() < 1e-6, "{h}");
        }
        // At 35 km the geometric height lies 193 m above the geopotential one.
        let z = 35_000.0;
        assert!((geometric_height_m(z) - z - 193.3).abs() < 0.1);
    }
}
