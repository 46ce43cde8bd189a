//! What the operator asked guidance to fly: the landing target and approach course, the
//! heading and course held, the localizer and its glide slope.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::control::{GlidePath, Localizer};
use crate::keep_out::KeepOutZones;

/// Why a plan was refused.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PlanRefused {
    /// The landing target lies in a keep-out zone.
    #[error(
        "the landing target ({north_m:.0} m N, {east_m:.0} m E) lies in keep-out zone '{zone}': choose a target outside it"
    )]
    TargetInZone {
        /// The zone's name.
        zone: String,
        /// The target, north of the frame's origin, m.
        north_m: f64,
        /// The target, east of the frame's origin, m.
        east_m: f64,
    },
}

/// What the operator asked to fly: targets of every mode.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Plan {
    /// Landing target on the ground, local NED, m.
    pub target_ned_m: Vector3<f64>,
    /// Course of the final approach, rad; `None` lands into the wind.
    pub approach_course_rad: Option<f64>,
    /// Heading held in heading mode, rad.
    pub heading_rad: f64,
    /// Course held in course mode, rad.
    pub course_rad: f64,
    /// Line followed in localizer mode.
    pub localizer: Localizer,
    /// Glide slope (sink over ground speed) followed down the localizer to its point, if any.
    pub localizer_glide_slope: Option<f64>,
}

impl Plan {
    /// Refuses a plan whose landing target lies in one of `zones` (the station asks before
    /// sending a plan; guidance before flying one, [`Guidance::try_set_plan`](super::Guidance::try_set_plan)).
    pub fn check_keep_out(&self, zones: &KeepOutZones) -> Result<(), PlanRefused> {
        let target = [self.target_ned_m.x, self.target_ned_m.y];
        match zones.zone_at(target) {
            Some(zone) => Err(PlanRefused::TargetInZone {
                zone: zone.name.clone(),
                north_m: target[0],
                east_m: target[1],
            }),
            None => Ok(()),
        }
    }

    /// The glide path localizer mode flies when the plan has a glide slope: down the localizer
    /// to its point, ending with the lowest hanging body — `hang_height_m` below the drone — on
    /// the target's ground. Aimed with the drone, the stack touched down the hang height's glide
    /// short of the point (13 m on `vertical`). Guidance flies it, and the tuner measures the
    /// vertical law's error against it.
    pub fn localizer_glide_path(&self, hang_height_m: f64) -> Option<GlidePath> {
        self.localizer_glide_slope.map(|slope| GlidePath {
            line: self.localizer,
            aim_height_m: -self.target_ned_m.z + hang_height_m,
            slope,
        })
    }
}

impl Default for Plan {
    fn default() -> Self {
        Self {
            target_ned_m: Vector3::zeros(),
            approach_course_rad: None,
            heading_rad: 0.0,
            course_rad: 0.0,
            localizer: Localizer {
                point_ne_m: [0.0, 0.0],
                course_rad: 0.0,
            },
            localizer_glide_slope: None,
        }
    }
}
