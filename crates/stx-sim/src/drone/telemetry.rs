//! What the drone tells the station, built from what the drone itself knows — its sensors'
//! measurements, its estimate, its servo commands, its guidance — never from the simulator's
//! truth, and scheduled on mission time. The one exception is the other bodies' IMUs (last
//! row): sensors of their own, modelled as perfect, so their attitudes are the model's.
//!
//! | message | rate | content |
//! |---|---|---|
//! | HEARTBEAT | 1 Hz (the link's own timer) | mode, stage, phase, state ([`crate::drone::Drone::status`]) |
//! | GPS_RAW_INT, GPS_INPUT, ATTITUDE, SCALED_PRESSURE | each measurement as it reaches the drone's computer (4 Hz) | the receiver's fix (converted to latitude/longitude from the launch site), the AHRS's angles (rates by difference of successive samples), the pitot's pressures and temperature; GPS_INPUT is the receiver's whole solution beside GPS_RAW_INT (its vertical velocity and accuracies, which GPS_RAW_INT lacks, so the station's estimator sees what the onboard one sees); without a fix for a second, GPS_RAW_INT says `NoFix` at 1 Hz (latitude/longitude 0) |
//! | GLOBAL_POSITION_INT, VFR_HUD, SERVO_OUTPUT_RAW | 4 Hz | the onboard estimate (once it has a solution), the servos' positions |
//! | WIND_COV, NAV_CONTROLLER_OUTPUT, SYS_STATUS, BATTERY_STATUS | 1 Hz | wind estimate, guidance state, health and battery |
//! | POSITION_TARGET_GLOBAL_INT (predicted landing) | every `telemetry.prediction_period_s` (2 s) | see `Drone` |
//! | STATUSTEXT | as they happen | stage changes, guidance phase changes with their reasons, failsafes, refusals |
//! | ATTITUDE from components 200–202 (`stx_types::stack::BodyImu`) | 2 Hz under the parafoil, until touchdown | the canopy's, capsule's and transponder's attitudes and body rates, from the 14-DOF truth (what an IMU on each would report); not affected by the rate commands |
//!
//! Rates can be changed by MAV_CMD_SET_MESSAGE_INTERVAL (intervals of at least one control
//! period, 0.25 s; −1 stops a message, 0 restores its rate) and a message asked for by
//! MAV_CMD_REQUEST_MESSAGE goes out at the next control period.
//!
//! # Battery
//! A lithium pack discharged by a constant avionics current plus a servo current proportional
//! to the servos' mean deflection (holding a line against its load costs current); its voltage
//! is the open-circuit voltage, linear in the state of charge from `empty_v` to `full_v`, less
//! the internal resistance's drop. Simple, but it falls through a long mission the way the
//! operators watch it fall.

use stx_dynamics::state::Controls;
use stx_gnc::estimate::Estimate;
use stx_gnc::geo::LocalFrame;
use stx_gnc::measurement::{AirDataSample, AttitudeSample, GpsFix as Fix};
use stx_link::command::CommandResult;
use stx_link::telemetry::{
    Actuators, AirData, Attitude, BatteryStatus, GlobalPosition, GpsFix, GpsRaw, GpsSolution, Hud,
    Wind,
};

use crate::drone::config::BatteryConfig;

/// MAVLink message ids of what the drone sends.
pub mod msg {
    /// HEARTBEAT.
    pub const HEARTBEAT: u32 = 0;
    /// SYS_STATUS.
    pub const SYS_STATUS: u32 = 1;
    /// GPS_RAW_INT.
    pub const GPS_RAW_INT: u32 = 24;
    /// GPS_INPUT (the receiver's whole solution).
    pub const GPS_INPUT: u32 = 232;
    /// SCALED_PRESSURE.
    pub const SCALED_PRESSURE: u32 = 29;
    /// ATTITUDE.
    pub const ATTITUDE: u32 = 30;
    /// GLOBAL_POSITION_INT.
    pub const GLOBAL_POSITION_INT: u32 = 33;
    /// SERVO_OUTPUT_RAW.
    pub const SERVO_OUTPUT_RAW: u32 = 36;
    /// NAV_CONTROLLER_OUTPUT.
    pub const NAV_CONTROLLER_OUTPUT: u32 = 62;
    /// VFR_HUD.
    pub const VFR_HUD: u32 = 74;
    /// POSITION_TARGET_GLOBAL_INT (the predicted landing).
    pub const POSITION_TARGET_GLOBAL_INT: u32 = 87;
    /// BATTERY_STATUS.
    pub const BATTERY_STATUS: u32 = 147;
    /// WIND_COV.
    pub const WIND_COV: u32 = 231;
}

