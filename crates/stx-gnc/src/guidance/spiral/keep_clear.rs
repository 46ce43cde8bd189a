//! Keep-out zones in the spiral: which final-approach course keeps the low legs clear of
//! them, and which reachable point outside them to fly to when the target is out of reach.
//!
//! A zone is a place the payload must not *land* on; flying over it high is harmless. What
//! lands the payload in a zone is the low end of the flight, so the legs that must stay clear
//! are the final approach (from where the base leg joins it, past the target by the flare's
//! overshoot), the narrow wedge about it in which the stack converges onto it, and the base
//! leg; the square spiral around the target, flown high, only decides between the two sides
//! of the wind at the same turn. Guidance lands into the wind; a zone on that line turns the final approach
//! away from the wind by the least multiple of [`COURSE_STEP_RAD`] (up to
//! [`MAX_OFFSET_RAD`]) that clears it. When no course clears, guidance flies the nominal one
//! and says why.
//!
//! Knowing the zones must never land the payload in them more often than not knowing them,
//! and a landing's accuracy is what keeps it out of a zone 35 m away: the scatter of the
//! into-wind landing is a few metres. Three things made guidance with zones land in them
//! several times as often as without (Monte Carlo, wind ≤ 4 m/s): the course was taken
//! afresh at every moment the axis may turn, so in a light wind its noisy direction flipped
//! it between off the wind and into it within half a second; the axis jumped to the course
//! chosen at once, by up to 60°, even on the turn onto the final, with the vehicle already
//! on the base leg of the old one; and the turn onto the final chose again. So now the
//! course is chosen only where the pattern is placed (the approximation, a loop's start),
//! not on the turn onto the final; a course chosen is kept while its low legs stay clear and
//! it stays within [`MAX_OFFSET_RAD`] of the wind (the legs depend on the course, not on the
//! wind, so the wind's noise no longer flips it); and the axis turns towards it within the
//! same limits as towards the wind (`pattern.rs`), since the vehicle is placed for the axis
//! it had whatever the reason for the turn.
//!
//! That was not the whole cost: with these fixed, guidance with zones still landed in them
//! more often than without. In the runs replayed, a final turned 20–50° off a 3–4 m/s wind
//! ended out of reach soon after the turn onto it (the energy sums plan with the wind along
//! the axis only, not the crab a crosswind costs), and the flight to the best reachable point
//! landed beside the target, in a zone. So the turn is also limited by the crosswind it
//! brings, [`MAX_CROSSWIND_MPS`] (in calm air the full [`MAX_OFFSET_RAD`]); past that the
//! nominal into-wind final is flown, whose few metres of scatter keep it out of a zone tens of
//! metres away better than a crosswind final does. Planning the energy along the turned final
//! would allow larger turns in stronger winds.
//!
//! With the target out of reach the best reachable point is the point of the glide's circle
//! nearest the target; when that lies in a zone (or within [`POINT_MARGIN_M`] of one), the
//! point of the glide's disc nearest the target and clear of every zone is flown to instead.

use super::config::SpiralConfig;
use super::reach::Reach;
use crate::keep_out::KeepOutZones;

/// Step between the candidate final-approach courses, rad (10°).
const COURSE_STEP_RAD: f64 = 0.174_532_925_199_432_95;
/// Largest turn of the final approach away from into-the-wind, rad (60°): further off the
/// wind the crosswind at touchdown costs more than the zone saves, and the energy sums
/// (planned along the wind) no longer hold.
const MAX_OFFSET_RAD: f64 = 6.0 * COURSE_STEP_RAD;
/// Largest crosswind a turned final may take, m/s: the energy sums plan the final along the
/// wind, and a crab into more than this puts the stack short of the target (Monte Carlo with
/// zones next to the target: finals 20–50° off a 3–4 m/s wind ended out of reach, 50 m from
/// the target, in the zones they were turned away from).
const MAX_CROSSWIND_MPS: f64 = 1.0;

