//! Landing prediction: where the vehicle comes down if it flies its current plan, and if it is
//! left uncontrolled, each with a 1-σ uncertainty ellipse — what the recovery team drives to.
//!
//! Both fly the [`PointMass`] to the ground in fast time from the current estimate: the planned
//! prediction runs a copy of guidance in the loop, the uncontrolled one holds neutral servos.
//! Uncertainty is carried by sigma points (the unscented transform): the flight is repeated
//! with the wind, the airspeed, the sink rate and the heading moved by ±√n σ, and the spread of
//! the touchdown points gives the covariance whose ellipse is reported.

use nalgebra::{Matrix2, Vector2, Vector3};
use serde::{Deserialize, Serialize};
use stx_types::atmosphere::Atmosphere;
use stx_types::controls::Controls;
use stx_types::wind::WindField;

use crate::descent_wind::{DEFAULT_FADE_HEIGHT_M, DescentWind};
use crate::estimate::Estimate;
use crate::guidance::Guidance;
use crate::mission::FlightMode;
use crate::performance::GlidePerformance;
use crate::pointmass::{Conditions, PointMass};

/// A predicted touchdown.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PredictedTouchdown {
    /// Touchdown point (north, east), local NED, m.
    pub position_ne_m: [f64; 2],
    /// Seconds from now to touchdown.
    pub time_to_land_s: f64,
    /// Semi-major axis of the 1-σ ellipse, m.
    pub semi_major_m: f64,
    /// Semi-minor axis of the 1-σ ellipse, m.
    pub semi_minor_m: f64,
    /// Direction of the major axis from north, rad.
    pub major_axis_rad: f64,
}

/// Both predictions.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LandingPrediction {
    /// Instant of the estimate they start from, s.
    pub time_s: f64,
    /// Flying the current plan (guidance in the loop).
    pub planned: PredictedTouchdown,
    /// With the servos left neutral.
    pub uncontrolled: PredictedTouchdown,
}

/// Settings of the predictor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PredictorConfig {
    /// Time step of the fast-time flight, s.
    pub step_s: f64,
    /// Guidance is updated every this many steps (its real rate is 4 Hz).
    pub guidance_every: usize,
    /// Longest flight predicted, s.
    pub horizon_s: f64,
    /// 1-σ of the airspeed relative to the nominal parafoil (fraction).
    pub airspeed_sigma_fraction: f64,
    /// 1-σ of the sink rate relative to the nominal parafoil (fraction).
    pub sink_sigma_fraction: f64,
    /// Height of the drone above the lowest body, m: touchdown is when it is this high.
    pub hang_height_m: f64,
    /// Height below the drone over which a wind profile's correction by the estimate fades
    /// out, m (see [`crate::descent_wind`]); used only by [`predict_in_wind`] with a profile.
    pub profile_fade_height_m: f64,
}

impl Default for PredictorConfig {
    fn default() -> Self {
        Self {
            step_s: 0.5,
            guidance_every: 1,
            horizon_s: 4.0 * 3600.0,
            airspeed_sigma_fraction: 0.05,
            sink_sigma_fraction: 0.05,
            hang_height_m: 8.4,
            profile_fade_height_m: DEFAULT_FADE_HEIGHT_M,
        }
    }
}

/// One perturbation of the sigma-point set: wind north/east offsets (m/s), airspeed and sink
/// scale factors, heading offset (rad).
#[derive(Debug, Clone, Copy)]
struct Perturbation {
    wind_ne_mps: [f64; 2],
    airspeed_scale: f64,
    sink_scale: f64,
    heading_rad: f64,
}

const DIMENSIONS: usize = 5;

