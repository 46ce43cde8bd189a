//! What really happened, from the simulated drone: its true state, its onboard software's
//! mode, phase, plan and prediction, and at the end where each body was at the first ground
//! contact. The station never sees any of this; the harness holds what it shows against it.

use nalgebra::Vector3;
use stx_dynamics::model::{Body, Kinematics};
use stx_gnc::mission::{FlightMode, FlightStage, GuidancePhase};
use stx_sim::drone::Drone;

/// The truth at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthSample {
    /// Mission time (the drone's clock), s.
    pub time_s: f64,
    /// The stage.
    pub stage: FlightStage,
    /// The mode the onboard software flies.
    pub mode: FlightMode,
    /// The onboard guidance phase the drone reports.
    pub phase: GuidancePhase,
    /// The onboard landing target (north, east of the site), m.
    pub target_ne_m: Option<[f64; 2]>,
    /// The onboard spiral's final-approach course, rad, while a spiral landing flies under the
    /// parafoil.
    pub final_course_rad: Option<f64>,
    /// The drone's own latest predicted landing (north, east), m.
    pub onboard_prediction_ne_m: Option<[f64; 2]>,
    /// The drone body's true position, NED from the site, m.
    pub position_ned_m: Vector3<f64>,
    /// The true wind at the drone, NED, m/s.
    pub wind_ned_mps: Vector3<f64>,
    /// The main-line trim the onboard guidance has learned, m.
    pub trim_m: f64,
}

impl TruthSample {
    /// The truth of `drone` now.
    pub fn of(drone: &Drone) -> Self {
        let stage = drone.stage();
        let onboard = drone.onboard();
        let mode = onboard.mode();
        let phase = onboard.phase(stage);
        let spiral_flying = stage == FlightStage::Parafoil
            && mode == FlightMode::SpiralLanding
            && !matches!(phase, GuidancePhase::Idle | GuidancePhase::Landed);
        let truth = drone.physics().truth();
        Self {
            time_s: drone.time_s(),
            stage,
            mode,
            phase,
            target_ne_m: drone.target_ned_m().map(|t| [t.x, t.y]),
            final_course_rad: (spiral_flying && onboard.guidance().spiral_has_run())
                .then(|| onboard.guidance().spiral_status().final_course_rad),
            onboard_prediction_ne_m: drone.predicted_landing_ne_m(),
            position_ned_m: truth.position_ned_m,
            wind_ned_mps: truth.wind_ned_mps,
            trim_m: onboard.guidance().learned_trim_m(),
        }
    }

    /// Height of the drone above the site's ground, m.
    pub fn height_m(&self) -> f64 {
        -self.position_ned_m.z
    }
}

/// Where the stack came down: the first ground contact, and where each body was then.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthLanding {
    /// Mission time of the first contact, s.
    pub time_s: f64,
    /// The body that touched first.
    pub first_body: Body,
    /// Each body's position (north, east of the site), m, in [`Body::ALL`] order, at the
    /// first contact. Under the round chute only the drone is modelled: every body is there.
    pub bodies_ne_m: [[f64; 2]; 4],
    /// Whether it landed under the parafoil.
    pub under_parafoil: bool,
}

impl TruthLanding {
    /// The landing of `drone`, once it is on the ground.
    pub fn of(drone: &Drone) -> Option<Self> {
        let physics = drone.physics();
        let touchdown = physics.touchdown()?;
        let bodies_ne_m = match physics.parafoil() {
            Some((model, x)) => {
                let k = Kinematics::new(physics.vehicle(), x, model.controls().main_line_m);
                Body::ALL.map(|b| {
                    let p = k.position_ned_m[b as usize];
                    [p.x, p.y]
                })
            }
            None => [touchdown.position_ne_m; 4],
        };
        Some(Self {
            time_s: touchdown.time_s,
            first_body: touchdown.body,
            bodies_ne_m,
            under_parafoil: physics.parafoil().is_some(),
        })
    }

    /// Where `body` was at the first contact (north, east), m.
    pub fn body_ne_m(&self, body: Body) -> [f64; 2] {
        self.bodies_ne_m[body as usize]
    }
}
