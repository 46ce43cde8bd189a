//! Spiral-landing guidance (seed §5.3, Fig. 5.4 and 5.7): approximation, a square spiral of
//! four branches around the target, the final approach into the wind, and the flare.
//!
//! Geometry lives in a wind frame centred on the target: `x` points downwind, `y` to its
//! right. The pattern's corners are at `(±ax, ±ay)`; the branches are flown clockwise with
//! localizer-and-course control: Branch1 downwind along `y = −ay`, Branch2 across at
//! `x = +ax`, Branch3 upwind along `y = +ay`, Branch4 across at `x = −ax`. The entry corner is
//! the one reached soonest from where the vehicle is (the region decision of Fig. 5.4: in
//! light wind, the corner of the quadrant it is in).
//!
//! **Branches scaled with the wind** (seed: "correct some wind perturbation by scaling the
//! branches length"). The half-width across the wind is `ay = half_size_m`; the half-length
//! along it is `ax = max(ay·(V − w)/V, r)`, with `V` the airspeed, `w` the wind along the
//! axis and `r` the corner's turn radius. The upwind leg then takes `2ay/V`, as long as in
//! still air, however strong the wind, and the pattern shrinks towards a weave across the wind
//! as the wind nears the airspeed. The pattern stays centred on the target: flown on
//! ground-referenced lines it does not slide, and the two along-wind legs, the same length
//! over the ground, put the vehicle upwind and downwind of the target for equal times. The
//! seed's slide spiral, flown on headings, needed one branch longer than the other to come
//! back over the target; here that is what the ground-referenced localizers do.
//!
//! The pattern's axis and its half-length follow the wind during the approximation; after that
//! they change only at the start of a loop (at most 45°, but fully at the first loop on a
//! settled wind if they were laid on an unsettled one) and onto the final (at most 20°), so the
//! vehicle's place in the pattern does not move under it while decisions taken on it are being
//! flown. Corners are started a turn radius early, at the turn rate the control gains in force
//! actually give ([`corner_turn_rate_rad_s`]), and energy decisions wait until the wind
//! estimate has been certain for a while. Each phase change is one decision, and its reason
//! says where, how high, in which loop, what was decided and why.
//!
//! Leaving the spiral is an energy decision recomputed at every update. The height needed to
//! turn base at `x` on Branch1 and glide in is `H(x) = hang + s₀·ay/g_cross + s_t·x/g_up +
//! 2·turn loss + margin`, planned for a little more headwind than measured. On Branch1, at the
//! normal corner, guidance loops again if one more loop still leaves at least `H(ax)`;
//! otherwise it extends the downwind leg and turns base at the first `x` where the height has
//! fallen to `H(x)`. The base leg ends on the final-approach line through the target, flown
//! upwind, and full brakes below the flare height.
//!
//! **Which law flies the final.** The brakes on the final approach are set by
//! [`FinalLaw::GlideInversion`] by default: every update, the brake whose steady glide over the
//! ground, into the planned headwind, ends on the aim point (the flare's start) from where the
//! vehicle is — the glide performance inverted. The seed's glide-slope law (eqs. 5.12–5.17,
//! [`control::vertical`](crate::control::vertical)) down a straight path whose slope is fixed
//! at the turn onto the final is [`FinalLaw::GlideSlope`]; the Monte Carlo comparison that
//! decided between them is in `crates/stx-gnc/GNC_NOTES.md`.
//!
//! **Too strong a wind.** At every update until the flare, in every phase, guidance checks the
//! glide's reach: the circle of radius `V·T` (T the time left to the ground at the current
//! sink) around the drift point, where the wind alone would carry the stack. When the target
//! lies outside it by more than the drift an error of 0.3 m/s in the wind makes over `T` (plus
//! 20 m), guidance says so — an event with the wind, the reach and the best reachable point —
//! and flies to that point, the one of the circle nearest the target, into the wind for the
//! last 40 m. A point moved clear of a keep-out zone lies inside the circle, so the way to it
//! is braked to the glide that ends on it. It announces the point again whenever it moves by 50
//! m (the recovery team drives to it), and goes back to the target only when it is well inside
//! the circle.
//!
//! # How the parts fit
//!
//! Each [`Spiral::update`] first *assesses* the situation (`situation.rs`): the planning wind
//! and whether it is known (`wind.rs`), the pattern's axis, frame and scaled branches
//! (`pattern.rs`), the energy sums (`energy.rs`) with the corner turn rate of the gains in
//! force (`turn_rate.rs`), the glide's reach (`reach.rs`) and the final approach's geometry
//! (`final_approach.rs`), all with the glide learned so far in flight (`learned.rs`) and the
//! turn rate (`learned_turn.rs`), the main-line gains divided by the turn rate's scale. The
//! phase machine (`phases.rs`) then takes at most one decision on
//! it, and the steering (`steering.rs`) flies the phase it leaves the vehicle in; the final
//! approach's brakes, S-turns and flare are in `final_approach.rs`. The settings are in
//! `config.rs`. Only this module holds the parts' memories together; the parts do not know
//! the [`Spiral`].

