//! The flight path of a whole STRAPLEX stack without steering: where the balloon bursts, where
//! the round chute is released and the parafoil deploys, and where the parafoil lands if its
//! servos stay neutral — from the launch pad, from a balloon still rising, or from the stack
//! already falling under its round chute. Pre-flight planning (`stx plan`, the dashboard's
//! Plan page) flies it many times over the uncertain inputs ([`spread`]); the live station's
//! round-chute and deploy-point predictions are the same question asked later in the flight.
//!
//! The physics, stage by stage (positions local NED from the origin on the ground, which is
//! `ground_msl_m` above sea level; the wind field takes altitude above that origin):
//!
//! - **Ascent**: the [`Balloon`] rises at `v₀·(ρ₀/ρ)^k`, its launch rate chosen so that the
//!   mean rate to burst is the planned one, and moves horizontally with the wind at its
//!   altitude (it is light and large). Integrated in altitude steps of
//!   [`StackConfig::step_m`] with the midpoint rule, so that a uniform wind `w` puts the burst
//!   point exactly at `launch + w·H/v̄` (H the climb).
//! - **Round chute**: the stack falls at its [`RoundChute`] terminal speed for the local air
//!   density and drifts with the wind. This is quasi-steady: the full drag equation the
//!   simulation integrates relaxes to the terminal speed within `v_t/g` (7 s at 35 km, under
//!   1 s near the ground), which moves the points by less than the wind's uncertainty.
//! - **Deployment**: when the drone is [`StackConfig::deploy_height_m`] above the origin (the
//!   onboard `MIS_DEPLOY_M`), or at once if the stack is already lower, heading along the
//!   drift (as the simulated drone deploys) or [`StackConfig::deploy_heading_deg`].
//! - **Parafoil, unsteered**: the [`PointMass`] with neutral servos, as the landing predictor
//!   flies "uncontrolled", down to the hang height of the drone above the lowest body.
//!
//! Besides the parafoil's landing the path gives where the stack would land if the round chute
//! were never released, and the disc of points the parafoil could reach by steering
//! ([`ReachDisc`], see [`reach`]).

pub mod forecast;
mod models;
pub mod plan;
pub mod reach;
pub mod region;
pub mod spread;
mod vertical;

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use stx_types::atmosphere::Atmosphere;
use stx_types::controls::Controls;
use stx_types::validate::check;
use stx_types::wind::WindField;

use crate::performance::GlidePerformance;
use crate::pointmass::{Conditions, PointMass};
pub use forecast::{Forecast, ForecastError, ForecastRow, merge_measured};
pub use models::{Balloon, RoundChute};
pub use plan::{PlanError, PlanReport, PlanRequest, plan, plan_each};
pub use reach::ReachDisc;
pub use region::SteeredRegion;
pub use spread::{
    Dispersion, Ellipse, PlanInputs, PlanSpread, PointSpread, WindCase, monte_carlo,
    monte_carlo_each,
};
pub use vertical::VerticalPath;

/// Mass of the STRAPLEX stack under its round chute (the four bodies, 9.1 kg, plus the chute
/// and the balloon's remains, 0.3 kg), kg: the simulated drone's default.
const STRAPLEX_CHUTE_MASS_KG: f64 = 9.4;

/// The stack and its flight as the planner needs them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(deny_unknown_fields, default)]
pub struct StackConfig {
    /// Mean ascent rate from launch to burst (climb over time), m/s (> 0).
    pub mean_ascent_rate_mps: f64,
    /// Exponent `k` of the ascent rate's density ratio, 0…0.5 (1/6: drag balance).
    pub ascent_density_exponent: f64,
    /// Altitude at which the balloon bursts, m above mean sea level.
    pub burst_altitude_msl_m: f64,
    /// Cd·A of the round chute, m² (> 0).
    pub chute_drag_area_m2: f64,
    /// Mass under the round chute, kg (> 0).
    pub chute_mass_kg: f64,
    /// Gravity, m/s².
    pub gravity_mps2: f64,
    /// Height above the origin at which the round chute is released, m (≥ 0).
    pub deploy_height_m: f64,
    /// Heading the parafoil deploys on, degrees from north; `None`: along the drift.
    pub deploy_heading_deg: Option<f64>,
    /// Height of the drone above the lowest body: the parafoil has landed when the drone is
    /// this high, m (≥ 0).
    pub hang_height_m: f64,
    /// Altitude step of the ascent and round-chute integration, m (> 0).
    pub step_m: f64,
    /// Time step of the parafoil's glide, s (> 0).
    pub glide_step_s: f64,
}

