//! Guidance: from the estimate and the operator's mode and plan to servo commands.
//!
//! [`Guidance::update`] runs at the drone's control rate (4 Hz) on the drone and, identically,
//! in the ground station. The simple modes wrap one control law each (seed §5.1–5.2); spiral
//! landing is the state machine of [`spiral`] (seed §5.3). Every phase change is an event with a
//! reason, kept for the operator's log. What guidance is configured with ([`GuidanceConfig`])
//! and what the operator asked it to fly ([`Plan`]) have files of their own, which the spiral
//! reads without depending on this module's [`Guidance`]. Every guided command flies with the
//! main-line trim learned in flight ([`trim`]); the spiral also learns the glide.

mod config;
mod plan;
pub mod spiral;
mod trim;

pub use config::GuidanceConfig;
pub use plan::{Plan, PlanRefused};
pub use spiral::{FinalLaw, LearnedPolar, SpiralConfig, SpiralStatus, SurfaceWind};

use serde::{Deserialize, Serialize};
use stx_types::controls::Controls;

use crate::control::{self, ControlGains, LawPhase};
use crate::estimate::Estimate;
use crate::keep_out::KeepOutZones;
use crate::mission::{FlightMode, GuidancePhase};

/// The drone's control period, s: [`Guidance::update`] runs at each whole multiple of it on the
/// drone's boot clock (4 Hz, seed §3.3.2). The station's replica updates at the same instants:
/// what guidance learns in flight (the trim, the glide) is summed per update, so a replica
/// updated at other instants, or fewer times, learns something else.
pub const CONTROL_PERIOD_S: f64 = 0.25;

/// A change of guidance phase, with why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PhaseEvent {
    /// When, s on the mission clock.
    pub time_s: f64,
    /// Phase left.
    pub from: GuidancePhase,
    /// Phase entered.
    pub to: GuidancePhase,
    /// Why, for the operator.
    pub reason: String,
}

/// What guidance commands for one control period.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Command {
    /// Servo commands.
    pub controls: Controls,
    /// Phase of guidance.
    pub phase: GuidancePhase,
}

/// Guidance state for one vehicle.
#[derive(Debug, Clone)]
pub struct Guidance {
    config: GuidanceConfig,
    mode: FlightMode,
    plan: Plan,
    spiral: spiral::Spiral,
    events: Vec<PhaseEvent>,
    /// Phases of the localizer and glide-slope laws at the last update, in localizer mode.
    law_phases: Option<(LawPhase, Option<LawPhase>)>,
    /// The main line's trim learned in flight.
    trim: trim::MainLineTrim,
    /// Main line sent at the last update, trim included, m.
    last_main_line_m: f64,
    /// The side of a heading, course or localizer turn from nearly behind.
    turn_latch: control::TurnLatch,
    /// Where the payload must not land: the spiral keeps its low legs and its best reachable
    /// point clear of them.
    keep_out: KeepOutZones,
    /// The wind at the ground by the target, uplinked, if any.
    surface_wind: Option<SurfaceWind>,
}

impl Guidance {
    /// Guidance in `Uncontrolled` mode with an empty plan.
    pub fn new(config: GuidanceConfig) -> Self {
        Self {
            config,
            mode: FlightMode::Uncontrolled,
            plan: Plan::default(),
            spiral: spiral::Spiral::new(),
            events: Vec::new(),
            law_phases: None,
            trim: trim::MainLineTrim::default(),
            last_main_line_m: 0.0,
            turn_latch: control::TurnLatch::default(),
            keep_out: KeepOutZones::default(),
            surface_wind: None,
        }
    }

    /// The keep-out zones in force.
    pub fn keep_out(&self) -> &KeepOutZones {
        &self.keep_out
    }

    /// Replaces the keep-out zones. A spiral under way keeps flying; it chooses its final
    /// approach against the new zones at the next moment its axis may turn. A target already
    /// in force is not checked again here: the station checks it when the zones change.
    pub fn set_keep_out(&mut self, zones: KeepOutZones) {
        self.spiral.set_keep_out(zones.clone());
        self.keep_out = zones;
    }

    /// Replaces the wind measured at the ground by the target (`None`: none known). The
    /// spiral mixes it into the wind it plans the final with, below the pattern.
    pub fn set_surface_wind(&mut self, wind: Option<SurfaceWind>) {
        self.spiral.set_surface_wind(wind);
        self.surface_wind = wind;
    }

    /// The wind measured at the ground that guidance holds (the drone's and the station's
    /// replica's must agree).
    pub fn surface_wind(&self) -> Option<SurfaceWind> {
        self.surface_wind
    }