/// The largest turn off the wind at `wind_speed_mps`: [`MAX_OFFSET_RAD`], less in a wind whose
/// crosswind on such a final would exceed [`MAX_CROSSWIND_MPS`].
fn max_offset_rad(wind_speed_mps: f64) -> f64 {
    if wind_speed_mps <= MAX_CROSSWIND_MPS {
        MAX_OFFSET_RAD
    } else {
        (MAX_CROSSWIND_MPS / wind_speed_mps)
            .asin()
            .min(MAX_OFFSET_RAD)
    }
}
/// Half-angle of the wedge about the final approach kept clear, rad (8°): after the base leg
/// the stack converges onto the final line from its side, near the target (where a zone
/// matters) in the point-mass flights up to about 6° off it.
const FINAL_WEDGE_RAD: f64 = 0.139_626_340_159_546_37;
/// How far past the target the final approach is kept clear, m (a long landing's overshoot).
const OVERSHOOT_M: f64 = 30.0;
/// Least distance from a best reachable point to a zone, m: the point is where the payload
/// comes down give or take the landing's scatter.
pub(super) const POINT_MARGIN_M: f64 = 15.0;

/// The legs a final-approach course flies low, in north/east from the target at `target_ne`,
/// for a pattern of half-size `sc.half_size_m`: the final (from twice the half-size out,
/// where an extended downwind leg turns base at the latest in the nominal pattern, to the
/// overshoot past the target), the wedge of [`FINAL_WEDGE_RAD`] either side of it in which
/// the stack converges onto it after the base leg, and the base leg from the downwind leg's
/// side.
fn low_legs(target_ne: [f64; 2], course_rad: f64, sc: &SpiralConfig) -> [[[f64; 2]; 2]; 4] {
    // Downwind unit vector (x) and its right (y); the final is flown along −x.
    let (s, c) = (course_rad + std::f64::consts::PI).sin_cos();
    let at = |x: f64, y: f64| [target_ne[0] + x * c - y * s, target_ne[1] + x * s + y * c];
    let a = sc.half_size_m;
    let final_start = (2.0 * a).max(sc.min_final_m);
    let (ws, wc) = FINAL_WEDGE_RAD.sin_cos();
    [
        [at(final_start, 0.0), at(-OVERSHOOT_M, 0.0)],
        [at(final_start * wc, final_start * ws), target_ne],
        [at(final_start * wc, -final_start * ws), target_ne],
        [at(a, -a), at(a, 0.0)],
    ]
}

/// The square spiral's four sides.
fn square(target_ne: [f64; 2], course_rad: f64, sc: &SpiralConfig) -> [[[f64; 2]; 2]; 4] {
    let (s, c) = (course_rad + std::f64::consts::PI).sin_cos();
    let at = |x: f64, y: f64| [target_ne[0] + x * c - y * s, target_ne[1] + x * s + y * c];
    let a = sc.half_size_m;
    let k = [at(-a, -a), at(a, -a), at(a, a), at(-a, a)];
    [[k[0], k[1]], [k[1], k[2]], [k[2], k[3]], [k[3], k[0]]]
}

/// The final-approach course keeping clear of the zones, held between the moments the
/// pattern's axis may turn.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct ClearApproach {
    /// The course chosen instead of into the wind, rad; `None` flies into the wind.
    chosen_rad: Option<f64>,
    /// Whether the last choice found nothing clear (said once until it changes).
    none_clear: bool,
}

