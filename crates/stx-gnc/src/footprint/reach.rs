//! The physics of the footprint: for one dispersed draw, the discs of ground the parafoil can
//! reach.
//!
//! The descent is integrated once per refresh over height layers (the wind field and the air
//! density read per layer) in two legs, down to the reserve height and the final below it,
//! giving for each brake setting `b` and leg three sums over its layers k of thickness `dz_k`
//! at sink rate `s_b(ρ_k)`: the time `T = Σ dz_k / s_b`, the drift of the air mass
//! `W = Σ w_k dz_k / s_b` and the distance through the air `R = Σ v_b(ρ_k) dz_k / s_b`.
//!
//! A draw scales the sink by `σ_s`-dispersed `s`, the airspeed by `a`, and offsets the wind by a
//! constant `δw` and the start by `δp`. The sums are linear in those, so a draw costs a few
//! multiplications per disc: the final (drift `W_f' = (W_f + δw T_f)/s`, air run `a R_f / s`)
//! is flown into its wind and ends on the point, so the point lies `W_f' − a R_f/s · Ŵ_f'` from
//! where the final starts, which is anywhere within `a R_b/s − margin` of
//! `p + δp + (W_b + δw T_b)/s`.

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

/// One leg of the descent at one brake setting, undispersed.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Leg {
    /// Time it takes, s.
    pub time_s: f64,
    /// Drift of the air mass over it (north, east), m.
    pub drift_ne_m: Vector2<f64>,
    /// Distance flown through the air, m.
    pub air_m: f64,
}

/// The descent at one brake setting: down to the reserve height, then the final.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Column {
    pub above: Leg,
    pub last: Leg,
}

/// Below this mean wind over the final, m/s (about 1 kn, what weather reports call calm), the
/// final has no upwind to be flown into and may be flown in any direction.
pub const CALM_FINAL_WIND_MPS: f64 = 0.5;

/// Integrates the descent from the estimate's height for each brake setting of the table.
pub(crate) fn columns(input: &FootprintInput, config: &FootprintConfig) -> [Column; BRAKE_POINTS] {
    let top = input.estimate.height_m();
    let bottom = config.hang_height_m;
    let reserve_top = (bottom + config.reserve_height_m).min(top);
    let mut out = [Column::default(); BRAKE_POINTS];
    for (b, column) in out.iter_mut().enumerate() {
        let brake = input.performance.brake_points[b];
        column.above = leg(input, config, brake, top, reserve_top, 0.0);
        column.last = leg(
            input,
            config,
            brake,
            reserve_top,
            bottom,
            column.above.time_s,
        );
    }
    out
}

/// Integrates from height `upper` down to `lower` at `brake`, starting `elapsed_s` after the
/// estimate (when the wind field is read).
fn leg(
    input: &FootprintInput,
    config: &FootprintConfig,
    brake: f64,
    mut upper: f64,
    bottom: f64,
    elapsed_s: f64,
) -> Leg {
    let est = input.estimate;
    let perf = input.performance;
    let mut out = Leg::default();
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
                field.wind_ned_mps(est.time_s + elapsed_s + out.time_s + 0.5 * dt, &at)
            }
            None => est.wind_ned_mps,
        };
        out.drift_ne_m += Vector2::new(wind.x, wind.y) * dt;
        out.time_s += dt;
        out.air_m += perf.horizontal_airspeed(brake, density) * dt;
        upper = lower;
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

/// Number of discs per draw: one per brake setting before the final, for the final at
/// released and at full brakes (the shortest and longest final guidance can fly between them).
pub(crate) const DISCS: usize = 2 * BRAKE_POINTS;

/// The discs reachable in draw `d`: for each brake setting down to the reserve height, the
/// ground its still-air reach covers about the drift, moved by a final flown into the wind at
/// released or at full brakes (in calm air, a final in any direction: a larger disc).
pub(crate) fn discs(
    columns: &[Column; BRAKE_POINTS],
    d: &Draw,
    edge_margin_m: f64,
) -> [Disc; DISCS] {
    let s = d.sink_scale;
    let moved = |l: &Leg| (l.drift_ne_m + d.wind_offset_ne_mps * l.time_s) / s;
    let finals = [columns[0].last, columns[BRAKE_POINTS - 1].last];
    std::array::from_fn(|k| {
        let (approach, last) = (&columns[k / 2].above, &finals[k % 2]);
        let reach = (d.airspeed_scale * approach.air_m / s - edge_margin_m).max(0.0);
        let final_air = d.airspeed_scale * last.air_m / s;
        let final_drift = moved(last);
        let final_time = last.time_s / s;
        let centre = d.position_ne_m + moved(approach) + final_drift;
        let wind_speed = if final_time > 0.0 {
            final_drift.norm() / final_time
        } else {
            0.0
        };
        if wind_speed < CALM_FINAL_WIND_MPS {
            Disc {
                centre_ne_m: centre,
                radius_m: reach + final_air,
            }
        } else {
            Disc {
                centre_ne_m: centre - final_drift / final_drift.norm() * final_air,
                radius_m: reach,
            }
        }
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
