//! What the onboard guidance knows and intends: the wind estimate ([`Wind`], WIND_COV), the
//! controller's state ([`GuidanceStatus`], NAV_CONTROLLER_OUTPUT) and the predicted touchdown
//! point ([`PredictedLanding`], POSITION_TARGET_GLOBAL_INT, chosen as the
//! [module documentation](super) explains).

use mavlink::dialects::common as mc;
use mavlink::dialects::common::MavMessage;
use serde::{Deserialize, Serialize};

use super::units::{deg_to_e7, e7_to_deg, nan_to_none, none_to_nan};

/// Onboard wind estimate (WIND_COV).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct Wind {
    /// Time, µs.
    pub time_usec: u64,
    /// Wind towards north, m/s (NED), `None` if unknown.
    pub wind_north_mps: Option<f64>,
    /// Wind towards east, m/s.
    pub wind_east_mps: Option<f64>,
    /// Wind down, m/s.
    pub wind_down_mps: Option<f64>,
    /// Horizontal variability, 1-σ m/s (wire `var_horiz`).
    pub var_horiz_mps: Option<f64>,
    /// Vertical variability, 1-σ m/s (wire `var_vert`).
    pub var_vert_mps: Option<f64>,
    /// Altitude MSL of the estimate, m.
    pub alt_msl_m: Option<f64>,
    /// Horizontal speed accuracy, 1-σ m/s (0 = unknown).
    pub horiz_accuracy_mps: f64,
    /// Vertical speed accuracy, 1-σ m/s (0 = unknown).
    pub vert_accuracy_mps: f64,
}

impl Wind {
    /// The WIND_COV carrying it.
    pub(super) fn to_mavlink(self) -> MavMessage {
        MavMessage::WIND_COV(mc::WIND_COV_DATA {
            time_usec: self.time_usec,
            wind_x: none_to_nan(self.wind_north_mps),
            wind_y: none_to_nan(self.wind_east_mps),
            wind_z: none_to_nan(self.wind_down_mps),
            var_horiz: none_to_nan(self.var_horiz_mps),
            var_vert: none_to_nan(self.var_vert_mps),
            wind_alt: none_to_nan(self.alt_msl_m),
            horiz_accuracy: self.horiz_accuracy_mps as f32,
            vert_accuracy: self.vert_accuracy_mps as f32,
        })
    }

    /// What a WIND_COV carries.
    pub(super) fn from_mavlink(w: &mc::WIND_COV_DATA) -> Self {
        Wind {
            time_usec: w.time_usec,
            wind_north_mps: nan_to_none(w.wind_x),
            wind_east_mps: nan_to_none(w.wind_y),
            wind_down_mps: nan_to_none(w.wind_z),
            var_horiz_mps: nan_to_none(w.var_horiz),
            var_vert_mps: nan_to_none(w.var_vert),
            alt_msl_m: nan_to_none(w.wind_alt),
            horiz_accuracy_mps: f64::from(w.horiz_accuracy),
            vert_accuracy_mps: f64::from(w.vert_accuracy),
        }
    }
}

/// Guidance state (NAV_CONTROLLER_OUTPUT).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct GuidanceStatus {
    /// Roll the controller asks for, degrees.
    pub desired_roll_deg: f64,
    /// Heading the controller asks for, whole degrees.
    pub desired_heading_deg: f64,
    /// Bearing from the vehicle to the target, whole degrees.
    pub bearing_to_target_deg: f64,
    /// Distance to the target, whole metres 0…65 535 (saturates).
    pub distance_to_target_m: f64,
    /// Altitude error (desired − actual), m.
    pub alt_error_m: f64,
    /// Cross-track error, m (positive right of the track).
    pub xtrack_error_m: f64,
}

impl GuidanceStatus {
    /// The NAV_CONTROLLER_OUTPUT carrying it.
    pub(super) fn to_mavlink(self) -> MavMessage {
        MavMessage::NAV_CONTROLLER_OUTPUT(mc::NAV_CONTROLLER_OUTPUT_DATA {
            nav_roll: self.desired_roll_deg as f32,
            nav_pitch: 0.0,
            alt_error: self.alt_error_m as f32,
            aspd_error: 0.0,
            xtrack_error: self.xtrack_error_m as f32,
            nav_bearing: self.desired_heading_deg.round() as i16,
            target_bearing: self.bearing_to_target_deg.round() as i16,
            wp_dist: self.distance_to_target_m.round() as u16,
        })
    }

