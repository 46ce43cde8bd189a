//! The drone of a mission flying a vehicle and sensors drawn from a dispersion set: what `stx
//! drone --dispersions`, `stx serve --sim` and the station's agreement harness fly, built in
//! one place so that they fly the same world for the same seed.

use stx_dynamics::vehicle::{Vehicle, VehicleError};

use super::{Drone, DroneError, MissionConfig};
use crate::dispersions::{DispersedFlight, Dispersions};

/// Why a dispersed drone cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum DispersedDroneError {
    /// The vehicle drawn is one the model refuses.
    #[error("the vehicle drawn from the dispersion set is refused")]
    Vehicle(#[source] VehicleError),
    /// The drone cannot be built (its mission).
    #[error(transparent)]
    Drone(#[from] DroneError),
}

impl DispersedDroneError {
    /// Whether the mission (the caller's input) was refused rather than the draw.
    pub fn is_mission(&self) -> bool {
        matches!(self, Self::Drone(_))
    }
}

/// The mission and the vehicle a drone of `mission` flies: drawn from `dispersions` with the
/// mission's seed (its sensors too), or the nominal STRAPLEX vehicle without them. The
/// onboard software keeps the nominal vehicle either way, as on a real flight.
pub fn dispersed_inputs(
    mission: &MissionConfig,
    dispersions: Option<&Dispersions>,
) -> Result<(MissionConfig, Vehicle), VehicleError> {
    let Some(d) = dispersions else {
        return Ok((mission.clone(), Vehicle::straplex()));
    };
    let drawn = DispersedFlight::draw(
        d,
        &Vehicle::straplex().config,
        &mission.sensors,
        mission.seed,
    )?;
    let mut m = mission.clone();
    m.sensors = drawn.sensors;
    Ok((m, drawn.vehicle))
}

impl Drone {
    /// The drone of `mission`, dispersed by `dispersions` (see [`dispersed_inputs`]).
    pub fn dispersed(
        mission: &MissionConfig,
        dispersions: Option<&Dispersions>,
    ) -> Result<Self, DispersedDroneError> {
        let (mission, vehicle) =
            dispersed_inputs(mission, dispersions).map_err(DispersedDroneError::Vehicle)?;
        Ok(Self::new(&mission, vehicle)?)
    }
}