fn sigma_points(est: &Estimate, config: &PredictorConfig) -> Vec<(f64, Perturbation)> {
    // Unscented transform with κ = 0: the centre weighs 0, each of the 2n points 1/(2n).
    let spread = (DIMENSIONS as f64).sqrt();
    let nominal = Perturbation {
        wind_ne_mps: [0.0, 0.0],
        airspeed_scale: 1.0,
        sink_scale: 1.0,
        heading_rad: 0.0,
    };
    let mut points = vec![(0.0, nominal)];
    let weight = 1.0 / (2.0 * DIMENSIONS as f64);
    for sign in [1.0, -1.0] {
        let d = sign * spread;
        let mut p = nominal;
        p.wind_ne_mps[0] = d * est.wind_sigma_mps.x;
        points.push((weight, p));
        let mut p = nominal;
        p.wind_ne_mps[1] = d * est.wind_sigma_mps.y;
        points.push((weight, p));
        let mut p = nominal;
        p.airspeed_scale = 1.0 + d * config.airspeed_sigma_fraction;
        points.push((weight, p));
        let mut p = nominal;
        p.sink_scale = (1.0 + d * config.sink_sigma_fraction).max(0.1);
        points.push((weight, p));
        let mut p = nominal;
        p.heading_rad = d * est.heading_sigma_rad;
        points.push((weight, p));
    }
    points
}

/// Predicts both touchdowns from `est` with `guidance` (cloned; the real one is untouched),
/// the ground `ground_altitude_msl_m` above sea level at the NED origin, and the atmosphere,
/// in the estimate's wind, the same at every altitude.
pub fn predict(
    est: &Estimate,
    guidance: &Guidance,
    perf: &GlidePerformance,
    atmosphere: &dyn Atmosphere,
    ground_altitude_msl_m: f64,
    config: &PredictorConfig,
) -> LandingPrediction {
    predict_in_wind(
        est,
        guidance,
        perf,
        atmosphere,
        ground_altitude_msl_m,
        config,
        None,
    )
}

/// As [`predict`], but below the drone in `profile` (altitudes above the NED origin) when
/// there is one: the estimate's wind at the drone's altitude, the profile's lower down, the
/// difference between them fading out over `config.profile_fade_height_m`.
pub fn predict_in_wind(
    est: &Estimate,
    guidance: &Guidance,
    perf: &GlidePerformance,
    atmosphere: &dyn Atmosphere,
    ground_altitude_msl_m: f64,
    config: &PredictorConfig,
    profile: Option<&dyn WindField>,
) -> LandingPrediction {
    let wind = DescentWind::below_estimate(est, profile, config.profile_fade_height_m);
    let points = sigma_points(est, config);
    let fly = |planned: bool| {
        let outcomes: Vec<(f64, [f64; 2], f64)> = points
            .iter()
            .map(|(w, p)| {
                let (ne, t) = fly_one(
                    est,
                    &wind,
                    planned.then_some(guidance),
                    perf,
                    atmosphere,
                    ground_altitude_msl_m,
                    config,
                    p,
                );
                (*w, ne, t)
            })
            .collect();
        summarise(&outcomes)
    };
    LandingPrediction {
        time_s: est.time_s,
        planned: fly(matches!(
            guidance.mode(),
            FlightMode::Heading
                | FlightMode::Course
                | FlightMode::Localizer
                | FlightMode::SpiralLanding
        )),
        uncontrolled: fly(false),
    }
}

/// Where the vehicle comes down flying its plan from `est` with `guidance` (cloned), the
/// nominal flight of [`predict`] alone (no sigma points, no uncontrolled flight): one fast-time
/// flight, for callers that need many predictions and no ellipse (the Monte Carlo's account
/// of where a run's miss grew). North, east, m.
pub fn planned_touchdown_ne_m(
    est: &Estimate,
    guidance: &Guidance,
    perf: &GlidePerformance,
    atmosphere: &dyn Atmosphere,
    ground_altitude_msl_m: f64,
    config: &PredictorConfig,
) -> [f64; 2] {
    let wind = DescentWind::below_estimate(est, None, config.profile_fade_height_m);
    let (_, nominal) = sigma_points(est, config)[0];
    fly_one(
        est,
        &wind,
        Some(guidance),
        perf,
        atmosphere,
        ground_altitude_msl_m,
        config,
        &nominal,
    )
    .0
}

