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
//! The pattern's axis and its half-length follow the wind during the approximation; after
//! that they change only at the start of a loop (at most 45°) and onto the final (at most
//! 20°), so the vehicle's place in the pattern does not move under it while decisions taken
//! on it are being flown. Corners are started a turn radius early, at the turn rate the
//! control gains in force actually give ([`corner_turn_rate_rad_s`]), and energy decisions
//! wait until the wind estimate has been certain for a while. Each phase change is one
//! decision, and its reason says where, how high, in which loop, what was decided and why.
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
//! [`FinalLaw::GlideInversion`] by default: every update, the brake whose steady glide over
//! the ground, into the planned headwind, ends on the aim point (the flare's start) from where
//! the vehicle is — the glide performance inverted. The seed's glide-slope law (eqs.
//! 5.12–5.17, [`control::vertical`]) down a straight path whose slope is fixed at the turn onto
//! the final is [`FinalLaw::GlideSlope`]; the Monte Carlo comparison that decided between them
//! is in `crates/stx-gnc/GNC_NOTES.md`.
//!
//! **Too strong a wind.** At every update until the flare, in every phase, guidance checks the
//! glide's reach: the circle of radius `V·T` (T the time left to the ground at the current
//! sink) around the drift point, where the wind alone would carry the stack. When the target
//! lies outside it by more than the drift an error of 0.3 m/s in the wind makes over `T`
//! (plus 20 m), guidance says so — an event with the wind, the reach and the best reachable
//! point — and flies to that point, the one of the circle nearest the target, into the wind
//! for the last 40 m. It announces the point again whenever it moves by 50 m (the recovery
//! team drives to it), and goes back to the target only when it is well inside the circle.

use serde::{Deserialize, Serialize};
use stx_dynamics::rotation::wrap_pi;
use stx_dynamics::state::Controls;

use crate::control::{self, ControlGains, GlidePath, Localizer};
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
    /// reach (checked in every phase until the flare; see the module doc).
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
    /// Which law sets the brakes on the final approach.
    pub final_law: FinalLaw,
    /// Whether the pattern's legs along the wind are shortened with the wind (see the module
    /// doc); without, the pattern is the square of side `2·half_size_m` in any wind.
    pub wind_scaled_branches: bool,
}

/// The law that sets the symmetric brakes on the final approach.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum FinalLaw {
    /// The brake whose steady glide over the ground, into the planned headwind, ends on the
    /// aim point from where the vehicle is: the glide performance inverted, every update.
    #[default]
    GlideInversion,
    /// The seed's glide-slope law (eqs. 5.12–5.17) down a straight path through the aim point
    /// whose slope is fixed at the turn onto the final, about a feed-forward brake.
    GlideSlope,
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
            final_law: FinalLaw::GlideInversion,
            wind_scaled_branches: true,
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
    /// Half-length of the pattern along the wind, m, held with the axis.
    half_length_m: Option<f64>,
    /// Slope of the glide path on this final approach (seed's GS0), fixed at the turn onto
    /// it, with [`FinalLaw::GlideSlope`].
    final_slope: Option<f64>,
    /// The best reachable point last announced (north, east), m, and when, s.
    announced_best_ne_m: Option<[f64; 2]>,
    announced_at_s: f64,
    /// Loops of the pattern begun (the first at the entry corner), for the operator's log.
    loop_number: u32,
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
/// `ax` is the half-length along the wind, `ay` the half-width across it.
fn corner_xy(branch: usize, ax: f64, ay: f64) -> [f64; 2] {
    match branch % 4 {
        0 => [-ax, -ay],
        1 => [ax, -ay],
        2 => [ax, ay],
        _ => [-ax, ay],
    }
}

type Change = Option<(GuidancePhase, GuidancePhase, String)>;

/// Height below the direct glide-in need at which guidance stops the pattern, m.
const LOW_MARGIN_M: f64 = 10.0;
/// Wind uncertainty (1-σ per component) below which guidance trusts the wind for its energy
/// decisions, m/s.
const WIND_KNOWN_SIGMA_MPS: f64 = 0.6;
/// Below this height of the lowest body the reach check is off: the last seconds are flown
/// into the wind whatever the reach, and a changed mind there costs more than it buys.
const REACH_CHECK_MIN_HEIGHT_M: f64 = 60.0;
/// Least distance between the best reachable point and the target for guidance to call the
/// target out of reach, m, to which is added the drift an error of [`WIND_ACCURACY_MPS`]
/// makes over the time left.
const MIN_SHORTFALL_M: f64 = 20.0;
/// Accuracy of the wind estimate guidance counts on, m/s (the project's goal for it, RMS).
const WIND_ACCURACY_MPS: f64 = 0.3;
/// The best reachable point is announced again when it has moved this far, m (the recovery
/// team drives to it).
const BEST_POINT_MOVED_M: f64 = 50.0;
/// Least time on the way to the best reachable point before guidance turns back to the
/// target, s: the reach ratio hovers about its threshold in gusts.
const MIN_BEST_REACHABLE_S: f64 = 10.0;
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

