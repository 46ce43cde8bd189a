//! An item of an uploaded mission plan (a waypoint or the landing point) in the mission's
//! local frame: what the link reads off the wire and guidance turns into its plan
//! (`stx_gnc::plan_upload::apply`, on the drone and in the station's replica alike).

use nalgebra::Vector3;

/// One item of an uploaded plan, in the local frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PlanPoint {
    /// A localizer point, NED, m.
    Waypoint {
        /// Position, NED, m.
        position_ned_m: Vector3<f64>,
    },
    /// The landing point, NED, m, with the final-approach course (rad; `None`: into the wind).
    Land {
        /// Position, NED, m.
        position_ned_m: Vector3<f64>,
        /// Course of the final approach, rad.
        approach_course_rad: Option<f64>,
    },
}
