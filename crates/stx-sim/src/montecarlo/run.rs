//! One run of a campaign: its conditions drawn from `(seed, index)`, its wind, its flight from
//! the steady-glide template, and what it gave.

use std::f64::consts::PI;
use std::sync::Arc;

use nalgebra::Vector3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use stx_dynamics::atmosphere::StandardAtmosphere;
use stx_dynamics::integrate::{Hooks, IntegrateError, Rk4, integrate};
use stx_dynamics::model::{Environment, ParafoilModel};
use stx_dynamics::rotation::wrap_pi;
use stx_dynamics::state::{Pose, StateVector, idx};
use stx_dynamics::vehicle::Vehicle;
use stx_dynamics::wind::{
    ProfileRow, Turbulence, TurbulenceParams, WindComposite, WindField, WindProfile,
};
use stx_gnc::control::Localizer;
use stx_gnc::estimate::Estimate;
use stx_gnc::guidance::{Guidance, LearnedPolar, PhaseEvent, Plan};
use stx_gnc::mission::{FlightMode, GuidancePhase};

use super::config::MonteCarloConfig;
use super::growth::{MissGrowth, PhaseSnapshots};
use crate::anemometer::{Anemometer, AnemometerConfig};
use crate::closed_loop::{GuidedFlight, Navigator, SensorErrors, phase_name};
use crate::dispersions::{DispersedFlight, DrawSummary, WindShape};
use crate::guided::{CONTROL_PERIOD_S, STEP_S};
use crate::sensors::SensorConfig;

/// The conditions of one run.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RunConditions {
    /// Release point relative to the target (north, east), m.
    pub release_ne_m: [f64; 2],
    /// Heading at release, degrees.
    pub heading_deg: f64,
    /// Mean wind speed, m/s.
    pub wind_speed_mps: f64,
    /// Direction it blows from at the ground, degrees.
    pub wind_from_deg: f64,
    /// Seed of this run's turbulence, sensors and dispersions.
    pub seed: u64,
}