impl Default for StackConfig {
    fn default() -> Self {
        Self {
            mean_ascent_rate_mps: 5.0,
            ascent_density_exponent: 1.0 / 6.0,
            burst_altitude_msl_m: 35_000.0,
            chute_drag_area_m2: 4.0,
            chute_mass_kg: STRAPLEX_CHUTE_MASS_KG,
            gravity_mps2: 9.80665,
            deploy_height_m: crate::params::MissionSettings::default().deploy_height_m,
            deploy_heading_deg: None,
            hang_height_m: crate::predict::PredictorConfig::default().hang_height_m,
            step_m: 10.0,
            glide_step_s: 0.5,
        }
    }
}

/// Why a flight path cannot be flown.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FlightPathError {
    /// A setting breaks its rule.
    #[error("`{field}` = {value} is invalid: must be {rule}")]
    Invalid {
        /// The setting.
        field: &'static str,
        /// Its value.
        value: f64,
        /// The rule it breaks.
        rule: &'static str,
    },
    /// The start lies below the ground.
    #[error("the start is {height_m} m above the origin: it must not be below the ground")]
    StartBelowGround {
        /// Height of the start above the origin, m.
        height_m: f64,
    },
}

stx_types::invalid_into!(FlightPathError);

impl StackConfig {
    /// Checks every setting against its rule (see the fields).
    pub fn validate(&self) -> Result<(), FlightPathError> {
        let s = self;
        check(
            "mean_ascent_rate_mps",
            s.mean_ascent_rate_mps,
            s.mean_ascent_rate_mps > 0.0,
            "> 0",
        )?;
        let k = s.ascent_density_exponent;
        check(
            "ascent_density_exponent",
            k,
            (0.0..=0.5).contains(&k),
            "in 0…0.5",
        )?;
        check(
            "burst_altitude_msl_m",
            s.burst_altitude_msl_m,
            s.burst_altitude_msl_m < 60_000.0,
            "finite, < 60 000",
        )?;
        check(
            "chute_drag_area_m2",
            s.chute_drag_area_m2,
            s.chute_drag_area_m2 > 0.0,
            "> 0",
        )?;
        check(
            "chute_mass_kg",
            s.chute_mass_kg,
            s.chute_mass_kg > 0.0,
            "> 0",
        )?;
        check("gravity_mps2", s.gravity_mps2, s.gravity_mps2 > 0.0, "> 0")?;
        check(
            "deploy_height_m",
            s.deploy_height_m,
            s.deploy_height_m >= 0.0,
            "≥ 0",
        )?;
        if let Some(h) = s.deploy_heading_deg {
            check("deploy_heading_deg", h, true, "finite")?;
        }
        check(
            "hang_height_m",
            s.hang_height_m,
            s.hang_height_m >= 0.0,
            "≥ 0",
        )?;
        check("step_m", s.step_m, s.step_m > 0.0, "> 0")?;
        Ok(check(
            "glide_step_s",
            s.glide_step_s,
            s.glide_step_s > 0.0,
            "> 0",
        )?)
    }

    /// The round chute's model.
    pub fn chute(&self) -> RoundChute {
        RoundChute {
            drag_area_m2: self.chute_drag_area_m2,
            mass_kg: self.chute_mass_kg,
            gravity_mps2: self.gravity_mps2,
        }
    }
}

/// Where the flight path starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Start {
    /// Rising with the balloon from here (local NED, m): the pad is `Vector3::zeros()`.
    Ascending(Vector3<f64>),
    /// Falling under the round chute from here (local NED, m).
    UnderRoundChute(Vector3<f64>),
}

impl Start {
    /// On the launch pad at the origin.
    pub fn pad() -> Self {
        Start::Ascending(Vector3::zeros())
    }
}

/// A point of the path.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct PathPoint {
    /// Position, local NED, m.
    pub position_ned_m: [f64; 3],
    /// Time from the start, s.
    pub time_s: f64,
}

impl PathPoint {
    fn at(p: &Vector3<f64>, time_s: f64) -> Self {
        Self {
            position_ned_m: [p.x, p.y, p.z],
            time_s,
        }
    }

    /// North and east, m.
    pub fn ne_m(&self) -> [f64; 2] {
        [self.position_ned_m[0], self.position_ned_m[1]]
    }
}

/// The unsteered flight path.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct FlightPath {
    /// Where the balloon bursts; `None` if the path started under the round chute.
    pub burst: Option<PathPoint>,
    /// Where the round chute is released and the parafoil deploys.
    pub deploy: PathPoint,
    /// Where the parafoil lands with its servos neutral (the drone's position).
    pub landing: PathPoint,
    /// Where the stack would land if the round chute were never released.
    pub round_chute_landing: PathPoint,
    /// The parafoil's heading at deployment, rad.
    pub deploy_heading_rad: f64,
    /// What steering could reach from the deploy point.
    pub reach: ReachDisc,
}