/// Direction a horizontal wind (north, east; the air's velocity) blows from, degrees 0…360.
fn wind_from_deg(wind_ne: [f64; 2]) -> f64 {
    (-wind_ne[1])
        .atan2(-wind_ne[0])
        .to_degrees()
        .rem_euclid(360.0)
}

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
            half_length_m: None,
            final_slope: None,
            announced_best_ne_m: None,
            announced_at_s: 0.0,
            loop_number: 0,
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

        // Wind used for planning: low-passed so the pattern does not twitch with gusts, but only
        // once the estimator trusts its wind. Before, its wind starts near zero and swings by
        // metres per second as it converges; a filter started there lagged the truth for many
        // time constants, and in a strong wind the reach check then saw a wind too weak to
        // call the target out of reach until the pattern had committed to it (issue 3 audit:
        // 8–10 m/s winds missed by up to 1.2 km unflagged). So the raw estimate is followed
        // until its uncertainty is small, and the filter starts from the estimate then.
        let measured = [est.wind_ned_mps.x, est.wind_ned_mps.y];
        let sigma_ok = est.wind_sigma_mps.x.max(est.wind_sigma_mps.y) < WIND_KNOWN_SIGMA_MPS;
        let dt = self
            .last_time_s
            .map(|t| (est.time_s - t).clamp(0.0, 5.0))
            .unwrap_or(0.0);
        self.last_time_s = Some(est.time_s);
        let wind = match self.wind_ne_mps {
            Some(w) if sigma_ok => {
                let k = dt / (sc.wind_filter_s + dt);
                [
                    w[0] + k * (measured[0] - w[0]),
                    w[1] + k * (measured[1] - w[1]),
                ]
            }
            _ => measured,
        };
        self.wind_ne_mps = sigma_ok.then_some(wind);
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
        let ay = sc.half_size_m;

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
        let downwind_y = self.downwind_y_m.unwrap_or(-ay);
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
        let turn_distance = perf.turn_radius_m(r, 0.0, density);
        // The branches scaled with the wind (seed §5.3): the legs along the wind are shortened
        // in proportion to the upwind leg's ground speed, `ax = a·(V − w)/V`, so the upwind leg
        // takes as long as in still air and the pattern shrinks to a weave across the wind as
        // the wind nears the airspeed (at least a turn's length, or the corners overlap). Held,
        // like the axis, from the start of a loop to its end.
        let ax = match self.half_length_m {
            Some(held) if frozen => held,
            _ if !sc.wind_scaled_branches => ay,
            _ => {
                let w = w_along_measured.clamp(0.0, v0);
                (ay * (v0 - w) / v0.max(1e-3)).max(turn_distance.min(ay))
            }
        };
        self.half_length_m = Some(ax);
        let loop_loss = s0 * (2.0 * ay / g_cross * 2.0 + 2.0 * ax / g_up0 + 2.0 * ax / g_down)
            + 4.0 * turn_loss;

        // Reach: the glide's circle around the drift point.
        let t_land = ((height - sc.hang_height_m) / s0).max(0.0);
        // With the estimator's wind as it is, not the planning filter's: the filter is there
        // to keep the pattern's axis still, and its lag would hold a best reachable point
        // announced on a wind already known to be stale.
        let drift = [rel[0] + measured[0] * t_land, rel[1] + measured[1] * t_land];
        let drift_distance = drift[0].hypot(drift[1]);
        let reach = v0 * t_land;
        let reach_ratio = if reach > 1e-6 {
            drift_distance / reach
        } else {
            f64::INFINITY
        };
        // Out of reach means beyond the glide's circle, and by more than what the wind
        // estimate's error carries the drift point over the time left: a shortfall within
        // that is not known to be one, and not worth the operator's attention or giving up
        // the approach for (tight approaches touch a reach ratio of 1 on their base leg). Once
        // called, the target counts as reachable again only well inside the circle.
        let reachable = if self.phase == GuidancePhase::BestReachable {
            reach_ratio <= sc.reach_margin - 0.1
        } else {
            reach_ratio <= sc.reach_margin
                || drift_distance - reach < MIN_SHORTFALL_M + WIND_ACCURACY_MPS * t_land
        };
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
            -final_line.along_track_m(position) - flare_glide * sc.flare_height_m + sc.aim_beyond_m;
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

        let place = |p: [f64; 2]| place_of(p, target_ne);
        // Phase decisions.
        match self.phase {
            GuidancePhase::Idle | GuidancePhase::Landed => {}
            GuidancePhase::Flare => {}
            _ if sc.flare && lowest_body_height <= sc.flare_height_m => {
                set(
                    self,
                    GuidancePhase::Flare,
                    format!(
                        "flare: lowest body {lowest_body_height:.1} m above the ground, {}: full \
                         brakes to slow the touchdown",
                        place(position)
                    ),
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
                let miss = best_rel[0].hypot(best_rel[1]);
                let best = [target_ne[0] + best_rel[0], target_ne[1] + best_rel[1]];
                self.base_x_m = None;
                self.extending = false;
                self.downwind_y_m = None;
                set(
                    self,
                    GuidancePhase::BestReachable,
                    format!(
                        "target out of reach at {height:.0} m: wind {wind_speed:.1} m/s from \
                         {:.0}°, the glide reaches {reach:.0} m around a drift point \
                         {drift_distance:.0} m from the target (ratio {reach_ratio:.2}); flying to \
                         the best reachable point ({:.0} N, {:.0} E), {miss:.0} m from the target",
                        wind_from_deg(wind),
                        best[0],
                        best[1]
                    ),
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
                    self.downwind_y_m = Some(if side >= 0.0 { ay } else { -ay });
                    self.extending = true;
                    set(
                        self,
                        GuidancePhase::Branch1,
                        format!(
                            "{final_excess_m:.0} m too high for the final even with full brakes \
                             ({height:.0} m, {}): back downwind to lose it",
                            place(position)
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
                             {x:.0} m out at {height:.0} m: back to the pattern over the target \
                             to lose it"
                        ),
                    );
                }
            }
            GuidancePhase::FinalApproach => {}
            GuidancePhase::BestReachable
                if reach_ratio > sc.reach_margin
                    && self.announced_best_ne_m.is_some_and(|a| {
                        let moved = (a[0] - target_ne[0] - best_rel[0])
                            .hypot(a[1] - target_ne[1] - best_rel[1]);
                        moved > BEST_POINT_MOVED_M
                    })
                    && now_s - self.announced_at_s >= MIN_BEST_REACHABLE_S =>
            {
                // The wind estimate firmed up or the wind changed: the operator's recovery team
                // drives to the announced point, so a point that moved is announced again.
                let best = [target_ne[0] + best_rel[0], target_ne[1] + best_rel[1]];
                let miss = best_rel[0].hypot(best_rel[1]);
                change = Some((
                    GuidancePhase::BestReachable,
                    GuidancePhase::BestReachable,
                    format!(
                        "best reachable point moved: now ({:.0} N, {:.0} E), {miss:.0} m from the \
                         target, at {height:.0} m in a wind of {wind_speed:.1} m/s from {:.0}° \
                         (reach ratio {reach_ratio:.2})",
                        best[0],
                        best[1],
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
                    set(
                        self,
                        GuidancePhase::Approximation,
                        format!(
                            "target within reach again at {height:.0} m (reach ratio \
                             {reach_ratio:.2}, wind {wind_speed:.1} m/s): approaching it"
                        ),
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
                    set(
                        self,
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
                    self.base_x_m = Some(x_base);
                    self.extending = false;
                    set(
                        self,
                        GuidancePhase::Branch2,
                        format!(
                            "{}: turning base at {height:.0} m (needed {needed:.0} m to turn \
                             base here and glide in) onto a base leg {x_base:.0} m downwind of the \
                             target, {}",
                            loop_tag(self.loop_number),
                            place(position)
                        ),
                    );
                } else if x_base >= sc.max_final_m {
                    self.base_x_m = Some(x_base);
                    self.extending = false;
                    set(
                        self,
                        GuidancePhase::Branch2,
                        format!(
                            "{}: turning base at the longest final approach allowed, \
                             {x_base:.0} m out, at {height:.0} m ({needed:.0} m needed): the \
                             final's brakes take off the rest",
                            self.loop_number
                        ),
                    );
                } else if !self.extending && to_corner < turn_distance {
                    if height - loop_loss >= needed_to_turn_base(ax) {
                        self.base_x_m = None;
                        set(
                            self,
                            GuidancePhase::Branch2,
                            format!(
                                "{}: downwind corner {}, at {height:.0} m; another loop \
                                 ({loop_loss:.0} m) still leaves the {:.0} m a final needs: across \
                                 the wind",
                                loop_tag(self.loop_number),
                                place(position),
                                needed_to_turn_base(ax)
                            ),
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
                                "{}: base leg meets the final line {}, at {height:.0} m: \
                                 turning final into a wind of {wind_speed:.1} m/s from {:.0}°",
                                loop_tag(self.loop_number),
                                place(position),
                                wind_from_deg(wind)
                            ),
                        );
                    }
                } else if ay - y < turn_distance {
                    set(
                        self,
                        GuidancePhase::Branch3,
                        format!(
                            "{}: across leg done {}, at {height:.0} m: upwind leg, {:.0} m",
                            loop_tag(self.loop_number),
                            place(position),
                            2.0 * ax
                        ),
                    );
                }
            }
            GuidancePhase::Branch3 => {
                if x - (-ax) < turn_distance {
                    set(
                        self,
                        GuidancePhase::Branch4,
                        format!(
                            "{}: upwind leg done {}, at {height:.0} m: across to the \
                             downwind leg",
                            loop_tag(self.loop_number),
                            place(position)
                        ),
                    );
                }
            }
            GuidancePhase::Branch4 => {
                if y - (-ay) < turn_distance {
                    self.downwind_y_m = None;
                    self.reorient = true;
                    self.loop_number += 1;
                    set(
                        self,
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
                    );
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
            let mut start = corner_xy(k, ax, ay);
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
                let corner = to_ne(corner_xy(k, ax, ay));
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
                let brake = if height_to_flare <= 0.0 || to_go_before_flare <= 0.0 {
                    if sc.flare { 1.0 } else { self.last_final_brake }
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
                        FinalLaw::GlideInversion => perf.brake_for_ground_glide(
                            to_go_before_flare / height_to_flare,
                            w_along_measured,
                            density,
                        ),
                        // The seed's vertical law (eqs. 5.12–5.17): a straight glide path
                        // through the aim point, its slope GS0 the geometry at the turn onto
                        // the final, flown about the brake that holds GS0 in the wind planned
                        // with (the performance model's feed-forward).
                        FinalLaw::GlideSlope => {
                            let slope = *self.final_slope.get_or_insert(
                                (height_to_flare / to_go_before_flare).clamp(0.05, 20.0),
                            );
                            let aim_ne = [
                                target_ne[0]
                                    + (sc.aim_beyond_m - flare_glide * sc.flare_height_m)
                                        * final_course.cos(),
                                target_ne[1]
                                    + (sc.aim_beyond_m - flare_glide * sc.flare_height_m)
                                        * final_course.sin(),
                            ];
                            let path = GlidePath {
                                line: Localizer {
                                    point_ne_m: aim_ne,
                                    course_rad: final_course,
                                },
                                aim_height_m: ground_m + sc.hang_height_m + sc.flare_height_m,
                                slope,
                            };
                            let trim =
                                perf.brake_for_ground_glide(1.0 / slope, w_along_measured, density);
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

        if self.phase != GuidancePhase::FinalApproach {
            self.final_slope = None;
        }
        if self.phase != GuidancePhase::BestReachable {
            self.announced_best_ne_m = None;
        } else if change
            .as_ref()
            .is_some_and(|c| c.1 == GuidancePhase::BestReachable)
        {
            self.announced_best_ne_m =
                Some([target_ne[0] + best_rel[0], target_ne[1] + best_rel[1]]);
            self.announced_at_s = est.time_s;
        }
        self.status = SpiralStatus {
            downwind_course_rad: downwind,
            final_course_rad: final_course,
            corners_ne_m: [0, 1, 2, 3].map(|k| to_ne(corner_xy(k, ax, ay))),
            final_entry_ne_m: to_ne([self.base_x_m.unwrap_or(ax), 0.0]),
            final_approach_height_m: needed_to_turn_base(self.base_x_m.unwrap_or(ax)),
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
                spiral.entry_branch, expected,
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

    fn spiral_turn_distance(config: &GuidanceConfig) -> f64 {
        let rate = corner_turn_rate_rad_s(&config.gains, &config.performance);
        config.performance.turn_radius_m(rate, 0.0, 1.2)
    }
}
