//! Gain tuning (seed §6.3): each controller's gains optimised on the linearised closed loop
//! and checked on the nonlinear model.
//!
//! The closed loop is the onboard guidance itself ([`stx_gnc::guidance::Guidance`], the same
//! code the drone runs) fed with what the drone would measure, at its 4 Hz control rate:
//! - *linear*: the plant is `ẋ = A x + B u` about the trim, discretised exactly over the
//!   simulator's 0.05 s step with the command held over each 0.25 s period; the measurements
//!   are the linear outputs `C x + D u` (drone position, NED velocity, attitude) plus the
//!   canopy's heading and heading rate, turned into an estimate the way the simulator's
//!   perfect navigation does. The laws, their phases and their saturation are not linearised.
//! - *nonlinear*: `stx-sim`'s [`GuidedFlight`] flies the 31-state model from the same trim
//!   with perfect navigation (what the control loop can do, not what the estimator costs: the
//!   Monte Carlo measures that).
//!
//! Each controller has one step experiment: a 30° heading or course change, a 6 m cross-track
//! offset onto a localizer, or starting 5 m above a glide path (with brakes trimmed at the
//! gains' `brake_trim`). A step response is scored by rise time (10–90 %), overshoot, settling
//! time (5 % band) and actuator use (RMS command deviation as a share of its authority); the
//! cost adds them with weights that make 10 % overshoot cost as much as a rise time 10 % of
//! the run, and an unsettled or unstable response a lot more. Nelder–Mead searches the
//! logarithm of the gains (they stay positive and are searched in proportion). The seed
//! minimised the distance between closed-loop eigenvalue real parts and chosen ones; the
//! closed-loop eigenvalues are reported here for comparison, but a time-domain cost is what
//! the operators feel and it handles the laws' saturation and phases, which eigenvalues do not.

use nalgebra::{DMatrix, DVector, Vector3};
use serde::Serialize;
use stx_dynamics::model::ParafoilModel;
use stx_dynamics::rotation::wrap_pi;
use stx_dynamics::state::{Controls, StateVector, idx};
use stx_dynamics::vehicle::Vehicle;
use stx_gnc::control::{ControlGains, Localizer};
use stx_gnc::estimate::Estimate;
use stx_gnc::guidance::{Guidance, GuidanceConfig, Plan};
use stx_gnc::mission::FlightMode;
use stx_sim::closed_loop::{GuidedFlight, PerfectNavigation, truth_estimate};
use stx_sim::guided::{CONTROL_PERIOD_S, STEP_S};

use crate::jacobian::{Step, jacobian};
use crate::linearize::{LinearModel, input_vector, linearize, state_scales};
use crate::lti::{DiscreteSystem, eigenvalues};
use crate::nelder_mead::{NelderMeadOptions, minimize};
use crate::seed;
use crate::trim::{Trim, TrimError, calm_environment, trim, uniform_environment};

/// The controllers `stx tune` knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Controller {
    /// Heading hold (seed eqs. 5.1–5.3): tunes HK1, HK2.
    Heading,
    /// Course hold (eqs. 5.4–5.6): tunes HK1, HK2 (shared with heading: one set of gains).
    Course,
    /// Localizer following phase (eq. 5.11): tunes HK3 with HK1, HK2 held.
    Localizer,
    /// Glide slope (eqs. 5.12–5.17): tunes VK1, VK2.
    Vertical,
}

impl Controller {
    /// All of them.
    pub const ALL: [Controller; 4] = [
        Controller::Heading,
        Controller::Course,
        Controller::Localizer,
        Controller::Vertical,
    ];

    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Controller::Heading => "heading",
            Controller::Course => "course",
            Controller::Localizer => "localizer",
            Controller::Vertical => "vertical",
        }
    }

    /// The gains it tunes, by their field names in [`ControlGains`].
    pub fn gain_names(self) -> &'static [&'static str] {
        match self {
            Controller::Heading | Controller::Course => &["hk1_m_per_rad", "hk2_m_s_per_rad"],
            Controller::Localizer => &["hk3_m_per_m"],
            Controller::Vertical => &["vk1", "vk2_per_m"],
        }
    }

    /// Current values of the tuned gains.
    pub fn get(self, g: &ControlGains) -> Vec<f64> {
        match self {
            Controller::Heading | Controller::Course => vec![g.hk1_m_per_rad, g.hk2_m_s_per_rad],
            Controller::Localizer => vec![g.hk3_m_per_m],
            Controller::Vertical => vec![g.vk1, g.vk2_per_m],
        }
    }

    /// `g` with the tuned gains replaced by `values`.
    pub fn with(self, g: &ControlGains, values: &[f64]) -> ControlGains {
        let mut out = *g;
        match self {
            Controller::Heading | Controller::Course => {
                out.hk1_m_per_rad = values[0];
                out.hk2_m_s_per_rad = values[1];
            }
            Controller::Localizer => out.hk3_m_per_m = values[0],
            Controller::Vertical => {
                out.vk1 = values[0];
                out.vk2_per_m = values[1];
            }
        }
        out
    }

    /// The seed's appendix A.13 gains read into ours (see [`seed`]).
    pub fn seed_gains(self, g: &ControlGains) -> ControlGains {
        let mut out = *g;
        match self {
            Controller::Heading => {
                out.hk1_m_per_rad = seed::HEADING.k1;
                out.hk2_m_s_per_rad = seed::HEADING.k2;
            }
            Controller::Course => {
                out.hk1_m_per_rad = seed::COURSE.k1;
                out.hk2_m_s_per_rad = seed::COURSE.k2;
            }
            Controller::Localizer => {
                out.hk1_m_per_rad = seed::LOCALIZER.k1;
                out.hk2_m_s_per_rad = seed::LOCALIZER.k2;
                out.hk3_m_per_m = seed::LOCALIZER.k3.unwrap_or(out.hk3_m_per_m);
            }
            Controller::Vertical => {
                out.vk1 = seed::VERTICAL.k1;
                out.vk2_per_m = seed::VERTICAL.k2;
            }
        }
        out
    }

    /// Step size of its experiment, in the response's unit.
    pub fn step(self) -> f64 {
        match self {
            Controller::Heading | Controller::Course => 30f64.to_radians(),
            Controller::Localizer => 6.0,
            Controller::Vertical => 5.0,
        }
    }

    /// Size of its large experiment: a 90° turn (a spiral corner, the law saturated), a
    /// 40 m offset (the convergence distance: the localizer's approach phase, then its
    /// following phase), 10 m above the glide path (its approach phase, the brake saturated).
    pub fn large_step(self) -> f64 {
        match self {
            Controller::Heading | Controller::Course => 90f64.to_radians(),
            Controller::Localizer => 40.0,
            Controller::Vertical => 10.0,
        }
    }

    /// Length of its experiment, s.
    pub fn duration_s(self) -> f64 {
        match self {
            Controller::Heading | Controller::Course => 40.0,
            Controller::Localizer => 60.0,
            Controller::Vertical => 80.0,
        }
    }

    /// What the response is, for plots.
    pub fn response_label(self) -> &'static str {
        match self {
            Controller::Heading => "canopy heading, deg",
            Controller::Course => "course over ground, deg",
            Controller::Localizer => "cross-track error, m",
            Controller::Vertical => "height above the glide path, m",
        }
    }

    /// The actuator it drives, for plots.
    pub fn command_label(self) -> &'static str {
        match self {
            Controller::Vertical => "symmetric brake, 0..1",
            _ => "main line, cm",
        }
    }
}

