//! Spiral-landing guidance (seed §5.3, Fig. 5.4 and 5.7): approximation, a square spiral of
//! four branches around the target, the final approach into the wind with glide-slope
//! control, and the flare.
//!
//! Geometry lives in a wind frame centred on the target: `x` points downwind, `y` to its
//! right. The square's corners are at `(±a, ±a)`; the branches are flown clockwise with
//! localizer-and-course control: Branch1 downwind along `y = −a`, Branch2 across at `x = +a`,
//! Branch3 upwind along `y = +a`, Branch4 across at `x = −a`. Ground-referenced localizers
//! already stretch the downwind branch and shrink the upwind one in ground-speed terms, which
//! is what the seed's wind-scaled ("slide") branches do.
//!
//! The pattern's axis follows the wind during the approximation; after that it turns only at
//! the start of a loop (at most 45°) and onto the final (at most 20°), so the vehicle's place
//! in the pattern does not move under it while decisions taken on it are being flown. Corners
//! are started a turn radius early, at the turn rate the control gains in force actually give
//! ([`corner_turn_rate_rad_s`]), and energy decisions wait until the wind estimate has been
//! certain for a while. Each phase change is one decision: the final is left as too high only
//! after some time on it, and a base leg meets its final line only out at the base leg.
//!
//! Leaving the spiral is an energy decision recomputed at every update. The height needed to
//! turn base at `x` on Branch1 and glide in is `H(x) = hang + s₀·a/g_cross + s_t·x/g_up + 2·turn
//! loss + margin`. On Branch1, at the normal corner, guidance loops again if one more loop still
//! leaves at least `H(a)`; otherwise it extends the downwind leg and turns base at the first `x`
//! where the height has fallen to `H(x)`. The base leg ends on the final-approach line through
//! the target, flown upwind with the vertical law absorbing what the plan got wrong, and full
//! brakes below the flare height. When the wind makes the target unreachable (the target
//! lies outside the circle the glide can reach around the drift point), guidance says so and
//! flies to the reachable point nearest the target instead.

use serde::{Deserialize, Serialize};
use stx_dynamics::rotation::wrap_pi;
use stx_dynamics::state::Controls;

use crate::control::{self, ControlGains, Localizer};
use crate::estimate::Estimate;
use crate::guidance::{GuidanceConfig, Plan};
use crate::mission::GuidancePhase;
use crate::performance::GlidePerformance;

/// Spiral-landing settings, with units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SpiralConfig {
    /// Half the side of the square spiral, m (each branch is twice as long).
    pub half_size_m: f64,
    /// Longest final approach the downwind leg may be extended to, m.
    pub max_final_m: f64,
    /// Shortest final approach, m: time to settle on the line before the ground.
    pub min_final_m: f64,
    /// Height of the drone above the lowest hanging body (the transponder), m: the drone is
    /// this high when the stack touches down.
    pub hang_height_m: f64,
    /// Height of the lowest body above the ground at which the flare starts, m.
    pub flare_height_m: f64,
    /// Whether to flare at all; without, the final approach's last brake setting is held to
    /// the ground (to measure what the flare is worth).
    pub flare: bool,
    /// Turn rate planned for the corners, rad/s; 0 (the default) plans with the rate the
    /// control gains actually turn at ([`corner_turn_rate_rad_s`]), which is what the
    /// corners should be cut for: a fixed rate goes stale whenever the gains are retuned.
    pub planned_turn_rate_rad_s: f64,
    /// Height kept in hand above the planned glide when leaving the spiral, m.
    pub final_margin_m: f64,
    /// Below this wind the approach direction is held as it is, m/s.
    pub calm_wind_mps: f64,
    /// Share of the glide's still-air reach guidance counts on before calling a target out of
    /// reach (checked until the base turn; the final glide is planned to use all of it).
    pub reach_margin: f64,
    /// Time constant of the wind filter that orients the pattern, s.
    pub wind_filter_s: f64,
    /// Touchdown aimed this far beyond the target along the final, m (corrects the trail of
    /// the hanging bodies and the flare's dynamics, measured by the Monte Carlo).
    pub aim_beyond_m: f64,
    /// Headwind added to the measured wind when planning the final, m/s.
    pub wind_margin_mps: f64,
    /// Headwind added as a share of the measured wind when planning the final.
    pub wind_margin_fraction: f64,
}

