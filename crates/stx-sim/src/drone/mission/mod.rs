//! The mission's physics, stage by stage: what the drone's true state is from the launch pad
//! to the landing field, whatever its software does.
//!
//! One [`MissionPhysics`] owns the truth of a whole flight and advances it one control period
//! at a time ([`MissionPhysics::step`]) with the servo commands held. Each stage has the model
//! it needs, no more:
//!
//! - **PreLaunch**: on the pad at the start position, still, until the launch time.
//! - **Ascent**, the balloon (a point mass): a balloon rises at the speed where its free lift
//!   balances its drag, `L = ½ρv²·C_D·A`. The free lift of a latex balloon stays about
//!   constant on the way up (the helium expands with the air, so the lift of the displaced air
//!   does not change), while its envelope grows as `V ∝ 1/ρ`, so `A ∝ ρ^(−2/3)` and
//!   `v = v₀·(ρ₀/ρ)^k` with `k = 1/6`. The exponent is a setting (0 gives a constant rate;
//!   cold gas and a falling drag coefficient make real balloons rise more evenly). What a
//!   flight is planned with, and what the mission file gives, is the *mean* ascent rate `v̄`
//!   from launch to burst (≈ 5 m/s for STRAPLEX: the filling is chosen for it); the launch
//!   rate follows from the time to burst `T = ∫dz/v = (1/v₀)∫(ρ/ρ₀)^k dz = H/v̄`, i.e.
//!   `v₀ = v̄·(1/H)∫(ρ/ρ₀)^k dz` over the climb `H` in the US Standard Atmosphere 1976
//!   ([`Balloon::with_mean_rate`]). For the 35-km mission (`v̄` = 5 m/s, `k` = 1/6) that is
//!   3.5 m/s at the launch site, 8.0 m/s at burst, and 1 h 56 min to burst. The balloon is
//!   light and large, so horizontally it moves with the wind at its altitude. It bursts at the
//!   burst altitude (MSL), or is cut away by a cutdown command.
//! - **RoundChute**, the whole stack under a round parachute (a point mass of the four bodies
//!   plus the chute): `m·dv/dt = m·g − ½ρ|v−w|(v−w)·C_D·A` with the density of the US
//!   Standard Atmosphere 1976 at its altitude and `w` the wind, integrated with RK4 in 0.05 s
//!   steps. The terminal speed `√(2mg/(ρ·C_D·A))` is about 6 m/s at the ground and 70 m/s
//!   (250 km/h) at 35 km; the stack drifts with the wind.
//! - **ParafoilDeploy**, when the onboard software releases the round chute
//!   ([`MissionPhysics::deploy`], at its deploy height): the 14-DOF [`ParafoilModel`] starts
//!   from a steady glide
//!   ([`crate::montecarlo::steady_glide_state`]) placed with its drone at the stack's position,
//!   heading along the drift (or a configured heading). The canopy inflates and settles for
//!   the settle time ([`MissionPhysics::settle_s`]) with whatever the servos are commanded (the
//!   onboard software holds them neutral).
//! - **Parafoil**: the same model, steered by the onboard software through the servo
//!   commands, integrated with RK4 by [`crate::closed_loop::fly_period`] up to the ground
//!   contact of its lowest body.
//! - **Landed**: on the ground where it touched down — under the parafoil, or under the round
//!   chute if it was never released.
//!
//! The drone's attitude is the model's under the parafoil. Under the balloon and the round
//! chute it is a swing: a pendulum of the flight train's length (about 15 m under the
//! balloon, 5 m under the chute, periods of 7.8 s and 4.5 s) with a few degrees of roll and
//! pitch out of phase, and a slow spin of the whole train (a few degrees per second, faster
//! under the chute) with a yaw wobble. Its phases and spin direction are drawn from the seed.
//! The pitot then sees mostly vertical air across its tube: its airspeed is of no use there,
//! as on the real capsule.
//!
//! Positions are local NED from the launch site (z = 0 is the site's ground, the ground level
//! of the whole mission); the point mass is the drone itself. The point-mass models are in
//! `point_mass`, the parafoil stages in `parafoil`, the round-chute landing forecast in
//! `forecast`.

