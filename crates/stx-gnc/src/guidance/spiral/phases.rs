//! The phase machine of spiral landing: from the approximation through the four branches to
//! the final approach and the flare, or to the best reachable point. Each update makes at most
//! one decision, and its reason says where, how high, in which loop, what was decided and why.
//!
//! The order of the checks is the order of their priority: the flare first, then the reach
//! (in every phase until the flare), then the final approach's energy, then running short of
//! height anywhere in the pattern, then each phase's own progress round the pattern.

use super::config::SpiralConfig;
use super::pattern::{BRANCHES, Pattern, branch_index, corner_xy};
use super::reach::{
    Announcement, MIN_BEST_REACHABLE_S, REACH_CHECK_MIN_HEIGHT_M, Reach, WIND_ACCURACY_MPS,
};
use super::situation::Situation;
use super::wind::wind_from_deg;
use crate::mission::GuidancePhase;

/// A phase change: from, to, and why (a change from a phase to itself re-announces it).
pub(super) type Change = Option<(GuidancePhase, GuidancePhase, String)>;

/// Height below the direct glide-in need at which guidance stops the pattern, m.
const LOW_MARGIN_M: f64 = 10.0;
/// Longest base leg flown diagonally to a shorter final, m across the wind: the plan's
/// margin for a stronger headwind grows with the way, and from further out the diagonal
/// arrives far too high for its short final (1.35 km out, planned 998 m, used 809 m).
const MAX_DIAGONAL_ACROSS_M: f64 = 300.0;
/// Height above the steepest glide on final at which guidance goes back downwind, m.
const REENTER_EXCESS_M: f64 = 40.0;
/// Least time on the final approach before guidance may call it too high and leave it, s:
/// the first seconds after the turn onto the line still carry the turn's errors.
const MIN_FINAL_BEFORE_REENTRY_S: f64 = 10.0;

/// Where `position_ne` (north, east, m) is relative to `target_ne`, for the operator: "120 m
/// NE of the target".
fn place_of(position_ne: [f64; 2], target_ne: [f64; 2]) -> String {
    const POINTS: [&str; 8] = ["N", "NE", "E", "SE", "S", "SW", "W", "NW"];
    let (dn, de) = (position_ne[0] - target_ne[0], position_ne[1] - target_ne[1]);
    let distance = dn.hypot(de);
    if distance < 5.0 {
        return "over the target".into();
    }
    let bearing = de.atan2(dn).to_degrees().rem_euclid(360.0);
    let point = POINTS[((bearing + 22.5) / 45.0) as usize % 8];
    format!("{distance:.0} m {point} of the target")
}

/// The loop of the pattern under way, for the operator's log.
fn loop_tag(loop_number: u32) -> String {
    match loop_number {
        0 => "no loop flown".into(),
        n => format!("loop {n}"),
    }
}

/// The phase and the decisions taken in it, kept between updates.
#[derive(Debug, Clone)]
pub(super) struct PhaseMachine {
    pub(super) phase: GuidancePhase,
    /// The branch the pattern is entered at.
    pub(super) entry_branch: GuidancePhase,
    /// Where the approach to the entry corner began (north, east), m.
    pub(super) approach_from_ne_m: Option<[f64; 2]>,
    /// Where the base leg is turned, m downwind of the target, once decided.
    pub(super) base_x_m: Option<f64>,
    /// Where that base leg meets the final line, m downwind of the target, when it is flown
    /// diagonally (short of height into a headwind); otherwise it is flown straight across.
    pub(super) base_join_x_m: Option<f64>,
    /// Lateral offset of the downwind leg (Branch1), m: −a in the pattern, or where the
    /// vehicle was when it ran short of height and went for the downwind leg directly.
    pub(super) downwind_y_m: Option<f64>,
    /// The downwind leg is extended past its corner until the height allows turning base.
    pub(super) extending: bool,
    /// The flare began while flying to the best reachable point, off the final line: it
    /// holds the heading into the wind rather than a line it may be drifting backwards on.
    pub(super) flare_off_line: bool,
    /// Time the current phase was entered, s.
    pub(super) phase_since_s: f64,
    /// The pattern's axis may follow the wind at the next update: in the approximation, and
    /// once at the start of each loop. Within a loop, and from the decision to leave the
    /// pattern to the ground, the axis is held: in light wind the estimated direction
    /// wanders, and every turn of the axis moves the vehicle within the pattern, upsetting
    /// decisions already taken (a base leg that never met its final line, a final turned
    /// from far out).
    pub(super) reorient: bool,
    /// Loops of the pattern begun (the first at the entry corner), for the operator's log.
    pub(super) loop_number: u32,
}