/// What one run gave.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RunResult {
    /// Index in the campaign.
    pub index: usize,
    /// Its conditions.
    pub conditions: RunConditions,
    /// How its vehicle differed from nominal (all ones and zero in a nominal campaign).
    pub vehicle_draw: DrawSummary,
    /// Its wind's shape.
    pub wind_shape: WindShape,
    /// Distance from the target to where the stack touched down, m.
    pub miss_m: f64,
    /// Canopy heading at touchdown minus the upwind direction, degrees.
    pub heading_vs_upwind_deg: f64,
    /// Canopy heading at touchdown minus where the surface wind comes from, degrees: the mean
    /// wind at the touchdown (shear, veer and the low-level turn, gusts left out), as a
    /// windsock or a weather report gives it; 0 in calm air.
    pub heading_vs_surface_wind_deg: f64,
    /// The mean wind where the stack touched down (gusts left out) was below
    /// [`CALM_WIND_MPS`]: there is no upwind to land into.
    pub calm: bool,
    /// Vertical speed of the first body to touch, m/s.
    pub touchdown_vertical_speed_mps: f64,
    /// Distance from the target to where the capsule (the payload) touched down, m: after
    /// the transponder's contact the stack flies on until it does.
    pub payload_miss_m: f64,
    /// For a payload miss of [`GROWTH_MISS_M`](super::GROWTH_MISS_M) or more: the guidance phase over which the
    /// landing guidance expected moved furthest from the target ([`MissGrowth`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub miss_grew: Option<MissGrowth>,
    /// What guidance had learned of the glide at each brake setting and of the turn by the
    /// touchdown.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub learned: Option<LearnedPolar>,
    /// The capsule's vertical speed at its touchdown, m/s.
    pub payload_touchdown_vertical_speed_mps: f64,
    /// Where the capsule touched down, north and east of the target, m.
    #[serde(default)]
    pub payload_touchdown_ne_m: [f64; 2],
    /// The keep-out zone the capsule came down in, by name (campaigns with zones only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub payload_zone: Option<String>,
    /// Time from the first contact to the capsule's, s.
    pub payload_after_first_contact_s: f64,
    /// RMS of the horizontal wind-estimate error from 30 s after release on, m/s.
    pub wind_estimate_rmse_mps: f64,
    /// What the estimator had learnt of the sensors by the touchdown, beside the truth (runs
    /// flown with sensors).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sensors_learned: Option<SensorsLearned>,
    /// Guidance found the target out of reach at some point.
    pub unreachable: bool,
    /// The best reachable point (north, east, m) guidance announced when it first called the
    /// target out of reach.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub best_reachable_ne_m: Option<[f64; 2]>,
    /// Distance from that point to where the stack touched down, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub from_best_reachable_m: Option<f64>,
    /// The best reachable point guidance announced last (it announces it again when it moves
    /// as the wind estimate firms up), north and east, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub last_best_reachable_ne_m: Option<[f64; 2]>,
    /// Distance from that point to the touchdown, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub from_last_best_reachable_m: Option<f64>,
    /// Called out of reach, then found the target within reach again and flew for it: the
    /// point guidance chose last is the target, not a best reachable point.
    #[serde(default)]
    pub back_in_reach: bool,
    /// For a run called out of reach, the payload's touchdown from the point guidance chose
    /// last (the best reachable point announced last, or the target if it came back within
    /// reach after that), m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub payload_from_last_aim_m: Option<f64>,
    /// Flight time, s.
    pub flight_time_s: f64,
    /// Touchdown point relative to the target along the upwind direction (positive: beyond
    /// the target, i.e. long) and across it (positive right), m.
    pub long_short_m: f64,
    /// See `long_short_m`.
    pub left_right_m: f64,
    /// The payload's touchdown the same way, m: it lands a couple of seconds after the first
    /// contact, further along.
    pub payload_long_short_m: f64,
    /// See `payload_long_short_m`.
    pub payload_left_right_m: f64,
    /// Guidance phase changes with their reasons (kept only when one run is replayed).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub events: Vec<PhaseEvent>,
    /// The flight every second (kept only when one run is replayed).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub track: Vec<TrackPoint>,
}

/// The sensor errors the estimator learns, as it had them at the touchdown beside the truth.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SensorsLearned {
    /// The AHRS's heading bias: the truth, the estimate and the estimate's 1-σ, degrees.
    pub heading_bias_deg: [f64; 3],
    /// The pitot's airspeed scale: the truth, the estimate and the estimate's 1-σ.
    pub pitot_scale: [f64; 3],
}

impl SensorsLearned {
    fn of(truth: SensorErrors, estimate: &Estimate) -> Self {
        Self {
            heading_bias_deg: [
                truth.heading_bias_rad.to_degrees(),
                estimate.heading_bias_rad.to_degrees(),
                estimate.heading_bias_sigma_rad.to_degrees(),
            ],
            pitot_scale: [
                truth.pitot_scale,
                estimate.pitot_scale,
                estimate.pitot_scale_sigma,
            ],
        }
    }

    /// The heading bias's estimate less the truth, degrees.
    pub fn heading_bias_error_deg(&self) -> f64 {
        self.heading_bias_deg[1] - self.heading_bias_deg[0]
    }

    /// The pitot scale's estimate less the truth.
    pub fn pitot_scale_error(&self) -> f64 {
        self.pitot_scale[1] - self.pitot_scale[0]
    }
}

/// One second of a replayed run: truth and what guidance saw.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct TrackPoint {
    /// Time, s.
    pub time_s: f64,
    /// True canopy position (north, east, height above the target), m.
    pub position_neh_m: [f64; 3],
    /// Estimated wind (north, east), m/s.
    pub wind_estimate_ne_mps: [f64; 2],
    /// True wind at the canopy (north, east), m/s.
    pub wind_ne_mps: [f64; 2],
    /// Guidance phase.
    pub phase: GuidancePhase,
    /// Final-approach height the spiral plans with, m.
    pub final_approach_height_m: f64,
    /// Symmetric brake commanded, 0…1.
    pub brake: f64,
}