/// Shortest interval a rate request may set, s: one control period.
pub const MIN_INTERVAL_S: f64 = 0.25;

/// One telemetry stream.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Stream {
    id: u32,
    /// Default interval, s; `None` for the sensor-driven messages.
    default_s: Option<f64>,
    /// Interval in force, s; `None` = stopped.
    interval_s: Option<f64>,
    next_s: f64,
    requested: bool,
}

/// The schedule of every stream, on mission time.
#[derive(Debug, Clone)]
pub struct Streams {
    streams: Vec<Stream>,
}

impl Streams {
    /// The default rates, the predicted landing every `prediction_period_s`.
    pub fn new(prediction_period_s: f64) -> Self {
        let scheduled = |id, s: f64| Stream {
            id,
            default_s: Some(s),
            interval_s: Some(s),
            next_s: 0.0,
            requested: false,
        };
        let sensor = |id| Stream {
            id,
            default_s: None,
            interval_s: Some(0.25),
            next_s: 0.0,
            requested: false,
        };
        Self {
            streams: vec![
                sensor(msg::GPS_RAW_INT),
                sensor(msg::GPS_INPUT),
                sensor(msg::ATTITUDE),
                sensor(msg::SCALED_PRESSURE),
                scheduled(msg::GLOBAL_POSITION_INT, 0.25),
                scheduled(msg::VFR_HUD, 0.25),
                scheduled(msg::SERVO_OUTPUT_RAW, 0.25),
                scheduled(msg::WIND_COV, 1.0),
                scheduled(msg::NAV_CONTROLLER_OUTPUT, 1.0),
                scheduled(msg::SYS_STATUS, 1.0),
                scheduled(msg::BATTERY_STATUS, 1.0),
                scheduled(msg::POSITION_TARGET_GLOBAL_INT, prediction_period_s),
            ],
        }
    }

    fn find(&mut self, id: u32) -> Option<&mut Stream> {
        self.streams.iter_mut().find(|s| s.id == id)
    }

    /// Whether a scheduled message is due at `time_s` (or was requested); advances its
    /// schedule. Sensor-driven messages: whether they are switched on.
    pub fn due(&mut self, id: u32, time_s: f64) -> bool {
        let Some(s) = self.find(id) else {
            return false;
        };
        if s.requested {
            s.requested = false;
            return true;
        }
        let Some(interval) = s.interval_s else {
            return false;
        };
        if s.default_s.is_none() {
            return true;
        }
        // A hair of slack: periods summed in floating point land a little early.
        if time_s + 1e-6 >= s.next_s {
            s.next_s = if time_s >= s.next_s + interval {
                time_s + interval
            } else {
                s.next_s + interval
            };
            true
        } else {
            false
        }
    }

    /// Whether `id` was asked for by a request and not yet sent (sensor-driven messages).
    pub fn take_request(&mut self, id: u32) -> bool {
        self.find(id)
            .is_some_and(|s| std::mem::take(&mut s.requested))
    }

    /// MAV_CMD_SET_MESSAGE_INTERVAL: −1 stops, 0 restores the default, else the interval in
    /// µs (at least [`MIN_INTERVAL_S`]; sensor-driven messages only stop or restore).
    pub fn set_interval(&mut self, id: u32, interval_us: i32) -> CommandResult {
        if id == msg::HEARTBEAT {
            return CommandResult::Denied;
        }
        let Some(s) = self.find(id) else {
            return CommandResult::Unsupported;
        };
        match interval_us {
            -1 => s.interval_s = None,
            0 => s.interval_s = s.default_s.or(Some(0.25)),
            us if us > 0 => {
                let interval = f64::from(us) / 1e6;
                if s.default_s.is_none() || interval < MIN_INTERVAL_S {
                    return CommandResult::Denied;
                }
                s.interval_s = Some(interval);
                s.next_s = 0.0;
            }
            _ => return CommandResult::Denied,
        }
        CommandResult::Accepted
    }

