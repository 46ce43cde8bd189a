//! The final approach and the flare: the final line through the target, into the wind; how
//! much height there is beyond what full brakes can take off before the flare; the brakes set
//! by the chosen [`FinalLaw`]; S-turns across the line while far too high; full brakes below
//! the flare height.

use stx_types::controls::Controls;
use stx_types::rotation::wrap_pi;

use super::config::{FinalLaw, SpiralConfig};
use super::energy::Energy;
use super::pattern::WindFrame;
use crate::control::{self, GlidePath, Localizer, TurnLatch};
use crate::estimate::Estimate;
use crate::guidance::config::GuidanceConfig;
use crate::performance::GlidePerformance;

/// Height above the steepest glide on final at which S-turns start in light air, m. A few
/// metres: there full brakes steepen the glide by only a seventh (1.75 against 2.04 in still
/// air), so each metre of height they cannot take off lands nearly two metres long (10 m here
/// left the long finals of the realistic Monte Carlo; the comparison is in GNC_NOTES.md).
const S_TURN_EXCESS_M: f64 = 5.0;
/// Headwind up to which S-turns start at [`S_TURN_EXCESS_M`], m/s.
const S_TURN_LIGHT_WIND_MPS: f64 = 1.5;
/// Height the S-turns' start rises by per m/s of headwind beyond that, m per m/s.
const S_TURN_EXCESS_PER_WIND_M_PER_MPS: f64 = 3.5;
/// Highest height above the full-brake glide at which S-turns start, m.
const S_TURN_EXCESS_MAX_M: f64 = 10.0;
/// S-turns swing this far either side of the final line, m.
const S_TURN_HALF_WIDTH_M: f64 = 40.0;
/// Course offset of an S-turn leg from the final course, rad (100°: slightly back downwind).
const S_TURN_ANGLE_RAD: f64 = 1.7453;
/// Time constant of the learned glide correction on final, s: long against gusts and the
/// brakes' own transient (≈ 2 s), short against a final of a minute or more.
const GLIDE_LEARN_TIME_S: f64 = 8.0;
/// The learned correction stays within this of the polar's glide over the ground.
const GLIDE_CORRECTION_LIMIT: f64 = 0.4;
/// Heading rate above which the glide is not learned (turning, not gliding), rad/s.
const GLIDE_LEARN_MAX_TURN_RAD_S: f64 = 0.1;
/// Sink rate below which the measured glide is not learned (a flare, a thermal), m/s.
const GLIDE_LEARN_MIN_SINK_MPS: f64 = 1.0;

/// Ground speed the way the stack faces below which its course over the ground no longer says
/// where it is pointed, m/s (`steered_rad`).
const MIN_HEADWAY_MPS: f64 = 0.5;

/// The final approach's geometry and energy at one update.
#[derive(Debug, Clone, Copy)]
pub(super) struct FinalGeometry {
    /// Course of the final approach (upwind), rad.
    pub(super) course_rad: f64,
    /// The final-approach line, through the target.
    pub(super) line: Localizer,
    /// Measured wind along the pattern's axis: the final's headwind, m/s.
    headwind_mps: f64,
    /// Glide over the ground with full brakes into that headwind (≥ 0).
    flare_glide: f64,
    /// Distance left along the final to the aim point (the flare's start), m.
    to_go_before_flare: f64,
    /// Height of the lowest body above the flare height, m.
    pub(super) height_to_flare: f64,
    /// Height beyond what full brakes can take off before the flare, the way across to the
    /// line included, m (−∞ when full brakes hold the stack still over the ground).
    pub(super) excess_m: f64,
}