/// Below this mean surface wind, m/s (about 1 kn), the air counts as calm: weather reports
/// (METAR) give a wind under 1 kn as calm, with no direction. Below it the gusts of a run outweigh its mean
/// wind and turn the instantaneous wind through any direction in seconds, so "upwind" at
/// touchdown is not something guidance could have known a final approach earlier.
pub const CALM_WIND_MPS: f64 = 0.5;

/// A steady glide (after the seed's initial conditions settle in still air), heading north at
/// the origin: the template every run's release state is rotated and moved from.
pub fn steady_glide_state(vehicle: &Vehicle) -> Result<StateVector, IntegrateError> {
    let mut model = ParafoilModel::new(
        vehicle.clone(),
        Environment {
            atmosphere: Arc::new(StandardAtmosphere),
            wind: Arc::new(stx_dynamics::wind::Calm),
            ground_altitude_msl_m: 0.0,
        },
    );
    let pose = Pose::seed_release(1000.0);
    let outcome = integrate(
        &mut Rk4::new(0.02),
        &mut model,
        0.0,
        &pose.to_state(),
        40.0,
        Hooks::default(),
    )?;
    let mut x = outcome.state;
    x[idx::POSITION] = 0.0;
    x[idx::POSITION + 1] = 0.0;
    x[idx::POSITION + 2] = 0.0;
    x[idx::CANOPY_EULER + 2] = 0.0;
    Ok(x)
}

/// Draws the conditions of run `index`.
pub fn conditions(config: &MonteCarloConfig, index: usize) -> RunConditions {
    let seed = config
        .seed
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add(index as u64);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let radius = config.release_radius_m * rng.random::<f64>().sqrt();
    let bearing = 2.0 * PI * rng.random::<f64>();
    RunConditions {
        release_ne_m: [radius * bearing.cos(), radius * bearing.sin()],
        heading_deg: 360.0 * rng.random::<f64>() - 180.0,
        wind_speed_mps: config.wind_max_mps * rng.random::<f64>(),
        wind_from_deg: 360.0 * rng.random::<f64>(),
        seed: rng.random::<u64>(),
    }
}

/// The wind of a run: the mean speed sheared over height (by the shape's fraction about the
/// mean from the ground to the release height, veering by its angle), turning by its low-level
/// angle near the ground, plus Dryden turbulence of 10 % of the mean speed (at least 0.1 m/s)
/// times its gust factor.
pub fn wind_field(
    c: &RunConditions,
    shape: &WindShape,
    altitude_m: f64,
) -> Result<WindComposite, stx_dynamics::wind::WindError> {
    let top = altitude_m + 100.0;
    let low = shape.low_level_height_m;
    let mut heights: Vec<f64> = (0..=4).map(|k| k as f64 / 4.0 * top).collect();
    if shape.low_level_turn_deg != 0.0 {
        heights.extend([low, 2.0 * low].into_iter().filter(|h| *h < top));
        heights.sort_by(f64::total_cmp);
        heights.dedup();
    }
    let rows = heights
        .into_iter()
        .map(|h| {
            let f = h / top;
            // The low-level turn is whole below `low` and fades out by twice that height.
            let turn = shape.low_level_turn_deg * ((2.0 * low - h) / low).clamp(0.0, 1.0);
            ProfileRow {
                altitude_m: h,
                speed_mps: c.wind_speed_mps
                    * (1.0 - shape.shear_fraction + 2.0 * shape.shear_fraction * f),
                from_deg: (c.wind_from_deg + shape.veer_deg * f + turn).rem_euclid(360.0),
            }
        })
        .collect();
    let sigma = (0.1 * c.wind_speed_mps).max(0.1) * shape.gust_factor;
    let turbulence = Turbulence::new(TurbulenceParams {
        sigma_horizontal_mps: sigma,
        sigma_vertical_mps: 0.5 * sigma,
        length_scale_horizontal_m: 200.0,
        length_scale_vertical_m: 50.0,
        reference_airspeed_mps: 6.7,
        seed: c.seed,
        components: 24,
    })?;
    Ok(WindComposite {
        mean: Box::new(WindProfile::new(rows)?),
        turbulence: Some(turbulence),
    })
}

