//! The physics of the footprint: for one dispersed draw, the discs of ground the parafoil can
//! reach, one per brake setting of the glide table.
//!
//! The descent is integrated once per refresh over height layers (the wind field and the air
//! density read per layer), giving for each brake setting `b` three sums over the layers k of
//! thickness `dz_k` at sink rate `s_b(ρ_k)`:
//!
//! - the time to the ground `T_b = Σ dz_k / s_b`,
//! - the drift of the air mass `W_b = Σ w_k dz_k / s_b`,
//! - the still-air reach `R_b = Σ v_b(ρ_k) dz_k / s_b`, counted only above the reserve height.
//!
//! A draw scales the sink by `σ_s`-dispersed `s`, the airspeed by `a`, and offsets the wind by a
//! constant `δw` and the start by `δp`. Everything above is linear in those, so a draw costs a
//! few multiplications per brake setting: centre `p + δp + (W_b + δw T_b)/s`, radius
//! `a R_b / s − margin`.

use nalgebra::Vector2;
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};

use super::FootprintInput;
use super::config::FootprintConfig;
use crate::performance::BRAKE_POINTS;

/// A disc of reachable ground, local (north, east), m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Disc {
    pub centre_ne_m: Vector2<f64>,
    pub radius_m: f64,
}

/// The descent's sums for one brake setting, undispersed.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Column {
    /// Time to touchdown, s.
    pub time_s: f64,
    /// Drift of the air mass over the descent (north, east), m.
    pub drift_ne_m: Vector2<f64>,
    /// Still-air reach above the reserve height, m.
    pub reach_m: f64,
}

/// Integrates the descent from the estimate's height for each brake setting of the table.
pub(crate) fn columns(input: &FootprintInput, config: &FootprintConfig) -> [Column; BRAKE_POINTS] {
    let est = input.estimate;
    let perf = input.performance;
    let top = est.height_m();
    let bottom = config.hang_height_m;
    let reserve_top = bottom + config.reserve_height_m;
    let uniform = est.wind_ned_mps;
    let mut out = [Column::default(); BRAKE_POINTS];
    for (b, column) in out.iter_mut().enumerate() {
        let brake = perf.brake_points[b];
        let mut upper = top;
        while upper > bottom {
            let lower = (upper - config.layer_m).max(bottom);
            let dz = upper - lower;
            let mid = 0.5 * (upper + lower);
            let density = input
                .atmosphere
                .air_at(input.ground_altitude_msl_m + mid)
                .density_kg_per_m3;
            let sink = perf.sink_rate(brake, 0.0, density).max(1e-3);
            let dt = dz / sink;
            let wind = match input.wind_below {
                Some(field) => {
                    let mut at = est.position_ned_m;
                    at.z = -mid;
                    field.wind_ned_mps(est.time_s + column.time_s + 0.5 * dt, &at)
                }
                None => uniform,
            };
            column.drift_ne_m += Vector2::new(wind.x, wind.y) * dt;
            column.time_s += dt;
            // The part of this layer above the reserve counts for the reach.
            let above_reserve = (upper - lower.max(reserve_top)).max(0.0);
            column.reach_m += perf.horizontal_airspeed(brake, density) * above_reserve / sink;
            upper = lower;
        }
    }
    out
}

/// One dispersion of the estimate and the parafoil.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Draw {
    pub position_ne_m: Vector2<f64>,
    pub wind_offset_ne_mps: Vector2<f64>,
    pub airspeed_scale: f64,
    pub sink_scale: f64,
}

/// Draws one dispersion from the estimate's uncertainties and the configured fractions.
pub(crate) fn draw(
    input: &FootprintInput,
    config: &FootprintConfig,
    rng: &mut (impl Rng + ?Sized),
) -> Draw {
    let est = input.estimate;
    let mut normal = || -> f64 { StandardNormal.sample(rng) };
    let wind_sigma = |s: f64| s.hypot(config.extra_wind_sigma_mps);
    let position = Vector2::new(
        est.position_ned_m.x + est.position_sigma_m.x * normal(),
        est.position_ned_m.y + est.position_sigma_m.y * normal(),
    );
    let wind = Vector2::new(
        wind_sigma(est.wind_sigma_mps.x) * normal(),
        wind_sigma(est.wind_sigma_mps.y) * normal(),
    );
    // Clamped so that a far tail never flies backwards or stops sinking.
    let airspeed = (1.0 + config.airspeed_sigma_fraction * normal()).max(0.2);
    let sink = (1.0 + config.sink_sigma_fraction * normal()).max(0.2);
    Draw {
        position_ne_m: position,
        wind_offset_ne_mps: wind,
        airspeed_scale: airspeed,
        sink_scale: sink,
    }
}

/// The discs reachable in draw `d`, one per brake setting.
pub(crate) fn discs(
    columns: &[Column; BRAKE_POINTS],
    d: &Draw,
    edge_margin_m: f64,
) -> [Disc; BRAKE_POINTS] {
    columns.map(|c| Disc {
        centre_ne_m: d.position_ne_m
            + (c.drift_ne_m + d.wind_offset_ne_mps * c.time_s) / d.sink_scale,
        radius_m: (d.airspeed_scale * c.reach_m / d.sink_scale - edge_margin_m).max(0.0),
    })
}

/// The nominal discs (no dispersion), for the closed-form checks and the grid's extent.
pub(crate) fn nominal(input: &FootprintInput) -> Draw {
    Draw {
        position_ne_m: input.estimate.position_ned_m.xy(),
        wind_offset_ne_mps: Vector2::zeros(),
        airspeed_scale: 1.0,
        sink_scale: 1.0,
    }
}