mod forecast;
mod parafoil;
mod point_mass;

use std::sync::Arc;

use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use stx_dynamics::atmosphere::{Atmosphere, StandardAtmosphere};
use stx_dynamics::integrate::IntegrateError;
use stx_dynamics::model::{Body, Environment, ParafoilModel};
use stx_dynamics::rotation::t_from_euler;
use stx_dynamics::state::{Controls, StateVector, idx};
use stx_dynamics::vehicle::Vehicle;
use stx_dynamics::wind::WindField;
use stx_gnc::mission::FlightStage;

use crate::closed_loop::Touchdown;
use crate::drone::config::MissionConfig;
use crate::sensors::Truth;
pub use point_mass::{Balloon, RoundChute, Swing};

/// Step of the point-mass stages' RK4, s: a tenth of the round chute's drag time constant
/// near the ground (`v_t/2g` ≈ 0.3 s).
const POINT_MASS_STEP_S: f64 = 0.05;

/// A stage change, for the operator's log.
#[derive(Debug, Clone, PartialEq)]
pub enum StageEvent {
    /// The balloon was released.
    Launched,
    /// The balloon burst at this altitude MSL, m.
    Burst { altitude_msl_m: f64 },
    /// The balloon was cut away (cutdown) at this altitude MSL, m.
    CutDown { altitude_msl_m: f64 },
    /// The round chute was released and the parafoil deploys at this height, m, heading, rad.
    Deployed { height_m: f64, heading_rad: f64 },
    /// The parafoil has settled: guidance takes over.
    Flying,
    /// Ground contact.
    Landed(Touchdown),
}

/// Why the physics could not go on.
#[derive(Debug, thiserror::Error)]
pub enum PhysicsError {
    /// The flight model's integration failed.
    #[error("flight model integration failed at t = {time_s:.2} s: {source}")]
    Integration {
        time_s: f64,
        #[source]
        source: IntegrateError,
    },
    /// The steady-glide template could not be made.
    #[error("cannot trim the parafoil for deployment: {0}")]
    Template(IntegrateError),
}

/// Why a cutdown is refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum CutdownRefused {
    /// Not launched yet: cutting the balloon on the pad would only lose it.
    #[error("still on the ground: nothing to cut")]
    OnGround,
    /// The balloon is already gone.
    #[error("no balloon to cut: the stage is {0:?}")]
    NoBalloon(FlightStage),
}

/// Why a deployment is refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("no round chute to release: the stage is {stage:?}")]
pub struct DeployRefused {
    /// The stage at the request.
    pub stage: FlightStage,
}

/// The true state of the whole flight.
pub struct MissionPhysics {
    vehicle: Vehicle,
    environment: Environment,
    template: StateVector,
    stage: FlightStage,
    time_s: f64,
    /// The drone in the point-mass stages (and where it lies after landing), NED m.
    position_ned_m: Vector3<f64>,
    /// Its velocity, NED m/s.
    velocity_ned_mps: Vector3<f64>,
    /// The 14-DOF model and its state, from deployment on.
    parafoil: Option<(ParafoilModel, StateVector)>,
    touchdown: Option<Touchdown>,
    balloon: Balloon,
    chute: RoundChute,
    ascent_swing: Swing,
    chute_swing: Swing,
    launch_at_s: f64,
    deployed_at_s: Option<f64>,
    deploy_heading_rad: Option<f64>,
    burst_altitude_msl_m: f64,
    /// Time from deployment to guided flight, s (the onboard `MIS_SETTLE_S`, which the station
    /// may change).
    pub settle_s: f64,
}

impl std::fmt::Debug for MissionPhysics {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MissionPhysics")
            .field("stage", &self.stage)
            .field("time_s", &self.time_s)
            .field("position_ned_m", &self.position_ned_m)
            .finish_non_exhaustive()
    }
}

