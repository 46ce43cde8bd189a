//! The decoded-telemetry channels: each telemetry message the station decodes, as stx-link's
//! typed value on `/telemetry/<MAVLINK_NAME>` (schema `stx.telemetry.<MAVLINK_NAME>`, from the
//! types themselves), and for Foxglove's map and 3-D panels the drone's GPS
//! ([`super::VEHICLE_GPS`], from GPS_RAW_INT: the receiver's own fix with its stated
//! accuracy, rather than the drone's filtered GLOBAL_POSITION_INT; only reports that are
//! positions, `stx_link::telemetry::has_position_fix`) and its attitude
//! ([`super::VEHICLE_ATTITUDE`], body in the local NED frame, from ATTITUDE).

use std::time::Duration;

use nalgebra::UnitQuaternion;
use schemars::{JsonSchema, schema_for};
use serde_json::Value;
use stx_link::telemetry::{
    Actuators, AirData, Attitude, BatteryStatus, GlobalPosition, GpsRaw, GpsSolution,
    GuidanceStatus, Hud, PredictedLanding, StatusText, SystemStatus, Telemetry, VehicleStatus,
    Wind,
};
use stx_record::foxglove::{
    self, FrameTransform, LocationFix, PositionCovarianceType, Quaternion, Timestamp, Vector3,
};
use stx_record::{ChannelId, ChannelSpec, RecorderCore, WriteError};

use super::compact_json;
use super::{VEHICLE_ATTITUDE, VEHICLE_GPS, telemetry_topic};

/// Every telemetry message the station decodes: its MAVLink name and the JSON Schema of its
/// typed value.
fn kinds() -> Vec<(&'static str, Value)> {
    fn s<T: JsonSchema>() -> Value {
        serde_json::to_value(schema_for!(T))
            .unwrap_or_else(|_| serde_json::json!({"type": "object"}))
    }
    vec![
        ("HEARTBEAT", s::<VehicleStatus>()),
        ("GPS_RAW_INT", s::<GpsRaw>()),
        ("GPS_INPUT", s::<GpsSolution>()),
        ("GLOBAL_POSITION_INT", s::<GlobalPosition>()),
        ("ATTITUDE", s::<Attitude>()),
        ("SCALED_PRESSURE", s::<AirData>()),
        ("VFR_HUD", s::<Hud>()),
        ("SERVO_OUTPUT_RAW", s::<Actuators>()),
        ("SYS_STATUS", s::<SystemStatus>()),
        ("BATTERY_STATUS", s::<BatteryStatus>()),
        ("STATUSTEXT", s::<StatusText>()),
        ("WIND_COV", s::<Wind>()),
        ("NAV_CONTROLLER_OUTPUT", s::<GuidanceStatus>()),
        ("POSITION_TARGET_GLOBAL_INT", s::<PredictedLanding>()),
    ]
}

/// The telemetry channels, registered in a recorder.
#[derive(Debug, Clone)]
pub struct TelemetryChannels {
    by_name: Vec<(&'static str, ChannelId)>,
    gps: ChannelId,
    attitude: ChannelId,
}

impl TelemetryChannels {
    /// Registers every telemetry channel in `core` at `now` (the core's clock).
    pub fn register(core: &mut RecorderCore, now: Duration) -> Result<Self, WriteError> {
        let mut by_name = Vec::new();
        for (name, schema) in kinds() {
            let spec = ChannelSpec::json(
                telemetry_topic(name),
                format!("stx.telemetry.{name}"),
                &schema,
            )?;
            by_name.push((name, core.add_channel(now, spec)?));
        }
        Ok(Self {
            by_name,
            gps: core.add_channel(now, foxglove::location_fix_channel(VEHICLE_GPS)?)?,
            attitude: core
                .add_channel(now, foxglove::frame_transform_channel(VEHICLE_ATTITUDE)?)?,
        })
    }

    /// What to record of `telemetry` received at `log_time_ns`.
    pub fn records(&self, log_time_ns: u64, telemetry: &Telemetry) -> Vec<(ChannelId, Vec<u8>)> {
        let name = telemetry.message_name();
        let mut out = Vec::with_capacity(2);
        if let Some((_, id)) = self.by_name.iter().find(|(n, _)| *n == name) {
            out.push((*id, value_json(telemetry)));
        }
        let ts = Timestamp::from_nanos(log_time_ns);
        match telemetry {
            // A report without a fix is kept on its telemetry channel as received, but it is
            // no position: as a LocationFix it would put the vehicle at 0°, 0° on the map.
            Telemetry::GpsRaw(g) if g.has_position_fix() => {
                out.push((self.gps, compact_json(&gps_fix(ts, g))))
            }
            Telemetry::Attitude(a) => {
                out.push((self.attitude, compact_json(&attitude_transform(ts, a))))
            }
            _ => {}
        }
        out
    }
}

/// The message's typed value, without the enum's tag (the topic names it).
fn value_json(t: &Telemetry) -> Vec<u8> {
    match t {
        Telemetry::Status(v) => compact_json(v),
        Telemetry::GpsRaw(v) => compact_json(v),
        Telemetry::GpsSolution(v) => compact_json(v),
        Telemetry::Position(v) => compact_json(v),
        Telemetry::Attitude(v) => compact_json(v),
        Telemetry::AirData(v) => compact_json(v),
        Telemetry::Hud(v) => compact_json(v),
        Telemetry::Actuators(v) => compact_json(v),
        Telemetry::System(v) => compact_json(v),
        Telemetry::Battery(v) => compact_json(v),
        Telemetry::StatusText(v) => compact_json(v),
        Telemetry::Wind(v) => compact_json(v),
        Telemetry::Guidance(v) => compact_json(v),
        Telemetry::PredictedLanding(v) => compact_json(v),
    }
}

/// The receiver's fix with its stated accuracy as an East-North-Up covariance.
fn gps_fix(timestamp: Timestamp, g: &GpsRaw) -> LocationFix {
    let (h, v) = (g.h_acc_m, g.v_acc_m);
    let var = |a: Option<f64>| a.map_or(0.0, |a| a * a);
    LocationFix {
        timestamp,
        frame_id: "gps".into(),
        latitude: g.lat_deg,
        longitude: g.lon_deg,
        altitude: g.alt_msl_m,
        position_covariance: [var(h), 0.0, 0.0, 0.0, var(h), 0.0, 0.0, 0.0, var(v)],
        position_covariance_type: if h.is_some() && v.is_some() {
            PositionCovarianceType::DiagonalKnown
        } else {
            PositionCovarianceType::Unknown
        },
    }
}

/// The body's orientation in the local NED frame (roll, pitch, yaw: Z-Y-X Euler angles).
fn attitude_transform(timestamp: Timestamp, a: &Attitude) -> FrameTransform {
    let q = UnitQuaternion::from_euler_angles(a.roll_rad, a.pitch_rad, a.yaw_rad);
    FrameTransform {
        timestamp,
        parent_frame_id: "ned".into(),
        child_frame_id: "body".into(),
        translation: Vector3 {
            x: 0.0,
            y: 0.0,
            z: 0.0,
        },
        rotation: Quaternion {
            x: q.i,
            y: q.j,
            z: q.k,
            w: q.w,
        },
    }
}

#[cfg(test)]
mod tests;
