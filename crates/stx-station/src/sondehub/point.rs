//! What SondeHub is sent: a telemetry point as its API names the fields, a listener (the
//! station, or a chase car), and how the station's state becomes points.

use serde::{Deserialize, Serialize};

use super::settings::SondehubConfig;
use crate::messages::VehicleView;

/// The name SondeHub is given for the uploading software.
pub const SOFTWARE_NAME: &str = "stx";

/// Its version.
pub const SOFTWARE_VERSION: &str = env!("CARGO_PKG_VERSION");

/// One telemetry point as `PUT /amateur/telemetry` takes it (fields and units of the API:
/// m, m/s, °, V, °C, hPa; times `YYYY-MM-DDTHH:MM:SS.ffffffZ`). What stx does not know is
/// left out rather than sent as a placeholder.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TelemetryPoint {
    /// [`SOFTWARE_NAME`].
    pub software_name: String,
    /// [`SOFTWARE_VERSION`].
    pub software_version: String,
    /// The station's callsign.
    pub uploader_callsign: String,
    /// When the station had the fix.
    pub time_received: String,
    /// The payload's callsign.
    pub payload_callsign: String,
    /// When the payload's GPS had the fix.
    pub datetime: String,
    /// Latitude, °.
    pub lat: f64,
    /// Longitude, °.
    pub lon: f64,
    /// Altitude above mean sea level, m.
    pub alt: f64,
    /// Ground speed, m/s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vel_h: Option<f64>,
    /// Climb rate, m/s (up positive).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vel_v: Option<f64>,
    /// Course over the ground, ° from true north.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heading: Option<f64>,
    /// GPS satellites used.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sats: Option<u8>,
    /// Battery, V.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub batt: Option<f64>,
    /// Air temperature, °C.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub temp: Option<f64>,
    /// Static pressure, hPa.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pressure: Option<f64>,
    /// The station's position, `[lat °, lon °, alt m]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uploader_position: Option<[f64; 3]>,
    /// The station's antenna.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uploader_antenna: Option<String>,
    /// Sent long after the fix: SondeHub takes it without its 24-hour check.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub historical: bool,
}

/// `PUT /amateur/listeners`: the station (`mobile: false`, a station icon for about 12 h) or
/// a chase car (`mobile: true`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ListenerBody {
    /// [`SOFTWARE_NAME`].
    pub software_name: String,
    /// [`SOFTWARE_VERSION`].
    pub software_version: String,
    /// Whose position.
    pub uploader_callsign: String,
    /// `[lat °, lon °, alt m]`.
    pub uploader_position: [f64; 3],
    /// The radio, free text.
    pub uploader_radio: String,
    /// The antenna, free text.
    pub uploader_antenna: String,
    /// A chase car.
    pub mobile: bool,
}

impl ListenerBody {
    /// The station as configured, if its position is.
    pub fn station(config: &SondehubConfig) -> Option<Self> {
        let at = config.station_position?;
        Some(Self {
            software_name: SOFTWARE_NAME.into(),
            software_version: SOFTWARE_VERSION.into(),
            uploader_callsign: config.uploader_callsign.clone(),
            uploader_position: at.as_array(),
            uploader_radio: config.radio.clone(),
            uploader_antenna: config.antenna.clone(),
            mobile: false,
        })
    }

    /// The chase car at `position` (`[lat, lon, alt]`).
    pub fn chase_car(config: &SondehubConfig, position: [f64; 3]) -> Self {
        Self {
            software_name: SOFTWARE_NAME.into(),
            software_version: SOFTWARE_VERSION.into(),
            uploader_callsign: config.chase_callsign(),
            uploader_position: position,
            uploader_radio: String::new(),
            uploader_antenna: String::new(),
            mobile: true,
        }
    }
}

