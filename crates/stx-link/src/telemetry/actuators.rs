//! The three actuators ([`Actuators`], SERVO_OUTPUT_RAW) and the servo pulse mapping:
//! main-line differential −1…+1 ↔ 1000…2000 µs (1500 neutral), brakes 0…1 ↔ 1000…2000 µs.

use mavlink::dialects::common as mc;
use mavlink::dialects::common::MavMessage;
use serde::{Deserialize, Serialize};

/// The three actuators (SERVO_OUTPUT_RAW).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct Actuators {
    /// Time, µs (wraps after ~71 min, as on the wire).
    pub time_usec: u32,
    /// Main-line differential, −1 (full left) … +1 (full right); servo1, 1500 µs neutral.
    pub main_line: f64,
    /// Right brake deflection 0 (up) … 1 (full); servo2, 1000…2000 µs.
    pub brake_right: f64,
    /// Left brake deflection 0 … 1; servo3, 1000…2000 µs.
    pub brake_left: f64,
}

/// Normalised −1…1 to 1000…2000 µs, 1500 neutral.
pub fn signed_to_pwm_us(v: f64) -> u16 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(-1.0, 1.0) };
    (1500.0 + 500.0 * v).round() as u16
}
/// 1000…2000 µs to −1…1 (clamped).
pub fn pwm_us_to_signed(us: u16) -> f64 {
    ((f64::from(us) - 1500.0) / 500.0).clamp(-1.0, 1.0)
}
/// Normalised 0…1 to 1000…2000 µs.
pub fn unit_to_pwm_us(v: f64) -> u16 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    (1000.0 + 1000.0 * v).round() as u16
}
/// 1000…2000 µs to 0…1 (clamped).
pub fn pwm_us_to_unit(us: u16) -> f64 {
    ((f64::from(us) - 1000.0) / 1000.0).clamp(0.0, 1.0)
}

impl Actuators {
    /// The SERVO_OUTPUT_RAW carrying it.
    pub(super) fn to_mavlink(self) -> MavMessage {
        MavMessage::SERVO_OUTPUT_RAW(mc::SERVO_OUTPUT_RAW_DATA {
            time_usec: self.time_usec,
            servo1_raw: signed_to_pwm_us(self.main_line),
            servo2_raw: unit_to_pwm_us(self.brake_right),
            servo3_raw: unit_to_pwm_us(self.brake_left),
            ..Default::default()
        })
    }

    /// What a SERVO_OUTPUT_RAW carries.
    pub(super) fn from_mavlink(s: &mc::SERVO_OUTPUT_RAW_DATA) -> Self {
        Actuators {
            time_usec: s.time_usec,
            main_line: pwm_us_to_signed(s.servo1_raw),
            brake_right: pwm_us_to_unit(s.servo2_raw),
            brake_left: pwm_us_to_unit(s.servo3_raw),
        }
    }
}