impl std::str::FromStr for Controller {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Controller::ALL
            .into_iter()
            .find(|c| c.name() == s)
            .ok_or_else(|| {
                format!("unknown controller `{s}`: heading, course, localizer or vertical")
            })
    }
}

/// A sampled step response (one sample per control period).
#[derive(Debug, Clone, Serialize)]
pub struct StepResponse {
    /// Sample times, s.
    pub time_s: Vec<f64>,
    /// The controlled quantity, SI (rad or m).
    pub output: Vec<f64>,
    /// The actuator command: main line (m) or symmetric brake (0…1).
    pub command: Vec<f64>,
    /// Where the output started.
    pub initial: f64,
    /// Where it was asked to go.
    pub reference: f64,
}

/// What a step response is judged by.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct StepMetrics {
    /// 10–90 % rise time, s (None: never reached 90 %).
    pub rise_time_s: Option<f64>,
    /// Overshoot beyond the reference, % of the step.
    pub overshoot_pct: f64,
    /// Time after which the output stays within 5 % of the step of the reference, s (None:
    /// still outside at the end).
    pub settling_time_s: Option<f64>,
    /// Largest |command − trim command|, in the command's unit.
    pub peak_command: f64,
    /// RMS of the command's deviation from trim over its authority (main-line limit, or the
    /// brake's room from the trim), 1.
    pub command_use: f64,
    /// Share of samples with the command at a limit.
    pub saturated_fraction: f64,
    /// |output − reference| at the end, % of the step.
    pub final_error_pct: f64,
    /// The tuning cost of this response.
    pub cost: f64,
}

/// Fraction of the step that counts as settled.
pub const SETTLING_BAND: f64 = 0.05;

/// Scores a response. `authority` is the command range that counts as full use and
/// `trim_command` the command at trim.
pub fn metrics(
    r: &StepResponse,
    trim_command: f64,
    authority: f64,
    limits: (f64, f64),
    duration_s: f64,
) -> StepMetrics {
    let step = r.reference - r.initial;
    let norm: Vec<f64> = r.output.iter().map(|y| (y - r.initial) / step).collect();
    let crossing = |level: f64| -> Option<f64> {
        norm.iter().position(|&v| v >= level).map(|k| {
            if k == 0 {
                r.time_s[0]
            } else {
                // Linear interpolation between the samples around the crossing.
                let (v0, v1) = (norm[k - 1], norm[k]);
                let (t0, t1) = (r.time_s[k - 1], r.time_s[k]);
                t0 + (level - v0) / (v1 - v0) * (t1 - t0)
            }
        })
    };
    let rise = match (crossing(0.1), crossing(0.9)) {
        (Some(a), Some(b)) => Some(b - a),
        _ => None,
    };
    let overshoot = norm.iter().fold(0.0f64, |m, &v| m.max(v - 1.0)) * 100.0;
    let settled = match norm.iter().rposition(|&v| (v - 1.0).abs() > SETTLING_BAND) {
        None => Some(r.time_s[0]),
        Some(k) if k + 1 < norm.len() => Some(r.time_s[k + 1]),
        Some(_) => None,
    };
    let deviations: Vec<f64> = r.command.iter().map(|u| u - trim_command).collect();
    let peak = deviations.iter().fold(0.0f64, |m, d| m.max(d.abs()));
    let rms =
        (deviations.iter().map(|d| d * d).sum::<f64>() / deviations.len().max(1) as f64).sqrt();
    let saturated = r
        .command
        .iter()
        .filter(|&&u| u <= limits.0 + 1e-9 || u >= limits.1 - 1e-9)
        .count() as f64
        / r.command.len().max(1) as f64;
    let final_error = norm.last().map_or(1.0, |v| (v - 1.0).abs()) * 100.0;
    let mut m = StepMetrics {
        rise_time_s: rise,
        overshoot_pct: overshoot,
        settling_time_s: settled,
        peak_command: peak,
        command_use: rms / authority,
        saturated_fraction: saturated,
        final_error_pct: final_error,
        cost: 0.0,
    };
    m.cost = cost(&m, duration_s);
    m
}