#[allow(clippy::too_many_arguments)]
fn fly_one(
    est: &Estimate,
    field: &DescentWind<'_>,
    guidance: Option<&Guidance>,
    perf: &GlidePerformance,
    atmosphere: &dyn Atmosphere,
    ground_altitude_msl_m: f64,
    config: &PredictorConfig,
    p: &Perturbation,
) -> ([f64; 2], f64) {
    let wind_at = |mass: &PointMass| {
        let w = field.wind_ne_mps(mass.time_s, &mass.position_ned_m);
        Vector3::new(w.x + p.wind_ne_mps[0], w.y + p.wind_ne_mps[1], 0.0)
    };
    let mut guidance = guidance.cloned();
    let mut mass = PointMass::new(
        est.time_s,
        est.position_ned_m,
        est.heading_rad + p.heading_rad,
    );
    let mut controls = Controls::default();
    let start = est.time_s;
    let touchdown_height = config.hang_height_m;
    let mut steps = 0usize;
    while -mass.position_ned_m.z > touchdown_height && mass.time_s - start < config.horizon_s {
        let density = atmosphere
            .air_at(ground_altitude_msl_m - mass.position_ned_m.z)
            .density_kg_per_m3;
        let wind = wind_at(&mass);
        if let Some(g) = guidance.as_mut()
            && steps.is_multiple_of(config.guidance_every.max(1))
        {
            controls = g.update(&mass.estimate(&wind), density).controls;
        }
        let before = mass;
        let air = Conditions {
            wind_ned_mps: wind,
            density_kg_per_m3: density,
            airspeed_scale: p.airspeed_scale,
            sink_scale: p.sink_scale,
        };
        mass.step(perf, &controls, &air, config.step_s);
        steps += 1;
        if -mass.position_ned_m.z <= touchdown_height {
            // Interpolate to the touchdown height inside the step.
            let h0 = -before.position_ned_m.z - touchdown_height;
            let h1 = -mass.position_ned_m.z - touchdown_height;
            let f = if (h0 - h1).abs() > 1e-12 {
                h0 / (h0 - h1)
            } else {
                1.0
            };
            let ne = before.position_ned_m + (mass.position_ned_m - before.position_ned_m) * f;
            return ([ne.x, ne.y], before.time_s + f * config.step_s - start);
        }
    }
    (
        [mass.position_ned_m.x, mass.position_ned_m.y],
        mass.time_s - start,
    )
}

