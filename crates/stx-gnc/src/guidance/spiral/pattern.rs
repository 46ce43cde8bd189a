//! The pattern's geometry: its axis (downwind, turned only when the phase machine allows), the
//! wind frame centred on the target, the corners, the branches scaled with the wind, and the
//! line each branch is flown on.

use stx_types::rotation::wrap_pi;

use super::config::SpiralConfig;
use super::wind::WindNow;
use crate::control::Localizer;
use crate::mission::GuidancePhase;

/// The branches in flying order.
pub(super) const BRANCHES: [GuidancePhase; 4] = [
    GuidancePhase::Branch1,
    GuidancePhase::Branch2,
    GuidancePhase::Branch3,
    GuidancePhase::Branch4,
];

/// Largest turn of the pattern's axis at the start of a loop, rad (45°).
const LOOP_REORIENT_MAX_RAD: f64 = std::f64::consts::FRAC_PI_4;
/// Largest turn of the final-approach course when turning final, rad (20°).
const FINAL_REORIENT_MAX_RAD: f64 = 0.3491;
/// On the final, the line may turn with the wind about the target by as much as moves the
/// vehicle this far off it, m: the wind turns under a final laid 150–300 m up (the low-level
/// turn), and a touchdown into the wind needs the line turned with it near the ground.
const FINAL_FOLLOW_OFFSET_M: f64 = 10.0;
/// Within this of the target the line's turn with the wind is held where the distance left
/// it, m: close in, a small turn of the wind would swing the line across the vehicle.
const FINAL_FOLLOW_HOLD_WITHIN_M: f64 = 30.0;
/// Largest turn of the final's line with the wind, from its course at the turn onto it, rad
/// (35°).
const FINAL_FOLLOW_MAX_RAD: f64 = 0.6109;

pub(super) fn branch_index(phase: GuidancePhase) -> Option<usize> {
    BRANCHES.iter().position(|b| *b == phase)
}

/// Corners in wind coordinates (x downwind, y right), start of each branch.
/// `ax` is the half-length along the wind, `ay` the half-width across it.
pub(super) fn corner_xy(branch: usize, ax: f64, ay: f64) -> [f64; 2] {
    match branch % 4 {
        0 => [-ax, -ay],
        1 => [ax, -ay],
        2 => [ax, ay],
        _ => [-ax, ay],
    }
}

/// Final-approach courses asked for instead of into the wind, rad.
#[derive(Debug, Clone, Copy)]
pub(super) struct Courses {
    /// The operator's: the axis is set to it at once and kept.
    pub(super) operator_rad: Option<f64>,
    /// The one keep-out zones ask for (see `keep_clear`): the axis turns towards it as it
    /// would towards the wind, within the same limits. The operator's wins over it.
    pub(super) keep_clear_rad: Option<f64>,
    /// Keep-out zones are in force: the final's course was checked clear of them where it
    /// was chosen, so it does not turn with the wind on the final.
    pub(super) zones_in_force: bool,
}

/// The pattern's axis and half-length, held between the moments they may follow the wind.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Axis {
    /// Direction of the pattern's x axis (downwind), rad from north.
    downwind_rad: Option<f64>,
    /// Half-length of the pattern along the wind, m.
    half_length_m: Option<f64>,
    /// Whether the axis was last placed on a wind the estimator had not yet settled on.
    placed_unsettled: bool,
    /// The downwind direction chosen at the turn onto the final, rad: what the final's line
    /// turns from as the wind turns under it.
    final_entry_rad: Option<f64>,
}

impl Axis {
    /// The downwind direction held, rad from north, once the axis has been set.
    pub(super) fn downwind_rad(&self) -> Option<f64> {
        self.downwind_rad
    }