/// The tuning cost (see the module doc): times as shares of the run, overshoot weighted ×2,
/// actuator use ×0.5, saturation ×0.5; a response that never rises or settles costs as if it
/// took twice the run, plus its final error.
pub fn cost(m: &StepMetrics, duration_s: f64) -> f64 {
    let never = 2.0 * duration_s;
    let rise = m.rise_time_s.unwrap_or(never) / duration_s;
    let settle = m.settling_time_s.unwrap_or(never) / duration_s;
    let unsettled = if m.settling_time_s.is_none() {
        m.final_error_pct / 100.0
    } else {
        0.0
    };
    rise + settle
        + 2.0 * m.overshoot_pct / 100.0
        + 0.5 * m.command_use
        + 0.5 * m.saturated_fraction
        + unsettled
}

/// Why tuning could not run.
#[derive(Debug, thiserror::Error)]
pub enum TuneError {
    /// No trim.
    #[error(transparent)]
    Trim(#[from] TrimError),
    /// The nonlinear check failed to fly.
    #[error("nonlinear check failed: {0}")]
    Nonlinear(String),
}

/// One controller's experiment, set up at a trim.
#[derive(Debug, Clone)]
pub struct Experiment {
    /// The controller.
    pub controller: Controller,
    /// Size of the step, in the response's unit (rad or m).
    pub step: f64,
    /// The vehicle.
    pub vehicle: Vehicle,
    /// The linear model about the experiment's trim.
    pub linear: LinearModel,
    /// Guidance settings other than the gains (spiral, performance).
    pub base: GuidanceConfig,
    plan: Plan,
    mode: FlightMode,
    discrete: DiscreteSystem,
    heading_rate_row: DMatrix<f64>,
    outputs_at_trim: DVector<f64>,
    drone_velocity: Vector3<f64>,
    template: Estimate,
}

impl Experiment {
    /// Trims at `altitude_m` (brakes at `gains.brake_trim` for the vertical law, released
    /// otherwise, as guidance commands them), linearises, and sets the step of size `step`
    /// up ([`Controller::step`] or [`Controller::large_step`]).
    pub fn new(
        controller: Controller,
        vehicle: &Vehicle,
        altitude_m: f64,
        base: GuidanceConfig,
        step: f64,
    ) -> Result<Self, TuneError> {
        let brake = if controller == Controller::Vertical {
            base.gains.brake_trim
        } else {
            0.0
        };
        let t = trim(vehicle, altitude_m, Controls::symmetric_brake(brake))?;
        let linear = linearize(vehicle, &t);
        let outputs_at_trim = crate::linearize::outputs(vehicle, &t.state, 0.0);
        let drone_velocity = Vector3::from(t.drone_velocity_ned_mps);
        let (plan, mode) = plan_for(
            controller,
            step,
            &outputs_at_trim,
            &drone_velocity,
            base.spiral.hang_height_m,
        );
        let model = ParafoilModel::new(vehicle.clone(), calm_environment());
        let mut template = truth_estimate(&model, 0.0, &t.state);
        template.position_sigma_m = Vector3::zeros();
        let heading_rate_row = linear.system.a.rows(idx::CANOPY_EULER + 2, 1).into_owned();
        Ok(Self {
            controller,
            step,
            vehicle: vehicle.clone(),
            discrete: DiscreteSystem::new(&linear.system.a, &linear.system.b, STEP_S),
            linear,
            base,
            plan,
            mode,
            heading_rate_row,
            outputs_at_trim,
            drone_velocity,
            template,
        })
    }

    /// The trim.
    pub fn trim(&self) -> &Trim {
        &self.linear.trim
    }

    fn guidance(&self, gains: &ControlGains, plan: Plan) -> Guidance {
        let mut config = self.base;
        config.gains = *gains;
        let mut g = Guidance::new(config);
        g.set_plan(plan, 0.0);
        g.set_mode(self.mode, 0.0);
        g
    }

    /// The estimate perfect navigation would give for the linear state `dx` at `time_s`
    /// with the command `u_held` held (it moves the drone through `D`).
    ///
    /// The dynamics do not depend on x, y or ψ, so the linear model is exact in them: the
    /// velocity is the linear one at heading 0 turned by the heading, and, in a simulation,
    /// the position is its integral (`position_ne_m`), so a 90° turn or a 45° intercept is
    /// represented as well as a small step. Without `position_ne_m` (small deviations, for
    /// the closed-loop Jacobian) the position is the linear output.
    fn linear_estimate(
        &self,
        time_s: f64,
        dx: &DVector<f64>,
        du_held: &DVector<f64>,
        position_ne_m: Option<[f64; 2]>,
    ) -> Estimate {
        let sys = &self.linear.system;
        let psi = self.linear.trim.state[idx::CANOPY_EULER + 2] + dx[idx::CANOPY_EULER + 2];
        let y = &self.outputs_at_trim + &sys.c * dx + &sys.d * du_held;
        let mut est = self.template;
        est.time_s = time_s;
        let z = y[2] + self.drone_velocity.z * time_s;
        let (v_n, v_e) = match position_ne_m {
            Some(_) => {
                // The velocity without the heading's own first-order turn, then turned by it.
                let psi_column = sys.c.column(idx::CANOPY_EULER + 2);
                let (n0, e0) = (
                    y[3] - psi_column[3] * dx[idx::CANOPY_EULER + 2],
                    y[4] - psi_column[4] * dx[idx::CANOPY_EULER + 2],
                );
                let (s, c) = psi.sin_cos();
                (c * n0 - s * e0, s * n0 + c * e0)
            }
            None => (y[3], y[4]),
        };
        est.position_ned_m = match position_ne_m {
            Some([n, e]) => Vector3::new(n, e, z),
            None => Vector3::new(
                y[0] + self.drone_velocity.x * time_s,
                y[1] + self.drone_velocity.y * time_s,
                z,
            ),
        };
        est.velocity_ned_mps = Vector3::new(v_n, v_e, y[5]);
        est.roll_rad = y[6];
        est.pitch_rad = y[7];
        est.drone_yaw_rad = y[8];
        est.heading_rad = wrap_pi(psi);
        est.heading_rate_rad_s = (&self.heading_rate_row * dx)[0];
        est.course_rad = v_e.atan2(v_n);
        est.sink_rate_mps = y[5];
        est
    }