    /// MAV_CMD_REQUEST_MESSAGE: sent at the next control period.
    pub fn request(&mut self, id: u32) -> CommandResult {
        if id == msg::HEARTBEAT {
            // Sent every second by the link anyway.
            return CommandResult::Accepted;
        }
        match self.find(id) {
            Some(s) => {
                s.requested = true;
                CommandResult::Accepted
            }
            None => CommandResult::Unsupported,
        }
    }
}

/// The battery model (see the module documentation).
#[derive(Debug, Clone)]
pub struct Battery {
    config: BatteryConfig,
    consumed_mah: f64,
    current_a: f64,
}

impl Battery {
    /// A pack as configured.
    pub fn new(config: &BatteryConfig) -> Self {
        Self {
            consumed_mah: config.capacity_mah * (1.0 - config.initial_pct / 100.0),
            current_a: config.base_current_a,
            config: config.clone(),
        }
    }

    /// Draws current for `dt_s` with the servos at `controls` (main line of travel
    /// `main_line_travel_m`).
    pub fn draw(&mut self, dt_s: f64, controls: &Controls, main_line_travel_m: f64) {
        let deflection = ((controls.main_line_m.abs() / main_line_travel_m.max(1e-9)).min(1.0)
            + controls.brake_right.clamp(0.0, 1.0)
            + controls.brake_left.clamp(0.0, 1.0))
            / 3.0;
        self.current_a = self.config.base_current_a + self.config.servo_current_a * deflection;
        self.consumed_mah =
            (self.consumed_mah + self.current_a * dt_s / 3.6).min(self.config.capacity_mah);
    }

    /// State of charge, 0…1.
    pub fn charge(&self) -> f64 {
        (1.0 - self.consumed_mah / self.config.capacity_mah).clamp(0.0, 1.0)
    }

    /// Terminal voltage, V.
    pub fn voltage_v(&self) -> f64 {
        let c = &self.config;
        c.empty_v + (c.full_v - c.empty_v) * self.charge()
            - c.internal_resistance_ohm * self.current_a
    }

    /// Current, A.
    pub fn current_a(&self) -> f64 {
        self.current_a
    }

    /// Remaining charge, %.
    pub fn remaining_pct(&self) -> u8 {
        (self.charge() * 100.0).round() as u8
    }

    /// BATTERY_STATUS.
    pub fn status(&self) -> BatteryStatus {
        BatteryStatus {
            id: 0,
            voltage_v: Some(self.voltage_v()),
            current_a: Some(self.current_a),
            consumed_mah: Some(self.consumed_mah.round() as i32),
            remaining_pct: Some(self.remaining_pct()),
            temperature_c: None,
        }
    }
}

/// Milliseconds since boot (mission time), as the wire's u32.
pub fn boot_ms(time_s: f64) -> u32 {
    (time_s.max(0.0) * 1000.0).round() as u32
}

fn course_deg(north: f64, east: f64) -> Option<f64> {
    (north.hypot(east) > 0.2).then(|| east.atan2(north).to_degrees().rem_euclid(360.0))
}

/// The receiver's time of a fix, µs on the drone's clock (GPS_RAW_INT and GPS_INPUT alike).
fn fix_time_usec(fix: &Fix) -> u64 {
    (fix.time_s.max(0.0) * 1e6).round() as u64
}