/// The air along the path: wind, atmosphere and the ground's altitude.
#[derive(Clone, Copy)]
pub struct Air<'a> {
    /// Wind over altitude above the origin (and time from the start).
    pub wind: &'a dyn WindField,
    /// The atmosphere, by altitude above sea level.
    pub atmosphere: &'a dyn Atmosphere,
    /// The origin's ground altitude above mean sea level, m.
    pub ground_msl_m: f64,
}

impl Air<'_> {
    fn density(&self, height_m: f64) -> f64 {
        self.atmosphere
            .air_at(self.ground_msl_m + height_m)
            .density_kg_per_m3
    }

    fn wind(&self, t: f64, p: &Vector3<f64>) -> Vector3<f64> {
        let w = self.wind.wind_ned_mps(t, p);
        Vector3::new(w.x, w.y, 0.0)
    }
}

/// Flies the stack from `start` through `air` (see the module doc): the unsteered path.
pub fn propagate(
    start: Start,
    stack: &StackConfig,
    air: Air<'_>,
    perf: &GlidePerformance,
) -> Result<FlightPath, FlightPathError> {
    let vertical = VerticalPath::new(start, stack, air.atmosphere, air.ground_msl_m)?;
    Ok(vertical.fly(air, perf))
}

/// [`propagate`]'s balloon ascent and round-chute fall as one leg, for callers that want the
/// trajectory and not only its end (the station's Tawhiri API): from `p` (local NED, m) at
/// time `t` (s) to `to_height_m` above the origin at the vertical speed
/// `speed_mps(air density)`, drifting with the wind, in altitude steps of about `step_m` with
/// the midpoint rule; `each_step` sees the position and time after every step. Returns the
/// end.
pub fn vertical_leg(
    air: Air<'_>,
    step_m: f64,
    mut p: Vector3<f64>,
    mut t: f64,
    to_height_m: f64,
    speed_mps: impl Fn(f64) -> f64,
    mut each_step: impl FnMut(&Vector3<f64>, f64),
) -> (Vector3<f64>, f64) {
    let span_m = to_height_m + p.z;
    if span_m == 0.0 {
        return (p, t);
    }
    let n = (span_m.abs() / step_m).ceil().max(1.0);
    // Signed height step: up for the balloon, down for the chute.
    let dh = span_m / n;
    for _ in 0..n as usize {
        let mid_height = -p.z + dh / 2.0;
        let dt = dh.abs() / speed_mps(air.density(mid_height));
        let w0 = air.wind(t, &p);
        let mid = Vector3::new(p.x + w0.x * dt / 2.0, p.y + w0.y * dt / 2.0, -mid_height);
        let w = air.wind(t + dt / 2.0, &mid);
        p += Vector3::new(w.x * dt, w.y * dt, -dh);
        t += dt;
        each_step(&p, t);
    }
    (p, t)
}

/// Glides the parafoil with neutral servos from `p` at `t` on `heading_rad` down to the hang
/// height. Returns the landing and the horizontal path flown through the air (north, east), m.
fn glide(
    perf: &GlidePerformance,
    air: Air<'_>,
    stack: &StackConfig,
    p: Vector3<f64>,
    t: f64,
    heading_rad: f64,
) -> (PathPoint, [f64; 2]) {
    let touchdown = stack.hang_height_m;
    let mut mass = PointMass::new(t, p, heading_rad);
    let mut through_air = [0.0, 0.0];
    let neutral = Controls::default();
    let dt = stack.glide_step_s;
    // A parafoil sinks at 3 m/s or more: ten times the time of that is a bound no real glide
    // reaches, and keeps a pathological performance table from looping for ever.
    let horizon_s = 10.0 * (-p.z).max(0.0) / 0.3 + 10.0 * dt;
    while -mass.position_ned_m.z > touchdown && mass.time_s - t < horizon_s {
        let before = mass;
        let wind = air.wind(mass.time_s, &mass.position_ned_m);
        let density = air.density(-mass.position_ned_m.z);
        mass.step(perf, &neutral, &Conditions::nominal(wind, density), dt);
        // Interpolate to the touchdown height inside the step.
        let h0 = -before.position_ned_m.z - touchdown;
        let h1 = -mass.position_ned_m.z - touchdown;
        let f = if h1 < 0.0 && h0 > h1 {
            h0 / (h0 - h1)
        } else {
            1.0
        };
        let air_velocity = mass.velocity_ned_mps - wind;
        through_air[0] += air_velocity.x * dt * f;
        through_air[1] += air_velocity.y * dt * f;
        if f < 1.0 {
            let at = before.position_ned_m + (mass.position_ned_m - before.position_ned_m) * f;
            return (PathPoint::at(&at, before.time_s + f * dt), through_air);
        }
    }
    (
        PathPoint::at(&mass.position_ned_m, mass.time_s),
        through_air,
    )
}