    /// The response variable of an estimate.
    fn response(&self, est: &Estimate) -> f64 {
        let position = [est.position_ned_m.x, est.position_ned_m.y];
        match self.controller {
            Controller::Heading => est.heading_rad,
            Controller::Course => est.course_rad,
            Controller::Localizer => self.plan.localizer.cross_track_m(position),
            Controller::Vertical => self
                .plan
                .localizer_glide_path(self.base.spiral.hang_height_m)
                .map_or(0.0, |path| path.altitude_error_m(position, est.height_m())),
        }
    }

    /// The actuator a controller moves.
    fn command_of(&self, c: &Controls) -> f64 {
        match self.controller {
            Controller::Vertical => 0.5 * (c.brake_right + c.brake_left),
            _ => c.main_line_m,
        }
    }

    /// Where the step starts and ends.
    fn initial_and_reference(&self) -> (f64, f64) {
        match self.controller {
            Controller::Heading | Controller::Course => (0.0, self.step),
            Controller::Localizer | Controller::Vertical => (self.step * self.sign(), 0.0),
        }
    }

    fn sign(&self) -> f64 {
        // Cross-track starts negative (left of the line), the glide path error positive
        // (above it); see `plan_for`.
        if self.controller == Controller::Localizer {
            -1.0
        } else {
            1.0
        }
    }

    /// The number of control periods of the experiment and a response to fill.
    fn empty_response(&self) -> (usize, StepResponse) {
        let periods = (self.controller.duration_s() / CONTROL_PERIOD_S).round() as usize;
        let (initial, reference) = self.initial_and_reference();
        let r = StepResponse {
            time_s: Vec::with_capacity(periods),
            output: Vec::with_capacity(periods),
            command: Vec::with_capacity(periods),
            initial,
            reference,
        };
        (periods, r)
    }

    /// The step response of the linear closed loop with `gains`.
    pub fn linear_response(&self, gains: &ControlGains) -> StepResponse {
        let mut guidance = self.guidance(gains, self.plan);
        let n = self.linear.system.n_states();
        let u0 = input_vector(&self.linear.trim.controls);
        let mut dx = DVector::zeros(n);
        let mut du = DVector::zeros(2);
        let substeps = (CONTROL_PERIOD_S / STEP_S).round() as usize;
        let (periods, mut r) = self.empty_response();
        let mut position = [self.outputs_at_trim[0], self.outputs_at_trim[1]];
        for k in 0..periods {
            let t = k as f64 * CONTROL_PERIOD_S;
            let est = self.linear_estimate(t, &dx, &du, Some(position));
            let command = guidance
                .update(&est, self.linear.trim.density_kg_per_m3)
                .controls;
            du = input_vector(&command) - &u0;
            r.time_s.push(t);
            r.output.push(self.response(&est));
            r.command.push(self.command_of(&command));
            for j in 0..substeps {
                // The position integrates the turned velocity (trapezoidal over the step).
                let before = self.linear_estimate(t + j as f64 * STEP_S, &dx, &du, Some(position));
                dx = self.discrete.step(&dx, &du);
                let after =
                    self.linear_estimate(t + (j + 1) as f64 * STEP_S, &dx, &du, Some(position));
                position[0] +=
                    0.5 * STEP_S * (before.velocity_ned_mps.x + after.velocity_ned_mps.x);
                position[1] +=
                    0.5 * STEP_S * (before.velocity_ned_mps.y + after.velocity_ned_mps.y);
            }
            if !dx.iter().all(|v| v.is_finite() && v.abs() < 1e6) {
                // Diverged: the rest of the run is as bad as its last sample.
                break;
            }
        }
        r
    }

    /// The step response of the nonlinear model with `gains` (perfect navigation).
    pub fn nonlinear_response(&self, gains: &ControlGains) -> Result<StepResponse, TuneError> {
        let model = ParafoilModel::new(self.vehicle.clone(), calm_environment());
        let mut flight = GuidedFlight::new(
            model,
            self.linear.trim.state,
            0.0,
            self.guidance(gains, self.plan),
            PerfectNavigation,
            STEP_S,
            CONTROL_PERIOD_S,
        );
        let (periods, mut r) = self.empty_response();
        for _ in 0..periods {
            let landed = flight
                .advance()
                .map_err(|e| TuneError::Nonlinear(e.to_string()))?;
            if let Some(est) = flight.estimate {
                r.time_s.push(est.time_s);
                r.output.push(self.response(&est));
                r.command.push(self.command_of(&flight.model.controls()));
            }
            if landed.is_some() {
                return Err(TuneError::Nonlinear(
                    "the stack reached the ground during the step: trim higher".into(),
                ));
            }
        }
        Ok(r)
    }

    /// Scores a response of this experiment.
    pub fn score(&self, r: &StepResponse, gains: &ControlGains) -> StepMetrics {
        let trim_command = self.command_of(&self.linear.trim.controls);
        let (authority, limits) = match self.controller {
            Controller::Vertical => (trim_command.max(1.0 - trim_command).max(0.05), (0.0, 1.0)),
            _ => (
                gains.main_line_limit_m,
                (-gains.main_line_limit_m, gains.main_line_limit_m),
            ),
        };
        metrics(
            r,
            trim_command,
            authority,
            limits,
            self.controller.duration_s(),
        )
    }

    /// Eigenvalues of the continuous closed loop `A + B ∂u/∂x` about the reference (no step,
    /// no sampling, no saturation): the seed's view of a tuned loop.
    pub fn closed_loop_eigenvalues(&self, gains: &ControlGains) -> Vec<(f64, f64)> {
        // On the reference: the step removed from the plan.
        let plan = self.plan_on_reference();
        let n = self.linear.system.n_states();
        let zero_u = DVector::zeros(2);
        let u0 = input_vector(&self.linear.trim.controls);
        let k = jacobian(
            |dx: &DVector<f64>| {
                let mut g = self.guidance(gains, plan);
                let est = self.linear_estimate(0.0, dx, &zero_u, None);
                input_vector(&g.update(&est, self.linear.trim.density_kg_per_m3).controls) - &u0
            },
            &DVector::zeros(n),
            &state_scales(),
            &vec![Step::Central; n],
        );
        let a_cl = &self.linear.system.a + &self.linear.system.b * k;
        eigenvalues(&a_cl)
    }

