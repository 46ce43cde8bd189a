//! The wind a landing prediction flies through below the drone: what the estimator measures
//! now at the drone's altitude, and a wind profile (the ascent's measured bands with the
//! forecast outside them) further down.
//!
//! Why not the profile alone: the profile is old (measured on the way up, hours ago, or
//! forecast the day before) and may be biased; the estimate is the wind here and now. Why not
//! the estimate alone: the wind changes with altitude, and a parafoil opened at 1200 m falls
//! through layers the estimate knows nothing of. So the profile is shifted by the difference
//! `estimate − profile` at the drone's altitude, and the shift fades out linearly over
//! [`DescentWind::fade_height_m`] below it: at the drone's altitude the prediction flies in
//! exactly the estimated wind, `fade_height_m` lower and below in the profile's own. A bias
//! the drone measures now is probably shared by the air just below it (the same weather
//! since the ascent), less so by air far below.

use nalgebra::{Vector2, Vector3};
use stx_types::wind::WindField;

use crate::estimate::Estimate;

/// Default height over which the correction of the profile fades out, m: the depth of air a
/// forecast's error or an hour's change of the weather tends to share (a few hundred metres
/// to a kilometre in the boundary layer and above).
pub const DEFAULT_FADE_HEIGHT_M: f64 = 500.0;

/// The horizontal wind below (and at) the drone for a prediction.
#[derive(Clone, Copy)]
pub struct DescentWind<'a> {
    /// The estimated wind at the start, NED, m/s (the vertical is ignored).
    estimate_ne_mps: Vector2<f64>,
    /// The profile and the correction at the start altitude (estimate − profile), NE, m/s.
    profile: Option<(&'a dyn WindField, Vector2<f64>)>,
    /// Altitude the prediction starts from, above the frame origin, m.
    start_altitude_m: f64,
    /// Height below the start over which the correction fades to nothing, m (> 0).
    fade_height_m: f64,
}

impl std::fmt::Debug for DescentWind<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DescentWind")
            .field("estimate_ne_mps", &self.estimate_ne_mps)
            .field("profile", &self.profile.map(|(_, c)| c))
            .field("start_altitude_m", &self.start_altitude_m)
            .field("fade_height_m", &self.fade_height_m)
            .finish()
    }
}

impl<'a> DescentWind<'a> {
    /// The estimate's wind everywhere: what a prediction flies in without a profile.
    pub fn uniform(estimate_ned_mps: Vector3<f64>) -> Self {
        Self {
            estimate_ne_mps: estimate_ned_mps.xy(),
            profile: None,
            start_altitude_m: 0.0,
            fade_height_m: DEFAULT_FADE_HEIGHT_M,
        }
    }

    /// The estimate's wind `estimate_ned_mps` at `start_position_ned_m` (m, local NED) at
    /// `time_s`, and `profile` below it, corrected by their difference there, the correction
    /// fading out over `fade_height_m` (m; a non-positive or non-finite height means no
    /// fading band: the profile's own wind right below the start).
    pub fn with_profile(
        estimate_ned_mps: Vector3<f64>,
        profile: &'a dyn WindField,
        time_s: f64,
        start_position_ned_m: &Vector3<f64>,
        fade_height_m: f64,
    ) -> Self {
        let there = profile.wind_ned_mps(time_s, start_position_ned_m).xy();
        let correction = estimate_ned_mps.xy() - there;
        // A profile that gives nonsense (NaN) must not poison the prediction: without a
        // usable correction the estimate is all there is.
        if !correction.iter().all(|c| c.is_finite()) {
            return Self::uniform(estimate_ned_mps);
        }
        Self {
            estimate_ne_mps: estimate_ned_mps.xy(),
            profile: Some((profile, correction)),
            start_altitude_m: -start_position_ned_m.z,
            fade_height_m,
        }
    }

    /// The wind below the drone of estimate `est`: its wind corrected `profile` when there is
    /// one (see [`Self::with_profile`]), else its wind everywhere. What the landing
    /// prediction and the reachable footprint both fly in.
    pub fn below_estimate(
        est: &Estimate,
        profile: Option<&'a dyn WindField>,
        fade_height_m: f64,
    ) -> Self {
        match profile {
            Some(p) => Self::with_profile(
                est.wind_ned_mps,
                p,
                est.time_s,
                &est.position_ned_m,
                fade_height_m,
            ),
            None => Self::uniform(est.wind_ned_mps),
        }
    }