impl FinalGeometry {
    /// The final for the pattern's axis in `frame`, the vehicle at `position` (north, east, m)
    /// and `height` m above the target's ground.
    pub(super) fn assess(
        sc: &SpiralConfig,
        perf: &GlidePerformance,
        density: f64,
        frame: &WindFrame,
        energy: &Energy,
        position: [f64; 2],
        height: f64,
    ) -> Self {
        let w_along_measured = energy.wind_along_mps;
        // The final approach's energy: how far to go before the flare, and how much height there
        // is beyond what even full brakes can take off in that distance.
        let final_course = wrap_pi(frame.downwind_rad + std::f64::consts::PI);
        let final_line = Localizer {
            point_ne_m: frame.target_ne,
            course_rad: final_course,
        };
        let flare_glide = perf.ground_glide(1.0, w_along_measured, density).max(0.0);
        let to_go_before_flare = -final_line.along_track_m(position)
            - flare_glide * sc.flare_height_m
            + aim_beyond_m(sc, perf, w_along_measured, density);
        let height_to_flare = height - sc.hang_height_m - sc.flare_height_m;
        // The way across to the line, if not on it yet, is flown too (brakes released).
        let across_m = final_line.cross_track_m(position).abs();
        let across_height_m = energy.s0 * across_m / energy.g_cross;
        let final_excess_m = if flare_glide > 1e-3 {
            height_to_flare - across_height_m - to_go_before_flare.max(0.0) / flare_glide
        } else {
            // Full brakes hold the stack still over the ground or back: no height is too much.
            f64::NEG_INFINITY
        };
        Self {
            course_rad: final_course,
            line: final_line,
            headwind_mps: w_along_measured,
            flare_glide,
            to_go_before_flare,
            height_to_flare,
            excess_m: final_excess_m,
        }
    }
}

/// What the final approach remembers between updates.
#[derive(Debug, Clone, Copy)]
pub(super) struct FinalApproach {
    /// The last brake set, held to the ground when not flaring.
    last_brake: f64,
    /// Side the S-turns swing to.
    weave_right: bool,
    /// Slope of the glide path on this final approach (seed's GS0), fixed at the turn onto
    /// it, with [`FinalLaw::GlideSlope`].
    slope: Option<f64>,
    /// Glide over the ground flown on this final minus what the polar gives for the brake and
    /// headwind flown (low-passed), added to the polar's glide when choosing the brake.
    glide_correction: f64,
    /// Estimate time of the last update on final, s.
    last_time_s: Option<f64>,
    /// The side of a turn onto the final's line from nearly behind.
    turn_latch: TurnLatch,
    /// Steering on the heading, not the course (`steered_rad`).
    on_heading: bool,
}

impl Default for FinalApproach {
    fn default() -> Self {
        Self {
            last_brake: 0.0,
            weave_right: true,
            slope: None,
            glide_correction: 0.0,
            last_time_s: None,
            turn_latch: TurnLatch::default(),
            on_heading: false,
        }
    }
}

