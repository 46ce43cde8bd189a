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
//! | `SetSurfaceWind` | guidance's surface wind, measured `age_s` before it arrived (said once) |
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

mod commands;
mod gps_loss;

use std::collections::VecDeque;

use nalgebra::Vector3;
use stx_dynamics::state::Controls;
use stx_gnc::control::{self, Localizer, TurnLatch};
use stx_gnc::estimate::Estimate;
use stx_gnc::geo::LocalFrame;
use stx_gnc::guidance::{Guidance, Plan};
use stx_gnc::mission::{FlightMode, FlightStage, GuidancePhase};
use stx_gnc::params::{CATALOG, OnboardSettings, ParamError, ParamKind};
use stx_link::manual::Sticks;
use stx_link::param::ParamSpec;
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
                integer: !matches!(p.kind, ParamKind::Real),
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
    /// The side of the into-wind turn when it starts from nearly downwind.
    turn_latch: TurnLatch,
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
            turn_latch: TurnLatch::default(),
        }
    }

    /// The mission's local frame (the site), in which guidance's positions and zones lie.
    pub fn frame(&self) -> &LocalFrame {
        &self.frame
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
        self.guidance
            .set_performance(self.settings.guidance.performance);
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
                    &mut self.turn_latch,
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
