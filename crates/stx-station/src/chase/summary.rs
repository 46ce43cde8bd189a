//! What one summary holds and how the station's state becomes the summaries to send.

use serde::Serialize;

use super::settings::ChaseConfig;

use crate::messages::StateMsg;

/// One `PAYLOAD_SUMMARY` datagram's contents.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PayloadSummary {
    /// Always `PAYLOAD_SUMMARY`.
    #[serde(rename = "type")]
    pub kind: &'static str,
    /// Whose position.
    pub callsign: String,
    /// Latitude, °.
    pub latitude: f64,
    /// Longitude, °.
    pub longitude: f64,
    /// Altitude above mean sea level, m.
    pub altitude: f64,
    /// Ground speed, km/h (−1: unknown).
    pub speed: f64,
    /// Course over the ground, ° from north (−1: unknown).
    pub heading: f64,
    /// Time of the position, "HH:MM:SS" UTC.
    pub time: String,
    /// What it is.
    pub comment: String,
    /// Air temperature, °C (−1: unknown, as Horus sends it).
    pub temp: f64,
    /// GPS satellites (−1: unknown).
    pub sats: i32,
    /// Battery, V (−1: unknown).
    pub batt_voltage: f64,
}

/// "HH:MM:SS" of a Unix time in ms, UTC.
pub fn utc_hms(wall_ms: u64) -> String {
    let s = (wall_ms / 1000) % 86_400;
    format!("{:02}:{:02}:{:02}", s / 3600, (s / 60) % 60, s % 60)
}

/// The summaries to send now: the payload at its last GPS fix (none without a fix, and never
/// at 0°, 0°, as horusdemodlib refuses too), and its predicted landing (steered if guidance
/// plans one, else unsteered) once there is one, at the flight path's landing altitude
/// (else `ground_msl_m`, the origin's ground).
pub fn summaries(config: &ChaseConfig, ground_msl_m: f64, state: &StateMsg) -> Vec<PayloadSummary> {
    let mut out = Vec::new();
    let Some(vehicle) = &state.vehicle else {
        return out;
    };
    let Some(gps) = vehicle
        .gps
        .as_ref()
        .filter(|g| !matches!(g.fix.as_str(), "no_gps" | "no_fix"))
        .filter(|g| g.lat_deg != 0.0 || g.lon_deg != 0.0)
    else {
        return out;
    };
    let fix_ms = state
        .wall_ms
        .saturating_sub((vehicle.age_s.max(0.0) * 1000.0) as u64);
    let [n, e, _] = gps.velocity_ned_mps;
    let stage = vehicle.stage.as_ref().map(|s| s.replace('_', " "));
    out.push(PayloadSummary {
        kind: "PAYLOAD_SUMMARY",
        callsign: config.callsign.clone(),
        latitude: gps.lat_deg,
        longitude: gps.lon_deg,
        altitude: gps.alt_msl_m,
        speed: n.hypot(e) * 3.6,
        heading: e.atan2(n).to_degrees().rem_euclid(360.0),
        time: utc_hms(fix_ms),
        comment: match stage {
            Some(s) => format!("stx: {s}"),
            None => "stx".into(),
        },
        temp: vehicle.air.as_ref().map_or(-1.0, |a| a.temperature_c),
        sats: gps.satellites.map_or(-1, i32::from),
        batt_voltage: vehicle
            .power
            .as_ref()
            .and_then(|p| p.voltage_v)
            .unwrap_or(-1.0),
    });
    if let Some(prediction) = &state.prediction {
        let (touchdown, which) = match &prediction.planned {
            Some(p) => (p, "steered"),
            None => (&prediction.uncontrolled, "unsteered"),
        };
        let ground = state
            .flight_path
            .as_ref()
            .map_or(ground_msl_m, |f| f.landing.alt_msl_m);
        out.push(PayloadSummary {
            kind: "PAYLOAD_SUMMARY",
            callsign: config.landing_callsign(),
            latitude: touchdown.lat_deg,
            longitude: touchdown.lon_deg,
            altitude: ground,
            speed: -1.0,
            heading: -1.0,
            time: utc_hms(state.wall_ms),
            comment: format!(
                "stx predicted landing ({which}) in {:.0} s",
                touchdown.time_to_land_s
            ),
            temp: -1.0,
            sats: -1,
            batt_voltage: -1.0,
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utc_time_is_hours_minutes_seconds_of_the_day() {
        // 2026-11-30T01:02:03.999Z
        assert_eq!(utc_hms(1_796_000_523_999), "01:02:03");
        assert_eq!(utc_hms(0), "00:00:00");
    }
}
