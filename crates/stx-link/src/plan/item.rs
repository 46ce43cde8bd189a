//! One element of the guidance plan, [`PlanItem`], and the MISSION_ITEM_INT that carries it
//! (refused with a [`PlanItemError`] naming the MISSION_ACK result to answer with).

use mavlink::dialects::common as mc;
use mavlink::dialects::common::{MavCmd, MavMessage, MavMissionResult};
use serde::{Deserialize, Serialize};

/// One element of the guidance plan.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PlanItem {
    /// A localizer point.
    Waypoint {
        lat_deg: f64,
        lon_deg: f64,
        alt_msl_m: f64,
    },
    /// The landing target; `approach_heading_deg: None` lands into the wind.
    Land {
        lat_deg: f64,
        lon_deg: f64,
        alt_msl_m: f64,
        approach_heading_deg: Option<f64>,
    },
}

impl PlanItem {
    /// The item in the mission's local frame, for guidance's `stx_gnc::plan_upload::apply` (the
    /// one mapping the drone and the station's replica share).
    pub fn to_local(&self, frame: &stx_types::geo::LocalFrame) -> stx_types::plan::PlanPoint {
        use stx_types::plan::PlanPoint;
        match *self {
            Self::Waypoint {
                lat_deg,
                lon_deg,
                alt_msl_m,
            } => PlanPoint::Waypoint {
                position_ned_m: frame.to_ned(lat_deg, lon_deg, alt_msl_m),
            },
            Self::Land {
                lat_deg,
                lon_deg,
                alt_msl_m,
                approach_heading_deg,
            } => PlanPoint::Land {
                position_ned_m: frame.to_ned(lat_deg, lon_deg, alt_msl_m),
                approach_course_rad: approach_heading_deg.map(f64::to_radians),
            },
        }
    }
}

/// Why a MISSION_ITEM_INT is not a [`PlanItem`], as the MISSION_ACK result to answer with.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum PlanItemError {
    /// Not a waypoint or land command.
    #[error("unsupported mission command {command:?}")]
    Unsupported { command: MavCmd },
    /// Not `MAV_FRAME_GLOBAL`.
    #[error("unsupported frame {frame:?}")]
    UnsupportedFrame { frame: mc::MavFrame },
    /// Latitude, longitude, altitude or heading out of range.
    #[error("invalid value in parameter {param}")]
    Invalid { param: u8 },
}

impl PlanItemError {
    pub(super) fn result(self) -> MavMissionResult {
        match self {
            Self::Unsupported { .. } => MavMissionResult::MAV_MISSION_UNSUPPORTED,
            Self::UnsupportedFrame { .. } => MavMissionResult::MAV_MISSION_UNSUPPORTED_FRAME,
            Self::Invalid { param: 4 } => MavMissionResult::MAV_MISSION_INVALID_PARAM4,
            Self::Invalid { param: 5 } => MavMissionResult::MAV_MISSION_INVALID_PARAM5_X,
            Self::Invalid { param: 6 } => MavMissionResult::MAV_MISSION_INVALID_PARAM6_Y,
            Self::Invalid { param: 7 } => MavMissionResult::MAV_MISSION_INVALID_PARAM7,
            Self::Invalid { .. } => MavMissionResult::MAV_MISSION_INVALID,
        }
    }
}

impl PlanItem {
    /// The MISSION_ITEM_INT carrying this item at `seq`.
    pub fn to_mavlink(&self, target: (u8, u8), seq: u16) -> MavMessage {
        let (command, lat, lon, alt, p4) = match *self {
            Self::Waypoint {
                lat_deg,
                lon_deg,
                alt_msl_m,
            } => (
                MavCmd::MAV_CMD_NAV_WAYPOINT,
                lat_deg,
                lon_deg,
                alt_msl_m,
                0.0,
            ),
            Self::Land {
                lat_deg,
                lon_deg,
                alt_msl_m,
                approach_heading_deg,
            } => (
                MavCmd::MAV_CMD_NAV_LAND,
                lat_deg,
                lon_deg,
                alt_msl_m,
                approach_heading_deg.map_or(f32::NAN, |h| h as f32),
            ),
        };
        MavMessage::MISSION_ITEM_INT(mc::MISSION_ITEM_INT_DATA {
            param1: 0.0,
            param2: 0.0,
            param3: 0.0,
            param4: p4,
            x: (lat * 1e7).round() as i32,
            y: (lon * 1e7).round() as i32,
            z: alt as f32,
            seq,
            command,
            target_system: target.0,
            target_component: target.1,
            frame: mc::MavFrame::MAV_FRAME_GLOBAL,
            current: u8::from(seq == 0),
            autocontinue: 1,
            mission_type: mc::MavMissionType::MAV_MISSION_TYPE_MISSION,
        })
    }

    /// The item a MISSION_ITEM_INT carries.
    pub fn from_mavlink(m: &mc::MISSION_ITEM_INT_DATA) -> Result<PlanItem, PlanItemError> {
        #[allow(deprecated)] // MAV_FRAME_GLOBAL_INT: deprecated synonym older senders use.
        let frame_ok = m.frame == mc::MavFrame::MAV_FRAME_GLOBAL
            || m.frame == mc::MavFrame::MAV_FRAME_GLOBAL_INT;
        if !matches!(
            m.command,
            MavCmd::MAV_CMD_NAV_WAYPOINT | MavCmd::MAV_CMD_NAV_LAND
        ) {
            return Err(PlanItemError::Unsupported { command: m.command });
        }
        if !frame_ok {
            return Err(PlanItemError::UnsupportedFrame { frame: m.frame });
        }
        let (lat_deg, lon_deg) = (f64::from(m.x) / 1e7, f64::from(m.y) / 1e7);
        if !(-90.0..=90.0).contains(&lat_deg) {
            return Err(PlanItemError::Invalid { param: 5 });
        }
        if !(-180.0..=180.0).contains(&lon_deg) {
            return Err(PlanItemError::Invalid { param: 6 });
        }
        if !m.z.is_finite() {
            return Err(PlanItemError::Invalid { param: 7 });
        }
        let alt_msl_m = f64::from(m.z);
        Ok(match m.command {
            MavCmd::MAV_CMD_NAV_LAND => {
                let approach_heading_deg = if m.param4.is_nan() {
                    None
                } else if m.param4.is_finite() && (-360.0..=360.0).contains(&m.param4) {
                    Some(f64::from(m.param4).rem_euclid(360.0))
                } else {
                    return Err(PlanItemError::Invalid { param: 4 });
                };
                PlanItem::Land {
                    lat_deg,
                    lon_deg,
                    alt_msl_m,
                    approach_heading_deg,
                }
            }
            _ => PlanItem::Waypoint {
                lat_deg,
                lon_deg,
                alt_msl_m,
            },
        })
    }
}

impl super::mission::MissionItem for PlanItem {
    const MISSION_TYPE: mc::MavMissionType = mc::MavMissionType::MAV_MISSION_TYPE_MISSION;
    type Error = PlanItemError;

    fn to_mavlink(&self, target: (u8, u8), seq: u16) -> MavMessage {
        PlanItem::to_mavlink(self, target, seq)
    }

    fn from_mavlink(m: &mc::MISSION_ITEM_INT_DATA) -> Result<Self, PlanItemError> {
        PlanItem::from_mavlink(m)
    }

    fn refusal(error: &PlanItemError) -> MavMissionResult {
        error.result()
    }
}
