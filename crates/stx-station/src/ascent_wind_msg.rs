//! The `ascent_wind` message of the API (`API.md`): the wind the station measured from the
//! balloon's drift during the ascent, by altitude band, as the dashboard's wind panel draws
//! it. Filled by the core (`core/ascent.rs`); re-exported with the other messages from
//! [`crate::messages`].

use schemars::JsonSchema;
use serde::Serialize;

/// The wind measured from the balloon's drift during the ascent, by altitude band: sent on
/// the WebSocket when the bands change, and by `GET /api/ascent_wind`.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct AscentWindMsg {
    /// Always `ascent_wind`.
    #[serde(rename = "type")]
    #[schemars(extend("const" = "ascent_wind"))]
    pub kind: &'static str,
    /// Mission clock, s.
    pub time_s: f64,
    /// Height of a band, m.
    pub band_height_m: f64,
    /// The end of the ascent (burst or cut-away) was seen: no more bands come.
    pub ascent_over: bool,
    /// GPS fixes used so far.
    pub fixes_used: u64,
    /// The bands with enough fixes, lowest first.
    pub bands: Vec<AscentBandView>,
}

/// One altitude band of the ascent's wind.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct AscentBandView {
    /// Altitude the wind is reported at (the middle of the altitudes flown through), above
    /// mean sea level, m.
    pub alt_msl_m: f64,
    /// Lowest altitude of the fixes used, above mean sea level, m.
    pub alt_min_msl_m: f64,
    /// Highest altitude of the fixes used, above mean sea level, m.
    pub alt_max_msl_m: f64,
    /// Wind speed, m/s.
    pub speed_mps: f64,
    /// Direction the wind blows from, degrees clockwise from north, 0…360.
    pub from_deg: f64,
    /// North component of the wind (where the air goes), m/s.
    pub wind_north_mps: f64,
    /// East component of the wind, m/s.
    pub wind_east_mps: f64,
    /// 1-σ of the north component, m/s.
    pub sigma_north_mps: f64,
    /// 1-σ of the east component, m/s.
    pub sigma_east_mps: f64,
    /// GPS fixes used.
    pub samples: u32,
    /// From the GPS velocities or from position differences.
    pub method: stx_gnc::ascent_wind::BandMethod,
    /// First fix used, s on the drone's clock (continued across its restarts).
    pub time_start_s: f64,
    /// Last fix used, s on the drone's clock.
    pub time_end_s: f64,
    /// Why the band is not believed (faster than any wind a balloon meets at its height, or
    /// too uncertain; `stx_gnc::ascent_wind::Implausible`): it is shown but not used for any
    /// prediction or plan. `null`: believed, and used.
    pub refused: Option<String>,
}

impl AscentBandView {
    /// The view of `b`, whose altitudes are above an origin `origin_msl_m` above sea level.
    pub fn of(b: &stx_gnc::ascent_wind::WindBand, origin_msl_m: f64) -> Self {
        let msl = |a: f64| a + origin_msl_m;
        Self {
            alt_msl_m: msl(b.altitude_m),
            alt_min_msl_m: msl(b.altitude_min_m),
            alt_max_msl_m: msl(b.altitude_max_m),
            speed_mps: b.speed_mps(),
            from_deg: b.from_deg(),
            wind_north_mps: b.wind_north_mps,
            wind_east_mps: b.wind_east_mps,
            sigma_north_mps: b.sigma_north_mps,
            sigma_east_mps: b.sigma_east_mps,
            samples: b.samples,
            method: b.method,
            time_start_s: b.time_start_s,
            time_end_s: b.time_end_s,
            refused: b.refused.map(|r| r.to_string()),
        }
    }
}
