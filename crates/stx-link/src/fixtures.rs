//! A mixed telemetry stream for benchmarks (the ingest benches of this crate and of the
//! station): what the drone sends in flight — attitude, position, GPS, air data, HUD,
//! actuators, wind, guidance and status, in turn — with values that change from message to
//! message as they would.

use stx_types::mission::{FlightMode, FlightStage, GuidancePhase};

use crate::telemetry::*;

/// The `i`-th message of the stream.
pub fn telemetry_sample(i: u32) -> Telemetry {
    let f = f64::from(i);
    match i % 9 {
        0 => Telemetry::Attitude(Attitude {
            time_boot_ms: i,
            roll_rad: 0.1,
            pitch_rad: -0.05,
            yaw_rad: f * 1e-3,
            roll_rate_radps: 0.01,
            pitch_rate_radps: 0.0,
            yaw_rate_radps: 0.2,
        }),
        1 => Telemetry::Position(GlobalPosition {
            time_boot_ms: i,
            lat_deg: 41.1779 + f * 1e-7,
            lon_deg: -8.5977,
            alt_msl_m: 3000.0 - f * 0.01,
            alt_rel_m: 2900.0,
            v_north_mps: 3.0,
            v_east_mps: -1.0,
            v_down_mps: 4.5,
            heading_deg: Some(271.0),
        }),
        2 => Telemetry::GpsRaw(GpsRaw {
            time_usec: u64::from(i) * 1000,
            fix: GpsFix::Fix3d,
            lat_deg: 41.1779,
            lon_deg: -8.5977,
            alt_msl_m: 3000.0,
            ground_speed_mps: Some(12.0),
            course_deg: Some(270.0),
            satellites: Some(12),
            h_acc_m: Some(2.5),
            v_acc_m: Some(4.0),
        }),
        3 => Telemetry::AirData(AirData {
            time_boot_ms: i,
            abs_pressure_pa: 70_000.0,
            diff_pressure_pa: 120.0,
            temperature_c: -20.0,
            diff_temperature_c: None,
        }),
        4 => Telemetry::Hud(Hud {
            airspeed_mps: 14.0,
            groundspeed_mps: 12.0,
            heading_deg: 270.0,
            climb_mps: -4.5,
            alt_msl_m: 3000.0,
        }),
        5 => Telemetry::Actuators(Actuators {
            time_usec: i,
            main_line: 0.2,
            brake_right: 0.1,
            brake_left: 0.3,
        }),
        6 => Telemetry::Wind(Wind {
            time_usec: u64::from(i),
            wind_north_mps: Some(3.0),
            wind_east_mps: Some(-2.0),
            wind_down_mps: Some(0.0),
            var_horiz_mps: Some(0.5),
            var_vert_mps: Some(0.1),
            alt_msl_m: Some(3000.0),
            horiz_accuracy_mps: 0.3,
            vert_accuracy_mps: 0.1,
        }),
        7 => Telemetry::Guidance(GuidanceStatus {
            desired_roll_deg: -10.0,
            desired_heading_deg: 260.0,
            bearing_to_target_deg: 255.0,
            distance_to_target_m: 1500.0,
            alt_error_m: 10.0,
            xtrack_error_m: -20.0,
        }),
        _ => Telemetry::Status(VehicleStatus {
            mode: FlightMode::SpiralLanding,
            stage: FlightStage::Parafoil,
            phase: GuidancePhase::Branch2,
            state: SystemState::Active,
        }),
    }
}
