//! The fields of a station recording's telemetry that a flight log is made of, read from the
//! JSON the station records (`/telemetry/<MAVLINK_NAME>`: stx-link's typed values).
//!
//! Why not stx-link's own types: the analysis reads files, not the link, and the crate graph
//! keeps it off the link (`tests/crate_graph.py`). Each struct names only what the log uses,
//! under the link's field names, and ignores the rest; the tests below serialise the link's
//! values and read them back here, so a renamed field fails them rather than a recording.

use serde::Deserialize;
use stx_gnc::geo::is_position;
use stx_gnc::mission::FlightStage;

/// GLOBAL_POSITION_INT: the drone's position estimate.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct GlobalPosition {
    /// Time since the drone booted, ms.
    pub time_boot_ms: u32,
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Longitude, degrees.
    pub lon_deg: f64,
    /// Altitude above mean sea level, m.
    pub alt_msl_m: f64,
    /// Velocity north, m/s.
    pub v_north_mps: f64,
    /// Velocity east, m/s.
    pub v_east_mps: f64,
    /// Velocity down, m/s.
    pub v_down_mps: f64,
}

impl GlobalPosition {
    /// Whether the estimate is a position: the link's rule, an autopilot sends 0°, 0° until
    /// its estimator has an origin.
    pub fn has_position(&self) -> bool {
        is_position(self.lat_deg, self.lon_deg)
    }
}

/// ATTITUDE: the drone's Euler angles.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct Attitude {
    /// Time since the drone booted, ms.
    pub time_boot_ms: u32,
    /// Roll, rad.
    pub roll_rad: f64,
    /// Pitch, rad.
    pub pitch_rad: f64,
    /// Yaw, rad.
    pub yaw_rad: f64,
}

/// VFR_HUD: the airspeed.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct Hud {
    /// Airspeed, m/s.
    pub airspeed_mps: f64,
}

/// SERVO_OUTPUT_RAW: the servo commands.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct Actuators {
    /// The drone's time stamp, µs (wraps).
    pub time_usec: u32,
    /// Main-line differential, −1…1.
    pub main_line: f64,
    /// Right brake, 0…1.
    pub brake_right: f64,
    /// Left brake, 0…1.
    pub brake_left: f64,
}

/// HEARTBEAT: the flight stage.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct VehicleStatus {
    /// Where in the mission the drone is.
    pub stage: FlightStage,
}

/// WIND_COV: the drone's wind estimate.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct Wind {
    /// Towards north, m/s; `None` if unknown.
    pub wind_north_mps: Option<f64>,
    /// Towards east, m/s.
    pub wind_east_mps: Option<f64>,
    /// Down, m/s.
    pub wind_down_mps: Option<f64>,
}

#[cfg(test)]
mod tests {
    use serde::Serialize;
    use serde::de::DeserializeOwned;
    use stx_link::fixtures::telemetry_sample;
    use stx_link::telemetry::Telemetry;

    use super::*;

    fn read<T: DeserializeOwned>(recorded: &impl Serialize) -> T {
        let json = serde_json::to_vec(recorded).expect("the link's value serialises");
        serde_json::from_slice(&json).expect("the recorded value reads here")
    }

    #[test]
    fn what_the_station_records_reads_field_for_field() {
        let mut seen = 0;
        for i in 0..9 {
            match telemetry_sample(i) {
                Telemetry::Position(p) => {
                    let q: GlobalPosition = read(&p);
                    assert_eq!(
                        (q.time_boot_ms, q.lat_deg, q.lon_deg, q.alt_msl_m),
                        (p.time_boot_ms, p.lat_deg, p.lon_deg, p.alt_msl_m)
                    );
                    assert_eq!(
                        [q.v_north_mps, q.v_east_mps, q.v_down_mps],
                        [p.v_north_mps, p.v_east_mps, p.v_down_mps]
                    );
                    assert_eq!(q.has_position(), p.has_position());
                }
                Telemetry::Attitude(a) => {
                    let b: Attitude = read(&a);
                    assert_eq!(
                        (b.time_boot_ms, b.roll_rad, b.pitch_rad, b.yaw_rad),
                        (a.time_boot_ms, a.roll_rad, a.pitch_rad, a.yaw_rad)
                    );
                }
                Telemetry::Hud(h) => assert_eq!(read::<Hud>(&h).airspeed_mps, h.airspeed_mps),
                Telemetry::Actuators(a) => {
                    let b: Actuators = read(&a);
                    assert_eq!(
                        (b.time_usec, b.main_line, b.brake_right, b.brake_left),
                        (a.time_usec, a.main_line, a.brake_right, a.brake_left)
                    );
                }
                Telemetry::Status(s) => assert_eq!(read::<VehicleStatus>(&s).stage, s.stage),
                Telemetry::Wind(w) => {
                    let v: Wind = read(&w);
                    assert_eq!(
                        (v.wind_north_mps, v.wind_east_mps, v.wind_down_mps),
                        (w.wind_north_mps, w.wind_east_mps, w.wind_down_mps)
                    );
                }
                _ => continue,
            }
            seen += 1;
        }
        assert_eq!(seen, 6, "every message the log reads");
    }

    #[test]
    fn a_position_at_zero_zero_is_none_by_the_link_s_rule_too() {
        let Telemetry::Position(mut p) = telemetry_sample(1) else {
            panic!("sample 1 is a position");
        };
        (p.lat_deg, p.lon_deg) = (0.0, 0.0);
        assert!(!p.has_position());
        assert!(!read::<GlobalPosition>(&p).has_position());
    }
}
