//! The keep-out zones as a MAVLink fence (`MAV_MISSION_TYPE_FENCE`), so the drone holds them
//! when the link is lost and MAVProxy or QGroundControl show them.
//!
//! Each zone's boundary is an exclusion polygon: one MISSION_ITEM_INT per vertex with command
//! `MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION`, param1 the polygon's vertex count (the same
//! on each of its vertices), x/y latitude/longitude in degE7, the polygon's vertices
//! consecutive and not closed (MAVLink's fence protocol; ArduPilot and PX4 read it so). The
//! transfer is the mission protocol's, with the fence's mission type
//! ([`FenceClient`]/[`FenceServer`]). A fence with another kind of item (inclusion polygons,
//! circles, a return point) is refused item by item; one whose vertex counts do not add up
//! is refused whole.
//!
//! Holes: a fence polygon has none, so a zone's holes are not sent — the drone keeps out of
//! the whole boundary, the stricter reading. Names are not carried either: the drone calls
//! its zones `fence polygon N`.

use mavlink::dialects::common as mc;
use mavlink::dialects::common::{MavCmd, MavMessage, MavMissionResult};
use serde::{Deserialize, Serialize};
use stx_types::geo::LocalFrame;
use stx_types::keep_out::{KeepOutZone, KeepOutZones};

use super::client::{MissionClient, TransferEvent};
use super::mission::MissionItem;
use super::server::MissionServer;

/// Ground side of the fence transfer.
pub type FenceClient = MissionClient<FenceItem>;
/// Vehicle side of the fence transfer.
pub type FenceServer = MissionServer<FenceItem>;
/// Outcome of a fence transfer on the ground side.
pub type FenceEvent = TransferEvent<FenceItem>;

/// Fewest vertices of a polygon.
const MIN_VERTICES: u16 = 3;

/// One vertex of an exclusion polygon.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FenceItem {
    /// Vertices of the polygon this vertex belongs to.
    pub vertex_count: u16,
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Longitude, degrees.
    pub lon_deg: f64,
}

/// Why a MISSION_ITEM_INT is not a fence vertex.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum FenceItemError {
    /// Not an exclusion polygon's vertex.
    #[error("unsupported fence command {command:?} (only exclusion polygons are kept out of)")]
    Unsupported { command: MavCmd },
    /// Not a global frame.
    #[error("unsupported fence frame {frame:?}")]
    UnsupportedFrame { frame: mc::MavFrame },
    /// Vertex count not a whole number of at least 3.
    #[error("fence vertex count {count} is not a whole number of at least {MIN_VERTICES}")]
    VertexCount { count: f32 },
    /// Latitude or longitude out of range.
    #[error("invalid value in parameter {param}")]
    Invalid { param: u8 },
}

/// Why a list of vertices, or a zone, is not a fence.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FenceError {
    /// Vertex counts that do not add up.
    #[error("fence item {item}: its polygon declares {declared} vertices but {reason}")]
    Malformed {
        /// Index of the polygon's first item.
        item: usize,
        /// The count it declares.
        declared: u16,
        /// What is wrong.
        reason: &'static str,
    },
    /// A zone with too many (or too few) vertices for one polygon.
    #[error("keep-out zone '{zone}' has {vertices} vertices: a fence polygon has 3 to 65535")]
    TooLarge { zone: String, vertices: usize },
}

/// Whether `frame` places a latitude and longitude (the altitude is not used).
#[allow(deprecated)] // The *_INT frames: deprecated synonyms older senders use.
fn global(frame: mc::MavFrame) -> bool {
    use mc::MavFrame::*;
    matches!(
        frame,
        MAV_FRAME_GLOBAL
            | MAV_FRAME_GLOBAL_INT
            | MAV_FRAME_GLOBAL_RELATIVE_ALT
            | MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
            | MAV_FRAME_GLOBAL_TERRAIN_ALT
            | MAV_FRAME_GLOBAL_TERRAIN_ALT_INT
    )
}

impl MissionItem for FenceItem {
    const MISSION_TYPE: mc::MavMissionType = mc::MavMissionType::MAV_MISSION_TYPE_FENCE;
    type Error = FenceItemError;

    fn to_mavlink(&self, target: (u8, u8), seq: u16) -> MavMessage {
        MavMessage::MISSION_ITEM_INT(mc::MISSION_ITEM_INT_DATA {
            param1: f32::from(self.vertex_count),
            param2: 0.0,
            param3: 0.0,
            param4: 0.0,
            x: (self.lat_deg * 1e7).round() as i32,
            y: (self.lon_deg * 1e7).round() as i32,
            z: 0.0,
            seq,
            command: MavCmd::MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION,
            target_system: target.0,
            target_component: target.1,
            frame: mc::MavFrame::MAV_FRAME_GLOBAL,
            current: 0,
            autocontinue: 0,
            mission_type: Self::MISSION_TYPE,
        })
    }