impl MissionPhysics {
    /// The physics of `config`'s mission for `vehicle` in `wind`, starting at mission time 0.
    pub fn new(
        config: &MissionConfig,
        vehicle: Vehicle,
        wind: Arc<dyn WindField>,
    ) -> Result<Self, PhysicsError> {
        let template =
            crate::montecarlo::steady_glide_state(&vehicle).map_err(PhysicsError::Template)?;
        let atmosphere: Arc<dyn Atmosphere> = Arc::new(StandardAtmosphere);
        let ground = config.site.alt_msl_m;
        let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
        rng.set_stream(41);
        let ascent_swing = Swing::new(15.0, 2.0, 3.0, &mut rng);
        let chute_swing = Swing::new(5.0, 8.0, 10.0, &mut rng);
        let start = &config.start;
        let mut physics = Self {
            chute: RoundChute {
                drag_area_m2: config.round_chute.drag_area_m2,
                mass_kg: vehicle.total_mass_kg() + config.round_chute.extra_mass_kg,
                gravity_mps2: vehicle.gravity_mps2,
            },
            vehicle,
            environment: Environment {
                atmosphere,
                wind,
                ground_altitude_msl_m: ground,
            },
            template,
            stage: start.stage,
            time_s: 0.0,
            position_ned_m: Vector3::from(start.position_ned_m),
            velocity_ned_mps: Vector3::zeros(),
            parafoil: None,
            touchdown: None,
            balloon: Balloon::with_mean_rate(
                config.balloon.mean_ascent_rate_mps,
                config.balloon.ascent_density_exponent,
                &StandardAtmosphere,
                ground,
                config.balloon.burst_altitude_msl_m,
            ),
            ascent_swing,
            chute_swing,
            launch_at_s: start.launch_delay_s,
            deployed_at_s: None,
            settle_s: config.onboard.mission.settle_s,
            deploy_heading_rad: config.parafoil.deploy_heading_deg.map(f64::to_radians),
            burst_altitude_msl_m: config.balloon.burst_altitude_msl_m,
        };
        match start.stage {
            FlightStage::Ascent => {
                physics.velocity_ned_mps = physics.ascent_velocity(&physics.position_ned_m);
            }
            FlightStage::RoundChute => {
                let wind = physics.wind_at(&physics.position_ned_m);
                let rho = physics.density_at(&physics.position_ned_m);
                physics.velocity_ned_mps =
                    wind + Vector3::new(0.0, 0.0, physics.chute.terminal_speed_mps(rho));
            }
            FlightStage::ParafoilDeploy => {
                physics.velocity_ned_mps = physics.wind_at(&physics.position_ned_m);
                physics.start_parafoil();
            }
            _ => {}
        }
        Ok(physics)
    }

    /// Mission time, s.
    pub fn time_s(&self) -> f64 {
        self.time_s
    }

    /// The stage.
    pub fn stage(&self) -> FlightStage {
        self.stage
    }

    /// Altitude at which the balloon bursts, m above mean sea level.
    pub fn burst_altitude_msl_m(&self) -> f64 {
        self.burst_altitude_msl_m
    }

    /// The balloon's ascent model.
    pub fn balloon(&self) -> &Balloon {
        &self.balloon
    }

    /// The vehicle flown.
    pub fn vehicle(&self) -> &Vehicle {
        &self.vehicle
    }

    /// The air the mission flies in.
    pub fn environment(&self) -> &Environment {
        &self.environment
    }

    /// Where and how it touched down, once landed.
    pub fn touchdown(&self) -> Option<&Touchdown> {
        self.touchdown.as_ref()
    }

    /// The 14-DOF model and its state, from deployment to landing.
    pub fn parafoil(&self) -> Option<&(ParafoilModel, StateVector)> {
        self.parafoil.as_ref()
    }

