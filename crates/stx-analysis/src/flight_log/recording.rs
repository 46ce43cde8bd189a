//! A flight log from a station recording's decoded telemetry (`/telemetry/<MAVLINK_NAME>`
//! topics, stx-link's typed values as JSON; see stx-station's `recording` module): GPS
//! position and velocity from GLOBAL_POSITION_INT (the time base: one sample per message),
//! attitude from ATTITUDE, airspeed from VFR_HUD, servo commands from SERVO_OUTPUT_RAW and
//! the wind estimate from WIND_COV, each the latest at or before the position's time.
//!
//! Pure: the caller reads the MCAP file (stx-record's `Recording`) and hands over the
//! messages. The local frame's origin is the first position, horizontally, and mean sea level.

use serde::de::DeserializeOwned;
use stx_gnc::geo::LocalFrame;
use stx_link::telemetry::{Actuators, Attitude, GlobalPosition, Hud, Wind};

use super::{FlightLog, FlightLogError, LogSample};

/// The topics read (the station's recording layout).
pub const POSITION: &str = "/telemetry/GLOBAL_POSITION_INT";
/// Attitude.
pub const ATTITUDE: &str = "/telemetry/ATTITUDE";
/// Airspeed.
pub const HUD: &str = "/telemetry/VFR_HUD";
/// Servo commands.
pub const ACTUATORS: &str = "/telemetry/SERVO_OUTPUT_RAW";
/// Wind estimate.
pub const WIND: &str = "/telemetry/WIND_COV";

/// Collects the telemetry a log is made of, message by message.
#[derive(Default)]
pub struct LogBuilder {
    positions: Vec<(f64, GlobalPosition)>,
    attitudes: Vec<(f64, Attitude)>,
    airspeeds: Vec<(f64, f64)>,
    commands: Vec<(f64, Actuators)>,
    winds: Vec<(f64, [f64; 3])>,
}

impl LogBuilder {
    /// Takes one recorded message (`log_time_ns`: ns since the Unix epoch; `data`: JSON).
    /// Topics it does not use are ignored.
    pub fn add(
        &mut self,
        topic: &str,
        log_time_ns: u64,
        data: &[u8],
    ) -> Result<(), FlightLogError> {
        let t = log_time_ns as f64 * 1e-9;
        fn parse<T: DeserializeOwned>(
            topic: &str,
            t: f64,
            data: &[u8],
        ) -> Result<T, FlightLogError> {
            serde_json::from_slice(data).map_err(|e| FlightLogError::BadMessage {
                topic: topic.to_owned(),
                time_s: t,
                message: e.to_string(),
            })
        }
        match topic {
            POSITION => self.positions.push((t, parse(topic, t, data)?)),
            ATTITUDE => self.attitudes.push((t, parse(topic, t, data)?)),
            HUD => self
                .airspeeds
                .push((t, parse::<Hud>(topic, t, data)?.airspeed_mps)),
            ACTUATORS => self.commands.push((t, parse(topic, t, data)?)),
            WIND => {
                let w: Wind = parse(topic, t, data)?;
                if let (Some(n), Some(e)) = (w.wind_north_mps, w.wind_east_mps) {
                    self.winds.push((t, [n, e, w.wind_down_mps.unwrap_or(0.0)]));
                }
            }
            _ => {}
        }
        Ok(())
    }