impl Default for SpiralConfig {
    fn default() -> Self {
        Self {
            half_size_m: 50.0,
            max_final_m: 300.0,
            min_final_m: 40.0,
            hang_height_m: 8.4,
            flare_height_m: 6.0,
            flare: true,
            planned_turn_rate_rad_s: 0.0,
            final_margin_m: 0.0,
            calm_wind_mps: 0.3,
            reach_margin: 1.0,
            wind_filter_s: 10.0,
            aim_beyond_m: 0.0,
            wind_margin_mps: 0.2,
            wind_margin_fraction: 0.1,
        }
    }
}

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

/// Average turn rate of a 90° course change flown by the course law with `gains` on the
/// point-mass parafoil `perf` (still air, the 4 Hz control period), rad/s: 90° over the
/// time to cover 90 % of the change from straight flight.
///
/// The seed planned corners at a fixed rate; with the gains `stx tune` produced the vehicle
/// turns at about two thirds of the 20°/s once assumed, and corners planned for 20°/s were
/// started late, overshooting every branch and misplacing the final approach.
pub fn corner_turn_rate_rad_s(gains: &ControlGains, perf: &GlidePerformance) -> f64 {
    use crate::pointmass::{Conditions, PointMass};
    use nalgebra::Vector3;
    const CONTROL_PERIOD_S: f64 = 0.25;
    const STEPS_PER_PERIOD: usize = 5;
    const LONGEST_S: f64 = 60.0;
    let quarter = std::f64::consts::FRAC_PI_2;
    let air = Conditions::nominal(Vector3::zeros(), perf.reference_density_kg_per_m3);
    let mut mass = PointMass::new(0.0, Vector3::zeros(), 0.0);
    while mass.time_s < LONGEST_S {
        let main_line_m = control::course(gains, mass.heading_rad, mass.turn_rate_rad_s, quarter);
        let controls = Controls {
            main_line_m,
            ..Controls::default()
        };
        for _ in 0..STEPS_PER_PERIOD {
            mass.step(
                perf,
                &controls,
                &air,
                CONTROL_PERIOD_S / STEPS_PER_PERIOD as f64,
            );
            if mass.heading_rad >= 0.9 * quarter {
                return quarter / mass.time_s;
            }
        }
    }
    quarter / LONGEST_S
}

/// Spiral-landing state.
#[derive(Debug, Clone)]
pub struct Spiral {
    phase: GuidancePhase,
    wind_ne_mps: Option<[f64; 2]>,
    last_time_s: Option<f64>,
    downwind_rad: Option<f64>,
    entry_branch: GuidancePhase,
    approach_from_ne_m: Option<[f64; 2]>,
    base_x_m: Option<f64>,
    /// Lateral offset of the downwind leg (Branch1), m: −a in the pattern, or where the
    /// vehicle was when it ran short of height and went for the downwind leg directly.
    downwind_y_m: Option<f64>,
    extending: bool,
    weave_right: bool,
    last_final_brake: f64,
    status: SpiralStatus,
    /// The corner turn rate for the gains and performance it was computed from (computing it
    /// flies a point mass, so it is kept until either changes).
    turn_rate: Option<(ControlGains, GlidePerformance, f64)>,
    /// Time the current phase was entered, s.
    phase_since_s: f64,
    /// The pattern's axis may follow the wind at the next update: in the approximation, and
    /// once at the start of each loop. Within a loop, and from the decision to leave the
    /// pattern to the ground, the axis is held: in light wind the estimated direction
    /// wanders, and every turn of the axis moves the vehicle within the pattern, upsetting
    /// decisions already taken (a base leg that never met its final line, a final turned
    /// from far out).
    reorient: bool,
    /// Since when the estimator's wind uncertainty has been small, s.
    wind_known_since_s: Option<f64>,
}

/// The branches in flying order.
const BRANCHES: [GuidancePhase; 4] = [
    GuidancePhase::Branch1,
    GuidancePhase::Branch2,
    GuidancePhase::Branch3,
    GuidancePhase::Branch4,
];

fn branch_index(phase: GuidancePhase) -> Option<usize> {
    BRANCHES.iter().position(|b| *b == phase)
}

/// Corners in wind coordinates (x downwind, y right), start of each branch.
fn corner_xy(branch: usize, a: f64) -> [f64; 2] {
    match branch % 4 {
        0 => [-a, -a],
        1 => [a, -a],
        2 => [a, a],
        _ => [-a, a],
    }
}