    /// The pattern's downwind direction for this update, rad, and whether the axis (and the
    /// half-length with it) is held. `reorient` says the phase machine lets the axis follow
    /// the wind at this update (the start of a loop, the turn onto the final); in the
    /// approximation and on the way to the best reachable point it always may.
    /// `courses` are the final-approach courses asked for instead of into the wind. `rel` is the
    /// vehicle's place from the target (north, east), m.
    pub(super) fn orient(
        &mut self,
        phase: GuidancePhase,
        reorient: bool,
        courses: Courses,
        wind: &WindNow,
        sc: &SpiralConfig,
        rel: [f64; 2],
    ) -> (f64, bool) {
        let Courses {
            operator_rad: approach_course_rad,
            keep_clear_rad,
            zones_in_force,
        } = courses;
        let wind_speed = wind.speed_mps;
        let wind_known = wind.known;
        let wind = wind.ne_mps;
        // The pattern's axis: downwind, unless the operator fixed the approach course; in calm
        // air it stays where it was (first: the final approach is flown towards the target
        // from where the vehicle is).
        let free = matches!(
            phase,
            GuidancePhase::Approximation | GuidancePhase::BestReachable
        );
        let frozen = !(reorient || free);
        // A turn of the axis at a loop's start or onto the final is limited: the vehicle is
        // placed for the axis it had, and a light wind's direction is barely known.
        // An axis placed on an unsettled wind (a release right at an entry corner, the
        // estimator's wind still near zero) was never a decision about the real wind: Monte
        // Carlo seed 12 run 252 laid its pattern on 0.8 m/s from 57° against 3.9 m/s from
        // 188°, turned 45° a loop, flew its "across" legs into the wind, came to the final 60 m
        // short and landed in the pond. The first loop on a settled wind may turn it fully.
        let resettle = reorient && self.placed_unsettled && wind_known;
        let largest_turn = match phase {
            _ if free => std::f64::consts::PI,
            GuidancePhase::FinalApproach => FINAL_REORIENT_MAX_RAD,
            _ if resettle => std::f64::consts::PI,
            _ => LOOP_REORIENT_MAX_RAD,
        };
        // Where the axis would go: a keep-out course (see `keep_clear`) in place of the
        // wind's direction, turned to within the same limits as the wind, since the vehicle is
        // placed for the axis it had whatever made the axis turn.
        let toward = keep_clear_rad
            .map(|course| wrap_pi(course + std::f64::consts::PI))
            .or_else(|| (wind_speed >= sc.calm_wind_mps).then(|| wind[1].atan2(wind[0])));
        let on_final = phase == GuidancePhase::FinalApproach;
        let asked_for = approach_course_rad.is_some() || keep_clear_rad.is_some() || zones_in_force;
        let follow = if on_final && !reorient && !asked_for {
            self.follow_on_final(toward, rel)
        } else {
            None
        };
        let downwind = match (approach_course_rad, self.downwind_rad, toward) {
            (Some(course), _, _) => wrap_pi(course + std::f64::consts::PI),
            _ if let Some(followed) = follow => followed,
            (None, Some(previous), None) => previous,
            (None, Some(previous), Some(_)) if frozen => previous,
            (None, Some(previous), Some(toward)) => {
                let turn = wrap_pi(toward - previous);
                wrap_pi(previous + turn.clamp(-largest_turn, largest_turn))
            }
            (None, None, Some(toward)) => toward,
            (None, None, None) => rel[1].atan2(rel[0]),
        };
        self.downwind_rad = Some(downwind);
        self.final_entry_rad = match (on_final, reorient) {
            (false, _) => None,
            (true, true) => Some(downwind),
            (true, false) => self.final_entry_rad,
        };
        if !frozen {
            self.placed_unsettled = !wind_known;
        }
        (downwind, frozen)
    }

    /// The final's line turned with the wind (`toward`, downwind, rad) about the target, the
    /// vehicle at `rel` (north, east of it, m): by as much as moves the vehicle
    /// [`FINAL_FOLLOW_OFFSET_M`] off the line, more as the target nears, up to
    /// [`FINAL_FOLLOW_MAX_RAD`] from the course at the turn onto the final. `None` (the line
    /// held) before that turn, in calm air and within [`FINAL_FOLLOW_HOLD_WITHIN_M`].
    ///
    /// Why: the final is laid into the wind 150–300 m up and the wind turns under it (by up to
    /// 30° below 100 m in the realistic dispersions); held, the canopy met the ground up to 48°
    /// off the wind (results/2026-12-01.md). Turning the line about the target keeps the
    /// landing point and leaves the localizer a small offset to take out.
    fn follow_on_final(&self, toward: Option<f64>, rel: [f64; 2]) -> Option<f64> {
        let (entry, toward) = (self.final_entry_rad?, toward?);
        let distance = rel[0].hypot(rel[1]);
        if distance <= FINAL_FOLLOW_HOLD_WITHIN_M {
            return None;
        }
        let largest = (FINAL_FOLLOW_OFFSET_M / distance)
            .min(1.0)
            .asin()
            .min(FINAL_FOLLOW_MAX_RAD);
        Some(wrap_pi(
            entry + wrap_pi(toward - entry).clamp(-largest, largest),
        ))
    }