impl ClearApproach {
    /// The final-approach course to plan with instead of into the wind (`None`: into the
    /// wind): when `may_turn`, a choice around `into_wind_rad` (the course into the wind,
    /// rad), else the one held. A course held stays while its low legs are clear and it is
    /// within [`MAX_OFFSET_RAD`] of the wind (see the module's doc). The second value is a
    /// note for the operator when the choice changed.
    pub(super) fn course(
        &mut self,
        zones: &KeepOutZones,
        into_wind_rad: Option<f64>,
        target_ne: [f64; 2],
        sc: &SpiralConfig,
        may_turn: bool,
        wind_speed_mps: f64,
    ) -> (Option<f64>, Option<String>) {
        let limit = max_offset_rad(wind_speed_mps);
        let Some(into_wind) = into_wind_rad.filter(|_| may_turn) else {
            return (self.chosen_rad, None);
        };
        let clear =
            |legs: &[[[f64; 2]; 2]]| legs.iter().all(|[a, b]| zones.crossed_by(*a, *b).is_none());
        if let Some(held) = self.chosen_rad
            && stx_types::rotation::wrap_pi(held - into_wind).abs() <= limit + 1e-9
            && clear(&low_legs(target_ne, held, sc))
        {
            return (Some(held), None);
        }
        let offsets = std::iter::once(0.0).chain((1..=6).flat_map(|k| {
            let o = k as f64 * COURSE_STEP_RAD;
            [o, -o]
        }));
        let candidates: Vec<f64> = offsets
            .filter(|o| o.abs() <= limit + 1e-9)
            .map(|o| into_wind + o)
            .collect();
        let low_clear = |c: f64| clear(&low_legs(target_ne, c, sc));
        let all_clear = |c: f64| low_clear(c) && clear(&square(target_ne, c, sc));
        // The least turn whose low legs are clear; of the two sides at that turn, the one
        // whose square is clear too.
        let pick = candidates
            .iter()
            .copied()
            .filter(|c| low_clear(*c))
            .min_by(|a, b| {
                let key = |c: f64| ((c - into_wind).abs(), !all_clear(c));
                key(*a)
                    .partial_cmp(&key(*b))
                    .unwrap_or(std::cmp::Ordering::Equal)
            });
        let blocking = zones
            .zones
            .iter()
            .find(|z| {
                low_legs(target_ne, into_wind, sc)
                    .iter()
                    .any(|[a, b]| z.crossed_by(*a, *b))
            })
            .map(|z| z.name.clone());
        let (new, note) = match (pick, blocking) {
            // Into the wind is clear (its low legs at least): the nominal plan.
            (Some(c), _) if c == into_wind => (None, None),
            (Some(c), blocking) => {
                let offset_deg = (c - into_wind).to_degrees();
                let note = self.chosen_rad.is_none().then(|| {
                    format!(
                        "keep-out: the final approach into the wind crosses zone '{}'; \
                         landing {offset_deg:+.0}° off the wind, on a course of {:.0}°, clear of every zone",
                        blocking.unwrap_or_else(|| "?".into()),
                        c.to_degrees().rem_euclid(360.0)
                    )
                });
                self.none_clear = false;
                (Some(c), note)
            }
            (None, blocking) => {
                let note = (!self.none_clear).then(|| {
                    format!(
                        "keep-out: no final approach within {:.0}° of the wind clears the zones \
                         (into the wind crosses '{}'; more would take over {MAX_CROSSWIND_MPS:.0} m/s \
                         of crosswind); flying the nominal approach",
                        limit.to_degrees(),
                        blocking.unwrap_or_else(|| "?".into())
                    )
                });
                self.none_clear = true;
                (None, note)
            }
        };
        self.chosen_rad = new;
        (new, note)
    }
}

/// Whether `p` (north, east) lies in a zone or within [`POINT_MARGIN_M`] of one.
fn near_zone(zones: &KeepOutZones, p: [f64; 2]) -> bool {
    zones.zone_at(p).is_some()
        || (0..8).any(|k| {
            let (s, c) = (k as f64 * std::f64::consts::FRAC_PI_4).sin_cos();
            zones
                .crossed_by(p, [p[0] + POINT_MARGIN_M * c, p[1] + POINT_MARGIN_M * s])
                .is_some()
        })
}