impl FinalApproach {
    /// Commands on the final approach for the estimate `est` at `position` (north, east, m),
    /// the target's ground `ground_m` high.
    pub(super) fn fly(
        &mut self,
        config: &GuidanceConfig,
        geometry: &FinalGeometry,
        est: &Estimate,
        position: [f64; 2],
        ground_m: f64,
        density: f64,
    ) -> Controls {
        let sc = &config.spiral;
        let perf = &config.performance;
        let gains = &config.gains;
        let FinalGeometry {
            course_rad: final_course,
            line: final_line,
            headwind_mps: w_along_measured,
            flare_glide,
            to_go_before_flare,
            height_to_flare,
            excess_m: final_excess_m,
        } = *geometry;
        let target_ne = final_line.point_ne_m;
        // Far enough above the full-brake glide to burn the height in S-turns, off the line.
        let weave = final_excess_m > s_turn_excess_m(w_along_measured);
        self.learn_glide(perf, est, final_course, w_along_measured, density, weave);
        let brake = if height_to_flare <= 0.0 || to_go_before_flare <= 0.0 {
            if sc.flare { 1.0 } else { self.last_brake }
        } else {
            match sc.final_law {
                // The brake whose glide over the ground ends the descent on the aim
                // point, recomputed every update (a closed loop on the predicted
                // touchdown). The aim is the flare's start: the flare's own glide, at
                // full brake, carries the stack the rest of the way. Planned for the
                // wind as measured: planned for the decisions' headwind margin, the
                // final kept height in hand and spent it late, which saved the odd
                // final caught by a strengthening wind but cost more elsewhere (the
                // Monte Carlo comparison is in GNC_NOTES.md).
                //
                // The polar's glide is corrected by what this final has flown
                // (`learn_glide`): a closed loop on the polar alone held the brakes on
                // while the stack sank faster than the polar says (gusts, the brakes'
                // working) and fell 20–40 m short into strong headwinds.
                FinalLaw::GlideInversion => perf.brake_for_ground_glide(
                    to_go_before_flare / height_to_flare - self.glide_correction,
                    w_along_measured,
                    density,
                ),
                // The seed's vertical law (eqs. 5.12–5.17): a straight glide path
                // through the aim point, its slope GS0 the geometry at the turn onto
                // the final, flown about the brake that holds GS0 in the wind planned
                // with (the performance model's feed-forward).
                FinalLaw::GlideSlope => {
                    let slope = *self
                        .slope
                        .get_or_insert((height_to_flare / to_go_before_flare).clamp(0.05, 20.0));
                    let beyond = aim_beyond_m(sc, perf, geometry.headwind_mps, density)
                        - flare_glide * sc.flare_height_m;
                    let aim_ne = [
                        target_ne[0] + beyond * final_course.cos(),
                        target_ne[1] + beyond * final_course.sin(),
                    ];
                    let path = GlidePath {
                        line: Localizer {
                            point_ne_m: aim_ne,
                            course_rad: final_course,
                        },
                        aim_height_m: ground_m + sc.hang_height_m + sc.flare_height_m,
                        slope,
                    };
                    let trim = perf.brake_for_ground_glide(1.0 / slope, w_along_measured, density);
                    control::vertical_about(
                        gains,
                        &path,
                        position,
                        est.height_m(),
                        [est.velocity_ned_mps.x, est.velocity_ned_mps.y],
                        est.sink_rate_mps,
                        trim,
                    )
                    .brake
                }
            }
        };
        // Horizontal: the final line; while far too high for even full brakes to
        // bring it down in time, S-turns across the line burn the height.
        self.last_brake = brake;
        let main_line_m = if weave {
            let ct = final_line.cross_track_m(position);
            if ct > S_TURN_HALF_WIDTH_M {
                self.weave_right = false;
            } else if ct < -S_TURN_HALF_WIDTH_M {
                self.weave_right = true;
            }
            let offset = if self.weave_right { 1.0 } else { -1.0 } * S_TURN_ANGLE_RAD;
            control::course(
                gains,
                &mut self.turn_latch,
                est.course_rad,
                est.heading_rate_rad_s,
                final_course + offset,
            )
        } else {
            follow(
                config,
                &mut self.turn_latch,
                &mut self.on_heading,
                &final_line,
                est,
                position,
            )
        };
        Controls {
            main_line_m,
            brake_right: brake,
            brake_left: brake,
        }
    }

    /// The flare: full brakes, still on the final line.
    pub(super) fn flare(
        &mut self,
        config: &GuidanceConfig,
        geometry: &FinalGeometry,
        est: &Estimate,
        position: [f64; 2],
    ) -> Controls {
        Controls {
            main_line_m: follow(
                config,
                &mut self.turn_latch,
                &mut self.on_heading,
                &geometry.line,
                est,
                position,
            ),
            brake_right: 1.0,
            brake_left: 1.0,
        }
    }

    /// Forgets the glide slope and what was learned of a final approach that has ended.
    pub(super) fn end(&mut self) {
        self.slope = None;
        self.glide_correction = 0.0;
        self.last_time_s = None;
    }

