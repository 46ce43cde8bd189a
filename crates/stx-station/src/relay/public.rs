//! The public picture a relay serves: where the payload is, how fast it goes, its stage, the
//! predicted landing and the target. Nothing of the operators' (link statistics, parameters,
//! commands, guidance internals, the go/no-go board, recordings) is in it.
//!
//! A relay reads it from its upstream: a station's full `state` (read through a viewer's
//! token, only the fields below picked out; unknown fields are ignored so a station newer than
//! the relay still feeds it) or another relay's `public_state`, unchanged.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A point on the map.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PublicPoint {
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Longitude, degrees.
    pub lon_deg: f64,
}

/// Where the payload is and how it moves.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PublicPosition {
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Longitude, degrees.
    pub lon_deg: f64,
    /// Altitude above mean sea level, m.
    pub alt_msl_m: f64,
    /// Speed over the ground, m/s.
    pub ground_speed_mps: f64,
    /// Course over the ground, degrees clockwise from north.
    pub course_deg: f64,
    /// Vertical speed, m/s, positive up.
    pub climb_mps: f64,
}

/// The public state, sent to a relay's viewers at most four times a second.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PublicStateMsg {
    /// Always `public_state`.
    #[serde(rename = "type")]
    #[schemars(extend("const" = "public_state"))]
    pub kind: String,
    /// Unix time the station sent it, ms (a delayed relay shows it that much later).
    pub wall_ms: u64,
    /// The mission clock (the drone's, s since its boot); `null` before the drone is heard.
    pub mission_time_s: Option<f64>,
    /// Mission stage (`ascent`, `descent`, `parafoil`, `landed`, …); `null` before the drone
    /// reports one.
    pub stage: Option<String>,
    /// The station hears the drone no more (what is shown is the last known).
    pub link_stale: bool,
    /// The payload; `null` before the first fix.
    pub position: Option<PublicPosition>,
    /// The predicted landing under the parafoil; `null` while there is none.
    pub landing: Option<PublicPoint>,
    /// The landing target; `null` while it is not known.
    pub target: Option<PublicPoint>,
    /// How long after the station this is shown, s (the relays' delays added up).
    pub delay_s: f64,
    /// Positions are rounded to a grid this coarse, m (0: as the station has them).
    pub coarsen_m: f64,
}

/// A point of the public track.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PublicTrackPoint {
    /// The mission clock, s.
    pub mission_time_s: f64,
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Longitude, degrees.
    pub lon_deg: f64,
    /// Altitude above mean sea level, m.
    pub alt_msl_m: f64,
}

/// A viewer's first message: the track so far.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PublicHistoryMsg {
    /// Always `public_history`.
    #[serde(rename = "type")]
    #[schemars(extend("const" = "public_history"))]
    pub kind: String,
    /// The track, oldest first, a point a second at most.
    pub track: Vec<PublicTrackPoint>,
}

/// `GET /api/relay` on a relay: what it serves and how it is fed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct RelayStatusBody {
    /// The upstream's address, without its token.
    pub upstream: String,
    /// The upstream's WebSocket is open.
    pub upstream_connected: bool,
    /// Viewers connected to this relay now (a relay below counts one).
    pub viewers: u32,
    /// Pages served through this relay: its own viewers, a relay below counted by the pages it
    /// reports. This is what the relay reports to its upstream.
    pub audience: u32,
    /// Most viewers this relay serves at once.
    pub max_viewers: u32,
    /// This relay's own delay, s.
    pub delay_s: f64,
    /// This relay's own grid, m.
    pub coarsen_m: f64,
}

// What a relay reads of a station's `state`: a typed mirror of the few fields it passes on.
#[derive(Deserialize)]
struct UpstreamState {
    wall_ms: u64,
    mission_time_s: Option<f64>,
    link: UpstreamLink,
    estimate: Option<UpstreamEstimate>,
    guidance: Option<UpstreamGuidance>,
    prediction: Option<UpstreamPrediction>,
    mission: UpstreamMission,
}

#[derive(Deserialize)]
struct UpstreamLink {
    stale: bool,
}

#[derive(Deserialize)]
struct UpstreamEstimate {
    lat_deg: f64,
    lon_deg: f64,
    alt_msl_m: f64,
    velocity_ned_mps: [f64; 3],
    ground_speed_mps: f64,
    course_deg: f64,
}

#[derive(Deserialize)]
struct UpstreamGuidance {
    target: Option<PublicPoint>,
}

#[derive(Deserialize)]
struct UpstreamPrediction {
    planned: Option<PublicPoint>,
}

#[derive(Deserialize)]
struct UpstreamMission {
    stage: Option<String>,
}

#[derive(Deserialize)]
struct UpstreamTrackPoint {
    mission_time_s: f64,
    lat_deg: f64,
    lon_deg: f64,
    alt_msl_m: f64,
}

#[derive(Deserialize)]
struct UpstreamHistory<P> {
    track: Vec<P>,
}

/// One message of the upstream, as a relay takes it.
#[derive(Debug, Clone, PartialEq)]
pub enum UpstreamNews {
    /// The public state now.
    State(PublicStateMsg),
    /// The track so far (on connecting).
    History(Vec<PublicTrackPoint>),
    /// Anything else the upstream sends (events, parameters, …): not public.
    Other,
}

/// Reads one upstream WebSocket text message; an error names what did not parse.
pub fn read_upstream(text: &str) -> Result<UpstreamNews, serde_json::Error> {
    #[derive(Deserialize)]
    struct Kind<'a> {
        #[serde(rename = "type", borrow)]
        kind: &'a str,
    }
    let kind: Kind = serde_json::from_str(text)?;
    Ok(match kind.kind {
        "state" => UpstreamNews::State(public_of(&serde_json::from_str(text)?)),
        "public_state" => UpstreamNews::State(serde_json::from_str(text)?),
        "history" => {
            let h: UpstreamHistory<UpstreamTrackPoint> = serde_json::from_str(text)?;
            let track = h.track.into_iter().map(|p| PublicTrackPoint {
                mission_time_s: p.mission_time_s,
                lat_deg: p.lat_deg,
                lon_deg: p.lon_deg,
                alt_msl_m: p.alt_msl_m,
            });
            UpstreamNews::History(track.collect())
        }
        "public_history" => {
            let h: UpstreamHistory<PublicTrackPoint> = serde_json::from_str(text)?;
            UpstreamNews::History(h.track)
        }
        _ => UpstreamNews::Other,
    })
}

fn public_of(s: &UpstreamState) -> PublicStateMsg {
    PublicStateMsg {
        kind: "public_state".into(),
        wall_ms: s.wall_ms,
        mission_time_s: s.mission_time_s,
        stage: s.mission.stage.clone(),
        link_stale: s.link.stale,
        position: s.estimate.as_ref().map(|e| PublicPosition {
            lat_deg: e.lat_deg,
            lon_deg: e.lon_deg,
            alt_msl_m: e.alt_msl_m,
            ground_speed_mps: e.ground_speed_mps,
            course_deg: e.course_deg,
            climb_mps: -e.velocity_ned_mps[2],
        }),
        landing: s.prediction.as_ref().and_then(|p| p.planned),
        target: s.guidance.as_ref().and_then(|g| g.target),
        delay_s: 0.0,
        coarsen_m: 0.0,
    }
}
