//! What the drone reports about itself as the dashboard reads it: its receivers and sensors
//! (GPS, AHRS, pitot), servos, battery, mode and stage, and its own predicted touchdown.

use schemars::JsonSchema;
use serde::Serialize;
use stx_gnc::mission::{FlightMode, FlightStage, GuidancePhase};
use stx_link::telemetry::GpsFix;

/// GPS as the drone's receiver reports it.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct GpsView {
    /// Fix type.
    #[schemars(with = "GpsFix")]
    pub fix: String,
    /// Satellites used.
    pub satellites: Option<u8>,
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Longitude, degrees.
    pub lon_deg: f64,
    /// Altitude MSL, m.
    pub alt_msl_m: f64,
    /// Velocity NED, m/s.
    pub velocity_ned_mps: [f64; 3],
    /// Horizontal accuracy, m.
    pub h_acc_m: Option<f64>,
}

/// Attitude from the AHRS.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct AttitudeView {
    /// The drone's clock when the attitude was measured (ms since its boot): which sample
    /// this is.
    pub time_boot_ms: u32,
    /// Roll, degrees.
    pub roll_deg: f64,
    /// Pitch, degrees.
    pub pitch_deg: f64,
    /// Yaw, degrees.
    pub yaw_deg: f64,
}

/// Pitot and static pressure.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct AirView {
    /// Static pressure, Pa.
    pub static_pressure_pa: f64,
    /// Differential pressure, Pa.
    pub differential_pressure_pa: f64,
    /// Temperature, °C.
    pub temperature_c: f64,
    /// Indicated airspeed from them, m/s.
    pub airspeed_mps: f64,
}

/// Servo positions.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct ServosView {
    /// Main line, −1…1.
    pub main_line: f64,
    /// Right brake, 0…1.
    pub brake_right: f64,
    /// Left brake, 0…1.
    pub brake_left: f64,
}

/// Battery.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct PowerView {
    /// Voltage, V.
    pub voltage_v: Option<f64>,
    /// Current, A.
    pub current_a: Option<f64>,
    /// Remaining, %.
    pub remaining_percent: Option<u8>,
}

/// What the drone reports about itself.
#[derive(Debug, Clone, Default, Serialize, JsonSchema)]
pub struct VehicleView {
    /// Mode.
    #[schemars(with = "Option<FlightMode>")]
    pub mode: Option<String>,
    /// Stage.
    #[schemars(with = "Option<FlightStage>")]
    pub stage: Option<String>,
    /// Guidance phase (onboard).
    #[schemars(with = "Option<GuidancePhase>")]
    pub phase: Option<String>,
    /// Times the onboard phase has become `final_approach` since the station started, counted
    /// on every status the drone sent. A page is sent the newest state when it is ready, so a
    /// final approach short enough to fall between two of its states shows only here.
    pub final_approaches: u32,
    /// GPS.
    pub gps: Option<GpsView>,
    /// Attitude.
    pub attitude: Option<AttitudeView>,
    /// Air data.
    pub air: Option<AirView>,
    /// Servos.
    pub servos: Option<ServosView>,
    /// Power.
    pub power: Option<PowerView>,
    /// The onboard estimate of the wind, NED, m/s.
    pub onboard_wind_ned_mps: Option<[f64; 3]>,
    /// The drone's own prediction of its touchdown (POSITION_TARGET_GLOBAL_INT), beside the
    /// station's in `prediction`.
    pub predicted_landing: Option<OnboardLandingView>,
    /// Seconds since the newest message from the drone arrived.
    pub age_s: f64,
    /// These data are old (see `API.md`): show them as stale.
    pub stale: bool,
}

/// The drone's own predicted touchdown.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct OnboardLandingView {
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Longitude, degrees.
    pub lon_deg: f64,
    /// Altitude MSL of the touchdown point, m.
    pub alt_msl_m: f64,
    /// Seconds since it arrived.
    pub age_s: f64,
    /// Old: show it as stale.
    pub stale: bool,
}