/// The wind shape of run `c` under the campaign's dispersions.
pub fn wind_shape(config: &MonteCarloConfig, c: &RunConditions) -> WindShape {
    WindShape::draw(
        &config.dispersions,
        &mut ChaCha8Rng::seed_from_u64(c.seed ^ 0x005E_ED0F_517D),
    )
}

/// Flies run `index` with navigation from `navigator(&conditions)`.
pub fn run_one<N: Navigator>(
    config: &MonteCarloConfig,
    vehicle: &Vehicle,
    template: &StateVector,
    index: usize,
    navigator: impl Fn(&RunConditions, &SensorConfig) -> Result<N, String>,
) -> Result<RunResult, String> {
    let c = conditions(config, index);
    let shape = wind_shape(config, &c);
    let composite = Arc::new(wind_field(&c, &shape, config.altitude_m).map_err(|e| e.to_string())?);
    let drawn = DispersedFlight::draw(
        &config.dispersions,
        &vehicle.config,
        &config.sensors,
        c.seed,
    )
    .map_err(|e| format!("dispersed vehicle refused: {e}"))?;
    // A failed run names the stack it was flying: a model that fails is usually a draw far
    // from nominal (a low rigging angle settles into a deep stall).
    let draw = drawn.summary;
    let with_draw = |e: String| {
        format!(
            "{e} (drawn stack: lift slope ×{:.2}, zero-lift drag ×{:.2}, brake lift ×{:.2}, \
             mass ×{:.2}, rigging {:+.1}°)",
            draw.cl_alpha, draw.cd0, draw.cl_ds, draw.mass, draw.rigging_deg
        )
    };
    let wind: Arc<dyn WindField> = composite.clone();
    let model = ParafoilModel::new(
        drawn.vehicle,
        Environment {
            atmosphere: Arc::new(StandardAtmosphere),
            wind: wind.clone(),
            ground_altitude_msl_m: stx_gnc::geo::LocalFrame::default().alt_msl_m,
        },
    );
    let mut x = *template;
    x[idx::POSITION] = c.release_ne_m[0];
    x[idx::POSITION + 1] = c.release_ne_m[1];
    x[idx::POSITION + 2] = -config.altitude_m;
    x[idx::CANOPY_EULER + 2] = c.heading_deg.to_radians();
    let mut guidance_config = config.guidance;
    guidance_config.spiral.flare = config.flare;
    let mut guidance = Guidance::new(guidance_config);
    if config.keep_out_guided {
        guidance.set_keep_out(config.keep_out.clone());
    }
    guidance.set_plan(
        Plan {
            target_ned_m: Vector3::zeros(),
            ..Plan::default()
        },
        0.0,
    );
    guidance.set_mode(FlightMode::SpiralLanding, 0.0);
    let mut flight = GuidedFlight::new(
        model,
        x,
        0.0,
        guidance,
        navigator(&c, &drawn.sensors)?,
        STEP_S,
        CONTROL_PERIOD_S,
    );
    flight.servos = drawn.servos;
    let mut wind_error_sq = 0.0;
    let mut wind_samples = 0usize;
    let replay = config.only_run == Some(index);
    let mut track = Vec::new();
    let mut next_track_s = 0.0;
    let mut anemometer = config
        .anemometer
        .then(|| Anemometer::new(AnemometerConfig::default(), c.seed));
    let mut snapshots = PhaseSnapshots::default();
    let touchdown = loop {
        if let Some(t) = flight.advance().map_err(|e| with_draw(e.to_string()))? {
            break t;
        }
        snapshots.observe(&flight.guidance, flight.estimate.as_ref());
        if let Some(report) = anemometer
            .as_mut()
            .and_then(|a| a.step(flight.time_s, &*wind))
        {
            flight.guidance.set_surface_wind(Some(report));
        }
        if replay
            && let Some(est) = flight.estimate
            && est.time_s >= next_track_s
        {
            next_track_s += 1.0;
            let p = Vector3::new(
                flight.state[idx::POSITION],
                flight.state[idx::POSITION + 1],
                flight.state[idx::POSITION + 2],
            );
            let truth = wind.wind_ned_mps(est.time_s, &p);
            track.push(TrackPoint {
                time_s: est.time_s,
                position_neh_m: [p.x, p.y, -p.z],
                wind_estimate_ne_mps: [est.wind_ned_mps.x, est.wind_ned_mps.y],
                wind_ne_mps: [truth.x, truth.y],
                phase: flight.guidance.phase(),
                final_approach_height_m: flight.guidance.spiral_status().final_approach_height_m,
                brake: flight.model.controls().brake_left,
            });
        }
        if let Some(est) = flight.estimate
            && est.time_s >= 30.0
        {
            let truth = wind.wind_ned_mps(est.time_s, &est.position_ned_m);
            let (dn, de) = (est.wind_ned_mps.x - truth.x, est.wind_ned_mps.y - truth.y);
            wind_error_sq += dn * dn + de * de;
            wind_samples += 1;
        }
        if flight.time_s > 4.0 * config.altitude_m {
            return Err(format!(
                "run {index} still flying after {} s",
                flight.time_s
            ));
        }
    };
    // Before the payload's landing: the estimate of the first contact, as guidance last had it.
    let sensors_learned = flight
        .navigator
        .sensor_errors()
        .zip(flight.estimate.as_ref())
        .map(|(truth, estimate)| SensorsLearned::of(truth, estimate));
    let payload = flight.land_payload(touchdown).map_err(with_draw)?;
    let payload_miss_m = payload.position_ne_m[0].hypot(payload.position_ne_m[1]);
    let miss_grew = snapshots.where_miss_grew(
        payload.position_ne_m,
        payload_miss_m,
        stx_gnc::geo::LocalFrame::default().alt_msl_m,
    );
    let heading_vs_upwind = if touchdown.upwind_rad.is_finite() {
        wrap_pi(touchdown.heading_rad - touchdown.upwind_rad).to_degrees()
    } else {
        0.0
    };
    let mean_wind_at_touchdown = composite.mean.wind_ned_mps(
        touchdown.time_s,
        &Vector3::new(touchdown.position_ne_m[0], touchdown.position_ne_m[1], 0.0),
    );
    let heading_vs_surface_wind = if mean_wind_at_touchdown.x.hypot(mean_wind_at_touchdown.y) > 1e-6
    {
        let upwind = (-mean_wind_at_touchdown.y).atan2(-mean_wind_at_touchdown.x);
        wrap_pi(touchdown.heading_rad - upwind).to_degrees()
    } else {
        0.0
    };
    let first_announced = flight.best_reachable_announced.first().map(|(_, ne)| *ne);
    let last_announced = flight.best_reachable_announced.last().map(|(_, ne)| *ne);
    let back_in_reach = chose_the_target_again(&flight.phases);
    let last_aim = last_announced.map(|best| if back_in_reach { [0.0, 0.0] } else { best });
    let apart = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let from_touchdown = |b: [f64; 2]| apart(touchdown.position_ne_m, b);
    // Touchdowns along the upwind line through the target (long +) and across it (right +);
    // zeros when the direction is unknown.
    let upwind = touchdown.upwind_rad.is_finite().then_some(Localizer {
        point_ne_m: [0.0, 0.0],
        course_rad: touchdown.upwind_rad,
    });
    let along_and_across = |ne_m: [f64; 2]| {
        upwind.map_or([0.0, 0.0], |line| {
            [line.along_track_m(ne_m), line.cross_track_m(ne_m)]
        })
    };
    let [long_short_m, left_right_m] = along_and_across(touchdown.position_ne_m);
    let [payload_long_short_m, payload_left_right_m] = along_and_across(payload.position_ne_m);
    Ok(RunResult {
        index,
        vehicle_draw: drawn.summary,
        wind_shape: shape,
        miss_m: touchdown.position_ne_m[0].hypot(touchdown.position_ne_m[1]),
        heading_vs_upwind_deg: heading_vs_upwind,
        heading_vs_surface_wind_deg: heading_vs_surface_wind,
        calm: mean_wind_at_touchdown.x.hypot(mean_wind_at_touchdown.y) < CALM_WIND_MPS,
        touchdown_vertical_speed_mps: touchdown.vertical_speed_mps,
        payload_miss_m,
        miss_grew,
        learned: Some(flight.guidance.learned_polar()),
        payload_touchdown_vertical_speed_mps: payload.vertical_speed_mps,
        payload_touchdown_ne_m: payload.position_ne_m,
        payload_zone: config
            .keep_out
            .zone_at(payload.position_ne_m)
            .map(|z| z.name.clone()),
        payload_after_first_contact_s: payload.time_s - touchdown.time_s,
        wind_estimate_rmse_mps: if wind_samples > 0 {
            (wind_error_sq / wind_samples as f64).sqrt()
        } else {
            0.0
        },
        sensors_learned,
        unreachable: !flight.best_reachable_announced.is_empty(),
        best_reachable_ne_m: first_announced,
        from_best_reachable_m: first_announced.map(from_touchdown),
        last_best_reachable_ne_m: last_announced,
        from_last_best_reachable_m: last_announced.map(from_touchdown),
        back_in_reach,
        payload_from_last_aim_m: last_aim.map(|aim| apart(payload.position_ne_m, aim)),
        flight_time_s: touchdown.time_s,
        long_short_m,
        left_right_m,
        payload_long_short_m,
        payload_left_right_m,
        conditions: c,
        events: if replay {
            std::mem::take(&mut flight.events)
        } else {
            Vec::new()
        },
        track,
    })
}

