//! The drone's software: what it flies (mode and plan), its parameters, manual control, and
//! what it does when the GPS goes quiet. It runs the same guidance as the station
//! (`stx_gnc::guidance`), fed by the onboard estimator, and it is pure: every call takes the
//! mission time, nothing here owns a clock or the link.
//!
//! # Modes and plan
//! The mode and the plan start from the scenario's `[plan]` (the onboard plan: what the drone
//! flies with no operator, normally a spiral landing on the target) and change by command or
//! plan upload. They are accepted in any stage and take effect once the parafoil flies;
//! before that the servos stay neutral.
//!
//! | command | effect |
//! |---|---|
//! | `SetMode(m)` | selects `m`; spiral landing needs a target, localizer a line, manual fresh sticks (else refused with a reason) |
//! | `HoldHeading` / `HoldCourse` | sets the heading / course and selects heading / course mode |
//! | `SetLandingTarget` | sets the target and final-approach course; a spiral landing under way replans from its approximation |
//! | `SetLocalizer` | sets the line (and glide slope) and selects localizer mode |
//! | plan upload | the `Land` item sets the target and approach; two waypoints (or one and the landing point) set the localizer line, their altitudes its glide slope |
//!
//! # Manual control
//! Sticks (MANUAL_CONTROL, normalised by stx-link) drive the servos directly: `y` (roll axis,
//! right +) sets the main line to `y` × the full main-line travel (right turns right), `z`
//! (thrust axis) sets both brakes to `z` clamped to 0…1 (released below 0), `x` and `r` are
//! unused. This is the dashboard's mapping. Manual mode is entered only with fresh sticks (the
//! operator holds the dead-man first); when they go stale (stx-link's receiver declares them
//! so after `MAN_TIMEOUT_S` without a message) the drone never holds the last values: it
//! returns at once to the autonomous mode it flew before manual — or, if that was
//! `uncontrolled`, to a spiral landing when it has a target — and says so.
//!
//! # GPS loss
//! The estimator dead-reckons through a GPS gap (air velocity, heading, barometer). When no
//! fix has been used for the estimator's GPS timeout the drone announces the loss; after
//! `FS_GPS_LOSS_S` seconds it acts by `FS_GPS_ACTION` ([`GpsLossAction`]), in parafoil flight
//! and in the modes that steer on position (course, localizer, spiral landing; heading mode
//! needs only the AHRS and goes on):
//! - `1` (into the wind, the default): it turns to the direction the last wind estimate comes
//!   from and holds that heading with the heading law (the heading is the AHRS's, good without
//!   GPS), brakes released, and flares below the flare height by the barometric height. Into
//!   the wind the vehicle drifts least over the ground and touches down slowest — the safe
//!   choice without knowing where it is. In calm air it holds its heading.
//! - `0`: it keeps flying the plan on the dead-reckoned estimate.
//! - `2`: servos neutral: the parafoil glides straight and lands unflared.
//!
//! A loss in a mode that does not steer on position (heading, manual) is announced and flown
//! through; if the operator then selects a mode that does (course, localizer, spiral landing)
//! while the GPS is still out, the action is taken at once — the drone never steers on a
//! position it has lost for longer than `FS_GPS_LOSS_S` unless `FS_GPS_ACTION` says so (`0`).
//!
//! When fixes return it says so, and a spiral landing replans from its approximation (the
//! dead-reckoned position may have jumped).
//!
//! # Mission decisions
//! On its estimate the software cuts the balloon away at `MIS_CUTDOWN_M` (if set and the
//! balloon has not burst) and releases the round chute at `MIS_DEPLOY_M` above the site
//! ([`Onboard::mission_request`]); the physics carries them out.
//!
//! # Parameters
//! Every parameter is described once, in `stx_gnc::params::CATALOG` (shared with the
//! station); [`param_specs`] turns it into the link's table and [`Onboard::set_param`] applies a
//! set through [`OnboardSettings::apply`] (range, kind and the rules between parameters; the
//! main-line limit also by the servo travel). A change takes effect at the next control
//! period.

