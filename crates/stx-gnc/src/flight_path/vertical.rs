//! The wind-free half of [`super::propagate`]: the balloon's ascent and the round chute's fall
//! step through fixed heights at speeds set by the air density alone, so every step's height
//! and duration are known before any wind is looked at. A launch window flies the same
//! samples through one wind per launch time; working the heights and durations out once per
//! sample ([`VerticalPath::new`]) and only the drift once per wind ([`VerticalPath::fly`])
//! takes the balloon's density law, the atmosphere and the launch rate's integral out of the
//! per-launch work.
//!
//! [`VerticalPath::fly`] does the arithmetic of [`super::vertical_leg`] in the same order, so
//! a path flown this way is the same to the last bit as the step-by-step leg.

use nalgebra::Vector3;
use stx_types::atmosphere::Atmosphere;
use stx_types::validate::check;

use super::{
    Air, Balloon, FlightPath, FlightPathError, PathPoint, ReachDisc, StackConfig, Start, glide,
};
use crate::performance::GlidePerformance;

/// One leg's steps: `dh_m` up each (negative: down), each taking its `dt_s`.
#[derive(Debug, Clone, PartialEq)]
struct Leg {
    dh_m: f64,
    dt_s: Vec<f64>,
}

impl Leg {
    /// The leg from NED z `z_m` to `to_height_m` above the origin at `speed_mps(density)`, and
    /// the z it ends at; [`super::vertical_leg`]'s steps.
    fn new(
        atmosphere: &dyn Atmosphere,
        ground_msl_m: f64,
        step_m: f64,
        mut z_m: f64,
        to_height_m: f64,
        speed_mps: impl Fn(f64) -> f64,
    ) -> (Self, f64) {
        let span_m = to_height_m + z_m;
        if span_m == 0.0 {
            return (
                Self {
                    dh_m: 0.0,
                    dt_s: Vec::new(),
                },
                z_m,
            );
        }
        let n = (span_m.abs() / step_m).ceil().max(1.0);
        let dh = span_m / n;
        let dt_s = (0..n as usize)
            .map(|_| {
                let mid_height = -z_m + dh / 2.0;
                let density = atmosphere
                    .air_at(ground_msl_m + mid_height)
                    .density_kg_per_m3;
                z_m += -dh;
                dh.abs() / speed_mps(density)
            })
            .collect();
        (Self { dh_m: dh, dt_s }, z_m)
    }

    fn empty() -> Self {
        Self {
            dh_m: 0.0,
            dt_s: Vec::new(),
        }
    }

    /// Drifts from `p` at `t` with the wind over the leg's steps (midpoint rule).
    fn fly(&self, air: Air<'_>, mut p: Vector3<f64>, mut t: f64) -> (Vector3<f64>, f64) {
        let dh = self.dh_m;
        for &dt in &self.dt_s {
            let mid_height = -p.z + dh / 2.0;
            let w0 = air.wind(t, &p);
            let mid = Vector3::new(p.x + w0.x * dt / 2.0, p.y + w0.y * dt / 2.0, -mid_height);
            let w = air.wind(t + dt / 2.0, &mid);
            p += Vector3::new(w.x * dt, w.y * dt, -dh);
            t += dt;
        }
        (p, t)
    }
}

/// A path's ascent and round-chute falls without their drift: what [`super::propagate`] works
/// out of the stack, the atmosphere and the ground alone.
#[derive(Debug, Clone, PartialEq)]
pub struct VerticalPath {
    start: Vector3<f64>,
    stack: StackConfig,
    ground_msl_m: f64,
    /// `None` when the path starts under the round chute.
    ascent: Option<Leg>,
    to_deploy: Leg,
    to_ground: Leg,
}

impl VerticalPath {
    /// The vertical part of the path from `start` (checked as [`super::propagate`] checks it).
    pub fn new(
        start: Start,
        stack: &StackConfig,
        atmosphere: &dyn Atmosphere,
        ground_msl_m: f64,
    ) -> Result<Self, FlightPathError> {
        stack.validate()?;
        check("ground_msl_m", ground_msl_m, true, "finite")?;
        let (p, ascending) = match start {
            Start::Ascending(p) => (p, true),
            Start::UnderRoundChute(p) => (p, false),
        };
        if !(p.iter().all(|v| v.is_finite()) && p.z <= 0.0) {
            return Err(FlightPathError::StartBelowGround { height_m: -p.z });
        }
        let leg = |z: f64, to_height_m: f64, speed: &dyn Fn(f64) -> f64| {
            Leg::new(
                atmosphere,
                ground_msl_m,
                stack.step_m,
                z,
                to_height_m,
                speed,
            )
        };
        let mut z = p.z;
        let mut ascent = None;
        if ascending {
            let burst_height = stack.burst_altitude_msl_m - ground_msl_m;
            let balloon = Balloon::with_mean_rate(
                stack.mean_ascent_rate_mps,
                stack.ascent_density_exponent,
                atmosphere,
                ground_msl_m,
                stack.burst_altitude_msl_m,
            );
            let rise = if burst_height > -z {
                let (rise, top) = leg(z, burst_height, &|rho| balloon.ascent_rate_mps(rho));
                z = top;
                rise
            } else {
                Leg::empty()
            };
            ascent = Some(rise);
        }
        let chute = stack.chute();
        let speed = |rho: f64| chute.terminal_speed_mps(rho);
        let mut fall = |to_height_m: f64| {
            if -z <= to_height_m {
                return Leg::empty();
            }
            let (leg, end) = leg(z, to_height_m, &speed);
            z = end;
            leg
        };
        let to_deploy = fall(stack.deploy_height_m);
        let to_ground = fall(0.0);
        Ok(Self {
            start: p,
            stack: *stack,
            ground_msl_m,
            ascent,
            to_deploy,
            to_ground,
        })
    }

