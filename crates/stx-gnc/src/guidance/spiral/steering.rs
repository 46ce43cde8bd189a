//! What each phase flies: the line to the entry corner, the branch lines, the final approach
//! and the flare, the heading to the best reachable point.

use stx_types::controls::Controls;

use super::final_approach::FinalApproach;
use super::pattern::branch_index;
use super::phases::PhaseMachine;
use super::situation::Situation;
use crate::control::{self, Localizer, TurnLatch};
use crate::estimate::Estimate;
use crate::guidance::config::GuidanceConfig;
use crate::mission::GuidancePhase;

/// Servo commands for the phase `machine` is in (after this update's decision), in situation
/// `s`; `final_approach` keeps the final's memory.
pub(super) fn steer(
    machine: &PhaseMachine,
    final_approach: &mut FinalApproach,
    config: &GuidanceConfig,
    s: &Situation,
    est: &Estimate,
    density: f64,
    latch: &mut TurnLatch,
) -> Controls {
    let gains = &config.gains;
    let position = s.position;
    let mut horizontal = |line: &Localizer| {
        control::localizer(
            gains,
            &mut *latch,
            line,
            position,
            est.course_rad,
            est.heading_rate_rad_s,
        )
        .main_line_m
    };
    let branch_line = |k: usize| {
        s.pattern
            .branch_line(k, machine.base_x_m, machine.base_join_x_m)
    };
    match machine.phase {
        GuidancePhase::Idle | GuidancePhase::Landed => Controls::default(),
        GuidancePhase::Approximation => {
            let k = branch_index(machine.entry_branch).unwrap_or(0);
            let corner = s.pattern.frame.to_ne(s.pattern.corner(k));
            let from = machine.approach_from_ne_m.unwrap_or(position);
            let line = if (corner[0] - from[0]).hypot(corner[1] - from[1]) > 1.0 {
                Localizer::through(from, corner)
            } else {
                branch_line(k)
            };
            Controls {
                main_line_m: horizontal(&line),
                ..Controls::default()
            }
        }
        GuidancePhase::Branch1
        | GuidancePhase::Branch2
        | GuidancePhase::Branch3
        | GuidancePhase::Branch4 => {
            let k = branch_index(machine.phase).unwrap_or(0);
            Controls {
                main_line_m: horizontal(&branch_line(k)),
                ..Controls::default()
            }
        }
        GuidancePhase::FinalApproach => final_approach.fly(
            config,
            &s.final_approach,
            est,
            position,
            s.ground_m,
            density,
        ),
        GuidancePhase::Flare if !machine.flare_off_line => {
            final_approach.flare(config, &s.final_approach, est, position)
        }
        GuidancePhase::BestReachable if s.reach.best_moved => {
            to_clear_point(config, s, est, density, latch)
        }
        GuidancePhase::Flare | GuidancePhase::BestReachable => {
            let brake = if machine.phase == GuidancePhase::Flare {
                1.0
            } else {
                0.0
            };
            Controls {
                main_line_m: control::heading(
                    gains,
                    latch,
                    est.heading_rad,
                    est.heading_rate_rad_s,
                    s.reach
                        .heading_rad(s.lowest_body_height, s.final_approach.course_rad),
                ),
                brake_right: brake,
                brake_left: brake,
            }
        }
    }
}

/// Commands on the way to a best reachable point moved clear of a keep-out zone. That point lies
/// inside the glide's circle, not on it, so the glide that reaches the nearest point overflies
/// it: Monte Carlo seed 12 run 726 was over its point (68 m E, past a road 35–47 m E) 70 m up
/// and glided on into the wind onto the road. So the brakes take the glide over the ground
/// down to what ends on the point (as the final's glide inversion), on the course to it, and
/// into the wind for the last stretch, as on the way to an unmoved point.
fn to_clear_point(
    config: &GuidanceConfig,
    s: &Situation,
    est: &Estimate,
    density: f64,
    latch: &mut TurnLatch,
) -> Controls {
    let perf = &config.performance;
    let aim = s.reach.best_ne(s.target_ne());
    let into_wind = s.lowest_body_height < super::reach::INTO_WIND_BELOW_M;
    let (course, to_go) = if into_wind {
        let line = Localizer {
            point_ne_m: aim,
            course_rad: s.final_approach.course_rad,
        };
        (s.final_approach.course_rad, -line.along_track_m(s.position))
    } else {
        let to = [aim[0] - s.position[0], aim[1] - s.position[1]];
        (to[1].atan2(to[0]), to[0].hypot(to[1]))
    };
    let wind = s.wind.measured_ne_mps;
    let headwind = -(wind[0] * course.cos() + wind[1] * course.sin());
    // On a course 60° off the wind (seed 12 run 726 of the keep-out campaign), brakes set for
    // the headwind alone left too little airspeed for the crab and the stack fell off its way.
    let crosswind = -wind[0] * course.sin() + wind[1] * course.cos();
    let height = s.final_approach.height_to_flare;
    let brake = if height <= 0.0 {
        0.0
    } else if to_go <= 0.0 {
        1.0
    } else {
        perf.brake_for_course_glide(to_go / height, headwind, crosswind, density)
    };
    Controls {
        main_line_m: control::course(
            &config.gains,
            latch,
            est.course_rad,
            est.heading_rate_rad_s,
            course,
        ),
        brake_right: brake,
        brake_left: brake,
    }
}