fn summarise(outcomes: &[(f64, [f64; 2], f64)]) -> PredictedTouchdown {
    // The nominal (first) flight is the prediction; the weighted spread about it the
    // covariance.
    let (_, centre, time) = outcomes[0];
    let c = Vector2::new(centre[0], centre[1]);
    let mut cov = Matrix2::zeros();
    for (w, ne, _) in &outcomes[1..] {
        let d = Vector2::new(ne[0], ne[1]) - c;
        cov += d * d.transpose() * *w;
    }
    let (a, b, d) = (cov[(0, 0)], cov[(0, 1)], cov[(1, 1)]);
    let mean = 0.5 * (a + d);
    let radius = (0.25 * (a - d) * (a - d) + b * b).sqrt();
    let major = (mean + radius).max(0.0).sqrt();
    let minor = (mean - radius).max(0.0).sqrt();
    let angle = 0.5 * (2.0 * b).atan2(a - d);
    PredictedTouchdown {
        position_ne_m: centre,
        time_to_land_s: time,
        semi_major_m: major,
        semi_minor_m: minor,
        major_axis_rad: angle,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guidance::{GuidanceConfig, Plan};
    use stx_types::atmosphere::AirState;
    use stx_types::atmosphere::UniformAir;

    fn still_estimate(height_m: f64, wind_ne: [f64; 2], wind_sigma: f64) -> Estimate {
        let perf = GlidePerformance::default();
        let mut mass = PointMass::new(0.0, Vector3::new(0.0, 0.0, -height_m), 0.0);
        let wind = Vector3::new(wind_ne[0], wind_ne[1], 0.0);
        mass.step(
            &perf,
            &Controls::default(),
            &Conditions::nominal(wind, 1.225),
            0.01,
        );
        let mut est = mass.estimate(&wind);
        est.wind_sigma_mps = Vector3::new(wind_sigma, wind_sigma, 0.0);
        est.heading_sigma_rad = 0.02;
        est
    }

    /// Guidance landing on (north, east) in spiral mode.
    fn spiral_landing_on(north_m: f64, east_m: f64) -> Guidance {
        let mut guidance = Guidance::new(GuidanceConfig::default());
        guidance.set_plan(
            Plan {
                target_ned_m: Vector3::new(north_m, east_m, 0.0),
                ..Plan::default()
            },
            0.0,
        );
        guidance.set_mode(FlightMode::SpiralLanding, 0.0);
        guidance
    }

    fn sea_level() -> UniformAir {
        UniformAir(AirState::sea_level())
    }

    #[test]
    fn uncontrolled_prediction_is_the_straight_glide_plus_drift_with_a_growing_ellipse() {
        let perf = GlidePerformance::default();
        let guidance = Guidance::new(GuidanceConfig::default());
        let est = still_estimate(308.4, [0.0, 2.0], 0.3);
        let p = predict(
            &est,
            &guidance,
            &perf,
            &sea_level(),
            0.0,
            &PredictorConfig::default(),
        );
        // 300 m at 2.95 m/s ≈ 102 s: 6.06 m/s north, 2 m/s east.
        let t = 300.0 / perf.sink_rate(0.0, 0.0, 1.225);
        let u = p.uncontrolled;
        assert!((u.time_to_land_s - t).abs() < 1.0, "{u:?}");
        assert!((u.position_ne_m[0] - perf.horizontal_airspeed(0.0, 1.225) * t).abs() < 5.0);
        assert!((u.position_ne_m[1] - 2.0 * t).abs() < 5.0);
        // The wind's 0.3 m/s over 102 s is the main uncertainty: about 30 m.
        assert!(u.semi_major_m > 20.0 && u.semi_major_m < 60.0, "{u:?}");
        let higher = predict(
            &still_estimate(608.4, [0.0, 2.0], 0.3),
            &guidance,
            &perf,
            &sea_level(),
            0.0,
            &PredictorConfig::default(),
        );
        assert!(higher.uncontrolled.semi_major_m > 1.5 * u.semi_major_m);
    }

    #[test]
    fn planned_prediction_of_a_spiral_landing_is_near_the_target() {
        let perf = GlidePerformance::default();
        let guidance = spiral_landing_on(200.0, 100.0);
        let est = still_estimate(500.0, [-1.0, 0.5], 0.2);
        let p = predict(
            &est,
            &guidance,
            &perf,
            &sea_level(),
            0.0,
            &PredictorConfig::default(),
        );
        let miss = (p.planned.position_ne_m[0] - 200.0).hypot(p.planned.position_ne_m[1] - 100.0);
        assert!(miss < 30.0, "planned touchdown {:?}", p.planned);
        let far = (p.uncontrolled.position_ne_m[0] - 200.0)
            .hypot(p.uncontrolled.position_ne_m[1] - 100.0);
        assert!(
            far > 300.0,
            "uncontrolled flies straight on: {:?}",
            p.uncontrolled
        );
    }

    /// The planned landing's ellipse: guidance steers most of the wind's uncertainty out, so
    /// it is much smaller than the uncontrolled one from the same estimate, and it grows when
    /// the wind is less certain.
    #[test]
    fn the_planned_landing_ellipse_is_tight_and_grows_with_the_wind_uncertainty() {
        let perf = GlidePerformance::default();
        let guidance = spiral_landing_on(200.0, 100.0);
        let predict_with = |wind_sigma: f64| {
            predict(
                &still_estimate(500.0, [-1.0, 0.5], wind_sigma),
                &guidance,
                &perf,
                &sea_level(),
                0.0,
                &PredictorConfig::default(),
            )
        };
        let sure = predict_with(0.1);
        let unsure = predict_with(1.0);
        let p = sure.planned;
        assert!(p.semi_major_m.is_finite() && p.semi_major_m >= p.semi_minor_m);
        assert!(p.semi_minor_m >= 0.0);
        assert!(
            p.semi_major_m < 0.25 * sure.uncontrolled.semi_major_m,
            "planned {p:?}, uncontrolled {:?}",
            sure.uncontrolled
        );
        assert!(
            unsure.planned.semi_major_m > p.semi_major_m,
            "{:?} vs {p:?}",
            unsure.planned
        );
        assert!(unsure.uncontrolled.semi_major_m > 2.0 * sure.uncontrolled.semi_major_m);
        // The time to land is the same flight's, not a fixed guess.
        assert!(
            p.time_to_land_s > 100.0 && p.time_to_land_s < 400.0,
            "{p:?}"
        );
    }

    /// A profile blowing east (from the west) at `rows` (altitude m, speed m/s).
    fn westerly(rows: &[(f64, f64)]) -> stx_types::wind::WindProfile {
        stx_types::wind::WindProfile::new(
            rows.iter()
                .map(|&(altitude_m, speed_mps)| stx_types::wind::ProfileRow {
                    altitude_m,
                    speed_mps,
                    from_deg: 270.0,
                })
                .collect(),
        )
        .expect("valid profile")
    }

    /// Both predictions from `est` in `profile` (no plan), over sea-level ground and air.
    fn in_profile(
        est: &Estimate,
        profile: &stx_types::wind::WindProfile,
        config: &PredictorConfig,
    ) -> LandingPrediction {
        let guidance = Guidance::new(GuidanceConfig::default());
        let perf = GlidePerformance::default();
        predict_in_wind(
            est,
            &guidance,
            &perf,
            &sea_level(),
            0.0,
            config,
            Some(profile),
        )
    }

    /// Two layers, 6 m/s above 400 m and 2 m/s below, the estimate agreeing with the upper
    /// one: the uncontrolled glide drifts 6 m/s × its time above 400 m plus 2 m/s × its
    /// time below (constant sink in sea-level air), where the estimate's wind alone would
    /// drift 6 m/s all the way down.
    #[test]
    fn a_two_layer_profile_moves_the_touchdown_by_each_layers_wind_times_the_time_in_it() {
        let perf = GlidePerformance::default();
        let guidance = Guidance::new(GuidanceConfig::default());
        let est = still_estimate(808.4, [0.0, 6.0], 0.3);
        let config = PredictorConfig::default();
        let profile = westerly(&[(0.0, 2.0), (400.0, 2.0), (400.001, 6.0), (3000.0, 6.0)]);
        let layered = in_profile(&est, &profile, &config);
        let uniform = predict(&est, &guidance, &perf, &sea_level(), 0.0, &config);
        let sink = perf.sink_rate(0.0, 0.0, 1.225);
        let (t_upper, t_lower) = ((808.4 - 0.01 * sink - 400.0) / sink, (400.0 - 8.4) / sink);
        let east = layered.uncontrolled.position_ne_m[1];
        // 0.5-s steps at 6 m/s: a few metres of discretisation.
        assert!(
            (east - (6.0 * t_upper + 2.0 * t_lower)).abs() < 3.0,
            "east {east:.1} m, closed form {:.1} m",
            6.0 * t_upper + 2.0 * t_lower
        );
        let shift = uniform.uncontrolled.position_ne_m[1] - east;
        assert!((shift - 4.0 * t_lower).abs() < 3.0, "shift {shift:.1} m");
        // The glide itself (north) does not depend on the wind.
        let north_gap =
            layered.uncontrolled.position_ne_m[0] - uniform.uncontrolled.position_ne_m[0];
        assert!(north_gap.abs() < 0.5, "{north_gap}");
        assert!(
            (layered.uncontrolled.time_to_land_s - uniform.uncontrolled.time_to_land_s).abs() < 0.1
        );
    }

    /// A profile of 2 m/s everywhere against an estimate of 5 m/s: the 3-m/s correction
    /// fades linearly over 500 m, adding 3 m/s × half the time spent in those 500 m to the
    /// profile's 2 m/s × the whole descent.
    #[test]
    fn a_biased_profile_is_corrected_by_the_estimate_fading_over_the_documented_height() {
        let perf = GlidePerformance::default();
        let est = still_estimate(808.4, [0.0, 5.0], 0.3);
        let config = PredictorConfig {
            profile_fade_height_m: 500.0,
            ..PredictorConfig::default()
        };
        let profile = westerly(&[(0.0, 2.0)]);
        let p = in_profile(&est, &profile, &config);
        let sink = perf.sink_rate(0.0, 0.0, 1.225);
        let expected = 2.0 * 800.0 / sink + 3.0 * 0.5 * 500.0 / sink;
        let east = p.uncontrolled.position_ne_m[1];
        assert!(
            (east - expected).abs() < 3.0,
            "east {east:.1} m, closed form {expected:.1} m"
        );
    }
}