    fn from_mavlink(m: &mc::MISSION_ITEM_INT_DATA) -> Result<Self, FenceItemError> {
        if m.command != MavCmd::MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION {
            return Err(FenceItemError::Unsupported { command: m.command });
        }
        if !global(m.frame) {
            return Err(FenceItemError::UnsupportedFrame { frame: m.frame });
        }
        let count = m.param1;
        if !(count.is_finite()
            && count.fract() == 0.0
            && (f32::from(MIN_VERTICES)..=f32::from(u16::MAX)).contains(&count))
        {
            return Err(FenceItemError::VertexCount { count });
        }
        let (lat_deg, lon_deg) = (f64::from(m.x) / 1e7, f64::from(m.y) / 1e7);
        if !(-90.0..=90.0).contains(&lat_deg) {
            return Err(FenceItemError::Invalid { param: 5 });
        }
        if !(-180.0..=180.0).contains(&lon_deg) {
            return Err(FenceItemError::Invalid { param: 6 });
        }
        Ok(Self {
            vertex_count: count as u16,
            lat_deg,
            lon_deg,
        })
    }

    fn refusal(error: &FenceItemError) -> MavMissionResult {
        match error {
            FenceItemError::Unsupported { .. } => MavMissionResult::MAV_MISSION_UNSUPPORTED,
            FenceItemError::UnsupportedFrame { .. } => {
                MavMissionResult::MAV_MISSION_UNSUPPORTED_FRAME
            }
            FenceItemError::VertexCount { .. } => MavMissionResult::MAV_MISSION_INVALID_PARAM1,
            FenceItemError::Invalid { param: 5 } => MavMissionResult::MAV_MISSION_INVALID_PARAM5_X,
            FenceItemError::Invalid { .. } => MavMissionResult::MAV_MISSION_INVALID_PARAM6_Y,
        }
    }

    fn check_list(items: &[Self]) -> Result<(), String> {
        fence_polygons(items).map(|_| ()).map_err(|e| e.to_string())
    }
}

/// The polygons (vertices as latitude, longitude in degrees, not closed) a fence's items
/// describe, checking that each polygon's vertices are consecutive, as many as each declares.
pub fn fence_polygons(items: &[FenceItem]) -> Result<Vec<Vec<[f64; 2]>>, FenceError> {
    let mut polygons = Vec::new();
    let mut i = 0;
    while i < items.len() {
        let declared = items[i].vertex_count;
        let n = usize::from(declared);
        let malformed = |reason| FenceError::Malformed {
            item: i,
            declared,
            reason,
        };
        if declared < MIN_VERTICES {
            return Err(malformed("a polygon needs at least 3"));
        }
        let Some(polygon) = items.get(i..i + n) else {
            return Err(malformed("the fence ends before them"));
        };
        if polygon.iter().any(|v| v.vertex_count != declared) {
            return Err(malformed("a vertex among them declares another count"));
        }
        polygons.push(polygon.iter().map(|v| [v.lat_deg, v.lon_deg]).collect());
        i += n;
    }
    Ok(polygons)
}

/// The fence keeping out of `zones` (in `frame`): one exclusion polygon per zone's boundary.
pub fn zones_to_fence(
    zones: &KeepOutZones,
    frame: &LocalFrame,
) -> Result<Vec<FenceItem>, FenceError> {
    let mut items = Vec::new();
    for zone in &zones.zones {
        let Some(boundary) = zone.rings_ne_m.first() else {
            continue;
        };
        let vertex_count = u16::try_from(boundary.len())
            .ok()
            .filter(|n| *n >= MIN_VERTICES)
            .ok_or_else(|| FenceError::TooLarge {
                zone: zone.name.clone(),
                vertices: boundary.len(),
            })?;
        for [lat_deg, lon_deg] in zone.boundary_lat_lon(frame) {
            items.push(FenceItem {
                vertex_count,
                lat_deg,
                lon_deg,
            });
        }
    }
    Ok(items)
}

/// The keep-out zones a fence describes, in `frame`; polygon `k` is named `fence polygon k`.
pub fn fence_to_zones(items: &[FenceItem], frame: &LocalFrame) -> Result<KeepOutZones, FenceError> {
    let zones = fence_polygons(items)?
        .into_iter()
        .enumerate()
        .map(|(k, polygon)| KeepOutZone {
            name: format!("fence polygon {k}"),
            rings_ne_m: vec![
                polygon
                    .iter()
                    .map(|[lat, lon]| {
                        let ned = frame.to_ned(*lat, *lon, frame.alt_msl_m);
                        [ned.x, ned.y]
                    })
                    .collect(),
            ],
        })
        .collect();
    Ok(KeepOutZones { zones })
}
