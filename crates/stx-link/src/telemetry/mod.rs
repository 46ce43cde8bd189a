//! stx's telemetry as plain Rust values in SI units, and their exact mapping to MAVLink
//! common-dialect messages.
//!
//! The rest of stx (estimator display, dashboard, recorder) works with these types and never
//! with MAVLink's scaled integers (degE7, mm, cdeg, cdegC, hPa, cA, …). The mapping is
//! two-way: [`Telemetry::to_mavlink`] on the drone, [`Telemetry::from_mavlink`] on the
//! station; a value survives the round trip within the wire's quantisation, and a value read
//! from the wire survives the reverse trip exactly.
//!
//! | stx type | MAVLink message | notes |
//! |---|---|---|
//! | [`VehicleStatus`] | HEARTBEAT | `custom_mode = mode \| stage << 8 \| phase << 16` (codes from `stx_types::mission`), `base_mode = CUSTOM_MODE_ENABLED`, `type = MAV_TYPE_PARAFOIL` (exists in the dialect, 28), autopilot `GENERIC` |
//! | [`GpsRaw`] | GPS_RAW_INT | extensions carry h_acc / v_acc; `UINT16_MAX` / `255` / `0` = unknown |
//! | [`GpsSolution`] | GPS_INPUT | the receiver's whole solution beside GPS_RAW_INT: NED velocity (vertical too) and accuracies as floats, for the station's estimator (see `gps_solution.rs`) |
//! | [`GlobalPosition`] | GLOBAL_POSITION_INT | onboard estimate; NED velocity in cm/s |
//! | [`Attitude`] | ATTITUDE | rad, rad/s |
//! | [`AirData`] | SCALED_PRESSURE | pitot: wire hPa ↔ Pa, cdegC ↔ °C |
//! | [`Hud`] | VFR_HUD | heading is whole degrees on the wire; throttle always 0 (no motor) |
//! | [`Actuators`] | SERVO_OUTPUT_RAW | servo1 main-line differential −1…+1 ↔ 1000…2000 µs (1500 neutral); servo2 right brake, servo3 left brake 0…1 ↔ 1000…2000 µs |
//! | [`SystemStatus`] | SYS_STATUS | battery voltage/current/remaining, load, comm drop rate, sensor bitmaps |
//! | [`BatteryStatus`] | BATTERY_STATUS | total voltage in cell 0, other cells `UINT16_MAX` (MAVLink's rule for an unknown cell split) |
//! | [`StatusText`] | STATUSTEXT | one chunk of ≤ 50 bytes; [`split_status_text`] and [`StatusTextAssembler`] handle longer text with `id`/`chunk_seq` |
//! | [`Wind`] | WIND_COV | NED m/s, 1-σ variability (the wire's `var_*` fields are standard deviations in m/s), altitude MSL |
//! | [`GuidanceStatus`] | NAV_CONTROLLER_OUTPUT | bearing to target, cross-track error, distance to target (m, saturates at 65 535), altitude error |
//! | [`PredictedLanding`] | POSITION_TARGET_GLOBAL_INT | see below |
//!
//! ## Why POSITION_TARGET_GLOBAL_INT for the predicted landing point
//! The common dialect has no message for a predicted touchdown point. We need one message
//! (so the point is atomic and `to_mavlink` stays one-to-one) with integer latitude and
//! longitude (degE7, 1 cm) and an MSL altitude:
//! - HOME_POSITION would move the home / return point in every generic ground station: unsafe.
//! - NAMED_VALUE_FLOAT triples carry f32 latitude/longitude (about 1.7 m steps at 180° of
//!   longitude) and need three messages re-assembled, which can arrive torn.
//! - LANDING_TARGET describes a sensor's view of a target relative to the vehicle.
//!
//! POSITION_TARGET_GLOBAL_INT carries degE7 latitude/longitude and an altitude in
//! `MAV_FRAME_GLOBAL` (MSL). We send it with every velocity, acceleration, yaw and yaw-rate
//! field marked ignored in `type_mask` (only the position is meaningful). For an unpowered
//! parafoil the "position target" generic tools show is where the vehicle is going to be
//! at the end of its descent, which is what the predicted landing point is. A frame other than
//! `MAV_FRAME_GLOBAL`, or a type mask with any position bit ignored, is not read as a
//! predicted landing point.
//!
//! ## Files
//! Each message family keeps its types and their mapping both ways together; this file holds
//! [`Telemetry`], which dispatches to them.
//! - `system.rs`: [`VehicleStatus`] (HEARTBEAT), [`SystemStatus`], [`BatteryStatus`].
//! - `gps_solution.rs`: [`GpsSolution`] (GPS_INPUT).
//! - `fix.rs`: when a GNSS report is a position ([`has_position_fix`]: a fix, and not 0°, 0°).
//! - `navigation.rs`: [`GpsRaw`], [`GlobalPosition`], [`Attitude`], [`AirData`], [`Hud`].
//! - `actuators.rs`: [`Actuators`] and the servo pulse mapping.
//! - `status_text.rs`: [`StatusText`], [`Severity`], splitting and re-assembly.
//! - `guidance.rs`: [`Wind`], [`GuidanceStatus`], [`PredictedLanding`].
//! - `units.rs`: the scaled integers of the wire.