    /// Learns how far the glide over the ground flown along the final differs from the
    /// polar's for the brake held and the headwind measured: only in straight flight along
    /// the line (not in S-turns or turns, where the glide along the line is not the glide).
    fn learn_glide(
        &mut self,
        perf: &GlidePerformance,
        est: &Estimate,
        final_course: f64,
        headwind_mps: f64,
        density: f64,
        s_turning: bool,
    ) {
        let dt = match self.last_time_s.replace(est.time_s) {
            Some(t) => (est.time_s - t).max(0.0),
            None => return,
        };
        let straight = est.heading_rate_rad_s.abs() < GLIDE_LEARN_MAX_TURN_RAD_S
            && !s_turning
            && est.sink_rate_mps > GLIDE_LEARN_MIN_SINK_MPS;
        if !straight || dt <= 0.0 {
            return;
        }
        let along_mps = est.velocity_ned_mps.x * final_course.cos()
            + est.velocity_ned_mps.y * final_course.sin();
        let flown = along_mps / est.sink_rate_mps;
        let polar = perf.ground_glide(self.last_brake, headwind_mps, density);
        let gain = (dt / GLIDE_LEARN_TIME_S).min(1.0);
        self.glide_correction = (self.glide_correction
            + gain * (flown - polar - self.glide_correction))
            .clamp(-GLIDE_CORRECTION_LIMIT, GLIDE_CORRECTION_LIMIT);
    }
}

/// Height above the steepest glide on final at which S-turns start in a headwind of
/// `headwind_mps`, m. Into a strong wind full brakes have more say over the glide (a third of
/// it at 4 m/s), and an S-turn's leg off the wind is blown back fast: from 5 m there, finals
/// into 3–4 m/s were blown out of reach (seed 1, run 87: 4.5 → 139 m), and one S-turn at full
/// brakes ended in a spiral dive (run 277).
fn s_turn_excess_m(headwind_mps: f64) -> f64 {
    (S_TURN_EXCESS_M
        + S_TURN_EXCESS_PER_WIND_M_PER_MPS * (headwind_mps - S_TURN_LIGHT_WIND_MPS).max(0.0))
    .min(S_TURN_EXCESS_MAX_M)
}

/// How far beyond the target the first contact is aimed along the final, m: the setting's
/// `aim_beyond_m`, less the way the stack flies with full brakes into `headwind_mps` while it
/// sinks the payload's height after the transponder touched, so that the payload lands on the
/// target.
fn aim_beyond_m(
    sc: &SpiralConfig,
    perf: &GlidePerformance,
    headwind_mps: f64,
    density: f64,
) -> f64 {
    let flare_ground_speed = (perf.horizontal_airspeed(1.0, density) - headwind_mps).max(0.0);
    let payload_delay_s = sc.payload_height_m / perf.sink_rate(1.0, 0.0, density);
    sc.aim_beyond_m - flare_ground_speed * payload_delay_s
}

/// The main line that follows `line` (localizer control), steering on [`steered_rad`].
fn follow(
    config: &GuidanceConfig,
    latch: &mut TurnLatch,
    on_heading: &mut bool,
    line: &Localizer,
    est: &Estimate,
    position: [f64; 2],
) -> f64 {
    control::localizer(
        &config.gains,
        latch,
        line,
        position,
        steered_rad(on_heading, est),
        est.heading_rate_rad_s,
    )
    .main_line_m
}

