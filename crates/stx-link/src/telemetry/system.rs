//! The drone's status and health: mode, flight stage and guidance phase ([`VehicleStatus`],
//! HEARTBEAT), system health and main battery ([`SystemStatus`], SYS_STATUS) and each battery
//! ([`BatteryStatus`], BATTERY_STATUS).

use mavlink::dialects::common as mc;
use mavlink::dialects::common::MavMessage;
use serde::{Deserialize, Serialize};
use stx_types::mission::{FlightMode, FlightStage, GuidancePhase};

use super::units::{
    amps_to_ca, c_to_cdeg, ca_to_amps, i8_to_pct, mv_to_volts, pct_to_i8, volts_to_mv,
};

/// Onboard system state (HEARTBEAT `system_status`, MAV_STATE).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "snake_case")]
pub enum SystemState {
    Uninit,
    Boot,
    Calibrating,
    Standby,
    Active,
    Critical,
    Emergency,
    Poweroff,
    FlightTermination,
}

impl SystemState {
    fn to_mav(self) -> mc::MavState {
        use mc::MavState as S;
        match self {
            Self::Uninit => S::MAV_STATE_UNINIT,
            Self::Boot => S::MAV_STATE_BOOT,
            Self::Calibrating => S::MAV_STATE_CALIBRATING,
            Self::Standby => S::MAV_STATE_STANDBY,
            Self::Active => S::MAV_STATE_ACTIVE,
            Self::Critical => S::MAV_STATE_CRITICAL,
            Self::Emergency => S::MAV_STATE_EMERGENCY,
            Self::Poweroff => S::MAV_STATE_POWEROFF,
            Self::FlightTermination => S::MAV_STATE_FLIGHT_TERMINATION,
        }
    }
    fn from_mav(s: mc::MavState) -> Self {
        use mc::MavState as S;
        match s {
            S::MAV_STATE_UNINIT => Self::Uninit,
            S::MAV_STATE_BOOT => Self::Boot,
            S::MAV_STATE_CALIBRATING => Self::Calibrating,
            S::MAV_STATE_STANDBY => Self::Standby,
            S::MAV_STATE_ACTIVE => Self::Active,
            S::MAV_STATE_CRITICAL => Self::Critical,
            S::MAV_STATE_EMERGENCY => Self::Emergency,
            S::MAV_STATE_POWEROFF => Self::Poweroff,
            S::MAV_STATE_FLIGHT_TERMINATION => Self::FlightTermination,
        }
    }
}

/// Mode, flight stage and guidance phase of the drone (HEARTBEAT).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct VehicleStatus {
    /// Control mode the operator selected.
    pub mode: FlightMode,
    /// Where in the mission the vehicle is.
    pub stage: FlightStage,
    /// Where spiral-landing guidance is.
    pub phase: GuidancePhase,
    /// Onboard system state.
    pub state: SystemState,
}

impl VehicleStatus {
    /// `custom_mode` value: `mode | stage << 8 | phase << 16`.
    pub fn custom_mode(&self) -> u32 {
        u32::from(self.mode.code())
            | u32::from(self.stage.code()) << 8
            | u32::from(self.phase.code()) << 16
    }

    /// Unpacks a `custom_mode`; `None` if any code is unknown or the top byte is not zero.
    pub fn unpack_custom_mode(
        custom_mode: u32,
    ) -> Option<(FlightMode, FlightStage, GuidancePhase)> {
        let [mode, stage, phase, top] = custom_mode.to_le_bytes();
        if top != 0 {
            return None;
        }
        Some((
            FlightMode::from_code(mode)?,
            FlightStage::from_code(stage)?,
            GuidancePhase::from_code(phase)?,
        ))
    }

    /// The HEARTBEAT carrying it.
    pub(super) fn to_mavlink(self) -> MavMessage {
        MavMessage::HEARTBEAT(mc::HEARTBEAT_DATA {
            custom_mode: self.custom_mode(),
            mavtype: mc::MavType::MAV_TYPE_PARAFOIL,
            autopilot: mc::MavAutopilot::MAV_AUTOPILOT_GENERIC,
            base_mode: mc::MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
            system_status: self.state.to_mav(),
            mavlink_version: 3,
        })
    }

    /// What a HEARTBEAT carries, `None` when it is not stx telemetry.
    pub(super) fn from_mavlink(h: &mc::HEARTBEAT_DATA) -> Option<Self> {
        if h.mavtype != mc::MavType::MAV_TYPE_PARAFOIL
            || !h
                .base_mode
                .contains(mc::MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED)
        {
            return None;
        }
        let (mode, stage, phase) = VehicleStatus::unpack_custom_mode(h.custom_mode)?;
        Some(VehicleStatus {
            mode,
            stage,
            phase,
            state: SystemState::from_mav(h.system_status),
        })
    }
}

/// Onboard system health and main battery (SYS_STATUS).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct SystemStatus {
    /// Battery voltage, V (wire: mV; `None` = UINT16_MAX).
    pub battery_voltage_v: Option<f64>,
    /// Battery current, A (wire: cA; `None` = −1).
    pub battery_current_a: Option<f64>,
    /// Remaining battery, % 0…100 (`None` = −1).
    pub battery_remaining_pct: Option<u8>,
    /// Main-loop load, % (wire: d%).
    pub load_pct: f64,
    /// Communication drop rate, % (wire: c%).
    pub comm_drop_rate_pct: f64,
    /// Communication errors.
    pub comm_errors: u16,
    /// MAV_SYS_STATUS_SENSOR bitmap: present.
    pub sensors_present: u32,
    /// MAV_SYS_STATUS_SENSOR bitmap: enabled.
    pub sensors_enabled: u32,
    /// MAV_SYS_STATUS_SENSOR bitmap: healthy.
    pub sensors_health: u32,
}