type Change = Option<(GuidancePhase, GuidancePhase, String)>;

/// Height below the direct glide-in need at which guidance stops the pattern, m.
const LOW_MARGIN_M: f64 = 10.0;
/// Wind uncertainty (1-σ per component) below which guidance trusts the wind for its energy
/// decisions, m/s.
const WIND_KNOWN_SIGMA_MPS: f64 = 0.6;
/// Below this height of the lowest body the reach check is off: the terminal phases are
/// planned to use all the height there is, so the glide's reach is always just enough.
const REACH_CHECK_MIN_HEIGHT_M: f64 = 60.0;
/// Height above the steepest glide on final at which S-turns start, m.
const S_TURN_EXCESS_M: f64 = 10.0;
/// Height above the steepest glide on final at which guidance goes back downwind, m.
const REENTER_EXCESS_M: f64 = 40.0;
/// Least time on the final approach before guidance may call it too high and leave it, s:
/// the first seconds after the turn onto the line still carry the turn's errors.
const MIN_FINAL_BEFORE_REENTRY_S: f64 = 10.0;
/// Largest turn of the pattern's axis at the start of a loop, rad (45°).
const LOOP_REORIENT_MAX_RAD: f64 = std::f64::consts::FRAC_PI_4;
/// Largest turn of the final-approach course when turning final, rad (20°).
const FINAL_REORIENT_MAX_RAD: f64 = 0.3491;
/// Time the wind uncertainty must have stayed small before energy decisions use it, s.
const WIND_SETTLE_S: f64 = 10.0;
/// S-turns swing this far either side of the final line, m.
const S_TURN_HALF_WIDTH_M: f64 = 40.0;
/// Course offset of an S-turn leg from the final course, rad (100°: slightly back downwind).
const S_TURN_ANGLE_RAD: f64 = 1.7453;

impl Spiral {
    /// A spiral that has not started (phase Idle).
    pub fn new() -> Self {
        Self {
            phase: GuidancePhase::Idle,
            wind_ne_mps: None,
            last_time_s: None,
            downwind_rad: None,
            entry_branch: GuidancePhase::Branch1,
            approach_from_ne_m: None,
            base_x_m: None,
            downwind_y_m: None,
            extending: false,
            weave_right: true,
            last_final_brake: 0.0,
            status: SpiralStatus::default(),
            turn_rate: None,
            phase_since_s: 0.0,
            reorient: true,
            wind_known_since_s: None,
        }
    }

    /// The phase.
    pub fn phase(&self) -> GuidancePhase {
        self.phase
    }

    /// Sets the phase without a decision (mode or plan changes).
    pub fn force_phase(&mut self, phase: GuidancePhase) {
        self.phase = phase;
    }