    fn plan_on_reference(&self) -> Plan {
        let mut plan = self.plan;
        match self.controller {
            Controller::Heading => plan.heading_rad = 0.0,
            Controller::Course => plan.course_rad = 0.0,
            Controller::Localizer => plan.localizer.point_ne_m[1] = self.outputs_at_trim[1],
            Controller::Vertical => plan.target_ned_m.z -= self.step,
        }
        plan
    }
}

/// The plan and mode of a controller's experiment, from the drone's outputs `y0` and velocity
/// at trim; `hang_height_m` places the vertical experiment's glide path as guidance flies it
/// ([`Plan::localizer_glide_path`]).
fn plan_for(
    controller: Controller,
    step: f64,
    y0: &DVector<f64>,
    v_drone: &Vector3<f64>,
    hang_height_m: f64,
) -> (Plan, FlightMode) {
    let on_track = Localizer {
        point_ne_m: [y0[0], y0[1]],
        course_rad: 0.0,
    };
    let mut plan = Plan::default();
    match controller {
        Controller::Heading => {
            plan.heading_rad = step;
            (plan, FlightMode::Heading)
        }
        Controller::Course => {
            plan.course_rad = step;
            (plan, FlightMode::Course)
        }
        Controller::Localizer => {
            // The line `step` to the right: the vehicle starts left of it. 6 m is inside CD/5
            // = 8 m with the default CD (the following phase of eq. 5.11); 40 m starts in the
            // approach phase.
            plan.localizer = Localizer {
                point_ne_m: [y0[0], y0[1] + step],
                ..on_track
            };
            (plan, FlightMode::Localizer)
        }
        Controller::Vertical => {
            // Along the trimmed track at the trimmed glide slope, `step` below the vehicle: the
            // path's aim height is the target's ground plus the hang height.
            plan.localizer = on_track;
            plan.localizer_glide_slope = Some(v_drone.z / v_drone.x);
            let height = -y0[2];
            plan.target_ned_m = Vector3::new(0.0, 0.0, -(height - step - hang_height_m));
            (plan, FlightMode::Localizer)
        }
    }
}

/// One experiment flown with one gain set.
#[derive(Debug, Clone, Serialize)]
pub struct Trial {
    /// Step size, rad or m.
    pub step: f64,
    /// Linear closed-loop step metrics.
    pub linear: StepMetrics,
    /// Nonlinear step metrics (None if the flight failed).
    pub nonlinear: Option<StepMetrics>,
    /// Why the nonlinear flight failed, if it did.
    pub nonlinear_error: Option<String>,
    /// Step responses (linear, nonlinear), for plots.
    #[serde(skip)]
    pub responses: (StepResponse, Option<StepResponse>),
}

impl Trial {
    fn fly(experiment: &Experiment, g: &ControlGains) -> Self {
        let linear_response = experiment.linear_response(g);
        let linear = experiment.score(&linear_response, g);
        let (nonlinear, nonlinear_error, nonlinear_response) =
            match experiment.nonlinear_response(g) {
                Ok(r) => (Some(experiment.score(&r, g)), None, Some(r)),
                Err(e) => (None, Some(e.to_string()), None),
            };
        Self {
            step: experiment.step,
            linear,
            nonlinear,
            nonlinear_error,
            responses: (linear_response, nonlinear_response),
        }
    }
}

/// One gain set's results.
#[derive(Debug, Clone, Serialize)]
pub struct Candidate {
    /// "current", "tuned" or "seed A.13".
    pub label: String,
    /// The full gain set.
    pub gains: ControlGains,
    /// The tuned gains' values, in the order of [`Controller::gain_names`].
    pub values: Vec<f64>,
    /// The small step (the law's linear range).
    pub small: Trial,
    /// The large step (saturation, approach phases).
    pub large: Trial,
    /// Mean of the two linear costs: what the optimiser minimised.
    pub linear_cost: f64,
    /// Mean of the two nonlinear costs (None if a flight failed): what adoption is judged on.
    pub nonlinear_cost: Option<f64>,
    /// Largest real part of the closed-loop eigenvalues other than the invariances, s⁻¹.
    pub closed_loop_max_real_part: f64,
    /// The closed-loop eigenvalues `[re, im]`.
    pub closed_loop_eigenvalues: Vec<[f64; 2]>,
}

/// What `stx tune` reports.
#[derive(Debug, Clone, Serialize)]
pub struct TuneReport {
    /// The controller.
    pub controller: Controller,
    /// Gains it tunes.
    pub gain_names: Vec<&'static str>,
    /// Trim altitude, m.
    pub altitude_m: f64,
    /// Trim airspeed, m/s.
    pub trim_airspeed_mps: f64,
    /// Symmetric brake at trim.
    pub trim_brake: f64,
    /// The two experiments, in words.
    pub experiment: String,
    /// Before tuning.
    pub current: Candidate,
    /// After tuning.
    pub tuned: Candidate,
    /// The seed's appendix A.13 gains.
    pub seed: Candidate,
    /// Cost evaluations of the optimiser, over its three runs.
    pub evaluations: usize,
    /// Whether the run that gave the result met its tolerance.
    pub converged: bool,
    /// Whether the tuned gains are adopted (better on the nonlinear model than the current).
    pub adopted: bool,
    /// Why or why not.
    pub verdict: String,
    /// The gains to write: tuned if adopted, else the current ones.
    pub gains_out: ControlGains,
}

/// `v` rounded to `digits` significant figures.
pub fn round_significant(v: f64, digits: i32) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let scale = 10f64.powi(digits - 1 - v.abs().log10().floor() as i32);
    (v * scale).round() / scale
}