/// Whether guidance, having called the target out of reach, found it within reach again and
/// flew for it: it leaves the best reachable point only for the target ("within reach again"
/// enters the approximation), so an approximation entered after the last best reachable point
/// is the target chosen again. `phases` as [`GuidedFlight::phases`] keeps them.
fn chose_the_target_again(phases: &[(String, f64)]) -> bool {
    let (best, approach) = (
        phase_name(GuidancePhase::BestReachable),
        phase_name(GuidancePhase::Approximation),
    );
    phases
        .iter()
        .rposition(|(name, _)| *name == best)
        .is_some_and(|i| phases[i..].iter().any(|(name, _)| *name == approach))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn phases(names: &[&str]) -> Vec<(String, f64)> {
        names
            .iter()
            .enumerate()
            .map(|(i, n)| (n.to_string(), i as f64 * 10.0))
            .collect()
    }

    /// Only a return to the approximation after the last call out of reach is the target chosen
    /// again: one before it, or a flare on the way to the best point, is not.
    #[test]
    fn the_target_is_chosen_again_only_by_an_approximation_after_the_last_best_point() {
        let back = phases(&[
            "approximation",
            "branch1",
            "best_reachable",
            "approximation",
            "final_approach",
        ]);
        assert!(chose_the_target_again(&back));
        let stayed = phases(&[
            "approximation",
            "best_reachable",
            "approximation",
            "best_reachable",
            "flare",
        ]);
        assert!(!chose_the_target_again(&stayed));
        assert!(!chose_the_target_again(&phases(&[
            "approximation",
            "branch1",
            "final_approach"
        ])));
        assert!(!chose_the_target_again(&[]));
    }
}