use std::collections::VecDeque;

use nalgebra::Vector3;
use stx_dynamics::rotation::wrap_pi;
use stx_dynamics::state::Controls;
use stx_gnc::control::{self, Localizer};
use stx_gnc::estimate::Estimate;
use stx_gnc::geo::LocalFrame;
use stx_gnc::guidance::{Guidance, Plan};
use stx_gnc::mission::{FlightMode, FlightStage, GuidancePhase};
use stx_gnc::params::ParamError;
use stx_gnc::params::{CATALOG, GpsLossAction, OnboardSettings};
use stx_link::command::{Command, CommandResult};
use stx_link::manual::Sticks;
use stx_link::param::ParamSpec;
use stx_link::plan::PlanItem;
use stx_link::telemetry::Severity;

use crate::drone::config::MissionConfig;

/// The parameter table of the onboard settings `settings` (their values as the table's
/// starting values), from the shared catalog `stx_gnc::params::CATALOG`. The main line's
/// limit is also bounded by the vehicle's servo travel `main_line_travel_m`.
pub fn param_specs(settings: &OnboardSettings, main_line_travel_m: f64) -> Vec<ParamSpec> {
    CATALOG
        .iter()
        .map(|p| {
            let max = if p.name == MAIN_LINE_LIMIT {
                p.max.min(main_line_travel_m)
            } else {
                p.max
            };
            let units = if p.units.is_empty() {
                String::new()
            } else {
                format!(", {}", p.units)
            };
            ParamSpec {
                name: p.name.to_string(),
                default: p.get(settings) as f32,
                min: p.min as f32,
                max: max as f32,
                description: format!("{}{units}", p.description),
            }
        })
        .collect()
}

/// The parameter bounded by the servo travel.
const MAIN_LINE_LIMIT: &str = "GN_LINE_MAX";

/// Where the GPS-loss policy stands.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GpsState {
    /// Fixes arrive (or none has ever arrived: nothing to lose yet).
    Ok,
    /// No fix used since `since_s` (mission time); `acted` once the action was decided.
    Lost { since_s: f64, acted: bool },
    /// Holding `heading_rad` into the wind since `since_s`.
    IntoWind { since_s: f64, heading_rad: f64 },
    /// Servos neutral since `since_s` (`FS_GPS_ACTION` 2).
    Neutral { since_s: f64 },
}

/// A change the onboard software asks of the vehicle's hardware.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HardwareRequest {
    /// Cut the balloon away.
    Cutdown,
    /// Release the round chute: the parafoil deploys.
    Deploy,
}

/// The drone's software.
#[derive(Debug, Clone)]
pub struct Onboard {
    settings: OnboardSettings,
    guidance: Guidance,
    frame: LocalFrame,
    main_line_travel_m: f64,
    has_target: bool,
    has_localizer: bool,
    /// The mode flown before manual, to return to when the sticks go stale.
    autonomous_mode: FlightMode,
    sticks: Option<Sticks>,
    gps: GpsState,
    had_fix: bool,
    /// The automatic cutdown was asked for (once is enough).
    cutdown_requested: bool,
    texts: VecDeque<(Severity, String)>,
}

/// A guidance mode that steers on position (needs GPS or a good dead reckoning).
fn steers_on_position(mode: FlightMode) -> bool {
    matches!(
        mode,
        FlightMode::Course | FlightMode::Localizer | FlightMode::SpiralLanding
    )
}

/// Snake-case name of a mode, as the operator reads it.
pub fn mode_name(mode: FlightMode) -> String {
    serde_json::to_value(mode)
        .ok()
        .and_then(|v| v.as_str().map(String::from))
        .unwrap_or_else(|| format!("{mode:?}"))
}