impl PhaseMachine {
    /// A machine that has not started (phase Idle).
    pub(super) fn new() -> Self {
        Self {
            phase: GuidancePhase::Idle,
            entry_branch: GuidancePhase::Branch1,
            approach_from_ne_m: None,
            base_x_m: None,
            base_join_x_m: None,
            downwind_y_m: None,
            extending: false,
            flare_off_line: false,
            phase_since_s: 0.0,
            reorient: true,
            loop_number: 0,
        }
    }

    /// Where the base leg is turned (m downwind of the target) and, flown diagonally, where
    /// it meets the final line; both together, so a base leg never keeps another's join.
    pub(super) fn set_base(&mut self, x_m: Option<f64>, join_x_m: Option<f64>) {
        self.base_x_m = x_m;
        self.base_join_x_m = join_x_m;
    }

    /// Whether the pattern's axis may follow the wind at this update; it may not at the next
    /// unless a decision allows it again.
    pub(super) fn take_reorient(&mut self) -> bool {
        std::mem::replace(&mut self.reorient, false)
    }

    fn go(&mut self, to: GuidancePhase, reason: String) -> Change {
        let from = self.phase;
        self.phase = to;
        if from == to {
            None
        } else {
            Some((from, to, reason))
        }
    }

    /// Enters `to` at `now_s` for `reason`; the change, if it is one.
    fn enter(&mut self, to: GuidancePhase, reason: String, now_s: f64) -> Change {
        let change = self.go(to, reason);
        if change.is_some() {
            self.phase_since_s = now_s;
        }
        change
    }