mod adopt;
pub(super) mod config;
mod energy;
mod final_approach;
mod keep_clear;
mod learned;
mod learned_turn;
mod pattern;
mod phases;
mod reach;
mod situation;
mod steering;
mod turn_rate;
mod wind;

pub use config::{FinalLaw, SpiralConfig};
pub use turn_rate::corner_turn_rate_rad_s;
pub use wind::SurfaceWind;

use serde::{Deserialize, Serialize};
use stx_types::controls::Controls;

use self::energy::Energy;
use self::final_approach::{FinalApproach, FinalGeometry};
use self::learned::LearnedGlide;
pub use self::learned::LearnedPolar;
use self::learned_turn::LearnedTurn;
use self::pattern::{Axis, Pattern, WindFrame};
use self::phases::{Change, PhaseMachine};
use self::reach::{Announcement, Reach};
use self::situation::Situation;
use self::steering::steer;
use self::turn_rate::CornerRate;
use self::wind::PlanningWind;
use crate::control::TurnLatch;
use crate::estimate::Estimate;
use crate::guidance::config::GuidanceConfig;
use crate::guidance::plan::Plan;
use crate::keep_out::KeepOutZones;
use crate::mission::GuidancePhase;

/// The spiral's plan as it stands, for the operator's map.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct SpiralStatus {
    /// Direction the pattern's x axis points (downwind), rad from north.
    pub downwind_course_rad: f64,
    /// Course of the final approach, rad.
    pub final_course_rad: f64,
    /// The square's corners (north, east), m, in branch order: start of Branch1…Branch4.
    pub corners_ne_m: [[f64; 2]; 4],
    /// Where the base leg meets the final-approach line (north, east), m.
    pub final_entry_ne_m: [f64; 2],
    /// Drone height needed to turn base from here and glide in (the seed's H3), m.
    pub final_approach_height_m: f64,
    /// Drone height above the target's ground now, m.
    pub height_m: f64,
    /// Distance from the drift point to the target over the glide's reach; > 1 unreachable.
    pub reach_ratio: f64,
    /// Whether guidance counts the target as reachable.
    pub target_reachable: bool,
    /// The reachable point nearest the target (north, east), m.
    pub best_reachable_ne_m: [f64; 2],
    /// Filtered wind guidance plans with, north and east, m/s.
    pub wind_ne_mps: [f64; 2],
    /// Turn rate the corners are planned with, rad/s.
    pub planned_turn_rate_rad_s: f64,
    /// Distance before a corner at which the next branch is started, m.
    pub turn_distance_m: f64,
}

/// Spiral-landing state.
#[derive(Debug, Clone)]
pub struct Spiral {
    /// The phase and the decisions taken in it.
    machine: PhaseMachine,
    /// The wind planned with.
    wind: PlanningWind,
    /// The pattern's axis and half-length, held within a loop.
    axis: Axis,
    /// The corner turn rate of the gains in force.
    corner_rate: CornerRate,
    /// The final approach's brake, S-turn side and glide slope.
    final_approach: FinalApproach,
    /// The best reachable point last announced.
    announced: Announcement,
    /// The glide learned in flight, which every plan is made with.
    glide: LearnedGlide,
    /// The turn rate learned in flight, which the corners are planned with.
    turn: LearnedTurn,
    /// The wind at the ground by the target, uplinked, if any.
    surface_wind: Option<SurfaceWind>,
    /// Symmetric brake of the last commands, 0…1.
    last_brake: f64,
    /// Main line of the last commands, m.
    last_main_line_m: f64,
    /// The side of a turn from nearly behind, on the branches and towards a best point.
    turn_latch: TurnLatch,
    status: SpiralStatus,
    /// The keep-out zones the low legs and the best reachable point keep clear of.
    keep_out: KeepOutZones,
    /// The final-approach course chosen to keep clear of them.
    clear_approach: keep_clear::ClearApproach,
    /// The best reachable point moved clear of them.
    clear_point: keep_clear::ClearPoint,
    /// Notes for the operator on keep-out choices since the last [`Spiral::take_notes`].
    notes: Vec<String>,
}