/// Cost evaluations of each optimiser run.
pub const MAX_EVALUATIONS: usize = 120;

/// Tunes `controller` starting from `current` (its other gains are kept), checks the result
/// on the nonlinear model, and compares with the seed's. `progress(done, total)` is called as
/// the optimiser and the checks proceed.
pub fn tune(
    controller: Controller,
    vehicle: &Vehicle,
    altitude_m: f64,
    base: GuidanceConfig,
    mut progress: impl FnMut(usize, usize),
) -> Result<TuneReport, TuneError> {
    let current = base.gains;
    let small = Experiment::new(controller, vehicle, altitude_m, base, controller.step())?;
    let large = Experiment::new(
        controller,
        vehicle,
        altitude_m,
        base,
        controller.large_step(),
    )?;
    let linear_cost = |g: &ControlGains| {
        0.5 * (small.score(&small.linear_response(g), g).cost
            + large.score(&large.linear_response(g), g).cost)
    };
    let start = controller.get(&current);
    // The logarithm of each gain, relative to where it starts (a zero gain starts at 10⁻⁴ of
    // a unit so that it can grow).
    let anchor: Vec<f64> = start.iter().map(|&g| g.max(1e-4)).collect();
    let gains_at = |p: &[f64]| -> ControlGains {
        let values: Vec<f64> = p.iter().zip(&anchor).map(|(z, a)| a * z.exp()).collect();
        controller.with(&current, &values)
    };
    // Nelder–Mead finds a local minimum, and saturation gives this cost more than one: start
    // from the current gains and from the seed's, then restart from the better end with a
    // fresh simplex (the usual cure for a simplex that collapsed early).
    let seed_start: Vec<f64> = controller
        .get(&controller.seed_gains(&current))
        .iter()
        .zip(&anchor)
        .map(|(g, a)| (g.max(1e-6) / a).ln())
        .collect();
    let total = 3 * MAX_EVALUATIONS + 10;
    let mut used = 0usize;
    let mut run = |from: &[f64], used_before: usize| {
        minimize(
            |p| linear_cost(&gains_at(p)),
            from,
            &NelderMeadOptions {
                initial_step: 0.7,
                cost_tolerance: 1e-4,
                position_tolerance: 0.01,
                max_evaluations: MAX_EVALUATIONS,
            },
            |n| progress(used_before + n.min(MAX_EVALUATIONS), total),
        )
    };
    let from_current = run(&vec![0.0; start.len()], used);
    used += from_current.evaluations;
    let from_seed = run(&seed_start, used);
    used += from_seed.evaluations;
    let better = if from_seed.cost < from_current.cost {
        from_seed
    } else {
        from_current
    };
    let restarted = run(&better.x, used);
    used += restarted.evaluations;
    let minimum = if restarted.cost <= better.cost {
        restarted
    } else {
        better
    };
    // Three significant figures: what a person can read and type, and well inside the
    // optimum's flat bottom.
    let rounded: Vec<f64> = controller
        .get(&gains_at(&minimum.x))
        .into_iter()
        .map(|v| round_significant(v, 3))
        .collect();
    let tuned_gains = controller.with(&current, &rounded);
    let candidate = |label: &str, g: ControlGains| -> Candidate {
        let small_trial = Trial::fly(&small, &g);
        let large_trial = Trial::fly(&large, &g);
        let nonlinear_cost = match (small_trial.nonlinear, large_trial.nonlinear) {
            (Some(a), Some(b)) => Some(0.5 * (a.cost + b.cost)),
            _ => None,
        };
        let cl = small.closed_loop_eigenvalues(&g);
        let max_real = cl
            .iter()
            .filter(|e| e.0.hypot(e.1) >= crate::analysis::zero_tolerance(small.trim()))
            .map(|e| e.0)
            .fold(f64::NEG_INFINITY, f64::max);
        Candidate {
            label: label.into(),
            gains: g,
            values: controller.get(&g),
            linear_cost: 0.5 * (small_trial.linear.cost + large_trial.linear.cost),
            nonlinear_cost,
            small: small_trial,
            large: large_trial,
            closed_loop_max_real_part: max_real,
            closed_loop_eigenvalues: cl.iter().map(|&(re, im)| [re, im]).collect(),
        }
    };
    let current_c = candidate("current", current);
    progress(total - 6, total);
    let tuned_c = candidate("tuned", tuned_gains);
    progress(total - 3, total);
    let seed_c = candidate("seed A.13", controller.seed_gains(&current));
    progress(total, total);
    let nonlinear_cost = |c: &Candidate| c.nonlinear_cost.unwrap_or(f64::INFINITY);
    let (adopted, verdict) = if nonlinear_cost(&tuned_c) < nonlinear_cost(&current_c) {
        (
            true,
            format!(
                "tuned gains lower the nonlinear cost from {:.3} to {:.3}",
                nonlinear_cost(&current_c),
                nonlinear_cost(&tuned_c)
            ),
        )
    } else {
        (
            false,
            format!(
                "tuned gains do not improve the nonlinear cost ({:.3} against {:.3} now): \
                 current gains kept",
                nonlinear_cost(&tuned_c),
                nonlinear_cost(&current_c)
            ),
        )
    };
    let t = small.trim();
    Ok(TuneReport {
        controller,
        gain_names: controller.gain_names().to_vec(),
        altitude_m,
        trim_airspeed_mps: t.airspeed_mps,
        trim_brake: t.controls.brake_right,
        experiment: match controller {
            Controller::Heading => "heading steps of 30° and 90° from a trimmed glide".into(),
            Controller::Course => "course steps of 30° and 90° from a trimmed glide".into(),
            Controller::Localizer => {
                "6 m (following phase) and 40 m (approach, then following) off a localizer".into()
            }
            Controller::Vertical => format!(
                "5 m (following phase) and 10 m (approach) above a glide path at the slope \
                 trimmed with brake {:.2}",
                t.controls.brake_right
            ),
        },
        gains_out: if adopted { tuned_gains } else { current },
        current: current_c,
        tuned: tuned_c,
        seed: seed_c,
        evaluations: used,
        converged: minimum.converged,
        adopted,
        verdict,
    })
}