    /// The decision of one update in situation `s`; `announced` is the best reachable point
    /// last announced.
    pub(super) fn decide(
        &mut self,
        sc: &SpiralConfig,
        s: &Situation,
        announced: &Announcement,
    ) -> Change {
        let Situation {
            now_s,
            position,
            x,
            y,
            height,
            lowest_body_height,
            ..
        } = *s;
        let target_ne = s.target_ne();
        let Pattern {
            ax, ay, downwind_y, ..
        } = s.pattern;
        let turn_distance = s.energy.turn_distance;
        let w_along = s.energy.wind_along_planned_mps;
        let v0 = s.energy.v0;
        let wind = s.wind.ne_mps;
        let wind_speed = s.wind.speed_mps;
        let wind_known = s.wind.known;
        let Reach {
            drift_distance,
            reach,
            reach_ratio,
            reachable,
            ..
        } = s.reach;
        let final_line = s.final_approach.line;
        let final_excess_m = s.final_approach.excess_m;
        let needed_direct = s.needed_direct();
        let loop_loss = s.loop_loss();
        let needed_to_turn_base = |x_base: f64| s.needed_to_turn_base(x_base);
        let in_phase_s = now_s - self.phase_since_s;
        let mut change: Change = None;

        let place = |p: [f64; 2]| place_of(p, target_ne);
        match self.phase {
            GuidancePhase::Idle | GuidancePhase::Landed => {}
            GuidancePhase::Flare => {}
            _ if sc.flare && lowest_body_height <= sc.flare_height_m => {
                self.flare_off_line = self.phase == GuidancePhase::BestReachable;
                change = self.enter(
                    GuidancePhase::Flare,
                    format!(
                        "flare: lowest body {lowest_body_height:.1} m above the ground, {}: full \
                         brakes to slow the touchdown",
                        place(position)
                    ),
                    now_s,
                );
            }
            // Checked in every phase until the flare, whatever has been decided: a base leg or
            // an extended downwind leg planned on a wind that turns out too strong still
            // cannot reach the target. (It was off once either was committed, and strong
            // winds were flown into the ground kilometres off with no word to the operator.)
            _ if wind_known
                && !reachable
                && self.phase != GuidancePhase::BestReachable
                && lowest_body_height > REACH_CHECK_MIN_HEIGHT_M =>
            {
                let miss = s.reach.miss_m();
                let best = s.reach.best_ne(target_ne);
                self.set_base(None, None);
                self.extending = false;
                self.downwind_y_m = None;
                change = self.enter(
                    GuidancePhase::BestReachable,
                    format!(
                        "target out of reach at {height:.0} m: wind {wind_speed:.1} m/s from \
                         {:.0}°, the glide reaches {reach:.0} m around a drift point \
                         {drift_distance:.0} m from the target (ratio {reach_ratio:.2}); flying to \
                         the best reachable point ({:.0} N, {:.0} E){}, {miss:.0} m from the \
                         target",
                        wind_from_deg(wind),
                        best[0],
                        best[1],
                        s.reach.clear_note()
                    ),
                    now_s,
                );
            }
            GuidancePhase::FinalApproach
                if final_excess_m > REENTER_EXCESS_M
                    && in_phase_s >= MIN_FINAL_BEFORE_REENTRY_S =>
            {
                self.set_base(None, None);
                if x < sc.max_final_m - 2.0 * turn_distance {
                    // Downwind on a leg beside the final line, and base again from it when
                    // the height has come down to what the glide in needs.
                    let side = final_line.cross_track_m(position);
                    self.downwind_y_m = Some(if side >= 0.0 { ay } else { -ay });
                    self.extending = true;
                    change = self.enter(
                        GuidancePhase::Branch1,
                        format!(
                            "{final_excess_m:.0} m too high for the final even with full brakes \
                             ({height:.0} m, {}): back downwind to lose it",
                            place(position)
                        ),
                        now_s,
                    );
                } else {
                    // Already at the longest final: more downwind only makes the way back
                    // longer; the pattern over the target burns the height instead.
                    self.downwind_y_m = None;
                    self.extending = false;
                    self.approach_from_ne_m = None;
                    self.reorient = true;
                    change = self.enter(
                        GuidancePhase::Approximation,
                        format!(
                            "{final_excess_m:.0} m too high for the final even with full brakes, \
                             {x:.0} m out at {height:.0} m: back to the pattern over the target \
                             to lose it"
                        ),
                        now_s,
                    );
                }
            }
            GuidancePhase::FinalApproach => {}
            GuidancePhase::BestReachable
                if reach_ratio > sc.reach_margin
                    && announced.is_stale(target_ne, &s.reach, now_s) =>
            {
                // The wind estimate firmed up or the wind changed: the operator's recovery team
                // drives to the announced point, so a point that moved is announced again.
                let best = s.reach.best_ne(target_ne);
                let miss = s.reach.miss_m();
                change = Some((
                    GuidancePhase::BestReachable,
                    GuidancePhase::BestReachable,
                    format!(
                        "best reachable point moved: now ({:.0} N, {:.0} E){}, {miss:.0} m from \
                         the target, at {height:.0} m in a wind of {wind_speed:.1} m/s from {:.0}° \
                         (reach ratio {reach_ratio:.2})",
                        best[0],
                        best[1],
                        s.reach.clear_note(),
                        wind_from_deg(wind)
                    ),
                ));
            }
            GuidancePhase::BestReachable => {
                // Back to the target only when it is clearly within reach again, after a while
                // on this course, and high enough to plan an approach: near the ground a
                // changed mind costs more than it buys.
                if reachable
                    && in_phase_s >= MIN_BEST_REACHABLE_S
                    && lowest_body_height > REACH_CHECK_MIN_HEIGHT_M
                {
                    self.approach_from_ne_m = None;
                    change = self.enter(
                        GuidancePhase::Approximation,
                        format!(
                            "target within reach again at {height:.0} m (reach ratio \
                             {reach_ratio:.2}, wind {wind_speed:.1} m/s): approaching it"
                        ),
                        now_s,
                    );
                }
            }
            _ if wind_known
                && self.base_x_m.is_none()
                && !self.extending
                && self.phase != GuidancePhase::Branch1
                && self.phase != GuidancePhase::BestReachable
                && height <= needed_direct + LOW_MARGIN_M =>
            {
                if x >= sc.min_final_m && y.abs() > 2.0 * turn_distance {
                    // A base leg from here to the final line (what `needed_direct` plans): the
                    // final's localizer would intercept it at 45°, a longer way that the height
                    // was not counted for. Straight across if the height covers it, else
                    // diagonally to a shorter final.
                    let join_x = if y.abs() <= MAX_DIAGONAL_ACROSS_M {
                        s.energy.base_join_x(x, y, height, WIND_ACCURACY_MPS)
                    } else {
                        x
                    };
                    self.set_base(Some(x), (join_x < x - 1.0).then_some(join_x));
                    self.downwind_y_m = Some(y);
                    let way = match self.base_join_x_m {
                        Some(j) => format!(
                            "diagonally to a final {j:.0} m out ({:.0} m needed that way)",
                            s.energy.needed_via(x, y, j, 0.0)
                        ),
                        None => format!("{:.0} m across to a final {x:.0} m out", y.abs()),
                    };
                    change = self.enter(
                        GuidancePhase::Branch2,
                        format!(
                            "short of height ({height:.0} m, {needed_direct:.0} m needed to glide \
                             in from here): base leg now, {way}"
                        ),
                        now_s,
                    );
                } else if x >= sc.min_final_m {
                    self.set_base(Some(x), None);
                    change = self.enter(
                        GuidancePhase::FinalApproach,
                        format!(
                            "short of height ({height:.0} m, {needed_direct:.0} m needed to glide \
                             in from here): straight to the final approach, {x:.0} m out"
                        ),
                        now_s,
                    );
                } else {
                    self.downwind_y_m = Some(if y.abs() < turn_distance {
                        -turn_distance
                    } else {
                        y
                    });
                    self.extending = true;
                    change = self.enter(
                        GuidancePhase::Branch1,
                        format!(
                            "short of height ({height:.0} m, {needed_direct:.0} m needed): \
                             downwind leg now, base and final from it"
                        ),
                        now_s,
                    );
                }
            }
            GuidancePhase::Approximation => {
                {
                    // Enter at the start corner reached soonest: with the wind, a downwind
                    // corner is cheaper than a nearer upwind one. Re-chosen as the wind
                    // estimate firms up, keeping the current one unless another is clearly
                    // sooner.
                    let time_to = |k: usize| {
                        let c = corner_xy(k, ax, ay);
                        let (dx, dy) = (c[0] - x, c[1] - y);
                        let d = dx.hypot(dy);
                        if d < 1e-6 {
                            return 0.0;
                        }
                        let (along, across) = (w_along * dx / d, w_along * dy / d);
                        let ground = along + (v0 * v0 - across * across).max(0.01).sqrt();
                        d / ground.max(0.3)
                    };
                    let soonest = (0..4)
                        .min_by(|i, j| time_to(*i).total_cmp(&time_to(*j)))
                        .unwrap_or(0);
                    let current = branch_index(self.entry_branch).unwrap_or(0);
                    if self.approach_from_ne_m.is_none()
                        || (soonest != current && time_to(soonest) < 0.8 * time_to(current))
                    {
                        self.entry_branch = BRANCHES[soonest];
                        self.approach_from_ne_m = Some(position);
                    }
                }
                let k = branch_index(self.entry_branch).unwrap_or(0);
                let corner = corner_xy(k, ax, ay);
                let to_corner = (corner[0] - x).hypot(corner[1] - y);
                if to_corner < turn_distance.max(10.0) {
                    self.loop_number = 1;
                    change = self.enter(
                        self.entry_branch,
                        format!(
                            "loop 1: entry corner reached {}, at {height:.0} m; the corner was \
                             chosen as the one reached soonest from where the approach began, \
                             the pattern {:.0} × {:.0} m with its long side across a wind of \
                             {wind_speed:.1} m/s from {:.0}°",
                            place(position),
                            2.0 * ax,
                            2.0 * ay,
                            wind_from_deg(wind)
                        ),
                        now_s,
                    );
                }
            }
            GuidancePhase::Branch1 => {
                let to_corner = ax - x;
                // The turn carries the vehicle about a turn radius further downwind before it
                // flies across: the base leg lies there, and the glide in is planned from it.
                let x_base = x + turn_distance;
                let needed = needed_to_turn_base(x_base.max(sc.min_final_m));
                if x_base >= sc.min_final_m.min(ax) && height <= needed {
                    self.set_base(Some(x_base), None);
                    self.extending = false;
                    change = self.enter(
                        GuidancePhase::Branch2,
                        format!(
                            "{}: turning base at {height:.0} m (needed {needed:.0} m to turn \
                             base here and glide in) onto a base leg {x_base:.0} m downwind of the \
                             target, {}",
                            loop_tag(self.loop_number),
                            place(position)
                        ),
                        now_s,
                    );
                } else if x_base >= sc.max_final_m {
                    self.set_base(Some(x_base), None);
                    self.extending = false;
                    change = self.enter(
                        GuidancePhase::Branch2,
                        format!(
                            "{}: turning base at the longest final approach allowed, \
                             {x_base:.0} m out, at {height:.0} m ({needed:.0} m needed): the \
                             final's brakes take off the rest",
                            self.loop_number
                        ),
                        now_s,
                    );
                } else if !self.extending && to_corner < turn_distance {
                    if height - loop_loss >= needed_to_turn_base(ax) {
                        self.set_base(None, None);
                        change = self.enter(
                            GuidancePhase::Branch2,
                            format!(
                                "{}: downwind corner {}, at {height:.0} m; another loop \
                                 ({loop_loss:.0} m) still leaves the {:.0} m a final needs: across \
                                 the wind",
                                loop_tag(self.loop_number),
                                place(position),
                                needed_to_turn_base(ax)
                            ),
                            now_s,
                        );
                    } else {
                        self.extending = true;
                    }
                }
            }
            GuidancePhase::Branch2 => {
                if let Some(x_base) = self.base_x_m {
                    // Final once the base leg meets the final line, not before the vehicle is
                    // out at the base leg (sent back downwind from the final line, it starts
                    // on that line). A diagonal leg turns less onto the final, and later.
                    let from_side = downwind_y.signum();
                    let (meets_x, lead) = match self.base_join_x_m {
                        Some(j) => {
                            let turn = std::f64::consts::PI - (-downwind_y).atan2(j - x_base).abs();
                            (j, turn_distance * (0.5 * turn).tan() * turn.sin())
                        }
                        None => (x_base, turn_distance),
                    };
                    if y * from_side < lead && x >= meets_x - turn_distance {
                        // The final course is taken from the wind as it is now.
                        self.reorient = true;
                        change = self.enter(
                            GuidancePhase::FinalApproach,
                            format!(
                                "{}: base leg meets the final line {}, at {height:.0} m: \
                                 turning final into a wind of {wind_speed:.1} m/s from {:.0}°",
                                loop_tag(self.loop_number),
                                place(position),
                                wind_from_deg(wind)
                            ),
                            now_s,
                        );
                    }
                } else if ay - y < turn_distance {
                    change = self.enter(
                        GuidancePhase::Branch3,
                        format!(
                            "{}: across leg done {}, at {height:.0} m: upwind leg, {:.0} m",
                            loop_tag(self.loop_number),
                            place(position),
                            2.0 * ax
                        ),
                        now_s,
                    );
                }
            }
            GuidancePhase::Branch3 => {
                if x - (-ax) < turn_distance {
                    change = self.enter(
                        GuidancePhase::Branch4,
                        format!(
                            "{}: upwind leg done {}, at {height:.0} m: across to the \
                             downwind leg",
                            loop_tag(self.loop_number),
                            place(position)
                        ),
                        now_s,
                    );
                }
            }
            GuidancePhase::Branch4 => {
                if y - (-ay) < turn_distance {
                    self.downwind_y_m = None;
                    self.reorient = true;
                    self.loop_number += 1;
                    change = self.enter(
                        GuidancePhase::Branch1,
                        format!(
                            "{}: begins {}, at {height:.0} m; downwind leg, {:.0} m, then \
                             the decision to loop again or turn base (a loop takes \
                             {loop_loss:.0} m, a final from the corner {:.0} m)",
                            loop_tag(self.loop_number),
                            place(position),
                            2.0 * ax,
                            needed_to_turn_base(ax)
                        ),
                        now_s,
                    );
                }
            }
        }

        change
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guidance::spiral::Spiral;
    use crate::guidance::{GuidanceConfig, Plan};
    use crate::pointmass::PointMass;
    use nalgebra::Vector3;

    /// Seed Fig. 5.4: the spiral is entered at the corner of the region the vehicle is in —
    /// in wind coordinates (x downwind, y right), a vehicle downwind and right of the target
    /// enters at the corner (+a, +a), the start of Branch3, and so on round the square.
    #[test]
    fn the_entry_corner_is_the_one_of_the_region_the_vehicle_is_in() {
        let config = GuidanceConfig::default();
        let plan = Plan {
            target_ned_m: Vector3::new(100.0, -50.0, 0.0),
            ..Plan::default()
        };
        // 1 m/s from the north: downwind is south, and right of south is west.
        let wind = Vector3::new(-1.0, 0.0, 0.0);
        let cases = [
            // (metres downwind, metres right of it) → branch entered
            ((250.0, 250.0), GuidancePhase::Branch3),
            ((250.0, -250.0), GuidancePhase::Branch2),
            ((-250.0, -250.0), GuidancePhase::Branch1),
            ((-250.0, 250.0), GuidancePhase::Branch4),
        ];
        for ((x, y), expected) in cases {
            let north = plan.target_ned_m.x - x;
            let east = plan.target_ned_m.y - y;
            let mut spiral = Spiral::new();
            spiral.force_phase(GuidancePhase::Approximation);
            let est = PointMass::new(0.0, Vector3::new(north, east, -600.0), 1.0).estimate(&wind);
            spiral.update(&config, &plan, &est, 1.2);
            assert_eq!(
                spiral.machine.entry_branch, expected,
                "vehicle {x} m downwind, {y} m right of the target"
            );
            // And that corner is the nearest of the pattern's corners.
            let corners = spiral.status().corners_ne_m;
            let nearest = (0..4)
                .min_by(|i, j| {
                    let d = |k: usize| (corners[k][0] - north).hypot(corners[k][1] - east);
                    d(*i).total_cmp(&d(*j))
                })
                .unwrap_or(0);
            assert_eq!(BRANCHES[nearest], expected);
        }
    }
}