/// GPS_RAW_INT of a fix.
pub fn gps_raw(frame: &LocalFrame, fix: &Fix) -> GpsRaw {
    let (lat_deg, lon_deg, alt_msl_m) = frame.to_geodetic(&fix.position_ned_m);
    let v = fix.velocity_ned_mps;
    GpsRaw {
        time_usec: fix_time_usec(fix),
        fix: GpsFix::Fix3d,
        lat_deg,
        lon_deg,
        alt_msl_m,
        ground_speed_mps: Some(v.x.hypot(v.y)),
        course_deg: course_deg(v.x, v.y),
        satellites: Some(12),
        h_acc_m: Some(fix.horizontal_accuracy_m),
        v_acc_m: Some(fix.vertical_accuracy_m),
    }
}

/// GPS_INPUT of a fix: the receiver's solution as it measured it.
pub fn gps_solution(frame: &LocalFrame, fix: &Fix) -> GpsSolution {
    let (lat_deg, lon_deg, alt_msl_m) = frame.to_geodetic(&fix.position_ned_m);
    let v = fix.velocity_ned_mps;
    GpsSolution {
        time_usec: fix_time_usec(fix),
        fix: GpsFix::Fix3d,
        lat_deg,
        lon_deg,
        alt_msl_m,
        velocity_ned_mps: Some([v.x, v.y, v.z]),
        speed_accuracy_mps: Some(fix.speed_accuracy_mps),
        horizontal_accuracy_m: Some(fix.horizontal_accuracy_m),
        vertical_accuracy_m: Some(fix.vertical_accuracy_m),
        satellites: Some(12),
    }
}

/// GPS_RAW_INT of a receiver without a fix.
pub fn gps_no_fix(time_s: f64) -> GpsRaw {
    GpsRaw {
        time_usec: (time_s.max(0.0) * 1e6).round() as u64,
        fix: GpsFix::NoFix,
        lat_deg: 0.0,
        lon_deg: 0.0,
        alt_msl_m: 0.0,
        ground_speed_mps: None,
        course_deg: None,
        satellites: Some(0),
        h_acc_m: None,
        v_acc_m: None,
    }
}

/// ATTITUDE of an AHRS sample; the rates by difference with the previous sample.
pub fn attitude(sample: &AttitudeSample, previous: Option<&AttitudeSample>) -> Attitude {
    let rates = previous
        .filter(|p| sample.time_s - p.time_s > 1e-3 && sample.time_s - p.time_s < 2.0)
        .map(|p| {
            let dt = sample.time_s - p.time_s;
            let d = |a: f64, b: f64| stx_dynamics::rotation::wrap_pi(a - b) / dt;
            [
                d(sample.roll_rad, p.roll_rad),
                d(sample.pitch_rad, p.pitch_rad),
                d(sample.yaw_rad, p.yaw_rad),
            ]
        })
        .unwrap_or([0.0; 3]);
    Attitude {
        time_boot_ms: boot_ms(sample.time_s),
        roll_rad: sample.roll_rad,
        pitch_rad: sample.pitch_rad,
        yaw_rad: sample.yaw_rad,
        roll_rate_radps: rates[0],
        pitch_rate_radps: rates[1],
        yaw_rate_radps: rates[2],
    }
}

/// SCALED_PRESSURE of a pitot sample (one thermometer serves both sensors).
pub fn air_data(sample: &AirDataSample) -> AirData {
    let celsius = sample.temperature_k - 273.15;
    AirData {
        time_boot_ms: boot_ms(sample.time_s),
        abs_pressure_pa: sample.static_pressure_pa,
        diff_pressure_pa: sample.differential_pressure_pa,
        temperature_c: celsius,
        diff_temperature_c: Some(celsius),
    }
}

/// GLOBAL_POSITION_INT of the estimate.
pub fn position(frame: &LocalFrame, est: &Estimate) -> GlobalPosition {
    let (lat_deg, lon_deg, alt_msl_m) = frame.to_geodetic(&est.position_ned_m);
    let v = est.velocity_ned_mps;
    GlobalPosition {
        time_boot_ms: boot_ms(est.time_s),
        lat_deg,
        lon_deg,
        alt_msl_m,
        alt_rel_m: est.height_m(),
        v_north_mps: v.x,
        v_east_mps: v.y,
        v_down_mps: v.z,
        heading_deg: Some(est.heading_rad.to_degrees().rem_euclid(360.0)),
    }
}

