//! What the drone's sensors report (seed §2.2, §3.3.2): a GPS receiver (position and NED
//! velocity), an AHRS (roll, pitch, yaw of the drone) and a pitot tube with a differential and
//! an absolute pressure sensor (airspeed along the drone's x axis only).
//!
//! Each measurement carries the instant it describes (`time_s`, the sensor's own timestamp on
//! the mission clock), which can be earlier than when it reaches the estimator: the radio and
//! the receivers add latency. Positions are in the local North-East-Down frame of the mission
//! (see `geo`), so the same types serve the simulated drone and the ground station.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// A GPS fix.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GpsFix {
    /// Instant the fix describes, s on the mission clock.
    pub time_s: f64,
    /// Antenna position (on the drone), local NED, m.
    pub position_ned_m: Vector3<f64>,
    /// Velocity over the ground, NED, m/s.
    pub velocity_ned_mps: Vector3<f64>,
    /// Receiver's 1-σ horizontal position accuracy, m.
    pub horizontal_accuracy_m: f64,
    /// Receiver's 1-σ vertical position accuracy, m.
    pub vertical_accuracy_m: f64,
    /// Receiver's 1-σ speed accuracy, m/s.
    pub speed_accuracy_mps: f64,
}

/// The AHRS's attitude of the drone relative to local NED (3-2-1 Euler angles).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AttitudeSample {
    /// Instant it describes, s.
    pub time_s: f64,
    /// Roll φ, rad.
    pub roll_rad: f64,
    /// Pitch θ, rad.
    pub pitch_rad: f64,
    /// Yaw ψ (heading of the drone's x axis from north), rad.
    pub yaw_rad: f64,
}

/// The pitot's pressures: the differential pressure is `½ρu²` of the air-relative velocity
/// along the drone's x axis; static pressure and temperature give the density.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AirDataSample {
    /// Instant it describes, s.
    pub time_s: f64,
    /// Total minus static pressure, Pa.
    pub differential_pressure_pa: f64,
    /// Static (absolute) pressure, Pa.
    pub static_pressure_pa: f64,
    /// Air temperature, K.
    pub temperature_k: f64,
}

/// Any of the three.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "sensor", rename_all = "snake_case")]
pub enum Measurement {
    /// GPS.
    Gps(GpsFix),
    /// AHRS.
    Attitude(AttitudeSample),
    /// Pitot.
    AirData(AirDataSample),
}

impl Measurement {
    /// The instant the measurement describes, s.
    pub fn time_s(&self) -> f64 {
        match self {
            Measurement::Gps(m) => m.time_s,
            Measurement::Attitude(m) => m.time_s,
            Measurement::AirData(m) => m.time_s,
        }
    }
}

/// Specific gas constant of dry air, J/(kg·K) (US Standard Atmosphere 1976: R*/M0).
pub const AIR_GAS_CONSTANT: f64 = 287.052_87;

impl AirDataSample {
    /// Air density from static pressure and temperature (ideal gas), kg/m³.
    pub fn density_kg_per_m3(&self) -> f64 {
        self.static_pressure_pa / (AIR_GAS_CONSTANT * self.temperature_k)
    }

    /// Airspeed along the drone's x axis by Bernoulli, `√(2Δp/ρ)`, m/s; zero for a
    /// non-positive differential pressure (the pitot cannot tell backwards flow).
    pub fn indicated_airspeed_mps(&self) -> f64 {
        let rho = self.density_kg_per_m3();
        if self.differential_pressure_pa > 0.0 && rho > 0.0 {
            (2.0 * self.differential_pressure_pa / rho).sqrt()
        } else {
            0.0
        }
    }
}