/// A Unix time in ms as SondeHub writes times: `YYYY-MM-DDTHH:MM:SS.ffffffZ`, UTC.
pub fn utc_datetime(wall_ms: u64) -> String {
    let days = (wall_ms / 86_400_000) as i64;
    let of_day_ms = wall_ms % 86_400_000;
    let (y, m, d) = civil_from_days(days);
    let s = of_day_ms / 1000;
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}.{:06}Z",
        s / 3600,
        (s / 60) % 60,
        s % 60,
        (of_day_ms % 1000) * 1000
    )
}

/// The proleptic Gregorian date of a day count since 1970-01-01 (Howard Hinnant's
/// `civil_from_days`).
fn civil_from_days(z: i64) -> (i64, u32, u32) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let y = yoe + era * 400 + i64::from(m <= 2);
    (y, m, d)
}

/// A point with when its fix was, Unix ms (its age decides `historical` when it is sent).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Sample {
    /// When the payload had the fix, Unix ms.
    pub fix_ms: u64,
    /// The point.
    pub point: TelemetryPoint,
}

/// Turns the station's states into points, each fix once.
#[derive(Debug, Default)]
pub struct Sampler {
    last_fix_ms: Option<u64>,
}

/// Fixes closer than this are the same fix seen twice (the state's age is in whole ms).
const SAME_FIX_MS: u64 = 500;

impl Sampler {
    /// The point of the drone's GPS fix in the station's state at `wall_ms` (`vehicle`), if
    /// there is a new one: none without a 2-D or 3-D fix, at 0°, 0°, with no satellites
    /// (pysondehub refuses those too), from stale data, or for a fix already sent. The values
    /// are the chase summary's ([`crate::chase::summaries`]).
    pub fn sample(
        &mut self,
        config: &SondehubConfig,
        wall_ms: u64,
        vehicle: Option<&VehicleView>,
    ) -> Option<Sample> {
        let vehicle = vehicle.filter(|v| !v.stale)?;
        let gps = vehicle
            .gps
            .as_ref()
            .filter(|g| !matches!(g.fix.as_str(), "no_gps" | "no_fix"))
            .filter(|g| g.lat_deg != 0.0 || g.lon_deg != 0.0)
            .filter(|g| g.satellites != Some(0))?;
        let fix_ms = wall_ms.saturating_sub((vehicle.age_s.max(0.0) * 1000.0) as u64);
        if self
            .last_fix_ms
            .is_some_and(|last| fix_ms < last + SAME_FIX_MS)
        {
            return None;
        }
        self.last_fix_ms = Some(fix_ms);
        let [n, e, d] = gps.velocity_ned_mps;
        let air = vehicle.air.as_ref();
        let at = utc_datetime(fix_ms);
        Some(Sample {
            fix_ms,
            point: TelemetryPoint {
                software_name: SOFTWARE_NAME.into(),
                software_version: SOFTWARE_VERSION.into(),
                uploader_callsign: config.uploader_callsign.clone(),
                time_received: at.clone(),
                payload_callsign: config.payload_callsign.clone(),
                datetime: at,
                lat: gps.lat_deg,
                lon: gps.lon_deg,
                alt: gps.alt_msl_m,
                vel_h: Some(n.hypot(e)),
                vel_v: Some(-d),
                heading: Some(e.atan2(n).to_degrees().rem_euclid(360.0)),
                sats: gps.satellites,
                batt: vehicle.power.as_ref().and_then(|p| p.voltage_v),
                temp: air.map(|a| a.temperature_c),
                pressure: air.map(|a| a.static_pressure_pa / 100.0),
                uploader_position: config.station_position.map(|p| p.as_array()),
                uploader_antenna: Some(config.antenna.clone()).filter(|a| !a.is_empty()),
                historical: false,
            },
        })
    }
}