    /// The servos' actual positions (neutral before deployment).
    pub fn servo_positions(&self) -> Controls {
        match &self.parafoil {
            Some((_, x)) => Controls {
                main_line_m: x[idx::MAIN_LINE],
                brake_right: x[idx::BRAKE_RIGHT],
                brake_left: x[idx::BRAKE_LEFT],
            },
            None => Controls::default(),
        }
    }

    fn wind_at(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.environment.wind.wind_ned_mps(self.time_s, p)
    }

    fn density_at(&self, p: &Vector3<f64>) -> f64 {
        self.environment
            .atmosphere
            .air_at(self.environment.ground_altitude_msl_m - p.z)
            .density_kg_per_m3
    }

    fn ascent_velocity(&self, p: &Vector3<f64>) -> Vector3<f64> {
        let w = self.wind_at(p);
        Vector3::new(w.x, w.y, -self.balloon.ascent_rate_mps(self.density_at(p)))
    }

    /// Altitude of the drone above mean sea level, m.
    pub fn altitude_msl_m(&self) -> f64 {
        self.environment.ground_altitude_msl_m - self.truth().position_ned_m.z
    }

    /// What the sensors see now.
    pub fn truth(&self) -> Truth {
        if let (Some((model, x)), None) = (&self.parafoil, &self.touchdown) {
            return Truth::from_model(model, self.time_s, x);
        }
        let (euler, rates) = match self.stage {
            FlightStage::Ascent => self.ascent_swing.attitude(self.time_s),
            FlightStage::RoundChute => self.chute_swing.attitude(self.time_s),
            // On the ground: level, facing where the swing left it (or north on the pad).
            _ => (
                Vector3::new(0.0, 0.0, self.landed_yaw_rad()),
                Vector3::zeros(),
            ),
        };
        let euler = Vector3::new(euler.x, euler.y, stx_dynamics::rotation::wrap_pi(euler.z));
        let p = self.position_ned_m;
        let wind = self.wind_at(&p);
        let air = self
            .environment
            .atmosphere
            .air_at(self.environment.ground_altitude_msl_m - p.z);
        Truth {
            time_s: self.time_s,
            position_ned_m: p,
            velocity_ned_mps: self.velocity_ned_mps,
            euler_rad: euler,
            euler_rate_rad_s: rates,
            air_velocity_body_mps: t_from_euler(&euler) * (self.velocity_ned_mps - wind),
            wind_ned_mps: wind,
            air,
        }
    }

    fn landed_yaw_rad(&self) -> f64 {
        self.touchdown
            .map(|t| t.heading_rad)
            .unwrap_or(self.ascent_swing.yaw0_rad)
    }

    /// Cuts the balloon away: only during the ascent.
    pub fn cutdown(&mut self) -> Result<StageEvent, CutdownRefused> {
        match self.stage {
            FlightStage::Ascent => {
                self.stage = FlightStage::RoundChute;
                Ok(StageEvent::CutDown {
                    altitude_msl_m: self.altitude_msl_m(),
                })
            }
            FlightStage::PreLaunch => Err(CutdownRefused::OnGround),
            other => Err(CutdownRefused::NoBalloon(other)),
        }
    }