    /// The pattern's half-length along the wind, m (see [the spiral](super): "branches scaled
    /// with the wind"); held, like the axis, while `frozen`. `wind_along_mps` is the measured
    /// wind along the axis, `v0` the airspeed with the brakes released, `turn_distance_m` a
    /// corner's turn radius.
    pub(super) fn half_length(
        &mut self,
        frozen: bool,
        sc: &SpiralConfig,
        wind_along_mps: f64,
        v0: f64,
        turn_distance_m: f64,
    ) -> f64 {
        let ay = sc.half_size_m;
        // The branches scaled with the wind (seed §5.3): the legs along the wind are shortened
        // in proportion to the upwind leg's ground speed, `ax = a·(V − w)/V`, so the upwind leg
        // takes as long as in still air and the pattern shrinks to a weave across the wind as
        // the wind nears the airspeed (at least a turn's length, or the corners overlap). Held,
        // like the axis, from the start of a loop to its end.
        let ax = match self.half_length_m {
            Some(held) if frozen => held,
            _ if !sc.wind_scaled_branches => ay,
            _ => {
                let w = wind_along_mps.clamp(0.0, v0);
                (ay * (v0 - w) / v0.max(1e-3)).max(turn_distance_m.min(ay))
            }
        };
        self.half_length_m = Some(ax);
        ax
    }
}

/// The wind frame of one update: centred on the target, `x` downwind, `y` to its right.
#[derive(Debug, Clone, Copy)]
pub(super) struct WindFrame {
    /// The target (north, east), m.
    pub(super) target_ne: [f64; 2],
    /// Direction of `x`, rad from north.
    pub(super) downwind_rad: f64,
    sin: f64,
    cos: f64,
}

impl WindFrame {
    pub(super) fn new(target_ne: [f64; 2], downwind_rad: f64) -> Self {
        let (sin, cos) = downwind_rad.sin_cos();
        Self {
            target_ne,
            downwind_rad,
            sin,
            cos,
        }
    }

    /// A vector's component along `x` (downwind).
    pub(super) fn along(&self, ne: [f64; 2]) -> f64 {
        ne[0] * self.cos + ne[1] * self.sin
    }

    /// A vector (north, east) in the frame's axes.
    pub(super) fn to_wind(self, ne: [f64; 2]) -> [f64; 2] {
        [self.along(ne), -ne[0] * self.sin + ne[1] * self.cos]
    }

    /// A point of the frame (x, y) as north, east, m.
    pub(super) fn to_ne(self, xy: [f64; 2]) -> [f64; 2] {
        [
            self.target_ne[0] + xy[0] * self.cos - xy[1] * self.sin,
            self.target_ne[1] + xy[0] * self.sin + xy[1] * self.cos,
        ]
    }
}

/// The pattern as it stands at one update.
#[derive(Debug, Clone, Copy)]
pub(super) struct Pattern {
    pub(super) frame: WindFrame,
    /// Half-length along the wind, m.
    pub(super) ax: f64,
    /// Half-width across the wind, m.
    pub(super) ay: f64,
    /// Lateral place of the downwind leg (Branch1), m: `−ay`, or where the phase machine moved
    /// it.
    pub(super) downwind_y: f64,
}

impl Pattern {
    /// The start corner of branch `k`, (x, y), m.
    pub(super) fn corner(&self, k: usize) -> [f64; 2] {
        corner_xy(k, self.ax, self.ay)
    }