/// A moved best point is kept while it stays in the glide's disc, clear of the zones, and
/// within this of the best candidate's miss, m. Seed 12 run 726 of the keep-out campaign (with
/// the AHRS heading bias learned) had two candidates 3 m apart in miss, 31 m apart on the
/// ground (either end of the clear stretch east of the road); the wind estimate's jitter
/// swapped them every update, the stack flew between the two and landed 30 m from the one
/// announced.
const KEEP_POINT_WITHIN_M: f64 = 10.0;

/// The best reachable point clear of the zones, held from one update to the next.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct ClearPoint {
    /// The point chosen last, from the target (north, east), m, while the nominal one was not
    /// clear.
    chosen_rel: Option<[f64; 2]>,
}

impl ClearPoint {
    /// The best reachable point clear of the zones, from the target (north, east), m, when the
    /// nominal one (`reach.best_rel`) is not clear; `None` when it is, or nothing in the
    /// glide's disc is. The point chosen last stays while it is still in the disc, clear, and
    /// misses the target by at most [`KEEP_POINT_WITHIN_M`] more than the best candidate.
    pub(super) fn best(
        &mut self,
        zones: &KeepOutZones,
        target_ne: [f64; 2],
        reach: &Reach,
    ) -> Option<[f64; 2]> {
        let at = |rel: [f64; 2]| [target_ne[0] + rel[0], target_ne[1] + rel[1]];
        let candidate = best_clear_rel(zones, target_ne, reach);
        let kept = match (self.chosen_rel, candidate) {
            (Some(last), Some(new)) => {
                let in_disc =
                    (last[0] - reach.drift[0]).hypot(last[1] - reach.drift[1]) <= reach.reach;
                let close = last[0].hypot(last[1]) <= new[0].hypot(new[1]) + KEEP_POINT_WITHIN_M;
                (in_disc && close && !near_zone(zones, at(last))).then_some(last)
            }
            _ => None,
        };
        self.chosen_rel = kept.or(candidate);
        self.chosen_rel
    }
}