    /// Flies one period of `period_s` with the servos commanded to `controls` (used from
    /// deployment on); returns the stage changes in it, in order.
    pub fn step(
        &mut self,
        controls: Controls,
        period_s: f64,
    ) -> Result<Vec<StageEvent>, PhysicsError> {
        let mut events = Vec::new();
        let end_s = self.time_s + period_s;
        match self.stage {
            FlightStage::PreLaunch => {
                self.time_s = end_s;
                if self.time_s + 1e-9 >= self.launch_at_s {
                    self.stage = FlightStage::Ascent;
                    self.velocity_ned_mps = self.ascent_velocity(&self.position_ned_m);
                    events.push(StageEvent::Launched);
                }
            }
            FlightStage::Ascent => {
                self.fly_point_mass(end_s, false);
                if self.altitude_msl_m() >= self.burst_altitude_msl_m {
                    self.stage = FlightStage::RoundChute;
                    events.push(StageEvent::Burst {
                        altitude_msl_m: self.altitude_msl_m(),
                    });
                }
            }
            FlightStage::RoundChute => {
                if self.fly_point_mass(end_s, true) {
                    self.stage = FlightStage::Landed;
                    let t = Touchdown {
                        time_s: self.time_s,
                        body: Body::Drone,
                        position_ne_m: [self.position_ned_m.x, self.position_ned_m.y],
                        vertical_speed_mps: self.velocity_ned_mps.z,
                        heading_rad: self.chute_swing.attitude(self.time_s).0.z,
                        upwind_rad: f64::NAN,
                    };
                    self.velocity_ned_mps = Vector3::zeros();
                    self.touchdown = Some(t);
                    events.push(StageEvent::Landed(t));
                }
            }
            FlightStage::ParafoilDeploy | FlightStage::Parafoil => {
                if let Some(t) = self.fly_parafoil(controls, period_s)? {
                    self.stage = FlightStage::Landed;
                    events.push(StageEvent::Landed(t));
                } else if self.stage == FlightStage::ParafoilDeploy
                    && self
                        .deployed_at_s
                        .is_some_and(|d| self.time_s + 1e-9 >= d + self.settle_s)
                {
                    self.stage = FlightStage::Parafoil;
                    events.push(StageEvent::Flying);
                }
            }
            FlightStage::Landed => self.time_s = end_s,
        }
        Ok(events)
    }

    /// Moves the point mass to `end_s`: the balloon kinematically, the round chute by RK4.
    /// Returns whether it reached the ground (then it lies there, at the crossing time).
    fn fly_point_mass(&mut self, end_s: f64, chute: bool) -> bool {
        while self.time_s < end_s - 1e-9 {
            let dt = POINT_MASS_STEP_S.min(end_s - self.time_s);
            let (p0, v0) = (self.position_ned_m, self.velocity_ned_mps);
            if chute {
                let t0 = self.time_s;
                let f = |t: f64, p: &Vector3<f64>, v: &Vector3<f64>| {
                    let wind = self.environment.wind.wind_ned_mps(t, p);
                    let rho = self.density_at(p);
                    (*v, self.chute.acceleration(v, &wind, rho))
                };
                let (k1p, k1v) = f(t0, &p0, &v0);
                let (k2p, k2v) = f(
                    t0 + dt / 2.0,
                    &(p0 + k1p * dt / 2.0),
                    &(v0 + k1v * dt / 2.0),
                );
                let (k3p, k3v) = f(
                    t0 + dt / 2.0,
                    &(p0 + k2p * dt / 2.0),
                    &(v0 + k2v * dt / 2.0),
                );
                let (k4p, k4v) = f(t0 + dt, &(p0 + k3p * dt), &(v0 + k3v * dt));
                self.position_ned_m = p0 + (k1p + 2.0 * k2p + 2.0 * k3p + k4p) * dt / 6.0;
                self.velocity_ned_mps = v0 + (k1v + 2.0 * k2v + 2.0 * k3v + k4v) * dt / 6.0;
            } else {
                // Midpoint rule on the prescribed velocity field.
                let mid = p0 + self.ascent_velocity(&p0) * dt / 2.0;
                let v = self.ascent_velocity(&mid);
                self.position_ned_m = p0 + v * dt;
                self.velocity_ned_mps = v;
            }
            self.time_s += dt;
            if self.position_ned_m.z >= 0.0 {
                // Back to the crossing, linearly within the step.
                let dz = self.position_ned_m.z - p0.z;
                let f = if dz > 0.0 {
                    (-p0.z / dz).clamp(0.0, 1.0)
                } else {
                    1.0
                };
                self.time_s -= (1.0 - f) * dt;
                self.position_ned_m = p0 + (self.position_ned_m - p0) * f;
                self.position_ned_m.z = 0.0;
                return true;
            }
        }
        self.time_s = end_s;
        false
    }
}