    /// The plan as it stands.
    pub fn status(&self) -> &SpiralStatus {
        &self.status
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

    /// One guidance update: servo commands and the phase change it made, if any.
    pub fn update(
        &mut self,
        config: &GuidanceConfig,
        plan: &Plan,
        est: &Estimate,
        density: f64,
    ) -> (Controls, Change) {
        let sc = &config.spiral;
        let perf = &config.performance;
        let gains = &config.gains;
        let target_ne = [plan.target_ned_m.x, plan.target_ned_m.y];
        let ground_m = -plan.target_ned_m.z;
        let position = [est.position_ned_m.x, est.position_ned_m.y];
        let rel = [position[0] - target_ne[0], position[1] - target_ne[1]];
        let height = est.height_m() - ground_m;

        // Wind used for planning: low-passed so the pattern does not twitch with gusts.
        let measured = [est.wind_ned_mps.x, est.wind_ned_mps.y];
        let dt = self
            .last_time_s
            .map(|t| (est.time_s - t).clamp(0.0, 5.0))
            .unwrap_or(0.0);
        self.last_time_s = Some(est.time_s);
        let wind = match self.wind_ne_mps {
            None => measured,
            Some(w) => {
                let k = dt / (sc.wind_filter_s + dt);
                [
                    w[0] + k * (measured[0] - w[0]),
                    w[1] + k * (measured[1] - w[1]),
                ]
            }
        };
        self.wind_ne_mps = Some(wind);
        let wind_speed = wind[0].hypot(wind[1]);

        // The pattern's axis: downwind, unless the operator fixed the approach course; in calm
        // air it stays where it was (first: the final approach is flown towards the target
        // from where the vehicle is).
        let free = matches!(
            self.phase,
            GuidancePhase::Approximation | GuidancePhase::BestReachable
        );
        let frozen = !(self.reorient || free);
        // A turn of the axis at a loop's start or onto the final is limited: the vehicle is
        // placed for the axis it had, and a light wind's direction is barely known.
        let largest_turn = match self.phase {
            _ if free => std::f64::consts::PI,
            GuidancePhase::FinalApproach => FINAL_REORIENT_MAX_RAD,
            _ => LOOP_REORIENT_MAX_RAD,
        };
        self.reorient = false;
        let downwind = match (plan.approach_course_rad, self.downwind_rad) {
            (Some(course), _) => wrap_pi(course + std::f64::consts::PI),
            (None, Some(previous)) if frozen || wind_speed < sc.calm_wind_mps => previous,
            (None, Some(previous)) => {
                let turn = wrap_pi(wind[1].atan2(wind[0]) - previous);
                wrap_pi(previous + turn.clamp(-largest_turn, largest_turn))
            }
            (None, None) if wind_speed >= sc.calm_wind_mps => wind[1].atan2(wind[0]),
            (None, None) => rel[1].atan2(rel[0]),
        };
        self.downwind_rad = Some(downwind);
        let (sx, cx) = downwind.sin_cos();
        let to_wind = |ne: [f64; 2]| [ne[0] * cx + ne[1] * sx, -ne[0] * sx + ne[1] * cx];
        let to_ne = |xy: [f64; 2]| {
            [
                target_ne[0] + xy[0] * cx - xy[1] * sx,
                target_ne[1] + xy[0] * sx + xy[1] * cx,
            ]
        };
        let [x, y] = to_wind(rel);
        // Plan for a little more headwind than measured: arriving high is corrected by the
        // brakes, arriving low only by releasing them, which buys much less.
        let w_along_measured = wind[0] * cx + wind[1] * sx;
        let w_along = w_along_measured
            + sc.wind_margin_fraction * w_along_measured.abs()
            + sc.wind_margin_mps;
        let a = sc.half_size_m;

        // Planning speeds.
        let v0 = perf.horizontal_airspeed(0.0, density);
        let vt = perf.horizontal_airspeed(gains.brake_trim, density);
        let s0 = perf.sink_rate(0.0, 0.0, density);
        let st = perf.sink_rate(gains.brake_trim, 0.0, density);
        let r = if sc.planned_turn_rate_rad_s > 0.0 {
            sc.planned_turn_rate_rad_s
        } else {
            match self.turn_rate {
                Some((g, p, rate)) if g == *gains && p == *perf => rate,
                _ => {
                    let rate = corner_turn_rate_rad_s(gains, perf);
                    self.turn_rate = Some((*gains, *perf, rate));
                    rate
                }
            }
        };
        let turn_loss = std::f64::consts::FRAC_PI_2 / r * perf.sink_rate(0.0, r, density)
            - std::f64::consts::FRAC_PI_2 / r * s0;
        let g_down = v0 + w_along;
        let g_up0 = (v0 - w_along).max(0.3);
        let g_up_t = (vt - w_along).max(0.3);
        let g_cross = (v0 * v0 - w_along * w_along).max(0.09).sqrt();
        let downwind_y = self.downwind_y_m.unwrap_or(-a);
        // Height needed to turn base at x from a downwind leg |lateral| off the final line.
        let needed_from = |x_base: f64, lateral: f64| {
            sc.hang_height_m
                + s0 * lateral.abs() / g_cross
                + st * x_base.max(0.0) / g_up_t
                + 2.0 * turn_loss
                + sc.final_margin_m
        };
        let needed_to_turn_base = |x_base: f64| needed_from(x_base, downwind_y);
        // Height needed to go for the final from here with no more pattern: downwind to the
        // shortest final if upwind of it, across to the final line, then the final glide.
        let needed_direct = {
            let x_entry = x.max(sc.min_final_m);
            needed_from(x_entry, y) + s0 * (x_entry - x) / g_down
        };
        let loop_loss =
            s0 * (2.0 * a / g_cross * 2.0 + 2.0 * a / g_up0 + 2.0 * a / g_down) + 4.0 * turn_loss;
        let turn_distance = perf.turn_radius_m(r, 0.0, density);

        // Reach: the glide's circle around the drift point.
        let t_land = ((height - sc.hang_height_m) / s0).max(0.0);
        let drift = [rel[0] + wind[0] * t_land, rel[1] + wind[1] * t_land];
        let drift_distance = drift[0].hypot(drift[1]);
        let reach = v0 * t_land;
        let reach_ratio = if reach > 1e-6 {
            drift_distance / reach
        } else {
            f64::INFINITY
        };
        let threshold = if self.phase == GuidancePhase::BestReachable {
            sc.reach_margin - 0.1
        } else {
            sc.reach_margin
        };
        let reachable = reach_ratio <= threshold;
        let best_rel = if drift_distance > 1e-9 {
            let k = (reach / drift_distance).min(1.0);
            [drift[0] * (1.0 - k), drift[1] * (1.0 - k)]
        } else {
            [0.0, 0.0]
        };

        // The final approach's energy: how far to go before the flare, and how much height there
        // is beyond what even full brakes can take off in that distance.
        let final_course = wrap_pi(downwind + std::f64::consts::PI);
        let final_line = Localizer {
            point_ne_m: target_ne,
            course_rad: final_course,
        };
        let flare_glide = perf.ground_glide(1.0, w_along_measured, density).max(0.0);
        let to_go_before_flare =
            -final_line.along_track_m(position) - flare_glide * sc.flare_height_m - sc.aim_beyond_m;
        let height_to_flare = height - sc.hang_height_m - sc.flare_height_m;
        // The way across to the line, if not on it yet, is flown too (brakes released).
        let across_m = final_line.cross_track_m(position).abs();
        let across_height_m = s0 * across_m / g_cross;
        let final_excess_m = if flare_glide > 1e-3 {
            height_to_flare - across_height_m - to_go_before_flare.max(0.0) / flare_glide
        } else {
            // Full brakes hold the stack still over the ground or back: no height is too much.
            f64::NEG_INFINITY
        };

        // Energy decisions wait until the wind is known: the estimator's first seconds can be
        // metres per second off, and a pattern abandoned on a wrong wind is not recovered.
        // ... and have stayed good for a while: the estimator's first converged seconds still
        // carry metres per second of error that its uncertainty does not show, and a pattern
        // committed to a wrong wind's axis is flown across the real one.
        let sigma_ok = est.wind_sigma_mps.x.max(est.wind_sigma_mps.y) < WIND_KNOWN_SIGMA_MPS;
        self.wind_known_since_s = match (sigma_ok, self.wind_known_since_s) {
            (false, _) => None,
            (true, None) => Some(est.time_s),
            (true, since) => since,
        };
        let wind_known = self
            .wind_known_since_s
            .is_some_and(|since| est.time_s - since >= WIND_SETTLE_S);
        let mut change: Change = None;
        let lowest_body_height = height - sc.hang_height_m;
        let now_s = est.time_s;
        let in_phase_s = now_s - self.phase_since_s;
        let mut set = |s: &mut Self, to: GuidancePhase, reason: String| {
            if let Some(c) = s.go(to, reason) {
                s.phase_since_s = now_s;
                change = Some(c);
            }
        };

        // Phase decisions.
        match self.phase {
            GuidancePhase::Idle | GuidancePhase::Landed => {}
            GuidancePhase::Flare => {}
            _ if sc.flare && lowest_body_height <= sc.flare_height_m => {
                set(
                    self,
                    GuidancePhase::Flare,
                    format!("flare: lowest body {lowest_body_height:.1} m above the ground"),
                );
            }
            GuidancePhase::FinalApproach
                if final_excess_m > REENTER_EXCESS_M
                    && in_phase_s >= MIN_FINAL_BEFORE_REENTRY_S =>
            {
                self.base_x_m = None;
                if x < sc.max_final_m - 2.0 * turn_distance {
                    // Downwind on a leg beside the final line, and base again from it when
                    // the height has come down to what the glide in needs.
                    let side = final_line.cross_track_m(position);
                    self.downwind_y_m = Some(if side >= 0.0 { a } else { -a });
                    self.extending = true;
                    set(
                        self,
                        GuidancePhase::Branch1,
                        format!(
                            "{final_excess_m:.0} m too high for the final even with full brakes: \
                             back downwind to lose it"
                        ),
                    );
                } else {
                    // Already at the longest final: more downwind only makes the way back
                    // longer; the pattern over the target burns the height instead.
                    self.downwind_y_m = None;
                    self.extending = false;
                    self.approach_from_ne_m = None;
                    self.reorient = true;
                    set(
                        self,
                        GuidancePhase::Approximation,
                        format!(
                            "{final_excess_m:.0} m too high for the final even with full brakes, \
                             {x:.0} m out: back to the pattern over the target to lose it"
                        ),
                    );
                }
            }
            GuidancePhase::FinalApproach => {}
            GuidancePhase::BestReachable => {
                if reachable {
                    self.approach_from_ne_m = None;
                    set(
                        self,
                        GuidancePhase::Approximation,
                        format!("target within reach again (reach ratio {reach_ratio:.2})"),
                    );
                }
            }
            _ if wind_known
                && !reachable
                && self.base_x_m.is_none()
                && !self.extending
                && lowest_body_height > REACH_CHECK_MIN_HEIGHT_M =>
            {
                let miss = best_rel[0].hypot(best_rel[1]);
                set(
                    self,
                    GuidancePhase::BestReachable,
                    format!(
                        "target out of reach: wind {wind_speed:.1} m/s, reach ratio \
                         {reach_ratio:.2}; flying to the best reachable point {miss:.0} m from it"
                    ),
                );
            }
            _ if wind_known
                && self.base_x_m.is_none()
                && !self.extending
                && self.phase != GuidancePhase::Branch1
                && self.phase != GuidancePhase::BestReachable
                && height <= needed_direct + LOW_MARGIN_M =>
            {
                if x >= sc.min_final_m && y.abs() > 2.0 * turn_distance {
                    // Straight across to the final line (what `needed_direct` plans), as a base
                    // leg from here: the final's localizer would intercept it at 45°, a longer
                    // way that the height was not counted for.
                    self.base_x_m = Some(x);
                    self.downwind_y_m = Some(y);
                    set(
                        self,
                        GuidancePhase::Branch2,
                        format!(
                            "short of height ({height:.0} m, {needed_direct:.0} m needed to glide \
                             in from here): base leg now, {:.0} m across to a final {x:.0} m out",
                            y.abs()
                        ),
                    );
                } else if x >= sc.min_final_m {
                    self.base_x_m = Some(x);
                    set(
                        self,
                        GuidancePhase::FinalApproach,
                        format!(
                            "short of height ({height:.0} m, {needed_direct:.0} m needed to glide \
                             in from here): straight to the final approach, {x:.0} m out"
                        ),
                    );
                } else {
                    self.downwind_y_m = Some(if y.abs() < turn_distance {
                        -turn_distance
                    } else {
                        y
                    });
                    self.extending = true;
                    set(
                        self,
                        GuidancePhase::Branch1,
                        format!(
                            "short of height ({height:.0} m, {needed_direct:.0} m needed): \
                             downwind leg now, base and final from it"
                        ),
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
                        let c = corner_xy(k, a);
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
                let corner = corner_xy(k, a);
                let to_corner = (corner[0] - x).hypot(corner[1] - y);
                if to_corner < turn_distance.max(10.0) {
                    set(
                        self,
                        self.entry_branch,
                        format!("reached the spiral's entry corner ({to_corner:.0} m)"),
                    );
                }
            }
            GuidancePhase::Branch1 => {
                let to_corner = a - x;
                // The turn carries the vehicle about a turn radius further downwind before it
                // flies across: the base leg lies there, and the glide in is planned from it.
                let x_base = x + turn_distance;
                let needed = needed_to_turn_base(x_base.max(sc.min_final_m));
                if x_base >= sc.min_final_m.min(a) && height <= needed {
                    self.base_x_m = Some(x_base);
                    self.extending = false;
                    set(
                        self,
                        GuidancePhase::Branch2,
                        format!(
                            "turning base at {height:.0} m (needed {needed:.0} m) onto a base leg \
                             {x_base:.0} m downwind of the target"
                        ),
                    );
                } else if x_base >= sc.max_final_m {
                    self.base_x_m = Some(x_base);
                    self.extending = false;
                    set(
                        self,
                        GuidancePhase::Branch2,
                        format!("turning base at the longest final approach, {x_base:.0} m"),
                    );
                } else if !self.extending && to_corner < turn_distance {
                    if height - loop_loss >= needed_to_turn_base(a) {
                        self.base_x_m = None;
                        set(
                            self,
                            GuidancePhase::Branch2,
                            format!("another loop: {height:.0} m, a loop takes {loop_loss:.0} m"),
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
                    // on that line).
                    let from_side = downwind_y.signum();
                    if y * from_side < turn_distance && x >= x_base - turn_distance {
                        // The final course is taken from the wind as it is now.
                        self.reorient = true;
                        set(
                            self,
                            GuidancePhase::FinalApproach,
                            format!(
                                "turning final into the wind at {height:.0} m, {x:.0} m from the \
                                 target"
                            ),
                        );
                    }
                } else if a - y < turn_distance {
                    set(self, GuidancePhase::Branch3, "branch 3".into());
                }
            }
            GuidancePhase::Branch3 => {
                if x - (-a) < turn_distance {
                    set(self, GuidancePhase::Branch4, "branch 4".into());
                }
            }
            GuidancePhase::Branch4 => {
                if y - (-a) < turn_distance {
                    self.downwind_y_m = None;
                    self.reorient = true;
                    set(self, GuidancePhase::Branch1, "branch 1".into());
                }
            }
        }

        // What to fly in the (possibly new) phase.
        let horizontal = |line: &Localizer| {
            control::localizer(
                gains,
                line,
                position,
                est.course_rad,
                est.heading_rate_rad_s,
            )
            .main_line_m
        };
        let branch_line = |k: usize| {
            let mut start = corner_xy(k, a);
            let mut course = downwind + std::f64::consts::FRAC_PI_2 * k as f64;
            match (k, self.base_x_m) {
                (0, _) => start[1] = downwind_y,
                (1, Some(x_base)) => {
                    // The base leg: across from the downwind leg towards the final line.
                    start = [x_base, downwind_y];
                    if downwind_y > 0.0 {
                        course += std::f64::consts::PI;
                    }
                }
                _ => {}
            }
            Localizer {
                point_ne_m: to_ne(start),
                course_rad: wrap_pi(course),
            }
        };
        let controls = match self.phase {
            GuidancePhase::Idle | GuidancePhase::Landed => Controls::default(),
            GuidancePhase::Approximation => {
                let k = branch_index(self.entry_branch).unwrap_or(0);
                let corner = to_ne(corner_xy(k, a));
                let from = self.approach_from_ne_m.unwrap_or(position);
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
                let k = branch_index(self.phase).unwrap_or(0);
                Controls {
                    main_line_m: horizontal(&branch_line(k)),
                    ..Controls::default()
                }
            }
            GuidancePhase::FinalApproach => {
                // Vertical: the brake whose glide over the ground ends the descent on the aim
                // point, recomputed every update (a closed loop on the predicted touchdown).
                // The aim is the flare's start: the flare's own glide, at full brake, carries
                // the stack the rest of the way.
                let brake = if height_to_flare <= 0.0 || to_go_before_flare <= 0.0 {
                    if sc.flare { 1.0 } else { self.last_final_brake }
                } else {
                    perf.brake_for_ground_glide(
                        to_go_before_flare / height_to_flare,
                        w_along_measured,
                        density,
                    )
                };
                // Horizontal: the final line; while far too high for even full brakes to
                // bring it down in time, S-turns across the line burn the height.
                self.last_final_brake = brake;
                let weave = final_excess_m > S_TURN_EXCESS_M;
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
                        est.course_rad,
                        est.heading_rate_rad_s,
                        final_course + offset,
                    )
                } else {
                    horizontal(&final_line)
                };
                Controls {
                    main_line_m,
                    brake_right: brake,
                    brake_left: brake,
                }
            }
            GuidancePhase::Flare => Controls {
                main_line_m: horizontal(&final_line),
                brake_right: 1.0,
                brake_left: 1.0,
            },
            GuidancePhase::BestReachable => {
                // Into the wind for the last stretch; before, the air heading that carries the
                // stack from its drift point straight towards the target, which is the
                // reachable point nearest it. (A course towards the target is no use when the
                // wind blows the vehicle backwards over the ground.)
                let heading = if lowest_body_height < 40.0 || drift_distance < 1e-6 {
                    final_course
                } else {
                    (-drift[1]).atan2(-drift[0])
                };
                Controls {
                    main_line_m: control::heading(
                        gains,
                        est.heading_rad,
                        est.heading_rate_rad_s,
                        heading,
                    ),
                    ..Controls::default()
                }
            }
        };

        self.status = SpiralStatus {
            downwind_course_rad: downwind,
            final_course_rad: final_course,
            corners_ne_m: [0, 1, 2, 3].map(|k| to_ne(corner_xy(k, a))),
            final_entry_ne_m: to_ne([self.base_x_m.unwrap_or(a), 0.0]),
            final_approach_height_m: needed_to_turn_base(self.base_x_m.unwrap_or(a)),
            height_m: height,
            reach_ratio,
            target_reachable: reachable,
            best_reachable_ne_m: [target_ne[0] + best_rel[0], target_ne[1] + best_rel[1]],
            wind_ne_mps: wind,
            planned_turn_rate_rad_s: r,
            turn_distance_m: turn_distance,
        };
        (controls, change)
    }
}

impl Default for Spiral {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pointmass::PointMass;
    use nalgebra::Vector3;

    fn status_after_one_update(config: &GuidanceConfig) -> SpiralStatus {
        let mut spiral = Spiral::new();
        spiral.force_phase(GuidancePhase::Approximation);
        let plan = Plan {
            target_ned_m: Vector3::zeros(),
            ..Plan::default()
        };
        let est = PointMass::new(0.0, Vector3::new(300.0, 0.0, -500.0), 0.0)
            .estimate(&Vector3::new(1.0, 0.0, 0.0));
        spiral.update(config, &plan, &est, 1.2);
        *spiral.status()
    }

    /// Regression: corners were planned at a fixed 20°/s, the rate of the hand-set gains,
    /// while the tuned gains in use turn at about 13°/s; every corner was started late.
    #[test]
    fn corners_are_planned_at_the_rate_the_gains_turn() {
        let perf = GlidePerformance::default();
        let tuned = corner_turn_rate_rad_s(&ControlGains::default(), &perf);
        assert!(
            (11.0..15.0).contains(&tuned.to_degrees()),
            "tuned gains turn at {:.1}°/s",
            tuned.to_degrees()
        );
        let hand_set = ControlGains {
            hk1_m_per_rad: 0.012,
            hk2_m_s_per_rad: 0.012,
            ..ControlGains::default()
        };
        let fast = corner_turn_rate_rad_s(&hand_set, &perf);
        assert!(
            (18.0..23.0).contains(&fast.to_degrees()),
            "hand-set gains turn at {:.1}°/s",
            fast.to_degrees()
        );

        // Planning uses the rate of the gains in force, and the turn distance follows it.
        let mut config = GuidanceConfig::default();
        let status = status_after_one_update(&config);
        assert!((status.planned_turn_rate_rad_s - tuned).abs() < 1e-12);
        let v0 = perf.horizontal_airspeed(0.0, 1.2);
        assert!((status.turn_distance_m - v0 / tuned).abs() < 1e-9);
        config.gains = hand_set;
        let status_fast = status_after_one_update(&config);
        assert!((status_fast.planned_turn_rate_rad_s - fast).abs() < 1e-12);
        assert!(status_fast.turn_distance_m < status.turn_distance_m);
        // A rate set by the operator overrides it.
        config.spiral.planned_turn_rate_rad_s = 0.5;
        assert_eq!(
            status_after_one_update(&config).planned_turn_rate_rad_s,
            0.5
        );
    }

    /// Regression (Monte Carlo seed 2, run 730): eight seconds after release the estimator's
    /// wind was 4 m/s off with a small uncertainty; guidance committed to a downwind leg on
    /// that wind's axis at once, flew it across the real wind and landed 64 m short.
    #[test]
    fn energy_decisions_wait_until_the_wind_estimate_has_settled() {
        let config = GuidanceConfig::default();
        let plan = Plan {
            target_ned_m: Vector3::zeros(),
            ..Plan::default()
        };
        let mut spiral = Spiral::new();
        spiral.force_phase(GuidancePhase::Approximation);
        // Low and far: short of height, whatever the wind.
        let wind = Vector3::new(-2.0, -3.0, 0.0);
        let mut first_change = None;
        for k in 0..80 {
            let t = 0.25 * k as f64;
            let mut est =
                PointMass::new(t, Vector3::new(250.0, 150.0, -120.0), 2.0).estimate(&wind);
            est.wind_sigma_mps = Vector3::new(0.3, 0.3, 0.3);
            let (_, change) = spiral.update(&config, &plan, &est, 1.2);
            if change.is_some() && first_change.is_none() {
                first_change = Some(t);
            }
        }
        let t = first_change.expect("guidance decides once the wind has settled");
        assert!(
            (WIND_SETTLE_S..WIND_SETTLE_S + 0.5).contains(&t),
            "first decision at {t} s"
        );
    }
}