    /// [`Guidance::set_plan`], refusing a plan whose target lies in a keep-out zone (the plan
    /// in force is kept).
    pub fn try_set_plan(&mut self, plan: Plan, time_s: f64) -> Result<(), PlanRefused> {
        plan.check_keep_out(&self.keep_out)?;
        self.set_plan(plan, time_s);
        Ok(())
    }

    /// In localizer mode, the phases of its horizontal law and (with a glide slope) its
    /// vertical law at the last update (seed §5.1.3, §5.2).
    pub fn law_phases(&self) -> Option<(LawPhase, Option<LawPhase>)> {
        self.law_phases
    }

    /// The configuration in use.
    pub fn config(&self) -> &GuidanceConfig {
        &self.config
    }

    /// Replaces the gains (parameters set by the operator).
    pub fn set_gains(&mut self, gains: ControlGains) {
        self.config.gains = gains;
    }

    /// Replaces the spiral settings.
    pub fn set_spiral_config(&mut self, spiral: SpiralConfig) {
        self.config.spiral = spiral;
    }

    /// Replaces the polar guidance plans with (a vehicle's table sent as parameters). What
    /// was learned in flight stays: its scales are on whichever polar is in force.
    pub fn set_performance(&mut self, performance: crate::performance::GlidePerformance) {
        self.config.performance = performance;
    }

    /// The mode in force.
    pub fn mode(&self) -> FlightMode {
        self.mode
    }

    /// Selects a mode; entering spiral landing starts its plan from the approximation.
    pub fn set_mode(&mut self, mode: FlightMode, time_s: f64) {
        if mode != self.mode {
            let reason = match mode {
                FlightMode::SpiralLanding => {
                    "spiral landing selected: approaching the target from here".to_string()
                }
                _ => format!("mode set to {mode:?}: spiral guidance idle"),
            };
            let to = if mode == FlightMode::SpiralLanding {
                GuidancePhase::Approximation
            } else {
                GuidancePhase::Idle
            };
            let from = self.phase();
            self.mode = mode;
            // The drone may fly the new mode without asking guidance (manual sticks), so the
            // trim cannot rely on seeing the gap in its updates.
            self.trim.interrupt();
            self.spiral = self.new_spiral();
            self.spiral.force_phase(to);
            if from != to {
                self.record(time_s, from, to, reason);
            }
        }
    }

    /// The plan in force.
    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    /// Replaces the plan; a spiral landing under way restarts from its approximation so the
    /// new target is flown from where the vehicle is.
    pub fn set_plan(&mut self, plan: Plan, time_s: f64) {
        self.plan = plan;
        if self.mode == FlightMode::SpiralLanding {
            let from = self.spiral.phase();
            self.spiral = self.new_spiral();
            self.spiral.force_phase(GuidancePhase::Approximation);
            self.record(
                time_s,
                from,
                GuidancePhase::Approximation,
                "new plan: flying to the new target".into(),
            );
        }
    }

    /// The current guidance phase.
    pub fn phase(&self) -> GuidancePhase {
        match self.mode {
            FlightMode::SpiralLanding => self.spiral.phase(),
            _ => GuidancePhase::Idle,
        }
    }

    /// Takes the phase `phase` from another copy of this guidance flying the same plan (the
    /// ground station's replica from the drone): in spiral landing only, without an event (the
    /// caller says why). The spiral goes on from there with what it has planned.
    pub fn adopt_phase(&mut self, phase: GuidancePhase, time_s: f64) {
        if self.mode == FlightMode::SpiralLanding {
            self.spiral.adopt_phase(phase, time_s);
        }
    }

    /// Whether the spiral has planned since the mode or plan last changed (its status is a
    /// plan only then).
    pub fn spiral_has_run(&self) -> bool {
        self.spiral.has_run()
    }

    /// The glide performance as learned in flight so far (the configured polar with the
    /// airspeed and sink scaled at each brake setting, and the turn rate), which the spiral
    /// plans with; the configured polar outside spiral landing.
    pub fn learned_performance(&self) -> crate::performance::GlidePerformance {
        match self.mode {
            FlightMode::SpiralLanding => self.spiral.learned_performance(&self.config.performance),
            _ => self.config.performance,
        }
    }

    /// What the spiral has learned in flight of the glide at each brake setting and of the
    /// turn (nothing, scales of 1, before it has flown).
    pub fn learned_polar(&self) -> LearnedPolar {
        self.spiral.learned_polar()
    }

