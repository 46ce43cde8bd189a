//! The drone of a mission flying a chosen truth: a vehicle file (`stx drone --vehicle`, `stx
//! serve --sim --sim-vehicle`), a vehicle and sensors drawn from a dispersion set (`stx drone
//! --dispersions`, the station's agreement harness), or both. Built in one place so that they
//! fly the same world for the same seed.
//!
//! How a vehicle and dispersions combine: the vehicle is the centre of the draw. The dispersion
//! set scatters the given vehicle's coefficients, masses and rigging as it would the shipped
//! one's, so `--vehicle FILE --dispersions realistic` flies a draw around the identified stack
//! and `--vehicle FILE --dispersions nominal` flies the file exactly. Whatever the truth, the
//! onboard software keeps its own polar and gains (the mission's onboard settings), as on a
//! real flight where the drone does not know the canopy it hangs under better than it was told.

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
    truth_inputs(mission, &Vehicle::straplex(), dispersions)
}

/// The mission and the vehicle a drone of `mission` flies when its truth is `vehicle`: the
/// vehicle itself without `dispersions`, else a draw centred on it with the mission's seed
/// (the sensors drawn too). The mission's onboard settings are not touched.
pub fn truth_inputs(
    mission: &MissionConfig,
    vehicle: &Vehicle,
    dispersions: Option<&Dispersions>,
) -> Result<(MissionConfig, Vehicle), VehicleError> {
    let Some(d) = dispersions else {
        return Ok((mission.clone(), vehicle.clone()));
    };
    let drawn = DispersedFlight::draw(d, &vehicle.config, &mission.sensors, mission.seed)?;
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
        Self::with_truth(mission, &Vehicle::straplex(), dispersions)
    }

    /// The drone of `mission` whose truth is `vehicle`, dispersed by `dispersions` around it
    /// (see [`truth_inputs`]); its onboard guidance starts from the mission's own settings.
    pub fn with_truth(
        mission: &MissionConfig,
        vehicle: &Vehicle,
        dispersions: Option<&Dispersions>,
    ) -> Result<Self, DispersedDroneError> {
        let (mission, vehicle) =
            truth_inputs(mission, vehicle, dispersions).map_err(DispersedDroneError::Vehicle)?;
        Ok(Self::new(&mission, vehicle)?)
    }
}
