//! The unsteered flight path as the dashboard draws it during the ascent and under the round
//! chute (issue 15 item 3): where the balloon bursts, where the parafoil deploys, where the
//! parafoil lands with neutral servos and where the round chute alone would come down.

use schemars::JsonSchema;
use serde::Serialize;

/// The latest flight-path prediction.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct FlightPathView {
    /// The station's clock when it was computed, s.
    pub computed_s: f64,
    /// The mission clock (the drone's) of the fix it started from, s: its `in_s` count from
    /// there, so a countdown is `in_s − (mission_time_s − computed_mission_s)`.
    pub computed_mission_s: f64,
    /// The stage it was computed in: `ascent` (or `pre_launch`) or `round_chute`.
    pub stage: String,
    /// Where the balloon bursts (at the drone's `MIS_BURST_M`, else the station config's
    /// burst altitude, or where the drone cuts it away at `MIS_CUTDOWN_M`); `null` under the
    /// round chute.
    pub burst: Option<PathPointView>,
    /// Where the round chute is released and the parafoil deploys (`MIS_DEPLOY_M`).
    pub deploy: PathPointView,
    /// Where the parafoil lands with its servos neutral.
    pub landing: PathPointView,
    /// Where the stack would land if the round chute were never released.
    pub round_chute_landing: PathPointView,
    /// The ground steering could reach from the deploy point: a disc's centre, degrees.
    pub reach_centre_lat_lon_deg: [f64; 2],
    /// The disc's radius, m.
    pub reach_radius_m: f64,
    /// Bands of the ascent's measured wind it flew in (the forecast above the highest and
    /// below the lowest); 0: the forecast alone.
    pub measured_bands: u32,
    /// Altitude of the highest measured band's top, m above mean sea level: above it the
    /// path flies the forecast; `null` without bands.
    pub measured_to_msl_m: Option<f64>,
    /// Where the burst altitude comes from: `drone` (its `MIS_BURST_M`, loaded before launch)
    /// or `station_config` (`[flight_path] burst_altitude_msl_m`).
    pub burst_source: String,
    /// Where the ascent rate comes from: `drone` (`MIS_ASCENT_MPS`) or `station_config`
    /// (`[flight_path] mean_ascent_rate_mps`).
    pub ascent_rate_source: String,
}

/// A point of the flight path.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct PathPointView {
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Longitude, degrees.
    pub lon_deg: f64,
    /// Altitude above mean sea level, m.
    pub alt_msl_m: f64,
    /// Time from when it was computed, s.
    pub in_s: f64,
}