    /// The log: one sample per position message. Times start at the first position.
    pub fn finish(mut self) -> Result<FlightLog, FlightLogError> {
        for (name, empty) in [
            ("GLOBAL_POSITION_INT", self.positions.is_empty()),
            ("ATTITUDE", self.attitudes.is_empty()),
            ("SERVO_OUTPUT_RAW", self.commands.is_empty()),
        ] {
            if empty {
                return Err(FlightLogError::MissingTelemetry(name));
            }
        }
        let by_time = |a: &f64, b: &f64| a.total_cmp(b);
        self.positions.sort_by(|a, b| by_time(&a.0, &b.0));
        self.attitudes.sort_by(|a, b| by_time(&a.0, &b.0));
        self.airspeeds.sort_by(|a, b| by_time(&a.0, &b.0));
        self.commands.sort_by(|a, b| by_time(&a.0, &b.0));
        self.winds.sort_by(|a, b| by_time(&a.0, &b.0));
        self.positions.dedup_by(|b, a| b.0 <= a.0);
        let first = &self.positions[0];
        let frame = LocalFrame {
            lat_deg: first.1.lat_deg,
            lon_deg: first.1.lon_deg,
            alt_msl_m: 0.0,
        };
        let t0 = first.0;
        let samples = self
            .positions
            .iter()
            .map(|(t, p)| {
                let a = latest(&self.attitudes, *t).copied();
                let c = latest(&self.commands, *t).copied();
                let (a, c) = (
                    a.unwrap_or(self.attitudes[0].1),
                    c.unwrap_or(self.commands[0].1),
                );
                let ned = frame.to_ned(p.lat_deg, p.lon_deg, p.alt_msl_m);
                LogSample {
                    time_s: t - t0,
                    position_ned_m: [ned.x, ned.y, ned.z],
                    velocity_ned_mps: [p.v_north_mps, p.v_east_mps, p.v_down_mps],
                    euler_rad: [a.roll_rad, a.pitch_rad, a.yaw_rad],
                    airspeed_mps: latest(&self.airspeeds, *t).copied(),
                    main_line: c.main_line,
                    brake_right: c.brake_right,
                    brake_left: c.brake_left,
                    wind_ned_mps: latest(&self.winds, *t).copied().unwrap_or([0.0; 3]),
                }
            })
            .collect();
        FlightLog::new(samples)
    }
}

/// The value of the last entry at or before `t` (or the first, if all are later).
fn latest<T>(series: &[(f64, T)], t: f64) -> Option<&T> {
    let i = series.partition_point(|(ts, _)| *ts <= t);
    series.get(i.saturating_sub(1)).map(|(_, v)| v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn telemetry_becomes_a_log_held_at_the_positions_times() {
        let mut b = LogBuilder::default();
        let ns = |s: f64| (s * 1e9) as u64;
        for i in 0..4 {
            let t = 100.0 + f64::from(i);
            let pos = format!(
                r#"{{"time_boot_ms":0,"lat_deg":41.0,"lon_deg":-8.0,"alt_msl_m":{},"alt_rel_m":0,"v_north_mps":5,"v_east_mps":0,"v_down_mps":2.5,"heading_deg":null}}"#,
                1000.0 - 2.5 * f64::from(i)
            );
            b.add(POSITION, ns(t), pos.as_bytes()).unwrap();
            let att = r#"{"time_boot_ms":0,"roll_rad":0.1,"pitch_rad":0.0,"yaw_rad":1.0,"roll_rate_radps":0,"pitch_rate_radps":0,"yaw_rate_radps":0}"#;
            b.add(ATTITUDE, ns(t - 0.1), att.as_bytes()).unwrap();
            let act = format!(
                r#"{{"time_usec":0,"main_line":0.5,"brake_right":{},"brake_left":0}}"#,
                0.1 * f64::from(i)
            );
            b.add(ACTUATORS, ns(t - 0.05), act.as_bytes()).unwrap();
        }
        b.add("/station/state", 0, b"not json").unwrap();
        let log = b.finish().unwrap();
        let s = log.samples();
        assert_eq!(s.len(), 4);
        assert_eq!(s[0].time_s, 0.0);
        assert!((s[3].position_ned_m[2] + 992.5).abs() < 1e-9);
        assert!((s[2].brake_right - 0.2).abs() < 1e-12);
        assert_eq!(s[1].euler_rad, [0.1, 0.0, 1.0]);

        let mut bad = LogBuilder::default();
        assert!(matches!(
            bad.add(POSITION, 0, b"{}"),
            Err(FlightLogError::BadMessage { .. })
        ));
        assert_eq!(
            LogBuilder::default().finish(),
            Err(FlightLogError::MissingTelemetry("GLOBAL_POSITION_INT"))
        );
    }
}