impl Spiral {
    /// A spiral that has not started (phase Idle).
    pub fn new() -> Self {
        Self {
            machine: PhaseMachine::new(),
            wind: PlanningWind::default(),
            axis: Axis::default(),
            corner_rate: CornerRate::default(),
            final_approach: FinalApproach::default(),
            announced: Announcement::default(),
            glide: LearnedGlide::default(),
            turn: LearnedTurn::default(),
            surface_wind: None,
            last_brake: 0.0,
            last_main_line_m: 0.0,
            turn_latch: TurnLatch::default(),
            status: SpiralStatus::default(),
            keep_out: KeepOutZones::default(),
            clear_approach: keep_clear::ClearApproach::default(),
            clear_point: keep_clear::ClearPoint::default(),
            notes: Vec::new(),
        }
    }

    /// Replaces the surface wind at the target (`None`: none known); it counts in the wind
    /// planned with below the pattern (see `wind.rs`).
    pub fn set_surface_wind(&mut self, wind: Option<SurfaceWind>) {
        self.surface_wind = wind;
    }

    /// Replaces the keep-out zones (see [`keep_clear`]); none flies the nominal spiral.
    pub fn set_keep_out(&mut self, zones: KeepOutZones) {
        self.keep_out = zones;
    }

    /// Takes the notes on keep-out choices (approach turned off the wind, nothing clear, best
    /// point moved) made since the last call.
    pub fn take_notes(&mut self) -> Vec<String> {
        std::mem::take(&mut self.notes)
    }

    /// The phase.
    pub fn phase(&self) -> GuidancePhase {
        self.machine.phase
    }

    /// Sets the phase without a decision (mode or plan changes).
    pub fn force_phase(&mut self, phase: GuidancePhase) {
        self.machine.phase = phase;
    }

    /// Takes `phase` from another copy of this guidance at `now_s` (see `adopt.rs`).
    pub fn adopt_phase(&mut self, phase: GuidancePhase, now_s: f64) {
        self.machine.adopt(phase, now_s);
    }

    /// The polar `perf` with the glide and turn rate learned so far.
    pub fn learned_performance(
        &self,
        perf: &crate::performance::GlidePerformance,
    ) -> crate::performance::GlidePerformance {
        self.turn.performance(&self.glide.performance(perf))
    }

    /// What has been learned in flight of the glide at each brake setting and of the turn.
    pub fn learned_polar(&self) -> LearnedPolar {
        LearnedPolar {
            turn_scale: self.turn.scale(),
            turn_sigma: self.turn.sigma(),
            turn_learned_s: self.turn.learned_s,
            ..self.glide.polar()
        }
    }

    /// Whether it has run since it was made: before, its status is not a plan.
    pub fn has_run(&self) -> bool {
        self.status != SpiralStatus::default()
    }

    /// The plan as it stands.
    pub fn status(&self) -> &SpiralStatus {
        &self.status
    }

    /// One guidance update: servo commands and the phase change it made, if any.
    pub fn update(
        &mut self,
        config: &GuidanceConfig,
        plan: &Plan,
        est: &Estimate,
        density: f64,
    ) -> (Controls, Change) {
        if !config.freeze_learning {
            self.glide
                .update(&config.performance, est, self.last_brake, density);
            self.turn
                .update(&config.performance, est, self.last_main_line_m);
        }
        // Whole per cent: the corner rate is flown again only when the gains change.
        let turn_scale = (self.turn.scale() * 100.0).round() / 100.0;
        let learned = GuidanceConfig {
            performance: self
                .turn
                .performance(&self.glide.performance(&config.performance)),
            gains: config.gains.for_turn_scale(turn_scale),
            ..*config
        };
        let config = &learned;
        let situation = self.assess(config, plan, est, density);
        let change = self
            .machine
            .decide(&config.spiral, &situation, &self.announced);
        let controls = steer(
            &self.machine,
            &mut self.final_approach,
            config,
            &situation,
            est,
            density,
            &mut self.turn_latch,
        );

        self.last_brake = 0.5 * (controls.brake_left + controls.brake_right);
        self.last_main_line_m = controls.main_line_m;
        let phase = self.machine.phase;
        if phase != GuidancePhase::FinalApproach {
            self.final_approach.end();
        }
        let announced = change
            .as_ref()
            .is_some_and(|c| c.1 == GuidancePhase::BestReachable);
        let best_ne = situation.reach.best_ne(situation.target_ne());
        self.announced.record(phase, announced, best_ne, est.time_s);
        self.status = self.report(&situation);
        (controls, change)
    }