    /// The path through `air` (whose atmosphere and ground must be those the vertical part was
    /// worked out for): [`super::propagate`]'s answer.
    pub fn fly(&self, air: Air<'_>, perf: &GlidePerformance) -> FlightPath {
        debug_assert_eq!(air.ground_msl_m, self.ground_msl_m);
        let stack = &self.stack;
        let (mut p, mut t) = (self.start, 0.0);
        let burst = self.ascent.as_ref().map(|rise| {
            (p, t) = rise.fly(air, p, t);
            PathPoint::at(&p, t)
        });
        let (p_deploy, t_deploy) = self.to_deploy.fly(air, p, t);
        let (p_chute, t_chute) = self.to_ground.fly(air, p_deploy, t_deploy);
        let drift = air.wind(t_deploy, &p_deploy);
        let heading = match stack.deploy_heading_deg {
            Some(h) => h.to_radians(),
            None if drift.x.hypot(drift.y) > 0.1 => drift.y.atan2(drift.x),
            None => 0.0,
        };
        let (landing, air_travel) = glide(perf, air, stack, p_deploy, t_deploy, heading);
        FlightPath {
            burst,
            deploy: PathPoint::at(&p_deploy, t_deploy),
            landing,
            round_chute_landing: PathPoint::at(&p_chute, t_chute),
            deploy_heading_rad: heading,
            reach: ReachDisc::from_unsteered_glide(landing.ne_m(), air_travel),
        }
    }
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use stx_types::atmosphere::StandardAtmosphere;
    use stx_types::wind::WindProfile;

    use super::super::spread::{Dispersion, PlanInputs, WindCase, monte_carlo, monte_carlo_each};
    use super::super::{Balloon, vertical_leg};
    use super::*;

    fn shear() -> WindProfile {
        WindProfile::from_rows(&[
            [0.0, 3.0, 200.0],
            [1500.0, 9.0, 250.0],
            [9000.0, 30.0, 280.0],
            [16_000.0, 12.0, 300.0],
            [30_000.0, 20.0, 90.0],
        ])
        .unwrap()
    }

    fn air(wind: &WindProfile) -> Air<'_> {
        Air {
            wind,
            atmosphere: &StandardAtmosphere,
            ground_msl_m: 245.0,
        }
    }

    /// The ascent and falls worked out ahead end where the step-by-step leg does, to the bit.
    #[test]
    fn the_path_is_the_step_by_step_legs_to_the_last_bit() {
        let wind = shear();
        let air = air(&wind);
        let stack = StackConfig {
            burst_altitude_msl_m: 31_234.5,
            ..StackConfig::default()
        };
        let path = VerticalPath::new(Start::pad(), &stack, air.atmosphere, air.ground_msl_m)
            .unwrap()
            .fly(air, &GlidePerformance::default());
        let balloon = Balloon::with_mean_rate(
            stack.mean_ascent_rate_mps,
            stack.ascent_density_exponent,
            air.atmosphere,
            air.ground_msl_m,
            stack.burst_altitude_msl_m,
        );
        let burst_height = stack.burst_altitude_msl_m - air.ground_msl_m;
        let (p, t) = vertical_leg(
            air,
            stack.step_m,
            Vector3::zeros(),
            0.0,
            burst_height,
            |rho| balloon.ascent_rate_mps(rho),
            |_, _| {},
        );
        assert_eq!(path.burst, Some(PathPoint::at(&p, t)));
        let chute = stack.chute();
        let fall = |p, t, to| {
            vertical_leg(
                air,
                stack.step_m,
                p,
                t,
                to,
                |rho| chute.terminal_speed_mps(rho),
                |_, _| {},
            )
        };
        let (p, t) = fall(p, t, stack.deploy_height_m);
        assert_eq!(path.deploy, PathPoint::at(&p, t));
        let (p, t) = fall(p, t, 0.0);
        assert_eq!(path.round_chute_landing, PathPoint::at(&p, t));
    }

    /// One wind among several gets the spread it gets alone, from the same seed.
    #[test]
    fn each_wind_of_many_gets_the_spread_it_gets_alone() {
        let winds = [
            shear(),
            WindProfile::from_rows(&[[0.0, 6.0, 10.0]]).unwrap(),
        ];
        let sigmas = [vec![(0.0, 1.0), (9000.0, 3.0)], vec![(100.0, 2.0)]];
        let inputs = |wind_sigma: Vec<(f64, f64)>| PlanInputs {
            start: Start::pad(),
            stack: StackConfig {
                burst_altitude_msl_m: 20_000.0,
                ..StackConfig::default()
            },
            dispersion: Dispersion {
                wind_sigma,
                ..Dispersion::default()
            },
            runs: 30,
            target_ne_m: Some([1000.0, 20_000.0]),
            region_share_of_best: 0.5,
        };
        let cases: Vec<WindCase<'_>> = winds
            .iter()
            .zip(&sigmas)
            .map(|(wind, s)| WindCase {
                wind,
                wind_sigma: s,
            })
            .collect();
        let perf = GlidePerformance::default();
        let together = monte_carlo_each(
            &inputs(Vec::new()),
            &cases,
            air(&winds[0]),
            &perf,
            &mut ChaCha8Rng::seed_from_u64(5),
        )
        .unwrap();
        for ((wind, sigma), spread) in winds.iter().zip(&sigmas).zip(&together) {
            let alone = monte_carlo(
                &inputs(sigma.clone()),
                air(wind),
                &perf,
                &mut ChaCha8Rng::seed_from_u64(5),
            )
            .unwrap();
            assert_eq!(*spread, alone);
        }
        assert_ne!(together[0].landing, together[1].landing);
    }
}