impl Onboard {
    /// The software as loaded before launch with `config`'s plan, for a vehicle of
    /// `main_line_travel_m` main-line travel.
    pub fn new(config: &MissionConfig, main_line_travel_m: f64) -> Self {
        let mut guidance = Guidance::new(config.onboard.guidance);
        let target = config.target_ned_m();
        let p = &config.plan;
        let localizer = p.localizer.map(|l| Localizer {
            point_ne_m: l.point_ne_m,
            course_rad: l.course_deg.to_radians(),
        });
        guidance.set_plan(
            Plan {
                target_ned_m: target.unwrap_or_else(Vector3::zeros),
                approach_course_rad: p.approach_course_deg.map(f64::to_radians),
                heading_rad: p.heading_deg.to_radians(),
                course_rad: p.course_deg.to_radians(),
                localizer: localizer.unwrap_or(Plan::default().localizer),
                localizer_glide_slope: p.glide_slope,
            },
            0.0,
        );
        guidance.set_mode(p.mode, 0.0);
        // The plan's initial phase changes are not news.
        guidance.drain_events();
        Self {
            settings: config.onboard,
            guidance,
            frame: config.site,
            main_line_travel_m,
            has_target: target.is_some(),
            has_localizer: localizer.is_some(),
            autonomous_mode: p.mode,
            sticks: None,
            gps: GpsState::Ok,
            had_fix: false,
            cutdown_requested: false,
            texts: VecDeque::new(),
        }
    }

    /// Guidance, for its phase, plan, events and spiral status.
    pub fn guidance(&self) -> &Guidance {
        &self.guidance
    }

    /// Guidance, to drain its events.
    pub fn guidance_mut(&mut self) -> &mut Guidance {
        &mut self.guidance
    }

    /// The mode in force.
    pub fn mode(&self) -> FlightMode {
        self.guidance.mode()
    }

    /// The settings in force (the parameters' values).
    pub fn settings(&self) -> &OnboardSettings {
        &self.settings
    }

    /// The parameter table with the current values as defaults (for the link's table).
    pub fn param_specs(&self) -> Vec<ParamSpec> {
        param_specs(&self.settings, self.main_line_travel_m)
    }

    /// A parameter's value.
    pub fn param(&self, name: &str) -> Option<f32> {
        stx_gnc::params::find(name).map(|p| p.get(&self.settings) as f32)
    }

    /// Whether a landing target is set.
    pub fn has_target(&self) -> bool {
        self.has_target
    }

    /// The GPS-loss state.
    pub fn gps_state(&self) -> GpsState {
        self.gps
    }

    /// Whether the GPS-loss action is steering now.
    pub fn gps_failsafe_active(&self) -> bool {
        matches!(
            self.gps,
            GpsState::IntoWind { .. } | GpsState::Neutral { .. }
        ) && steers_on_position(self.mode())
    }

    /// The current sticks (`None`: stale or never received).
    pub fn sticks(&self) -> Option<Sticks> {
        self.sticks
    }

    /// Takes the next message for the operator.
    pub fn poll_text(&mut self) -> Option<(Severity, String)> {
        self.texts.pop_front()
    }

    fn say(&mut self, severity: Severity, text: String) {
        self.texts.push_back((severity, text));
    }

    /// The settings `name = value` would give, or why it is refused (the checks of
    /// [`set_param`](Self::set_param)); nothing changes.
    pub fn check_param(&self, name: &str, value: f32) -> Result<OnboardSettings, ParamError> {
        let value = f64::from(value);
        if name == MAIN_LINE_LIMIT && value > self.main_line_travel_m {
            return Err(ParamError::OutOfRange {
                name: MAIN_LINE_LIMIT,
                value,
                min: stx_gnc::params::find(MAIN_LINE_LIMIT).map_or(0.0, |p| p.min),
                max: self.main_line_travel_m,
            });
        }
        let mut settings = self.settings;
        settings.apply(name, value)?;
        Ok(settings)
    }