    /// The situation at this update; the wind filter, the pattern's axis and the corner rate
    /// move on with it.
    fn assess(
        &mut self,
        config: &GuidanceConfig,
        plan: &Plan,
        est: &Estimate,
        density: f64,
    ) -> Situation {
        let sc = &config.spiral;
        let perf = &config.performance;
        let target_ne = [plan.target_ned_m.x, plan.target_ned_m.y];
        let ground_m = -plan.target_ned_m.z;
        let position = [est.position_ned_m.x, est.position_ned_m.y];
        let rel = [position[0] - target_ne[0], position[1] - target_ne[1]];
        let height = est.height_m() - ground_m;
        let phase = self.machine.phase;

        let wind = self.wind.update(est, sc.wind_filter_s).toward_surface(
            self.surface_wind.as_ref(),
            height - sc.hang_height_m,
            est.time_s,
        );
        let reorient = self.machine.take_reorient();
        let keep_clear_rad = if self.keep_out.zones.is_empty() || plan.approach_course_rad.is_some()
        {
            None
        } else {
            // Into the wind, or in calm air along the axis held (the final is flown upwind,
            // against the axis).
            let into_wind = if wind.speed_mps >= sc.calm_wind_mps {
                Some((-wind.ne_mps[1]).atan2(-wind.ne_mps[0]))
            } else {
                self.axis.downwind_rad().map(|d| d + std::f64::consts::PI)
            };
            // Chosen where the pattern is placed (the approximation, a loop's start), not on
            // the turn onto the final: the vehicle is already on the base leg of the course
            // chosen at the loop's start, and that course was checked clear for it.
            let may_turn = (reorient && phase != GuidancePhase::FinalApproach)
                || matches!(
                    phase,
                    GuidancePhase::Approximation | GuidancePhase::BestReachable
                );
            let (course, note) = self.clear_approach.course(
                &self.keep_out,
                into_wind,
                target_ne,
                sc,
                may_turn,
                wind.speed_mps,
            );
            self.notes.extend(note);
            course
        };
        let (downwind, frozen) = self.axis.orient(
            phase,
            reorient,
            pattern::Courses {
                operator_rad: plan.approach_course_rad,
                keep_clear_rad,
                zones_in_force: !self.keep_out.zones.is_empty(),
            },
            &wind,
            sc,
            rel,
        );
        let frame = WindFrame::new(target_ne, downwind);
        let [x, y] = frame.to_wind(rel);
        let turn_rate = self
            .corner_rate
            .planned(sc.planned_turn_rate_rad_s, &config.gains, perf);
        let energy = Energy::plan(
            sc,
            perf,
            config.gains.brake_trim,
            density,
            frame.along(wind.ne_mps),
            turn_rate,
        );
        let ax = self.axis.half_length(
            frozen,
            sc,
            energy.wind_along_mps,
            energy.v0,
            energy.turn_distance,
        );
        let ay = sc.half_size_m;
        let pattern = Pattern {
            frame,
            ax,
            ay,
            downwind_y: self.machine.downwind_y_m.unwrap_or(-ay),
        };
        let reach = Reach::assess(
            rel,
            wind.measured_ne_mps,
            height,
            energy.v0,
            energy.s0,
            sc,
            phase == GuidancePhase::BestReachable,
        );
        let mut reach = reach;
        if !self.keep_out.zones.is_empty()
            && let Some(best) = self.clear_point.best(&self.keep_out, target_ne, &reach)
        {
            reach.move_best(best);
        }
        let final_approach =
            FinalGeometry::assess(sc, perf, density, &frame, &energy, position, height);
        Situation {
            now_s: est.time_s,
            ground_m,
            position,
            x,
            y,
            height,
            lowest_body_height: height - sc.hang_height_m,
            wind,
            pattern,
            energy,
            reach,
            final_approach,
        }
    }

    /// The plan as it stands after this update's decision, for the operator's map.
    fn report(&self, s: &Situation) -> SpiralStatus {
        let p = &s.pattern;
        let base_x = self.machine.base_x_m.unwrap_or(p.ax);
        let final_entry_x = self.machine.base_join_x_m.unwrap_or(base_x);
        SpiralStatus {
            downwind_course_rad: p.frame.downwind_rad,
            final_course_rad: s.final_approach.course_rad,
            corners_ne_m: [0, 1, 2, 3].map(|k| p.frame.to_ne(p.corner(k))),
            final_entry_ne_m: p.frame.to_ne([final_entry_x, 0.0]),
            final_approach_height_m: match self.machine.base_join_x_m {
                Some(join_x) => s.energy.needed_via(base_x, p.downwind_y, join_x, 0.0),
                None => s.needed_to_turn_base(base_x),
            },
            height_m: s.height,
            reach_ratio: s.reach.reach_ratio,
            target_reachable: s.reach.reachable,
            best_reachable_ne_m: s.reach.best_ne(s.target_ne()),
            wind_ne_mps: s.wind.ne_mps,
            planned_turn_rate_rad_s: s.energy.turn_rate_rad_s,
            turn_distance_m: s.energy.turn_distance,
        }
    }
}

impl Default for Spiral {
    fn default() -> Self {
        Self::new()
    }
}