/// A state perturbed by `delta` (in the state's units) from a trim, for comparing the linear
/// and nonlinear models.
pub fn perturbed(trim: &Trim, delta: &[(usize, f64)]) -> StateVector {
    let mut x = trim.state;
    for &(i, d) in delta {
        x[i] += d;
    }
    x
}

/// Samples `(time s, nonlinear deviation, linear deviation)` of [`forced_responses`].
pub type ResponseSamples = Vec<(f64, DVector<f64>, DVector<f64>)>;

/// Responses of the nonlinear model and of its linearisation from the same perturbed state
/// `delta` with the input stepped by `du` (`[U_L m, U_S]`) at time 0, sampled every `sample_s`
/// over `duration_s`: `(time, nonlinear deviation from the trim's motion, linear deviation)`.
/// The nonlinear model flies in air of the trim's density ([`uniform_environment`]).
pub fn forced_responses(
    vehicle: &Vehicle,
    lin: &LinearModel,
    delta: &[(usize, f64)],
    du: [f64; 2],
    duration_s: f64,
    sample_s: f64,
) -> Result<ResponseSamples, String> {
    use stx_dynamics::integrate::{Hooks, Rk4, integrate};
    let t = &lin.trim;
    let mut model = ParafoilModel::new(vehicle.clone(), uniform_environment(t.altitude_m));
    let u = input_vector(&t.controls) + DVector::from_row_slice(&du);
    model.set_controls(crate::linearize::controls_of(&u));
    let disc = DiscreteSystem::new(&lin.system.a, &lin.system.b, sample_s);
    let mut x_nl = perturbed(t, delta);
    let mut dx_lin = DVector::from_column_slice((x_nl - t.state).as_slice());
    let du = DVector::from_row_slice(&du);
    let mut out = Vec::new();
    let steps = (duration_s / sample_s).round() as usize;
    for k in 0..=steps {
        let time = k as f64 * sample_s;
        // The trim moves: its position advances at the trim's rates.
        let mut reference = t.state;
        for i in 0..3 {
            reference[i] += t.derivative[i] * time;
        }
        let dev = DVector::from_column_slice((x_nl - reference).as_slice());
        out.push((time, dev, dx_lin.clone()));
        if k == steps {
            break;
        }
        let outcome = integrate(
            &mut Rk4::new(0.01),
            &mut model,
            time,
            &x_nl,
            time + sample_s,
            Hooks::default(),
        )
        .map_err(|e| e.to_string())?;
        x_nl = outcome.state;
        dx_lin = disc.step(&dx_lin, &du);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sampled(f: impl Fn(f64) -> f64, duration: f64, dt: f64) -> StepResponse {
        let n = (duration / dt).round() as usize;
        let time_s: Vec<f64> = (0..=n).map(|k| k as f64 * dt).collect();
        StepResponse {
            output: time_s.iter().map(|&t| f(t)).collect(),
            command: vec![0.0; time_s.len()],
            time_s,
            initial: 0.0,
            reference: 1.0,
        }
    }

    #[test]
    fn metrics_of_a_first_order_lag_match_its_closed_form() {
        let tau = 2.0;
        let r = sampled(|t| 1.0 - (-t / tau).exp(), 40.0, 0.01);
        let m = metrics(&r, 0.0, 1.0, (-1.0, 1.0), 40.0);
        // 10–90 % rise: τ ln 9; 5 % settling: τ ln 20; no overshoot.
        let rise = m.rise_time_s.expect("rises");
        assert!((rise - tau * 9f64.ln()).abs() < 0.02, "{rise}");
        let settle = m.settling_time_s.expect("settles");
        assert!((settle - tau * 20f64.ln()).abs() < 0.02, "{settle}");
        assert_eq!(m.overshoot_pct, 0.0);
        assert!(m.final_error_pct < 1e-3);
    }

    #[test]
    fn overshoot_of_a_second_order_system_matches_its_closed_form() {
        let (zeta, omega) = (0.3f64, 1.5f64);
        let wd = omega * (1.0 - zeta * zeta).sqrt();
        let phi = (1.0 - zeta * zeta).sqrt().atan2(zeta);
        let y = |t: f64| {
            1.0 - (-zeta * omega * t).exp() * (wd * t + phi).sin() / (1.0 - zeta * zeta).sqrt()
        };
        let r = sampled(y, 60.0, 0.005);
        let m = metrics(&r, 0.0, 1.0, (-1.0, 1.0), 60.0);
        let expected = 100.0 * (-std::f64::consts::PI * zeta / (1.0 - zeta * zeta).sqrt()).exp();
        assert!(
            (m.overshoot_pct - expected).abs() < 0.05,
            "{} vs {expected}",
            m.overshoot_pct
        );
        // A decreasing step (initial 1 → reference 0) scores the same as its mirror.
        let mut down = r.clone();
        down.output.iter_mut().for_each(|v| *v = 1.0 - *v);
        down.initial = 1.0;
        down.reference = 0.0;
        let md = metrics(&down, 0.0, 1.0, (-1.0, 1.0), 60.0);
        assert!((md.overshoot_pct - m.overshoot_pct).abs() < 1e-9);
        assert_eq!(md.settling_time_s, m.settling_time_s);
    }

    #[test]
    fn a_response_that_never_arrives_costs_more_than_any_that_does() {
        let never = sampled(|t| 0.5 * (1.0 - (-t).exp()), 40.0, 0.25);
        let slow = sampled(|t| 1.0 - (-t / 12.0).exp(), 40.0, 0.25);
        let mn = metrics(&never, 0.0, 1.0, (-1.0, 1.0), 40.0);
        let ms = metrics(&slow, 0.0, 1.0, (-1.0, 1.0), 40.0);
        assert!(mn.rise_time_s.is_none() && mn.settling_time_s.is_none());
        assert!(mn.cost > ms.cost, "{} vs {}", mn.cost, ms.cost);
        assert!(mn.cost > 4.0);
    }

    #[test]
    fn the_linear_loop_turns_through_90_degrees_like_the_nonlinear_one() {
        // The dynamics do not depend on the heading, so the linear estimate turns the velocity
        // by it: a 90° course change must settle in the linear loop as in the 14-DOF one.
        let vehicle = Vehicle::straplex();
        let g = ControlGains::default();
        let exp = Experiment::new(
            Controller::Course,
            &vehicle,
            600.0,
            GuidanceConfig::default(),
            Controller::Course.large_step(),
        )
        .expect("trim");
        let linear = exp.score(&exp.linear_response(&g), &g);
        let nonlinear = exp.score(&exp.nonlinear_response(&g).expect("flies"), &g);
        let (l, n) = (
            linear.settling_time_s.expect("linear settles"),
            nonlinear.settling_time_s.expect("nonlinear settles"),
        );
        // Settling is a threshold crossing: the 14-DOF loop crosses the 5 % band on a
        // swing the linear one takes one more to damp (7.75 s against 6.0 s here).
        assert!((l - n).abs() < 2.5, "settling {l} against {n}");
        let (l, n) = (
            linear.rise_time_s.expect("rises"),
            nonlinear.rise_time_s.expect("rises"),
        );
        assert!((l - n).abs() < 1.0, "rise {l} against {n}");
    }

    #[test]
    fn rounding_keeps_three_significant_figures() {
        assert_eq!(round_significant(0.010502721, 3), 0.0105);
        assert_eq!(round_significant(6.54321, 3), 6.54);
        assert_eq!(round_significant(-0.000226183, 3), -0.000226);
        assert_eq!(round_significant(0.0, 3), 0.0);
    }

    #[test]
    fn tuning_the_heading_loop_from_bad_gains_lowers_its_cost_on_both_models() {
        let vehicle = Vehicle::straplex();
        // Too much proportional gain and almost no damping: a lightly damped turn.
        let bad = ControlGains {
            hk1_m_per_rad: 0.04,
            hk2_m_s_per_rad: 0.001,
            ..ControlGains::default()
        };
        let base = GuidanceConfig {
            gains: bad,
            ..GuidanceConfig::default()
        };
        let mut calls = 0;
        let report = tune(Controller::Heading, &vehicle, 600.0, base, |_, _| {
            calls += 1
        })
        .expect("tunes");
        assert!(calls > 10);
        assert!(report.adopted, "{}", report.verdict);
        let before = report.current.nonlinear_cost.expect("flies");
        let after = report.tuned.nonlinear_cost.expect("flies");
        assert!(after < 0.8 * before, "{before} → {after}");
        assert!(report.tuned.linear_cost < report.current.linear_cost);
        assert!(report.tuned.closed_loop_max_real_part < 0.0);
        // The other gains are untouched.
        assert_eq!(report.gains_out.hk3_m_per_m, bad.hk3_m_per_m);
        assert_eq!(report.gains_out.vk1, bad.vk1);
        // And the linear closed loop predicts the nonlinear one: same metrics within a few
        // tenths of a second and per cent.
        let (l, n) = (
            report.tuned.small.linear,
            report.tuned.small.nonlinear.expect("flies"),
        );
        let (lr, nr) = (l.rise_time_s.expect("rises"), n.rise_time_s.expect("rises"));
        assert!((lr - nr).abs() < 0.5, "{lr} vs {nr}");
        assert!((l.overshoot_pct - n.overshoot_pct).abs() < 3.0);
    }

    /// Regression: guidance's glide path began to end with the lowest body, not the drone, on
    /// the ground (8.4 m higher) while the experiment still measured the error against the old
    /// path; the vehicle started below the path it flew and never "arrived" for any gains.
    #[test]
    fn the_vertical_experiment_starts_its_step_above_the_path_guidance_flies_and_settles_on_it() {
        let vehicle = Vehicle::straplex();
        let g = ControlGains::default();
        let exp = Experiment::new(
            Controller::Vertical,
            &vehicle,
            600.0,
            GuidanceConfig::default(),
            Controller::Vertical.step(),
        )
        .expect("trim");
        let linear = exp.linear_response(&g);
        let first = linear.output[0];
        assert!(
            (first - exp.step).abs() < 0.5,
            "starts {first:.2} m above the flown path, not {} m",
            exp.step
        );
        for m in [
            exp.score(&linear, &g),
            exp.score(&exp.nonlinear_response(&g).expect("flies"), &g),
        ] {
            let settle = m.settling_time_s.expect("settles on the path");
            assert!(settle < 40.0, "{m:?}");
        }
    }

    #[test]
    fn the_seed_localizer_gains_saturate_and_destabilise_our_loop() {
        // Regression pin for ANALYSIS_NOTES: K_H3b read literally (HK1 = 0.56 m/rad …) is
        // 20 to 1000 times our gains and drives the main line from stop to stop.
        let vehicle = Vehicle::straplex();
        let exp = Experiment::new(
            Controller::Localizer,
            &vehicle,
            600.0,
            GuidanceConfig::default(),
            Controller::Localizer.step(),
        )
        .expect("trim");
        let seed = Controller::Localizer.seed_gains(&ControlGains::default());
        let m = exp.score(&exp.linear_response(&seed), &seed);
        assert!(m.saturated_fraction > 0.5, "{m:?}");
        let max_re = exp
            .closed_loop_eigenvalues(&seed)
            .iter()
            .filter(|e| e.0.hypot(e.1) > 1e-3)
            .map(|e| e.0)
            .fold(f64::NEG_INFINITY, f64::max);
        assert!(max_re > 0.0, "{max_re}");
    }
}
