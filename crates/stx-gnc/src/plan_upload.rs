//! An uploaded mission plan (waypoints and a landing point) turned into guidance's [`Plan`]:
//! one mapping, used by the drone that flies the plan and by the ground station's guidance
//! replica that must fly it the same way to draw and predict it.
//!
//! The rule (the seed's two-point localizer, §5.1.3):
//! - the `Land` point sets the landing target and the final-approach course (`None`: into the
//!   wind);
//! - the first two waypoints, or a single waypoint and the landing point, set the localizer
//!   line from the first towards the second; if the second is lower, the drop over the
//!   distance is the glide slope followed down the line;
//! - points less than [`MIN_LINE_M`] apart define no line: the localizer is left as it was;
//! - everything the plan does not mention (heading, course, and the target or the line when
//!   absent) stays as it was.
//!
//! Points arrive in the mission's local frame (north, east, down; m), converted from the
//! wire's latitude and longitude by the caller with its own [`crate::geo::LocalFrame`] (the
//! link's plan protocol does it, into [`PlanPoint`]s).

use crate::control::Localizer;
use crate::guidance::Plan;
// The link reads plan items off the wire without guidance, so the item type is a shared one.
pub use stx_types::plan::PlanPoint;
use stx_types::rotation::wrap_pi;

/// Two localizer points closer than this define no line, m.
pub const MIN_LINE_M: f64 = 1.0;

/// What an upload changed in the localizer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LineChange {
    /// The plan has no localizer points: the line is unchanged.
    None,
    /// A new line (and glide slope, if the points descend).
    Set,
    /// The points coincide: no line can be drawn through them, the old one stays.
    PointsCoincide,
}

/// The plan after an upload, and what the upload set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanUpdate {
    /// The plan to fly.
    pub plan: Plan,
    /// The landing target (and approach) came from the upload.
    pub target_set: bool,
    /// What happened to the localizer line.
    pub line: LineChange,
}

/// Applies the items of an upload to the plan in force.
pub fn apply(current: &Plan, items: &[PlanPoint]) -> PlanUpdate {
    let mut plan = *current;
    let mut waypoints = Vec::new();
    let mut land = None;
    for item in items {
        match *item {
            PlanPoint::Waypoint { position_ned_m } => waypoints.push(position_ned_m),
            PlanPoint::Land {
                position_ned_m,
                approach_course_rad,
            } => land = Some((position_ned_m, approach_course_rad)),
        }
    }
    if let Some((target, approach)) = land {
        plan.target_ned_m = target;
        plan.approach_course_rad = approach.map(wrap_pi);
    }
    let ends = match (waypoints.as_slice(), land) {
        ([a, b, ..], _) => Some((*a, *b)),
        ([a], Some((t, _))) => Some((*a, t)),
        _ => None,
    };
    let line = match ends {
        None => LineChange::None,
        Some((a, b)) => {
            let distance = (b.x - a.x).hypot(b.y - a.y);
            if distance > MIN_LINE_M {
                plan.localizer = Localizer::through([a.x, a.y], [b.x, b.y]);
                // Down is positive: a second point below the first means a descent.
                let drop = b.z - a.z;
                plan.localizer_glide_slope = (drop > 0.0).then_some(drop / distance);
                LineChange::Set
            } else {
                LineChange::PointsCoincide
            }
        }
    };
    PlanUpdate {
        plan,
        target_set: land.is_some(),
        line,
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;

    use super::*;

    fn waypoint(n: f64, e: f64, d: f64) -> PlanPoint {
        PlanPoint::Waypoint {
            position_ned_m: Vector3::new(n, e, d),
        }
    }

    #[test]
    fn the_landing_point_sets_the_target_and_approach_and_nothing_else() {
        let current = Plan {
            heading_rad: 1.0,
            ..Plan::default()
        };
        let u = apply(
            &current,
            &[PlanPoint::Land {
                position_ned_m: Vector3::new(300.0, 2500.0, 0.0),
                approach_course_rad: Some(4.0),
            }],
        );
        assert!(u.target_set);
        assert_eq!(u.line, LineChange::None);
        assert_eq!(u.plan.target_ned_m, Vector3::new(300.0, 2500.0, 0.0));
        // Wrapped into (−π, π].
        assert!(
            (u.plan.approach_course_rad.expect("approach") - (4.0 - std::f64::consts::TAU)).abs()
                < 1e-12
        );
        assert_eq!(u.plan.heading_rad, 1.0);
        assert_eq!(u.plan.localizer, current.localizer);
    }

    #[test]
    fn two_waypoints_make_a_localizer_with_the_glide_slope_of_their_drop() {
        let u = apply(
            &Plan::default(),
            &[waypoint(0.0, 0.0, -300.0), waypoint(0.0, 1000.0, -200.0)],
        );
        assert_eq!(u.line, LineChange::Set);
        assert!(!u.target_set);
        assert!((u.plan.localizer.course_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert_eq!(u.plan.localizer.point_ne_m, [0.0, 0.0]);
        assert!((u.plan.localizer_glide_slope.expect("slope") - 0.1).abs() < 1e-12);
    }

    #[test]
    fn one_waypoint_and_the_landing_point_make_the_line_and_a_climb_has_no_slope() {
        let u = apply(
            &Plan::default(),
            &[
                waypoint(-1000.0, 0.0, 10.0),
                PlanPoint::Land {
                    position_ned_m: Vector3::new(0.0, 0.0, 0.0),
                    approach_course_rad: None,
                },
            ],
        );
        assert_eq!(u.line, LineChange::Set);
        assert!(u.target_set);
        assert!(u.plan.localizer.course_rad.abs() < 1e-12, "north");
        assert_eq!(u.plan.localizer_glide_slope, None);
    }

    #[test]
    fn coincident_points_leave_the_line_alone() {
        let current = Plan::default();
        let u = apply(
            &current,
            &[waypoint(5.0, 5.0, 0.0), waypoint(5.0, 5.5, -10.0)],
        );
        assert_eq!(u.line, LineChange::PointsCoincide);
        assert_eq!(u.plan, current);
    }
}