/// The best reachable point clear of the zones, from the target (north, east), m, when the
/// nominal one (`reach.best_rel`) is not clear; `None` when it is, or nothing in the glide's
/// disc is. Candidates are the disc's points on rings of a tenth of its radius and 5° apart.
fn best_clear_rel(zones: &KeepOutZones, target_ne: [f64; 2], reach: &Reach) -> Option<[f64; 2]> {
    let at = |rel: [f64; 2]| [target_ne[0] + rel[0], target_ne[1] + rel[1]];
    if !near_zone(zones, at(reach.best_rel)) {
        return None;
    }
    let mut best: Option<([f64; 2], f64)> = None;
    for ring in 1..=10 {
        let r = reach.reach * ring as f64 / 10.0;
        for k in 0..72 {
            let (s, c) = (k as f64 * 5.0_f64.to_radians()).sin_cos();
            let rel = [reach.drift[0] + r * c, reach.drift[1] + r * s];
            let miss = rel[0].hypot(rel[1]);
            if best.is_none_or(|(_, m)| miss < m) && !near_zone(zones, at(rel)) {
                best = Some((rel, miss));
            }
        }
    }
    best.map(|(rel, _)| rel)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::keep_out::KeepOutZone;

    fn square_zone(name: &str, n0: f64, n1: f64, e0: f64, e1: f64) -> KeepOutZones {
        KeepOutZones {
            zones: vec![KeepOutZone {
                name: name.into(),
                rings_ne_m: vec![vec![[n0, e0], [n1, e0], [n1, e1], [n0, e1]]],
            }],
        }
    }

    #[test]
    fn the_turn_off_the_wind_is_limited_by_the_crosswind_it_brings() {
        assert_eq!(max_offset_rad(0.5), MAX_OFFSET_RAD);
        assert_eq!(max_offset_rad(MAX_CROSSWIND_MPS), MAX_OFFSET_RAD);
        // 4 m/s: a turn of asin(1/4) = 14.5° at most, so a zone needing 20° is not avoided
        // by turning: the nominal final is flown.
        let limit = max_offset_rad(4.0);
        assert!(
            (limit.to_degrees() - 14.48).abs() < 0.01,
            "{}",
            limit.to_degrees()
        );
        assert!((4.0 * limit.sin() - MAX_CROSSWIND_MPS).abs() < 1e-12);
        let sc = SpiralConfig::default();
        // A pond across the final from the south, wide enough that 10° does not clear it.
        let zones = square_zone("Pond", -120.0, -60.0, -40.0, 40.0);
        let mut calm = ClearApproach::default();
        let (turned, _) = calm.course(&zones, Some(0.0), [0.0, 0.0], &sc, true, 0.5);
        assert!(turned.is_some_and(|c| c.abs() > 0.15), "{turned:?}");
        let mut windy = ClearApproach::default();
        let (kept, _) = windy.course(&zones, Some(0.0), [0.0, 0.0], &sc, true, 4.0);
        assert_eq!(kept, None, "into the wind, not {kept:?}");
    }

    #[test]
    fn a_zone_on_the_final_into_the_wind_turns_the_approach_by_the_least_clear_step() {
        let sc = SpiralConfig::default();
        // Into the wind is north (course 0): the final comes from the south, over a pond
        // 40–80 m south of the target.
        let zones = square_zone("pond", -80.0, -40.0, -10.0, 10.0);
        let mut clear = ClearApproach::default();
        let (course, note) = clear.course(&zones, Some(0.0), [0.0, 0.0], &sc, true, 0.0);
        let course = course.expect("a turned approach");
        assert!(course.abs() > 0.0 && course.abs() <= MAX_OFFSET_RAD + 1e-9);
        assert!(note.unwrap().contains("'pond'"));
        for [a, b] in low_legs([0.0, 0.0], course, &sc) {
            assert!(zones.crossed_by(a, b).is_none());
        }
        // Held while the axis may not turn, whatever the wind.
        let (held, note) = clear.course(&zones, Some(1.0), [0.0, 0.0], &sc, false, 0.0);
        assert_eq!((held, note), (Some(course), None));
    }

    #[test]
    fn with_no_zone_on_the_way_nothing_changes() {
        let sc = SpiralConfig::default();
        let zones = square_zone("far", 500.0, 600.0, 500.0, 600.0);
        let mut clear = ClearApproach::default();
        assert_eq!(
            clear.course(&zones, Some(0.3), [0.0, 0.0], &sc, true, 0.0),
            (None, None)
        );
    }

    #[test]
    fn a_course_chosen_is_kept_while_clear_and_near_the_wind_not_flipped_by_its_noise() {
        let sc = SpiralConfig::default();
        let zones = square_zone("pond", -80.0, -40.0, -10.0, 10.0);
        let mut clear = ClearApproach::default();
        let (course, _) = clear.course(&zones, Some(0.0), [0.0, 0.0], &sc, true, 0.0);
        let course = course.expect("a turned approach");
        // The wind veers so that into the wind is clear now, and back: the course stays, and
        // nothing is said.
        for wind in [0.5, -0.2, 0.3] {
            assert_eq!(
                clear.course(&zones, Some(wind), [0.0, 0.0], &sc, true, 0.0),
                (Some(course), None)
            );
        }
        // Further than the largest offset from the wind it is chosen again.
        let far = course + MAX_OFFSET_RAD + 0.3;
        assert_ne!(
            clear
                .course(&zones, Some(far), [0.0, 0.0], &sc, true, 0.0)
                .0,
            Some(course)
        );
    }

    #[test]
    fn zones_all_around_fall_back_to_the_nominal_approach_with_a_reason() {
        let sc = SpiralConfig::default();
        // A ring of water around the target: every final crosses it.
        let mut zones = square_zone("lake", -90.0, 90.0, -90.0, 90.0);
        zones.zones[0].rings_ne_m.push(vec![
            [-20.0, -20.0],
            [20.0, -20.0],
            [20.0, 20.0],
            [-20.0, 20.0],
        ]);
        let mut clear = ClearApproach::default();
        let (course, note) = clear.course(&zones, Some(0.0), [0.0, 0.0], &sc, true, 0.0);
        assert_eq!(course, None);
        assert!(note.unwrap().contains("flying the nominal approach"));
        // Said once.
        assert_eq!(
            clear.course(&zones, Some(0.0), [0.0, 0.0], &sc, true, 0.0),
            (None, None)
        );
    }

    #[test]
    fn a_best_reachable_point_in_a_zone_moves_to_the_nearest_clear_point_of_the_disc() {
        let sc = SpiralConfig::default();
        // Drift 400 m south of the target, reach 300 m: the nominal best point 100 m south.
        let reach = Reach::assess([-400.0, 0.0], [0.0, 0.0], 108.4, 3.0, 1.0, &sc, false);
        assert!(
            (reach.best_rel[0] + 100.0).abs() < 1e-6,
            "{:?}",
            reach.best_rel
        );
        let zones = square_zone("forest", -150.0, -60.0, -40.0, 40.0);
        let best = best_clear_rel(&zones, [0.0, 0.0], &reach).expect("moved");
        assert!(!near_zone(&zones, best));
        let from_drift = (best[0] - reach.drift[0]).hypot(best[1] - reach.drift[1]);
        assert!(from_drift <= reach.reach + 1e-6);
        // Beside the forest, not behind it: within 150 m of the target.
        assert!(best[0].hypot(best[1]) < 150.0, "{best:?}");
        // A point already clear is left alone.
        let elsewhere = square_zone("far", 500.0, 600.0, 500.0, 600.0);
        assert_eq!(best_clear_rel(&elsewhere, [0.0, 0.0], &reach), None);
    }

    #[test]
    fn a_moved_best_point_is_held_while_the_other_side_of_the_zone_is_barely_better() {
        let sc = SpiralConfig::default();
        let zones = square_zone("forest", -150.0, -60.0, -40.0, 40.0);
        // Drift a metre east of the forest's axis: the disc's point beside the forest's west
        // side is the nearer to the target, by a little.
        let east = Reach::assess([-400.0, 1.0], [0.0, 0.0], 108.4, 3.0, 1.0, &sc, false);
        let west = Reach::assess([-400.0, -1.0], [0.0, 0.0], 108.4, 3.0, 1.0, &sc, false);
        let first = best_clear_rel(&zones, [0.0, 0.0], &east).expect("moved");
        let other = best_clear_rel(&zones, [0.0, 0.0], &west).expect("moved");
        assert!(first[1] < 0.0 && other[1] > 0.0, "{first:?} {other:?}");
        let mut point = ClearPoint::default();
        assert_eq!(point.best(&zones, [0.0, 0.0], &east), Some(first));
        // The wind estimate's jitter moves the drift two metres west: the point stays west.
        assert_eq!(point.best(&zones, [0.0, 0.0], &west), Some(first));
        // A point the glide no longer reaches is given up for the best one.
        let lower = Reach::assess([-430.0, -1.0], [0.0, 0.0], 108.4, 3.0, 1.0, &sc, false);
        let now = point.best(&zones, [0.0, 0.0], &lower).expect("moved");
        assert_ne!(now, first);
        assert_eq!(Some(now), best_clear_rel(&zones, [0.0, 0.0], &lower));
        // Once the nominal point is clear again the held one is forgotten.
        let clear = square_zone("far", 500.0, 600.0, 500.0, 600.0);
        assert_eq!(point.best(&clear, [0.0, 0.0], &west), None);
        assert_eq!(point.best(&zones, [0.0, 0.0], &west), Some(other));
    }
}