mod actuators;
mod fix;
mod gps_solution;
mod guidance;
mod navigation;
mod status_text;
mod system;
mod units;

pub use actuators::{
    Actuators, pwm_us_to_signed, pwm_us_to_unit, signed_to_pwm_us, unit_to_pwm_us,
};
pub use fix::{has_position_fix, is_position};
pub use gps_solution::GpsSolution;
pub use guidance::{GuidanceStatus, PredictedLanding, Wind};
pub use navigation::{AirData, Attitude, GlobalPosition, GpsFix, GpsRaw, Hud};
pub use status_text::{
    STATUSTEXT_LEN, Severity, StatusText, StatusTextAssembler, split_status_text,
};
pub use system::{BatteryStatus, SystemState, SystemStatus, VehicleStatus};

use mavlink::dialects::common::MavMessage;
use serde::{Deserialize, Serialize};

/// Every telemetry item the drone sends.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Telemetry {
    Status(VehicleStatus),
    GpsRaw(GpsRaw),
    GpsSolution(GpsSolution),
    Position(GlobalPosition),
    Attitude(Attitude),
    AirData(AirData),
    Hud(Hud),
    Actuators(Actuators),
    System(SystemStatus),
    Battery(BatteryStatus),
    StatusText(StatusText),
    Wind(Wind),
    Guidance(GuidanceStatus),
    PredictedLanding(PredictedLanding),
}

impl Telemetry {
    /// Name of the MAVLink message this maps to.
    pub fn message_name(&self) -> &'static str {
        match self {
            Self::Status(_) => "HEARTBEAT",
            Self::GpsRaw(_) => "GPS_RAW_INT",
            Self::GpsSolution(_) => "GPS_INPUT",
            Self::Position(_) => "GLOBAL_POSITION_INT",
            Self::Attitude(_) => "ATTITUDE",
            Self::AirData(_) => "SCALED_PRESSURE",
            Self::Hud(_) => "VFR_HUD",
            Self::Actuators(_) => "SERVO_OUTPUT_RAW",
            Self::System(_) => "SYS_STATUS",
            Self::Battery(_) => "BATTERY_STATUS",
            Self::StatusText(_) => "STATUSTEXT",
            Self::Wind(_) => "WIND_COV",
            Self::Guidance(_) => "NAV_CONTROLLER_OUTPUT",
            Self::PredictedLanding(_) => "POSITION_TARGET_GLOBAL_INT",
        }
    }

    /// The MAVLink message carrying this item.
    pub fn to_mavlink(&self) -> MavMessage {
        match self {
            Self::Status(s) => s.to_mavlink(),
            Self::GpsRaw(g) => g.to_mavlink(),
            Self::GpsSolution(g) => g.to_mavlink(),
            Self::Position(p) => p.to_mavlink(),
            Self::Attitude(a) => a.to_mavlink(),
            Self::AirData(d) => d.to_mavlink(),
            Self::Hud(h) => h.to_mavlink(),
            Self::Actuators(a) => a.to_mavlink(),
            Self::System(s) => s.to_mavlink(),
            Self::Battery(b) => b.to_mavlink(),
            Self::StatusText(t) => t.to_mavlink(),
            Self::Wind(w) => w.to_mavlink(),
            Self::Guidance(g) => g.to_mavlink(),
            Self::PredictedLanding(p) => p.to_mavlink(),
        }
    }

    /// The telemetry item a MAVLink message carries, `None` for messages that are not stx
    /// telemetry (including heartbeats of other vehicle types or with unknown stx codes).
    pub fn from_mavlink(msg: &MavMessage) -> Option<Telemetry> {
        Some(match msg {
            MavMessage::HEARTBEAT(h) => Self::Status(VehicleStatus::from_mavlink(h)?),
            MavMessage::GPS_RAW_INT(g) => Self::GpsRaw(GpsRaw::from_mavlink(g)),
            MavMessage::GPS_INPUT(g) => Self::GpsSolution(GpsSolution::from_mavlink(g)),
            MavMessage::GLOBAL_POSITION_INT(p) => Self::Position(GlobalPosition::from_mavlink(p)),
            MavMessage::ATTITUDE(a) => Self::Attitude(Attitude::from_mavlink(a)),
            MavMessage::SCALED_PRESSURE(d) => Self::AirData(AirData::from_mavlink(d)),
            MavMessage::VFR_HUD(h) => Self::Hud(Hud::from_mavlink(h)),
            MavMessage::SERVO_OUTPUT_RAW(s) => Self::Actuators(Actuators::from_mavlink(s)),
            MavMessage::SYS_STATUS(s) => Self::System(SystemStatus::from_mavlink(s)),
            MavMessage::BATTERY_STATUS(b) => Self::Battery(BatteryStatus::from_mavlink(b)),
            MavMessage::STATUSTEXT(t) => Self::StatusText(StatusText::from_mavlink(t)),
            MavMessage::WIND_COV(w) => Self::Wind(Wind::from_mavlink(w)),
            MavMessage::NAV_CONTROLLER_OUTPUT(n) => Self::Guidance(GuidanceStatus::from_mavlink(n)),
            MavMessage::POSITION_TARGET_GLOBAL_INT(p) => {
                Self::PredictedLanding(PredictedLanding::from_mavlink(p)?)
            }
            _ => return None,
        })
    }
}

#[cfg(test)]
mod tests;