    /// Sets a parameter: its catalog range and kind, the servo travel for `GN_LINE_MAX`, and
    /// the rules between parameters are checked; on refusal nothing changes. It takes effect
    /// at the next control period.
    pub fn set_param(&mut self, name: &str, value: f32) -> Result<(), ParamError> {
        self.settings = self.check_param(name, value)?;
        self.guidance.set_gains(self.settings.guidance.gains);
        self.guidance
            .set_spiral_config(self.settings.guidance.spiral);
        Ok(())
    }

    /// The mission decisions on the estimate, one control period: the automatic cutdown at
    /// `MIS_CUTDOWN_M` during the ascent, the release of the round chute at `MIS_DEPLOY_M`
    /// above the site under the round chute. `est` is `None` until the estimator has a
    /// solution; without one nothing is decided (on the real capsule a timer would back this
    /// up; the simulation then lands under the round chute, which the operator sees).
    pub fn mission_request(
        &mut self,
        stage: FlightStage,
        est: Option<&Estimate>,
    ) -> Option<HardwareRequest> {
        let est = est?;
        let m = self.settings.mission;
        match stage {
            FlightStage::Ascent if m.cutdown_altitude_msl_m > 0.0 && !self.cutdown_requested => {
                let altitude_msl_m = self.frame.alt_msl_m + est.height_m();
                (altitude_msl_m >= m.cutdown_altitude_msl_m).then(|| {
                    self.cutdown_requested = true;
                    self.say(
                        Severity::Notice,
                        format!(
                            "automatic cutdown at {altitude_msl_m:.0} m (MIS_CUTDOWN_M {:.0} m)",
                            m.cutdown_altitude_msl_m
                        ),
                    );
                    HardwareRequest::Cutdown
                })
            }
            FlightStage::RoundChute if est.height_m() <= m.deploy_height_m => {
                self.say(
                    Severity::Notice,
                    format!(
                        "releasing the round chute at {:.0} m above the site (MIS_DEPLOY_M {:.0} m)",
                        est.height_m(),
                        m.deploy_height_m
                    ),
                );
                Some(HardwareRequest::Deploy)
            }
            _ => None,
        }
    }

    /// The stick state as the link's receiver has it now (`None` when stale). In manual mode,
    /// stale sticks send the drone back to its autonomous mode at once.
    pub fn set_sticks(&mut self, time_s: f64, sticks: Option<Sticks>) {
        self.sticks = sticks;
        if sticks.is_none() && self.mode() == FlightMode::Manual {
            let back = self.fallback_mode();
            self.guidance.set_mode(back, time_s);
            self.say(
                Severity::Warning,
                format!("manual: sticks stale, back to {}", mode_name(back)),
            );
        }
    }

    fn fallback_mode(&self) -> FlightMode {
        match self.autonomous_mode {
            FlightMode::Uncontrolled | FlightMode::Manual if self.has_target => {
                FlightMode::SpiralLanding
            }
            FlightMode::Manual => FlightMode::Uncontrolled,
            m => m,
        }
    }

    fn select(&mut self, mode: FlightMode, time_s: f64) {
        if mode != FlightMode::Manual {
            self.autonomous_mode = mode;
        }
        self.guidance.set_mode(mode, time_s);
    }