    /// The line branch `k` is flown on; with `base_x_m`, Branch2 is the base leg across from
    /// the downwind leg to the final-approach line at that `x`, or, with `join_x_m`, from
    /// there diagonally to the final line at `join_x_m`.
    pub(super) fn branch_line(
        &self,
        k: usize,
        base_x_m: Option<f64>,
        join_x_m: Option<f64>,
    ) -> Localizer {
        let downwind_y = self.downwind_y;
        let mut start = self.corner(k);
        let mut course = self.frame.downwind_rad + std::f64::consts::FRAC_PI_2 * k as f64;
        match (k, base_x_m) {
            (0, _) => start[1] = downwind_y,
            (1, Some(x_base)) => {
                // The base leg: across from the downwind leg towards the final line.
                start = [x_base, downwind_y];
                match join_x_m {
                    Some(join_x) => {
                        course = self.frame.downwind_rad + (-downwind_y).atan2(join_x - x_base);
                    }
                    None if downwind_y > 0.0 => course += std::f64::consts::PI,
                    None => {}
                }
            }
            _ => {}
        }
        Localizer {
            point_ne_m: self.frame.to_ne(start),
            course_rad: wrap_pi(course),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guidance::spiral::{Spiral, corner_turn_rate_rad_s};
    use crate::guidance::{GuidanceConfig, Plan};
    use crate::pointmass::PointMass;
    use nalgebra::Vector3;

    /// A planning wind of `speed_mps` from `from_deg`, as measured.
    fn wind_from(speed_mps: f64, from_deg: f64, known: bool) -> WindNow {
        let to = (from_deg + 180.0).to_radians();
        let ne_mps = [speed_mps * to.cos(), speed_mps * to.sin()];
        WindNow {
            measured_ne_mps: ne_mps,
            ne_mps,
            speed_mps,
            known,
        }
    }

    /// The branches along the wind shrink as the wind grows (seed §5.3, "scaling the branches
    /// length"): the upwind leg takes as long as in still air, down to a turn's length.
    #[test]
    fn the_legs_along_the_wind_shrink_with_the_wind_so_the_upwind_leg_keeps_its_duration() {
        let config = GuidanceConfig::default();
        let plan = Plan::default();
        let perf = &config.performance;
        let v0 = perf.horizontal_airspeed(0.0, 1.2);
        let half_length = |speed: f64| {
            let mut spiral = Spiral::new();
            spiral.force_phase(GuidancePhase::Approximation);
            let wind = Vector3::new(-speed, 0.0, 0.0);
            let mut est =
                PointMass::new(0.0, Vector3::new(300.0, 0.0, -600.0), 0.0).estimate(&wind);
            est.wind_sigma_mps = Vector3::new(0.1, 0.1, 0.0);
            spiral.update(&config, &plan, &est, 1.2);
            let c = spiral.status().corners_ne_m;
            // Branch1 runs from corner 0 to corner 1 along the wind.
            0.5 * (c[1][0] - c[0][0]).hypot(c[1][1] - c[0][1])
        };
        let a = config.spiral.half_size_m;
        assert!((half_length(0.0) - a).abs() < 1e-9);
        for speed in [1.0, 2.0] {
            let ax = half_length(speed);
            assert!(
                (ax - a * (v0 - speed) / v0).abs() < 1e-6,
                "{speed} m/s: half-length {ax}"
            );
            // The upwind leg's duration is the still-air one.
            assert!((2.0 * ax / (v0 - speed) - 2.0 * a / v0).abs() < 1e-6);
        }
        // Near the airspeed: a turn's length, not less.
        let turn = spiral_turn_distance(&config);
        assert!((half_length(0.95 * v0) - turn).abs() < 1e-6);
        // Without the scaling, the square of any wind.
        let mut fixed = config;
        fixed.spiral.wind_scaled_branches = false;
        let mut spiral = Spiral::new();
        spiral.force_phase(GuidancePhase::Approximation);
        let est = PointMass::new(0.0, Vector3::new(300.0, 0.0, -600.0), 0.0)
            .estimate(&Vector3::new(-3.0, 0.0, 0.0));
        spiral.update(&fixed, &plan, &est, 1.2);
        let c = spiral.status().corners_ne_m;
        assert!((0.5 * (c[1][0] - c[0][0]).hypot(c[1][1] - c[0][1]) - a).abs() < 1e-9);
    }

    /// An axis placed on the estimator's unsettled wind turns fully at the first loop on a
    /// settled one (Monte Carlo seed 12 run 252); one placed on a settled wind still turns at
    /// most 45° a loop.
    #[test]
    fn an_axis_placed_on_an_unsettled_wind_turns_fully_at_the_first_loop_on_a_settled_one() {
        let sc = SpiralConfig::default();
        let no_courses = Courses {
            operator_rad: None,
            keep_clear_rad: None,
            zones_in_force: false,
        };
        let wind = |from_deg: f64, known: bool| wind_from(3.9, from_deg, known);
        let deg = |rad: f64| rad.to_degrees().rem_euclid(360.0);
        // Downwind of a wind from 188° is 8°; the first axis was laid for one from 57°.
        for (placed_known, expected_deg) in [(false, 8.0), (true, 237.0 + 45.0)] {
            let mut axis = Axis::default();
            let (first, _) = axis.orient(
                GuidancePhase::Approximation,
                false,
                no_courses,
                &wind(57.0, placed_known),
                &sc,
                [0.0, -60.0],
            );
            assert!((deg(first) - 237.0).abs() < 1e-6);
            // Within the loop the axis holds, whatever the wind.
            let (held, frozen) = axis.orient(
                GuidancePhase::Branch3,
                false,
                no_courses,
                &wind(188.0, true),
                &sc,
                [0.0, -60.0],
            );
            assert!(frozen && (deg(held) - 237.0).abs() < 1e-6);
            let (turned, _) = axis.orient(
                GuidancePhase::Branch1,
                true,
                no_courses,
                &wind(188.0, true),
                &sc,
                [0.0, -60.0],
            );
            assert!(
                (deg(turned) - expected_deg).abs() < 1e-6,
                "placed on a {} wind: turned to {}°",
                if placed_known { "settled" } else { "unsettled" },
                deg(turned)
            );
        }
    }

    /// On the final the line turns with the wind about the target, more as the target nears
    /// (the vehicle at most 10 m off the turned line), and is held within 30 m of it and for a
    /// course the operator set.
    #[test]
    fn the_final_line_turns_with_the_wind_as_the_target_nears_and_is_held_close_in() {
        let sc = SpiralConfig::default();
        let courses = |operator_rad: Option<f64>, zones_in_force: bool| Courses {
            operator_rad,
            keep_clear_rad: None,
            zones_in_force,
        };
        let wind = |from_deg: f64| wind_from(3.0, from_deg, true);
        let deg = |rad: f64| wrap_pi(rad).to_degrees();
        let final_at = |operator_rad: Option<f64>| {
            let mut axis = Axis::default();
            // Turned onto the final into a wind from the south: downwind is north (0°), the
            // vehicle north of the target.
            let (entry, _) = axis.orient(
                GuidancePhase::FinalApproach,
                true,
                courses(operator_rad, false),
                &wind(180.0),
                &sc,
                [200.0, 0.0],
            );
            (axis, entry)
        };
        let (mut axis, entry) = final_at(None);
        assert!(deg(entry).abs() < 1e-9);
        // The wind turns 30° (from 210°: downwind 30°) as the vehicle comes in.
        let mut at = |north_m: f64| {
            let (downwind, _) = axis.orient(
                GuidancePhase::FinalApproach,
                false,
                courses(None, false),
                &wind(210.0),
                &sc,
                [north_m, 0.0],
            );
            deg(downwind)
        };
        let expect = |d: f64| (10.0 / d).asin().to_degrees();
        assert!((at(200.0) - expect(200.0)).abs() < 1e-9);
        assert!((at(40.0) - expect(40.0)).abs() < 1e-9);
        // Within 30 m the line stays where it was.
        assert!((at(25.0) - expect(40.0)).abs() < 1e-9);
        // Far out it never turns further than the offset allows, whatever the wind did.
        assert!(at(1000.0) < 0.6);
        // A course the operator set is kept.
        let (mut axis, _) = final_at(Some(std::f64::consts::PI));
        let (held, _) = axis.orient(
            GuidancePhase::FinalApproach,
            false,
            courses(Some(std::f64::consts::PI), false),
            &wind(210.0),
            &sc,
            [40.0, 0.0],
        );
        assert!(deg(held).abs() < 1e-9);
        // So is one checked clear of keep-out zones.
        let (mut axis, _) = final_at(None);
        let (held, _) = axis.orient(
            GuidancePhase::FinalApproach,
            false,
            courses(None, true),
            &wind(210.0),
            &sc,
            [40.0, 0.0],
        );
        assert!(deg(held).abs() < 1e-9);
    }

    fn spiral_turn_distance(config: &GuidanceConfig) -> f64 {
        let rate = corner_turn_rate_rad_s(&config.gains, &config.performance);
        config.performance.turn_radius_m(rate, 0.0, 1.2)
    }
}