    /// The main-line trim learned in flight, m: the offset the stack flies with (the command
    /// that flies straight is its negative).
    pub fn learned_trim_m(&self) -> f64 {
        self.trim.offset_m
    }

    /// The spiral's planning state for display (pattern, final-approach height, reach).
    pub fn spiral_status(&self) -> &SpiralStatus {
        self.spiral.status()
    }

    /// Takes the phase events recorded since the last call.
    pub fn drain_events(&mut self) -> Vec<PhaseEvent> {
        std::mem::take(&mut self.events)
    }

    /// A spiral that has not started, with the zones in force.
    fn new_spiral(&self) -> spiral::Spiral {
        let mut spiral = spiral::Spiral::new();
        spiral.set_keep_out(self.keep_out.clone());
        spiral.set_surface_wind(self.surface_wind);
        spiral
    }

    fn record(&mut self, time_s: f64, from: GuidancePhase, to: GuidancePhase, reason: String) {
        self.events.push(PhaseEvent {
            time_s,
            from,
            to,
            reason,
        });
    }

    /// Commands for the estimate `est`. Speeds are planned in the air density the estimate
    /// measured (the pitot's static pressure and temperature); `fallback_density_kg_per_m3`
    /// (e.g. a standard atmosphere at the estimated height) stands in while it has none.
    /// Until the estimator has a navigation solution (its position uncertainty is not finite)
    /// guidance holds the servos neutral and decides nothing.
    pub fn update(&mut self, est: &Estimate, fallback_density_kg_per_m3: f64) -> Command {
        let density_kg_per_m3 =
            if est.air_density_kg_per_m3.is_finite() && est.air_density_kg_per_m3 > 0.0 {
                est.air_density_kg_per_m3
            } else {
                fallback_density_kg_per_m3
            };
        if !est.position_sigma_m.iter().all(|s| s.is_finite()) {
            return Command {
                controls: Controls::default(),
                phase: self.phase(),
            };
        }
        let g = &self.config.gains;
        let position = [est.position_ned_m.x, est.position_ned_m.y];
        let neutral = Controls::default();
        let main_line = |m: f64| Controls {
            main_line_m: m,
            ..neutral
        };
        let controls = match self.mode {
            FlightMode::Uncontrolled | FlightMode::Manual => neutral,
            FlightMode::Heading => main_line(control::heading(
                g,
                &mut self.turn_latch,
                est.heading_rad,
                est.heading_rate_rad_s,
                self.plan.heading_rad,
            )),
            FlightMode::Course => main_line(control::course(
                g,
                &mut self.turn_latch,
                est.course_rad,
                est.heading_rate_rad_s,
                self.plan.course_rad,
            )),
            FlightMode::Localizer => {
                let horizontal = control::localizer(
                    g,
                    &mut self.turn_latch,
                    &self.plan.localizer,
                    position,
                    est.course_rad,
                    est.heading_rate_rad_s,
                );
                let mut vertical_phase = None;
                let brake = match self
                    .plan
                    .localizer_glide_path(self.config.spiral.hang_height_m)
                {
                    Some(path) => {
                        let out = control::vertical(
                            g,
                            &path,
                            position,
                            est.height_m(),
                            [est.velocity_ned_mps.x, est.velocity_ned_mps.y],
                            est.sink_rate_mps,
                        );
                        vertical_phase = Some(out.phase);
                        out.brake
                    }
                    None => 0.0,
                };
                self.law_phases = Some((horizontal.phase, vertical_phase));
                Controls {
                    main_line_m: horizontal.main_line_m,
                    brake_right: brake,
                    brake_left: brake,
                }
            }
            FlightMode::SpiralLanding => {
                let (controls, change) =
                    self.spiral
                        .update(&self.config, &self.plan, est, density_kg_per_m3);
                if let Some((from, to, reason)) = change {
                    self.record(est.time_s, from, to, reason);
                }
                let phase = self.spiral.phase();
                for note in self.spiral.take_notes() {
                    self.record(est.time_s, phase, phase, note);
                }
                controls
            }
        };
        // Every guided command flies with the trim learned; hands-off and manual ones do not.
        let guided = !matches!(self.mode, FlightMode::Uncontrolled | FlightMode::Manual)
            && !self.config.freeze_learning;
        let mut controls = controls;
        if guided {
            self.trim
                .update(&self.config.performance, est, self.last_main_line_m);
            controls.main_line_m -= self.trim.offset_m;
        } else {
            self.trim.interrupt();
        }
        self.last_main_line_m = controls.main_line_m;
        Command {
            controls,
            phase: self.phase(),
        }
    }
}