/// VFR_HUD of the estimate.
pub fn hud(frame: &LocalFrame, est: &Estimate) -> Hud {
    Hud {
        airspeed_mps: est.airspeed_mps,
        groundspeed_mps: est.ground_speed_mps(),
        heading_deg: est.heading_rad.to_degrees().rem_euclid(360.0),
        climb_mps: -est.velocity_ned_mps.z,
        alt_msl_m: frame.alt_msl_m + est.height_m(),
    }
}

/// SERVO_OUTPUT_RAW of the servo commands.
pub fn actuators(time_s: f64, controls: &Controls, main_line_travel_m: f64) -> Actuators {
    Actuators {
        time_usec: ((time_s.max(0.0) * 1e6).round() as u64 & u64::from(u32::MAX)) as u32,
        main_line: (controls.main_line_m / main_line_travel_m.max(1e-9)).clamp(-1.0, 1.0),
        brake_right: controls.brake_right,
        brake_left: controls.brake_left,
    }
}

/// WIND_COV of the estimate.
pub fn wind(frame: &LocalFrame, est: &Estimate) -> Wind {
    let w = est.wind_ned_mps;
    let s = est.wind_sigma_mps;
    Wind {
        time_usec: (est.time_s.max(0.0) * 1e6).round() as u64,
        wind_north_mps: Some(w.x),
        wind_east_mps: Some(w.y),
        wind_down_mps: Some(0.0),
        var_horiz_mps: Some(s.x.hypot(s.y)),
        var_vert_mps: None,
        alt_msl_m: Some(frame.alt_msl_m + est.height_m()),
        horiz_accuracy_mps: s.x.hypot(s.y),
        vert_accuracy_mps: 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_keep_their_rates_and_obey_requests() {
        let mut s = Streams::new(2.0);
        let sent: usize = (0..40)
            .filter(|i| s.due(msg::GLOBAL_POSITION_INT, *i as f64 * 0.25))
            .count();
        assert_eq!(sent, 40);
        let sent: usize = (0..40)
            .filter(|i| s.due(msg::WIND_COV, *i as f64 * 0.25))
            .count();
        assert_eq!(sent, 10);
        assert_eq!(s.set_interval(msg::WIND_COV, -1), CommandResult::Accepted);
        assert!(!(40..80).any(|i| s.due(msg::WIND_COV, i as f64 * 0.25)));
        assert_eq!(s.request(msg::WIND_COV), CommandResult::Accepted);
        assert!(s.due(msg::WIND_COV, 20.0));
        assert_eq!(s.set_interval(msg::WIND_COV, 100), CommandResult::Denied);
        assert_eq!(
            s.set_interval(msg::WIND_COV, 500_000),
            CommandResult::Accepted
        );
        let sent = (0..40)
            .filter(|i| s.due(msg::WIND_COV, 30.0 + *i as f64 * 0.25))
            .count();
        assert_eq!(sent, 20);
        assert_eq!(s.set_interval(9999, 0), CommandResult::Unsupported);
        assert_eq!(s.request(9999), CommandResult::Unsupported);
        assert_eq!(s.set_interval(msg::ATTITUDE, -1), CommandResult::Accepted);
        assert!(!s.due(msg::ATTITUDE, 1.0));
    }

    #[test]
    fn the_battery_drains_with_the_servos_and_sags_under_load() {
        let config = BatteryConfig::default();
        let mut idle = Battery::new(&config);
        let mut busy = Battery::new(&config);
        let full = Controls {
            main_line_m: 0.03,
            brake_right: 1.0,
            brake_left: 1.0,
        };
        for _ in 0..3600 {
            idle.draw(1.0, &Controls::default(), 0.03);
            busy.draw(1.0, &full, 0.03);
        }
        // One hour at 0.45 A is 450 mAh of 5000: 91 % left.
        assert_eq!(idle.remaining_pct(), 91);
        assert!(busy.remaining_pct() < idle.remaining_pct());
        assert!(busy.voltage_v() < idle.voltage_v());
        assert!(idle.voltage_v() < config.full_v && idle.voltage_v() > config.empty_v);
    }
}