#[cfg(test)]
impl Sample {
    /// A point at `fix_ms` with the required fields only, for the tests of what carries it.
    pub(crate) fn bare(fix_ms: u64) -> Self {
        let at = utc_datetime(fix_ms);
        Self {
            fix_ms,
            point: TelemetryPoint {
                software_name: SOFTWARE_NAME.into(),
                software_version: SOFTWARE_VERSION.into(),
                uploader_callsign: "CT1ABC".into(),
                time_received: at.clone(),
                payload_callsign: "STRAPLEX1".into(),
                datetime: at,
                lat: 38.0,
                lon: -7.0,
                alt: 100.0,
                vel_h: None,
                vel_v: None,
                heading: None,
                sats: None,
                batt: None,
                temp: None,
                pressure: None,
                uploader_position: None,
                uploader_antenna: None,
                historical: false,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::messages::GpsView;

    fn config() -> SondehubConfig {
        toml::from_str(
            "uploader_callsign = \"CT1ABC\"\npayload_callsign = \"STRAPLEX1\"\n\
             station_position = { lat_deg = 38.5, lon_deg = -7.9, alt_m = 245.0 }\n",
        )
        .expect("parses")
    }

    fn state(wall_ms: u64, age_s: f64, lat: f64, sats: Option<u8>) -> (u64, VehicleView) {
        (
            wall_ms,
            VehicleView {
                gps: Some(GpsView {
                    fix: "fix_3d".into(),
                    satellites: sats,
                    lat_deg: lat,
                    lon_deg: -7.88,
                    alt_msl_m: 900.0,
                    velocity_ned_mps: [3.0, 4.0, 5.0],
                    h_acc_m: None,
                }),
                age_s,
                ..Default::default()
            },
        )
    }

    fn sample(s: &mut Sampler, (wall_ms, vehicle): (u64, VehicleView)) -> Option<Sample> {
        s.sample(&config(), wall_ms, Some(&vehicle))
    }

    #[test]
    fn times_are_written_as_sondehub_reads_them() {
        assert_eq!(utc_datetime(0), "1970-01-01T00:00:00.000000Z");
        // 2026-11-30T01:02:03.999Z
        assert_eq!(
            utc_datetime(1_796_000_523_999),
            "2026-11-30T01:02:03.999000Z"
        );
        // A leap day.
        assert_eq!(utc_datetime(951_782_400_000), "2000-02-29T00:00:00.000000Z");
    }

    #[test]
    fn each_fix_becomes_one_point_with_the_apis_units() {
        let mut s = Sampler::default();
        let first = sample(&mut s, state(1_796_000_523_000, 0.25, 38.6, Some(9))).expect("a point");
        assert_eq!(first.fix_ms, 1_796_000_522_750);
        let p = &first.point;
        assert_eq!(p.datetime, "2026-11-30T01:02:02.750000Z");
        assert_eq!(
            (p.vel_h, p.vel_v, p.sats, p.uploader_position),
            (Some(5.0), Some(-5.0), Some(9), Some([38.5, -7.9, 245.0]))
        );
        assert!((p.heading.expect("heading") - 53.13).abs() < 0.01);
        // The same fix a moment later (the state's age grew with the clock): not again.
        assert!(sample(&mut s, state(1_796_000_523_300, 0.55, 38.6, Some(9))).is_none());
        assert!(sample(&mut s, state(1_796_000_525_000, 0.1, 38.6, Some(9))).is_some());
        let json = serde_json::to_value(p).expect("json");
        assert!(json.get("historical").is_none() && json.get("batt").is_none());
    }

    #[test]
    fn no_point_without_a_usable_fix() {
        let mut s = Sampler::default();
        let mut null_island = state(1_000_000, 0.0, 0.0, Some(9));
        if let Some(g) = null_island.1.gps.as_mut() {
            g.lon_deg = 0.0;
        }
        assert!(sample(&mut s, null_island).is_none());
        assert!(sample(&mut s, state(1_000_000, 0.0, 38.6, Some(0))).is_none());
        let mut stale = state(1_000_000, 9.0, 38.6, Some(9));
        stale.1.stale = true;
        assert!(sample(&mut s, stale).is_none());
        assert!(s.sample(&config(), 1_000_000, None).is_none());
    }
}