    /// Executes an operator command (all but cutdown and the telemetry requests, which the
    /// drone handles itself); the result goes back in COMMAND_ACK, the reason of a refusal to
    /// the operator's log.
    pub fn handle_command(&mut self, time_s: f64, command: &Command) -> CommandResult {
        match *command {
            Command::SetMode(mode) => {
                let refusal = match mode {
                    FlightMode::Manual if self.sticks.is_none() => Some((
                        CommandResult::TemporarilyRejected,
                        "manual refused: no stick input (hold the dead-man first)",
                    )),
                    FlightMode::SpiralLanding if !self.has_target => Some((
                        CommandResult::Denied,
                        "spiral landing refused: no landing target",
                    )),
                    FlightMode::Localizer if !self.has_localizer => Some((
                        CommandResult::Denied,
                        "localizer refused: no localizer line",
                    )),
                    _ => None,
                };
                if let Some((result, why)) = refusal {
                    self.say(Severity::Warning, why.to_string());
                    return result;
                }
                if mode != self.mode() {
                    self.say(Severity::Info, format!("mode {}", mode_name(mode)));
                }
                self.select(mode, time_s);
                CommandResult::Accepted
            }
            Command::HoldHeading { heading_deg } => {
                let mut plan = *self.guidance.plan();
                plan.heading_rad = wrap_pi(heading_deg.to_radians());
                self.guidance.set_plan(plan, time_s);
                self.select(FlightMode::Heading, time_s);
                self.say(Severity::Info, format!("heading {heading_deg:.0}°"));
                CommandResult::Accepted
            }
            Command::HoldCourse { course_deg } => {
                let mut plan = *self.guidance.plan();
                plan.course_rad = wrap_pi(course_deg.to_radians());
                self.guidance.set_plan(plan, time_s);
                self.select(FlightMode::Course, time_s);
                self.say(Severity::Info, format!("course {course_deg:.0}°"));
                CommandResult::Accepted
            }
            Command::SetLandingTarget {
                lat_deg,
                lon_deg,
                alt_msl_m,
                approach_heading_deg,
            } => {
                let target = self.frame.to_ned(lat_deg, lon_deg, alt_msl_m);
                if !(target.iter().all(|v| v.is_finite()) && target.x.hypot(target.y) < 1.0e6) {
                    self.say(
                        Severity::Warning,
                        "landing target refused: more than 1000 km away".into(),
                    );
                    return CommandResult::Denied;
                }
                let mut plan = *self.guidance.plan();
                plan.target_ned_m = target;
                plan.approach_course_rad = approach_heading_deg.map(|d| wrap_pi(d.to_radians()));
                self.guidance.set_plan(plan, time_s);
                self.has_target = true;
                self.say(
                    Severity::Info,
                    format!(
                        "landing target {lat_deg:.6} {lon_deg:.6} ({:.0} m N, {:.0} m E)",
                        target.x, target.y
                    ),
                );
                CommandResult::Accepted
            }
            Command::SetLocalizer {
                lat_deg,
                lon_deg,
                course_deg,
                glide_slope_deg,
            } => {
                let point = self.frame.to_ned(lat_deg, lon_deg, self.frame.alt_msl_m);
                if !(point.iter().all(|v| v.is_finite()) && point.x.hypot(point.y) < 1.0e6) {
                    self.say(
                        Severity::Warning,
                        "localizer refused: more than 1000 km away".into(),
                    );
                    return CommandResult::Denied;
                }
                let mut plan = *self.guidance.plan();
                plan.localizer = Localizer {
                    point_ne_m: [point.x, point.y],
                    course_rad: wrap_pi(course_deg.to_radians()),
                };
                plan.localizer_glide_slope = glide_slope_deg.map(|d| d.to_radians().tan());
                self.guidance.set_plan(plan, time_s);
                self.has_localizer = true;
                self.select(FlightMode::Localizer, time_s);
                self.say(Severity::Info, format!("localizer course {course_deg:.0}°"));
                CommandResult::Accepted
            }
            Command::Cutdown
            | Command::RequestMessage { .. }
            | Command::SetMessageInterval { .. } => CommandResult::Unsupported,
        }
    }

    /// Takes an uploaded plan (see the module documentation): the mapping of
    /// [`stx_gnc::plan_upload`], shared with the station's guidance replica.
    pub fn handle_plan(&mut self, time_s: f64, items: &[PlanItem]) {
        use stx_gnc::plan_upload::{LineChange, apply};
        let points: Vec<_> = items.iter().map(|i| i.to_local(&self.frame)).collect();
        let update = apply(self.guidance.plan(), &points);
        let plan = update.plan;
        let mut said = Vec::new();
        if update.target_set {
            self.has_target = true;
            let target = plan.target_ned_m;
            said.push(format!("target {:.0} m N {:.0} m E", target.x, target.y));
        }
        match update.line {
            LineChange::Set => {
                self.has_localizer = true;
                said.push(format!(
                    "localizer course {:.0}°",
                    plan.localizer.course_rad.to_degrees().rem_euclid(360.0)
                ));
            }
            LineChange::PointsCoincide => {
                said.push("localizer points coincide: line ignored".into());
            }
            LineChange::None => {}
        }
        self.guidance.set_plan(plan, time_s);
        self.say(
            Severity::Info,
            format!("plan received ({} items): {}", items.len(), said.join(", ")),
        );
    }