    /// Height below the start over which the correction fades, m.
    pub fn fade_height_m(&self) -> f64 {
        self.fade_height_m
    }

    /// The share of the correction kept `below_m` metres below the start: 1 at and above
    /// it, falling linearly to 0 at `fade_height_m`.
    fn weight(&self, below_m: f64) -> f64 {
        if !(self.fade_height_m > 0.0 && self.fade_height_m.is_finite()) {
            return if below_m <= 0.0 { 1.0 } else { 0.0 };
        }
        (1.0 - below_m / self.fade_height_m).clamp(0.0, 1.0)
    }

    /// Horizontal wind, NE, m/s, at `time_s` and `position_ned_m`.
    pub fn wind_ne_mps(&self, time_s: f64, position_ned_m: &Vector3<f64>) -> Vector2<f64> {
        let Some((profile, correction)) = self.profile else {
            return self.estimate_ne_mps;
        };
        let below = self.start_altitude_m + position_ned_m.z;
        let wind = profile.wind_ned_mps(time_s, position_ned_m).xy();
        if !wind.iter().all(|c| c.is_finite()) {
            return self.estimate_ne_mps;
        }
        wind + correction * self.weight(below)
    }
}

/// The descent wind as a field, for fast flights that take one (the reachable footprint).
impl WindField for DescentWind<'_> {
    fn wind_ned_mps(&self, time_s: f64, position_ned_m: &Vector3<f64>) -> Vector3<f64> {
        let ne = self.wind_ne_mps(time_s, position_ned_m);
        Vector3::new(ne.x, ne.y, 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use stx_types::wind::{ProfileRow, WindProfile};

    fn east_profile(rows: &[(f64, f64)]) -> WindProfile {
        WindProfile::new(
            rows.iter()
                .map(|&(altitude_m, east)| ProfileRow {
                    altitude_m,
                    speed_mps: east,
                    from_deg: 270.0,
                })
                .collect(),
        )
        .expect("valid profile")
    }

    fn at(altitude_m: f64) -> Vector3<f64> {
        Vector3::new(0.0, 0.0, -altitude_m)
    }

    #[test]
    fn the_estimate_holds_at_the_start_and_the_correction_fades_linearly_below() {
        let profile = east_profile(&[(0.0, 2.0), (2000.0, 2.0)]);
        let estimate = Vector3::new(1.0, 5.0, 0.3);
        let wind = DescentWind::with_profile(estimate, &profile, 0.0, &at(1000.0), 500.0);
        let close = |a: Vector2<f64>, b: [f64; 2]| (a - Vector2::new(b[0], b[1])).norm() < 1e-9;
        // Correction (1, 3): whole at the start (and above), half 250 m down, none 500 m down.
        assert!(close(wind.wind_ne_mps(0.0, &at(1000.0)), [1.0, 5.0]));
        assert!(close(wind.wind_ne_mps(0.0, &at(1200.0)), [1.0, 5.0]));
        assert!(close(wind.wind_ne_mps(0.0, &at(750.0)), [0.5, 3.5]));
        assert!(close(wind.wind_ne_mps(0.0, &at(500.0)), [0.0, 2.0]));
        assert!(close(wind.wind_ne_mps(0.0, &at(10.0)), [0.0, 2.0]));
    }

    #[test]
    fn without_a_profile_or_with_a_broken_one_the_estimate_is_used_everywhere() {
        let estimate = Vector3::new(-1.0, 2.0, 0.0);
        let wind = DescentWind::uniform(estimate);
        assert_eq!(wind.wind_ne_mps(0.0, &at(5.0)), Vector2::new(-1.0, 2.0));
        struct Broken;
        impl WindField for Broken {
            fn wind_ned_mps(&self, _: f64, _: &Vector3<f64>) -> Vector3<f64> {
                Vector3::repeat(f64::NAN)
            }
        }
        let wind = DescentWind::with_profile(estimate, &Broken, 0.0, &at(800.0), 500.0);
        assert_eq!(wind.wind_ne_mps(0.0, &at(100.0)), Vector2::new(-1.0, 2.0));
    }
}