/// The direction the final steers: the course over the ground while the stack makes headway
/// the way it faces, its heading through the air once it does not.
///
/// Why: in a wind stronger than the stack flies, the stack goes backwards and its course over
/// the ground points downwind while it faces the wind as it should. Steered on the course, the
/// final turned it round and ran downwind to the ground: seed 3 run 925 (realistic, 3.8 m/s
/// aloft, 5.4 m/s below 70 m) turned at 70 m, 26 m past the target, and landed its payload
/// 96 m away, 123° off the wind, touching down at 5.4 m/s.
fn steered_rad(on_heading: &mut bool, est: &Estimate) -> f64 {
    let headway_mps = est.velocity_ned_mps.x * est.heading_rad.cos()
        + est.velocity_ned_mps.y * est.heading_rad.sin();
    if headway_mps < MIN_HEADWAY_MPS {
        *on_heading = true;
    } else if headway_mps > 2.0 * MIN_HEADWAY_MPS {
        *on_heading = false;
    }
    if *on_heading {
        est.heading_rad
    } else {
        est.course_rad
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;

    use super::*;
    use crate::guidance::spiral::energy::Energy;
    use crate::guidance::spiral::pattern::WindFrame;
    use crate::pointmass::{Conditions, PointMass};

    /// A point mass flown straight up the final (north, into a 3.5 m/s north wind) at a fixed
    /// brake for 60 s; what the final approach learned of its glide.
    fn learned(sink_scale: f64, turning: bool) -> f64 {
        let perf = GlidePerformance::default();
        let wind = Vector3::new(-3.5, 0.0, 0.0);
        let air = Conditions {
            sink_scale,
            ..Conditions::nominal(wind, perf.reference_density_kg_per_m3)
        };
        let mut stack = PointMass::new(0.0, Vector3::new(-200.0, 0.0, -400.0), 0.0);
        let mut fa = FinalApproach {
            last_brake: 0.8,
            ..FinalApproach::default()
        };
        let controls = Controls {
            main_line_m: if turning { 0.02 } else { 0.0 },
            brake_right: 0.8,
            brake_left: 0.8,
        };
        for _ in 0..600 {
            stack.step(&perf, &controls, &air, 0.1);
            let est = stack.estimate(&wind);
            fa.learn_glide(&perf, &est, 0.0, 3.5, air.density_kg_per_m3, false);
        }
        fa.glide_correction
    }

    /// A point mass put on the final 150 m short of the target into a wind of `wind_mps`,
    /// `excess_m` higher than the polar says full brakes need to reach the flare's start, and
    /// flown by the final approach until its lowest body is at the flare height: how far it
    /// then is past the flare's start along the line (positive long), and how far it strayed
    /// from the line on the way, m.
    fn flown_to_the_flare(excess_m: f64, wind_mps: f64) -> (f64, f64) {
        let config = GuidanceConfig::default();
        let sc = &config.spiral;
        let perf = config.performance;
        let density = perf.reference_density_kg_per_m3;
        // Wind from the north: the final is flown north, the frame's downwind is south.
        let wind = Vector3::new(-wind_mps, 0.0, 0.0);
        let air = Conditions::nominal(wind, density);
        let frame = WindFrame::new([0.0, 0.0], std::f64::consts::PI);
        let energy = Energy::plan(sc, &perf, config.gains.brake_trim, density, wind_mps, 0.3);
        let geometry = |position: [f64; 2], height: f64| {
            FinalGeometry::assess(sc, &perf, density, &frame, &energy, position, height)
        };
        let start = [-150.0, 0.0];
        let height = excess_m - geometry(start, 0.0).excess_m;
        let mut stack = PointMass::new(0.0, Vector3::new(start[0], start[1], -height), 0.0);
        let mut fa = FinalApproach::default();
        let mut strayed: f64 = 0.0;
        for _ in 0..6000 {
            let est = stack.estimate(&wind);
            let position = [est.position_ned_m.x, est.position_ned_m.y];
            strayed = strayed.max(position[1].abs());
            let g = geometry(position, est.height_m());
            if g.height_to_flare <= 0.0 {
                return (-g.to_go_before_flare, strayed);
            }
            let controls = fa.fly(&config, &g, &est, position, 0.0, density);
            stack.step(&perf, &controls, &air, 0.1);
        }
        panic!("the stack never came down to the flare height");
    }

    #[test]
    fn a_final_a_few_metres_too_high_for_full_brakes_s_turns_the_height_away_in_light_air() {
        // Just high enough for full brakes: the flare starts on the aim, on the line.
        let (long, strayed) = flown_to_the_flare(0.0, 1.0);
        assert!(
            long.abs() < 2.0 && strayed < 1.0,
            "{long:.1} m long, {strayed:.1} m off"
        );
        // 8 m too high into 1 m/s: full brakes alone would fly it 8 × 1.37 = 11 m past the aim
        // (their glide over the ground there); S-turns burn the height first.
        let (long, strayed) = flown_to_the_flare(8.0, 1.0);
        assert!(
            long.abs() < 5.0 && strayed > 10.0,
            "{long:.1} m long, {strayed:.1} m off"
        );
        // Into 4 m/s the same 8 m is left to the brakes, whose glide over the ground is 0.5
        // there (4 m long at most): an S-turn's leg off the wind would be blown back.
        let (long, strayed) = flown_to_the_flare(8.0, 4.0);
        assert!(
            long.abs() < 5.0 && strayed < 1.0,
            "{long:.1} m long, {strayed:.1} m off"
        );
    }

    #[test]
    fn a_final_blown_backwards_keeps_facing_the_wind() {
        let config = GuidanceConfig::default();
        let sc = &config.spiral;
        let perf = config.performance;
        let density = perf.reference_density_kg_per_m3;
        // From the north, 1 m/s more than the stack flies with its brakes off.
        let wind_mps = perf.horizontal_airspeed(0.0, density) + 1.0;
        let wind = Vector3::new(-wind_mps, 0.0, 0.0);
        let air = Conditions::nominal(wind, density);
        let frame = WindFrame::new([0.0, 0.0], std::f64::consts::PI);
        let energy = Energy::plan(sc, &perf, config.gains.brake_trim, density, wind_mps, 0.3);
        // On the line 20 m short of the target, 80 m up, facing the wind.
        let mut stack = PointMass::new(0.0, Vector3::new(-20.0, 0.0, -80.0), 0.0);
        let mut fa = FinalApproach::default();
        let mut worst: f64 = 0.0;
        for _ in 0..200 {
            let est = stack.estimate(&wind);
            let position = [est.position_ned_m.x, est.position_ned_m.y];
            let g = FinalGeometry::assess(sc, &perf, density, &frame, &energy, position, 60.0);
            let controls = fa.fly(&config, &g, &est, position, 0.0, density);
            stack.step(&perf, &controls, &air, 0.1);
            worst = worst.max(wrap_pi(est.heading_rad).abs());
        }
        let est = stack.estimate(&wind);
        assert!(
            est.velocity_ned_mps.x < 0.0,
            "the stack is blown backwards, as the test means"
        );
        // Steered on its course, which points downwind, it turned round within seconds.
        assert!(
            worst < 15f64.to_radians(),
            "turned {:.0}° off the wind",
            worst.to_degrees()
        );
    }

    #[test]
    fn the_final_learns_the_glide_it_flies_and_only_in_straight_flight() {
        // As the polar says: nothing to correct.
        assert!(learned(1.0, false).abs() < 0.02, "{}", learned(1.0, false));
        // Sinking 15 % faster than the polar: the glide over the ground is 13 % shorter.
        let perf = GlidePerformance::default();
        let polar = perf.ground_glide(0.8, 3.5, perf.reference_density_kg_per_m3);
        let want = polar / 1.15 - polar;
        let got = learned(1.15, false);
        assert!(
            (got - want).abs() < 0.02,
            "learned {got:.3}, flown − polar {want:.3}"
        );
        // Turning, the glide along the line is not the glide: nothing learned but in the
        // second the turn takes to build up.
        assert!(learned(1.15, true).abs() < 0.01, "{}", learned(1.15, true));
    }
}