    /// The plan held, as mission items (what a station's download returns).
    pub fn plan_items(&self) -> Vec<PlanItem> {
        let plan = self.guidance.plan();
        let mut items = Vec::new();
        if self.has_localizer {
            let l = plan.localizer;
            let along = Vector3::new(
                l.point_ne_m[0] + 1000.0 * l.course_rad.cos(),
                l.point_ne_m[1] + 1000.0 * l.course_rad.sin(),
                0.0,
            );
            let drop = plan.localizer_glide_slope.unwrap_or(0.0) * 1000.0;
            for (p, alt_offset) in [
                (Vector3::new(l.point_ne_m[0], l.point_ne_m[1], 0.0), drop),
                (along, 0.0),
            ] {
                let (lat_deg, lon_deg, alt_msl_m) = self.frame.to_geodetic(&p);
                items.push(PlanItem::Waypoint {
                    lat_deg,
                    lon_deg,
                    alt_msl_m: alt_msl_m + alt_offset,
                });
            }
        }
        if self.has_target {
            let (lat_deg, lon_deg, alt_msl_m) = self.frame.to_geodetic(&plan.target_ned_m);
            items.push(PlanItem::Land {
                lat_deg,
                lon_deg,
                alt_msl_m,
                approach_heading_deg: plan
                    .approach_course_rad
                    .map(|c| c.to_degrees().rem_euclid(360.0)),
            });
        }
        items
    }

    /// Follows the GPS: announces its loss, takes the GPS-loss action after `FS_GPS_LOSS_S`,
    /// and announces its return. Called every control period with the age of the last fix
    /// that reached the drone (∞ before the first), the age beyond which the GPS counts as
    /// lost (the estimator's GPS timeout) and the latest estimate.
    pub fn update_gps(
        &mut self,
        time_s: f64,
        stage: FlightStage,
        gps_age_s: f64,
        timeout_s: f64,
        est: Option<&Estimate>,
    ) {
        let gps_ok = gps_age_s <= timeout_s;
        if gps_ok {
            self.had_fix = true;
        }
        match self.gps {
            GpsState::Ok => {
                if self.had_fix && !gps_ok && stage != FlightStage::Landed {
                    self.gps = GpsState::Lost {
                        since_s: time_s - gps_age_s.min(time_s),
                        acted: false,
                    };
                    self.say(
                        Severity::Warning,
                        "GPS lost: navigating by dead reckoning".into(),
                    );
                }
            }
            GpsState::Lost { since_s, acted } => {
                if gps_ok {
                    self.gps = GpsState::Ok;
                    self.say(
                        Severity::Notice,
                        format!("GPS back after {:.0} s", time_s - since_s),
                    );
                } else if (!acted || self.gps_action_pending())
                    && stage == FlightStage::Parafoil
                    && time_s - since_s >= self.settings.failsafe.gps_loss_s
                    && let Some(est) = est
                {
                    self.act_on_gps_loss(time_s, since_s, est);
                }
            }
            GpsState::IntoWind { since_s, .. } | GpsState::Neutral { since_s } => {
                if gps_ok {
                    self.gps = GpsState::Ok;
                    let mode = self.mode();
                    // A spiral under way replans from where the fixes say the vehicle is.
                    let plan = *self.guidance.plan();
                    self.guidance.set_plan(plan, time_s);
                    self.say(
                        Severity::Notice,
                        format!(
                            "GPS back after {:.0} s: resuming {}",
                            time_s - since_s,
                            mode_name(mode)
                        ),
                    );
                }
            }
        }
    }