    /// What a NAV_CONTROLLER_OUTPUT carries.
    pub(super) fn from_mavlink(n: &mc::NAV_CONTROLLER_OUTPUT_DATA) -> Self {
        GuidanceStatus {
            desired_roll_deg: f64::from(n.nav_roll),
            desired_heading_deg: f64::from(n.nav_bearing),
            bearing_to_target_deg: f64::from(n.target_bearing),
            distance_to_target_m: f64::from(n.wp_dist),
            alt_error_m: f64::from(n.alt_error),
            xtrack_error_m: f64::from(n.xtrack_error),
        }
    }
}

/// The onboard prediction of the touchdown point (POSITION_TARGET_GLOBAL_INT; see the
/// [module documentation](super)).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct PredictedLanding {
    /// Time since boot, ms.
    pub time_boot_ms: u32,
    /// Latitude, degrees (wire: degE7).
    pub lat_deg: f64,
    /// Longitude, degrees (wire: degE7).
    pub lon_deg: f64,
    /// Altitude MSL of the touchdown point, m (wire: f32).
    pub alt_msl_m: f64,
}

/// Type mask of the predicted-landing POSITION_TARGET_GLOBAL_INT: everything but position
/// ignored.
fn predicted_landing_mask() -> mc::PositionTargetTypemask {
    use mc::PositionTargetTypemask as M;
    M::POSITION_TARGET_TYPEMASK_VX_IGNORE
        | M::POSITION_TARGET_TYPEMASK_VY_IGNORE
        | M::POSITION_TARGET_TYPEMASK_VZ_IGNORE
        | M::POSITION_TARGET_TYPEMASK_AX_IGNORE
        | M::POSITION_TARGET_TYPEMASK_AY_IGNORE
        | M::POSITION_TARGET_TYPEMASK_AZ_IGNORE
        | M::POSITION_TARGET_TYPEMASK_YAW_IGNORE
        | M::POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE
}

impl PredictedLanding {
    /// The POSITION_TARGET_GLOBAL_INT carrying it.
    pub(super) fn to_mavlink(self) -> MavMessage {
        MavMessage::POSITION_TARGET_GLOBAL_INT(mc::POSITION_TARGET_GLOBAL_INT_DATA {
            time_boot_ms: self.time_boot_ms,
            lat_int: deg_to_e7(self.lat_deg),
            lon_int: deg_to_e7(self.lon_deg),
            alt: self.alt_msl_m as f32,
            vx: 0.0,
            vy: 0.0,
            vz: 0.0,
            afx: 0.0,
            afy: 0.0,
            afz: 0.0,
            yaw: 0.0,
            yaw_rate: 0.0,
            type_mask: predicted_landing_mask(),
            coordinate_frame: mc::MavFrame::MAV_FRAME_GLOBAL,
        })
    }

    /// What a POSITION_TARGET_GLOBAL_INT carries, `None` when it is not stx telemetry.
    pub(super) fn from_mavlink(p: &mc::POSITION_TARGET_GLOBAL_INT_DATA) -> Option<Self> {
        use mc::PositionTargetTypemask as M;
        let position_ignored = M::POSITION_TARGET_TYPEMASK_X_IGNORE
            | M::POSITION_TARGET_TYPEMASK_Y_IGNORE
            | M::POSITION_TARGET_TYPEMASK_Z_IGNORE;
        if p.coordinate_frame != mc::MavFrame::MAV_FRAME_GLOBAL
            || p.type_mask.intersects(position_ignored)
        {
            return None;
        }
        Some(PredictedLanding {
            time_boot_ms: p.time_boot_ms,
            lat_deg: e7_to_deg(p.lat_int),
            lon_deg: e7_to_deg(p.lon_int),
            alt_msl_m: f64::from(p.alt),
        })
    }
}
