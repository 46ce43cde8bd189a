//! The parafoil stages: the round chute released, the 14-DOF model started from a steady
//! glide with its drone where the point mass was, and flown one control period at a time up
//! to the ground contact of its lowest body.

use nalgebra::Vector3;
use stx_dynamics::model::{Body, Kinematics, ParafoilModel};
use stx_dynamics::state::{Controls, idx};
use stx_gnc::mission::FlightStage;

use super::{DeployRefused, MissionPhysics, PhysicsError, StageEvent};
use crate::closed_loop::{Touchdown, fly_period, touchdown};
use crate::guided::STEP_S;
use crate::sensors::Truth;

impl MissionPhysics {
    /// Releases the round chute (the onboard software's decision): the parafoil deploys at
    /// the drone's position, heading along the drift or as configured.
    pub fn deploy(&mut self) -> Result<StageEvent, DeployRefused> {
        if self.stage != FlightStage::RoundChute {
            return Err(DeployRefused { stage: self.stage });
        }
        let heading_rad = self.start_parafoil();
        Ok(StageEvent::Deployed {
            height_m: -self.position_ned_m.z,
            heading_rad,
        })
    }

    /// Starts the parafoil model at the drone's position. Returns the heading, rad.
    pub(super) fn start_parafoil(&mut self) -> f64 {
        let v = self.velocity_ned_mps;
        let heading = self.deploy_heading_rad.unwrap_or_else(|| {
            if v.x.hypot(v.y) > 0.1 {
                v.y.atan2(v.x)
            } else {
                0.0
            }
        });
        let mut x = self.template;
        x[idx::CANOPY_EULER + 2] = heading;
        // Place the stack so that its drone is where the point mass was.
        let k = Kinematics::new(&self.vehicle, &x, 0.0);
        let offset = self.position_ned_m - k.position_ned_m[Body::Drone as usize];
        for axis in 0..3 {
            x[idx::POSITION + axis] += offset[axis];
        }
        let model = ParafoilModel::new(self.vehicle.clone(), self.environment.clone());
        self.parafoil = Some((model, x));
        self.stage = FlightStage::ParafoilDeploy;
        self.deployed_at_s = Some(self.time_s);
        heading
    }
    pub(super) fn fly_parafoil(
        &mut self,
        controls: Controls,
        period_s: f64,
    ) -> Result<Option<Touchdown>, PhysicsError> {
        let Some((model, x)) = self.parafoil.as_mut() else {
            self.time_s += period_s;
            return Ok(None);
        };
        model.set_controls(controls);
        let (time_s, state, contact_s) = fly_period(model, self.time_s, x, STEP_S, period_s)
            .map_err(|source| PhysicsError::Integration {
                time_s: self.time_s,
                source,
            })?;
        *x = state;
        self.time_s = time_s;
        let truth = Truth::from_model(model, time_s, x);
        self.position_ned_m = truth.position_ned_m;
        self.velocity_ned_mps = truth.velocity_ned_mps;
        Ok(contact_s.map(|t| {
            let td = touchdown(model, x, t);
            // The drone comes to rest on the ground beside the bodies below it.
            self.position_ned_m.z = 0.0;
            self.velocity_ned_mps = Vector3::zeros();
            self.touchdown = Some(td);
            td
        }))
    }
}