    /// After the loss was flown through in a mode that does not need the GPS: whether the
    /// mode now steers on position and the policy has an action for that.
    fn gps_action_pending(&self) -> bool {
        steers_on_position(self.mode())
            && self.settings.failsafe.gps_loss_action != GpsLossAction::Continue
    }

    fn act_on_gps_loss(&mut self, time_s: f64, since_s: f64, est: &Estimate) {
        let mode = self.mode();
        let lost_s = time_s - since_s;
        let action = self.settings.failsafe.gps_loss_action;
        if action == GpsLossAction::Uncontrolled && steers_on_position(mode) {
            self.gps = GpsState::Neutral { since_s };
            self.say(
                Severity::Critical,
                format!("GPS lost {lost_s:.0} s: servos neutral, gliding straight"),
            );
        } else if action == GpsLossAction::IntoWind && steers_on_position(mode) {
            let wind = est.wind_ned_mps;
            let speed = wind.x.hypot(wind.y);
            let heading_rad = if speed > 0.5 {
                (-wind.y).atan2(-wind.x)
            } else {
                est.heading_rad
            };
            self.gps = GpsState::IntoWind {
                since_s,
                heading_rad,
            };
            self.say(
                Severity::Critical,
                format!(
                    "GPS lost {lost_s:.0} s: holding heading {:.0}° into the wind ({speed:.1} m/s), flare by barometer",
                    heading_rad.to_degrees().rem_euclid(360.0)
                ),
            );
        } else {
            self.gps = GpsState::Lost {
                since_s,
                acted: true,
            };
            self.say(
                Severity::Warning,
                format!(
                    "GPS lost {lost_s:.0} s: continuing {} on dead reckoning",
                    mode_name(mode)
                ),
            );
        }
    }

    /// The servo commands for this control period: neutral until the parafoil flies; then the
    /// sticks in manual mode, the GPS-loss action when it is steering, guidance otherwise.
    /// `est` is `None` until the estimator has a solution; `density_kg_per_m3` is the air's
    /// at the estimated altitude.
    pub fn control(
        &mut self,
        stage: FlightStage,
        est: Option<&Estimate>,
        density_kg_per_m3: f64,
    ) -> Controls {
        if stage != FlightStage::Parafoil {
            return Controls::default();
        }
        if self.mode() == FlightMode::Manual {
            return match self.sticks {
                Some(s) => Controls {
                    main_line_m: s.y.clamp(-1.0, 1.0) * self.main_line_travel_m,
                    brake_right: s.z.clamp(0.0, 1.0),
                    brake_left: s.z.clamp(0.0, 1.0),
                },
                None => Controls::default(),
            };
        }
        let Some(est) = est else {
            return Controls::default();
        };
        if matches!(self.gps, GpsState::Neutral { .. }) && steers_on_position(self.mode()) {
            return Controls::default();
        }
        if let (GpsState::IntoWind { heading_rad, .. }, true) =
            (self.gps, steers_on_position(self.mode()))
        {
            let spiral = &self.settings.guidance.spiral;
            let low = est.height_m() - spiral.hang_height_m <= spiral.flare_height_m;
            let brake = if spiral.flare && low { 1.0 } else { 0.0 };
            return Controls {
                main_line_m: control::heading(
                    &self.settings.guidance.gains,
                    est.heading_rad,
                    est.heading_rate_rad_s,
                    heading_rad,
                ),
                brake_right: brake,
                brake_left: brake,
            };
        }
        self.guidance.update(est, density_kg_per_m3).controls
    }

    /// The guidance phase to report: guidance's in parafoil flight, `Landed` on the ground,
    /// `Idle` before.
    pub fn phase(&self, stage: FlightStage) -> GuidancePhase {
        match stage {
            FlightStage::Parafoil => self.guidance.phase(),
            FlightStage::Landed => GuidancePhase::Landed,
            _ => GuidancePhase::Idle,
        }
    }
}