impl SystemStatus {
    /// The SYS_STATUS carrying it.
    pub(super) fn to_mavlink(self) -> MavMessage {
        MavMessage::SYS_STATUS(mc::SYS_STATUS_DATA {
            onboard_control_sensors_present: mc::MavSysStatusSensor::from_bits_retain(
                self.sensors_present,
            ),
            onboard_control_sensors_enabled: mc::MavSysStatusSensor::from_bits_retain(
                self.sensors_enabled,
            ),
            onboard_control_sensors_health: mc::MavSysStatusSensor::from_bits_retain(
                self.sensors_health,
            ),
            load: (self.load_pct * 10.0).round().clamp(0.0, 65535.0) as u16,
            voltage_battery: volts_to_mv(self.battery_voltage_v),
            current_battery: amps_to_ca(self.battery_current_a),
            drop_rate_comm: (self.comm_drop_rate_pct * 100.0)
                .round()
                .clamp(0.0, 10000.0) as u16,
            errors_comm: self.comm_errors,
            errors_count1: 0,
            errors_count2: 0,
            errors_count3: 0,
            errors_count4: 0,
            battery_remaining: pct_to_i8(self.battery_remaining_pct),
            onboard_control_sensors_present_extended: mc::MavSysStatusSensorExtended::empty(),
            onboard_control_sensors_enabled_extended: mc::MavSysStatusSensorExtended::empty(),
            onboard_control_sensors_health_extended: mc::MavSysStatusSensorExtended::empty(),
        })
    }

    /// What a SYS_STATUS carries.
    pub(super) fn from_mavlink(s: &mc::SYS_STATUS_DATA) -> Self {
        SystemStatus {
            battery_voltage_v: mv_to_volts(s.voltage_battery),
            battery_current_a: ca_to_amps(s.current_battery),
            battery_remaining_pct: i8_to_pct(s.battery_remaining),
            load_pct: f64::from(s.load) / 10.0,
            comm_drop_rate_pct: f64::from(s.drop_rate_comm) / 100.0,
            comm_errors: s.errors_comm,
            sensors_present: s.onboard_control_sensors_present.bits(),
            sensors_enabled: s.onboard_control_sensors_enabled.bits(),
            sensors_health: s.onboard_control_sensors_health.bits(),
        }
    }
}

/// One battery (BATTERY_STATUS).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct BatteryStatus {
    /// Battery id.
    pub id: u8,
    /// Total voltage, V (wire: mV in cell 0, ≤ 65.534 V).
    pub voltage_v: Option<f64>,
    /// Current, A (wire: cA, −1 = unknown).
    pub current_a: Option<f64>,
    /// Charge consumed, mAh (−1 = unknown).
    pub consumed_mah: Option<i32>,
    /// Remaining, % (−1 = unknown).
    pub remaining_pct: Option<u8>,
    /// Temperature, °C (wire: cdegC, INT16_MAX = unknown).
    pub temperature_c: Option<f64>,
}

impl BatteryStatus {
    /// The BATTERY_STATUS carrying it.
    pub(super) fn to_mavlink(self) -> MavMessage {
        let mut voltages = [u16::MAX; 10];
        voltages[0] = volts_to_mv(self.voltage_v);
        MavMessage::BATTERY_STATUS(mc::BATTERY_STATUS_DATA {
            current_consumed: self.consumed_mah.map_or(-1, |c| c.max(0)),
            energy_consumed: -1,
            temperature: self
                .temperature_c
                .map_or(i16::MAX, |c| c_to_cdeg(c).min(i16::MAX - 1)),
            voltages,
            current_battery: amps_to_ca(self.current_a),
            id: self.id,
            battery_function: mc::MavBatteryFunction::MAV_BATTERY_FUNCTION_UNKNOWN,
            mavtype: mc::MavBatteryType::MAV_BATTERY_TYPE_UNKNOWN,
            battery_remaining: pct_to_i8(self.remaining_pct),
            time_remaining: 0,
            charge_state: mc::MavBatteryChargeState::MAV_BATTERY_CHARGE_STATE_UNDEFINED,
            voltages_ext: [0; 4],
            mode: mc::MavBatteryMode::MAV_BATTERY_MODE_UNKNOWN,
            fault_bitmask: mc::MavBatteryFault::empty(),
        })
    }

    /// What a BATTERY_STATUS carries.
    pub(super) fn from_mavlink(b: &mc::BATTERY_STATUS_DATA) -> Self {
        BatteryStatus {
            id: b.id,
            voltage_v: mv_to_volts(b.voltages[0]),
            current_a: ca_to_amps(b.current_battery),
            consumed_mah: if b.current_consumed < 0 {
                None
            } else {
                Some(b.current_consumed)
            },
            remaining_pct: i8_to_pct(b.battery_remaining),
            temperature_c: if b.temperature == i16::MAX {
                None
            } else {
                Some(f64::from(b.temperature) / 100.0)
            },
        }
    }
}
