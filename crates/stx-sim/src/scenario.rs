//! Scenario files (`config/scenarios/*.toml`): initial conditions, environment, integrator,
//! open-loop servo commands and output settings of one simulated flight.
//!
//! The scenarios shipped with stx are compiled in, so `stx sim --scenario NAME` works from any
//! directory; a path to a TOML file runs any other.

use serde::Deserialize;
use stx_dynamics::integrate::{DormandPrince54, Rk4};
use stx_dynamics::state::{Controls, Pose};
use stx_dynamics::wind::WindConfig;
use stx_gnc::control::Localizer;
use stx_gnc::estimator::EstimatorConfig;
use stx_gnc::guidance::{GuidanceConfig, Plan};
use stx_gnc::mission::FlightMode;
use thiserror::Error;

use crate::sensors::SensorConfig;

/// The scenarios shipped with stx, by name.
pub const BUILTIN: &[(&str, &str)] = &[
    (
        "uncontrolled",
        include_str!("../../../config/scenarios/uncontrolled.toml"),
    ),
    (
        "spiral-exit",
        include_str!("../../../config/scenarios/spiral-exit.toml"),
    ),
    (
        "stratospheric",
        include_str!("../../../config/scenarios/stratospheric.toml"),
    ),
    (
        "localizer",
        include_str!("../../../config/scenarios/localizer.toml"),
    ),
    (
        "vertical",
        include_str!("../../../config/scenarios/vertical.toml"),
    ),
    (
        "spiral-landing",
        include_str!("../../../config/scenarios/spiral-landing.toml"),
    ),
];

/// The entry `name` of a table of built-in files (name, TOML text); otherwise the names
/// there are, comma-separated, for the error that lists them.
pub(crate) fn find_builtin(
    table: &'static [(&'static str, &'static str)],
    name: &str,
) -> Result<(&'static str, &'static str), String> {
    table
        .iter()
        .copied()
        .find(|(n, _)| *n == name)
        .ok_or_else(|| table.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", "))
}

/// Why a scenario was refused.
#[derive(Debug, Error)]
pub enum ScenarioError {
    /// No built-in scenario has this name (and it is not a file path).
    #[error("unknown scenario `{name}`; built-in scenarios: {known}")]
    Unknown { name: String, known: String },
    /// The text is not a valid scenario (unknown or missing field, wrong type).
    #[error("scenario `{name}` is not valid")]
    Parse {
        name: String,
        #[source]
        source: toml::de::Error,
    },
    /// A field breaks a rule.
    #[error("scenario field `{field}` = {value} breaks the rule: {rule}")]
    Invalid {
        field: String,
        value: String,
        rule: &'static str,
    },
    /// The wind description is invalid.
    #[error("scenario wind is invalid: {0}")]
    Wind(#[from] stx_dynamics::wind::WindError),
    /// The sensor description is invalid.
    #[error("scenario sensors are invalid: {0}")]
    Sensors(#[from] crate::sensors::SensorConfigError),
    /// The estimator description is invalid.
    #[error("scenario estimator is invalid: {0}")]
    Estimator(#[from] stx_gnc::estimator::EstimatorConfigError),
}

/// A localizer as written in a scenario.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LocalizerSpec {
    /// A point of the line (north, east), m.
    pub point_ne_m: [f64; 2],
    /// Its course, degrees from north.
    pub course_deg: f64,
}

/// Onboard guidance flying the scenario in closed loop (seed chapter 5).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GuidanceScenario {
    /// Mode guidance flies: heading, course, localizer or spiral_landing.
    pub mode: FlightMode,
    /// When guidance takes over, s from the start (the open-loop commands fly before).
    #[serde(default)]
    pub start_s: f64,
    /// Landing target, local NED, m (z = 0 is the ground).
    #[serde(default)]
    pub target_ned_m: [f64; 3],
    /// Heading held in heading mode, degrees.
    #[serde(default)]
    pub heading_deg: f64,
    /// Course held in course mode, degrees.
    #[serde(default)]
    pub course_deg: f64,
    /// Line followed in localizer mode.
    pub localizer: Option<LocalizerSpec>,
    /// Glide slope (sink over ground speed) down the localizer to its point, if any.
    pub glide_slope: Option<f64>,
    /// Final-approach course of a spiral landing, degrees; absent lands into the wind.
    pub approach_course_deg: Option<f64>,
    /// Gains, performance model and spiral settings; the defaults unless given.
    #[serde(default)]
    pub config: GuidanceConfig,
    /// Seed of the sensors' noise.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// The drone's sensors.
    #[serde(default)]
    pub sensors: SensorConfig,
    /// The onboard estimator.
    #[serde(default)]
    pub estimator: EstimatorConfig,
}

fn default_seed() -> u64 {
    1
}

impl GuidanceScenario {
    /// The plan guidance is given.
    pub fn plan(&self) -> Plan {
        let localizer = self.localizer.map(|l| Localizer {
            point_ne_m: l.point_ne_m,
            course_rad: l.course_deg.to_radians(),
        });
        Plan {
            target_ned_m: nalgebra::Vector3::from(self.target_ned_m),
            approach_course_rad: self.approach_course_deg.map(f64::to_radians),
            heading_rad: self.heading_deg.to_radians(),
            course_rad: self.course_deg.to_radians(),
            localizer: localizer.unwrap_or(Plan::default().localizer),
            localizer_glide_slope: self.glide_slope,
        }
    }

    /// The point landings are measured against: the spiral's target, or the localizer's point
    /// when a glide slope leads down to it.
    pub fn aim_ne_m(&self) -> Option<[f64; 2]> {
        match self.mode {
            FlightMode::SpiralLanding => Some([self.target_ned_m[0], self.target_ned_m[1]]),
            FlightMode::Localizer if self.glide_slope.is_some() => {
                self.localizer.map(|l| l.point_ne_m)
            }
            _ => None,
        }
    }
}

/// Which integrator flies the scenario.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "method", rename_all = "snake_case", deny_unknown_fields)]
pub enum IntegratorConfig {
    /// Fixed-step classical Runge–Kutta.
    Rk4 {
        /// Step, s.
        step_s: f64,
    },
    /// Adaptive Dormand–Prince 5(4).
    DormandPrince {
        /// Relative tolerance, dimensionless.
        rel_tol: f64,
        /// Absolute tolerance, in state units (m, m/s, rad, rad/s).
        abs_tol: f64,
        /// Largest step, s.
        #[serde(default = "default_max_step_s")]
        max_step_s: f64,
    },
}

fn default_max_step_s() -> f64 {
    0.5
}

impl Default for IntegratorConfig {
    /// Dormand–Prince at the tolerance `stx bench` shows keeps a stratospheric landing within
    /// 1 m of a reference run at a 10× tighter tolerance.
    fn default() -> Self {
        IntegratorConfig::DormandPrince {
            rel_tol: 1e-6,
            abs_tol: 1e-6,
            max_step_s: default_max_step_s(),
        }
    }
}

/// A built integrator.
#[derive(Debug, Clone)]
pub enum Integrator {
    /// Fixed step.
    Rk4(Rk4),
    /// Adaptive.
    DormandPrince(DormandPrince54),
}

impl IntegratorConfig {
    /// The integrator, checked.
    pub fn build(&self) -> Result<Integrator, ScenarioError> {
        let invalid = |field: &str, value: f64, rule| ScenarioError::Invalid {
            field: format!("integrator.{field}"),
            value: value.to_string(),
            rule,
        };
        match *self {
            IntegratorConfig::Rk4 { step_s } => {
                if !(step_s > 0.0 && step_s <= 1.0) {
                    return Err(invalid("step_s", step_s, "must be in (0, 1] s"));
                }
                Ok(Integrator::Rk4(Rk4::new(step_s)))
            }
            IntegratorConfig::DormandPrince {
                rel_tol,
                abs_tol,
                max_step_s,
            } => {
                if !(rel_tol > 0.0 && rel_tol < 1.0) {
                    return Err(invalid("rel_tol", rel_tol, "must be in (0, 1)"));
                }
                if !(abs_tol > 0.0 && abs_tol.is_finite()) {
                    return Err(invalid("abs_tol", abs_tol, "must be a finite number > 0"));
                }
                if !(max_step_s > 0.0 && max_step_s.is_finite()) {
                    return Err(invalid(
                        "max_step_s",
                        max_step_s,
                        "must be a finite number > 0",
                    ));
                }
                Ok(Integrator::DormandPrince(
                    DormandPrince54::new(rel_tol, abs_tol).with_max_step_s(max_step_s),
                ))
            }
        }
    }
}

/// A main-line command: metres, or a named position.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum MainLineCommand {
    /// Differential displacement, m (positive turns right).
    Metres(f64),
    /// A named position.
    Named(NamedMainLine),
}

/// Named main-line positions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NamedMainLine {
    /// Full travel to the right.
    FullRight,
    /// Full travel to the left.
    FullLeft,
    /// Centred.
    Neutral,
}

impl Default for MainLineCommand {
    fn default() -> Self {
        MainLineCommand::Named(NamedMainLine::Neutral)
    }
}

/// One open-loop command, held from `at_s` until the next one.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControlStep {
    /// When it takes effect, s from the start.
    pub at_s: f64,
    /// Main-line command.
    #[serde(default)]
    pub main_line: MainLineCommand,
    /// Right brake, 0…1.
    #[serde(default)]
    pub brake_right: f64,
    /// Left brake, 0…1.
    #[serde(default)]
    pub brake_left: f64,
}

impl ControlStep {
    /// The servo commands, with named main-line positions resolved for a travel (m).
    pub fn controls(&self, main_line_travel_m: f64) -> Controls {
        let main_line_m = match self.main_line {
            MainLineCommand::Metres(m) => m,
            MainLineCommand::Named(NamedMainLine::FullRight) => main_line_travel_m,
            MainLineCommand::Named(NamedMainLine::FullLeft) => -main_line_travel_m,
            MainLineCommand::Named(NamedMainLine::Neutral) => 0.0,
        };
        Controls {
            main_line_m,
            brake_right: self.brake_right,
            brake_left: self.brake_left,
        }
    }
}

/// Where the air comes from.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EnvironmentConfig {
    /// Ground level above mean sea level, m (Évora is about 300 m).
    pub ground_altitude_msl_m: f64,
    /// Wind; calm if absent.
    pub wind: Option<WindConfig>,
}

/// What is recorded.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OutputConfig {
    /// Interval between recorded samples, s.
    pub interval_s: f64,
}

impl Default for OutputConfig {
    fn default() -> Self {
        Self { interval_s: 0.05 }
    }
}

/// How the summary finds steady flight.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SteadyConfig {
    /// Rates below which the motion counts as settled, rad/s.
    pub rate_threshold_rad_s: f64,
    /// Length of the steady stretch averaged, s.
    pub window_s: f64,
    /// Longest extension of a run that has no steady stretch, s.
    pub max_extension_s: f64,
}

impl Default for SteadyConfig {
    fn default() -> Self {
        Self {
            rate_threshold_rad_s: 0.05,
            window_s: 5.0,
            max_extension_s: 120.0,
        }
    }
}

/// A scenario file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Short name, as given on the command line.
    pub name: String,
    /// What it reproduces.
    pub description: String,
    /// Longest flight, s; a run stops earlier at ground contact.
    pub duration_s: f64,
    /// Initial conditions.
    #[serde(default)]
    pub initial: Pose,
    /// Air and ground.
    #[serde(default)]
    pub environment: EnvironmentConfig,
    /// Integrator.
    #[serde(default)]
    pub integrator: IntegratorConfig,
    /// Open-loop servo commands, by time.
    #[serde(default)]
    pub controls: Vec<ControlStep>,
    /// Recording.
    #[serde(default)]
    pub output: OutputConfig,
    /// Steady-flight detection for the summary.
    #[serde(default)]
    pub steady: SteadyConfig,
    /// Closed-loop guidance, if the scenario is flown by the onboard software.
    pub guidance: Option<GuidanceScenario>,
}

impl Scenario {
    /// Parses and checks a scenario; `name` is used in errors.
    pub fn from_toml_str(name: &str, text: &str) -> Result<Self, ScenarioError> {
        let scenario: Scenario = toml::from_str(text).map_err(|source| ScenarioError::Parse {
            name: name.to_string(),
            source,
        })?;
        scenario.check()?;
        Ok(scenario)
    }

    /// A built-in scenario by name.
    pub fn builtin(name: &str) -> Result<Self, ScenarioError> {
        match find_builtin(BUILTIN, name) {
            Ok((n, text)) => Self::from_toml_str(n, text),
            Err(known) => Err(ScenarioError::Unknown {
                name: name.to_string(),
                known,
            }),
        }
    }

    fn check(&self) -> Result<(), ScenarioError> {
        let invalid = |field: &str, value: f64, rule| {
            Err(ScenarioError::Invalid {
                field: field.to_string(),
                value: value.to_string(),
                rule,
            })
        };
        if !(self.duration_s > 0.0 && self.duration_s.is_finite()) {
            return invalid("duration_s", self.duration_s, "must be a finite number > 0");
        }
        if !(self.output.interval_s > 0.0 && self.output.interval_s.is_finite()) {
            return invalid("output.interval_s", self.output.interval_s, "must be > 0");
        }
        let s = &self.steady;
        if !(s.rate_threshold_rad_s > 0.0 && s.window_s > 0.0 && s.max_extension_s >= 0.0) {
            return invalid(
                "steady",
                s.window_s,
                "threshold and window must be > 0, extension ≥ 0",
            );
        }
        let mut previous = f64::NEG_INFINITY;
        for (i, step) in self.controls.iter().enumerate() {
            if !(step.at_s >= 0.0 && step.at_s > previous && step.at_s.is_finite()) {
                return invalid(
                    &format!("controls[{i}].at_s"),
                    step.at_s,
                    "must be ≥ 0 and after the previous command",
                );
            }
            previous = step.at_s;
            for (field, v) in [
                ("brake_right", step.brake_right),
                ("brake_left", step.brake_left),
            ] {
                if !(0.0..=1.0).contains(&v) {
                    return invalid(&format!("controls[{i}].{field}"), v, "must be in 0…1");
                }
            }
            if let MainLineCommand::Metres(m) = step.main_line
                && !m.is_finite()
            {
                return invalid(&format!("controls[{i}].main_line"), m, "must be finite");
            }
        }
        let state = self.initial.to_state();
        if let Some(i) = state.iter().position(|v| !v.is_finite()) {
            return invalid("initial", state[i], "every value must be finite");
        }
        if state[2] > 0.0 {
            return invalid(
                "initial.position_ned_m",
                state[2],
                "z is down: the start must be above the ground (z ≤ 0)",
            );
        }
        self.integrator.build()?;
        if let Some(wind) = &self.environment.wind {
            wind.build()?;
        }
        if let Some(g) = &self.guidance {
            g.sensors.validate()?;
            g.estimator.validate()?;
            if !(g.start_s >= 0.0 && g.start_s.is_finite()) {
                return invalid("guidance.start_s", g.start_s, "must be ≥ 0");
            }
            if g.mode == FlightMode::Localizer && g.localizer.is_none() {
                return Err(ScenarioError::Invalid {
                    field: "guidance.localizer".into(),
                    value: "absent".into(),
                    rule: "localizer mode needs a localizer",
                });
            }
            if let Some(slope) = g.glide_slope
                && !(slope > 0.0 && slope.is_finite())
            {
                return invalid("guidance.glide_slope", slope, "must be a finite number > 0");
            }
        }
        Ok(())
    }

    /// The commands in effect at `time_s`, for a main-line travel (m).
    pub fn controls_at(&self, time_s: f64, main_line_travel_m: f64) -> Controls {
        self.controls
            .iter()
            .rev()
            .find(|c| c.at_s <= time_s)
            .map(|c| c.controls(main_line_travel_m))
            .unwrap_or_default()
    }

    /// Times at which the commands change, after the start.
    pub fn control_change_times(&self) -> Vec<f64> {
        self.controls
            .iter()
            .map(|c| c.at_s)
            .filter(|t| *t > 0.0)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_scenario_is_valid_and_named_as_listed() {
        for (name, text) in BUILTIN {
            let s = Scenario::from_toml_str(name, text).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(&s.name, name);
        }
    }

    #[test]
    fn an_unknown_name_lists_the_known_ones() {
        let err = Scenario::builtin("sprial-exit").unwrap_err().to_string();
        assert!(
            err.contains("sprial-exit") && err.contains("spiral-exit"),
            "{err}"
        );
    }

    #[test]
    fn bad_fields_are_named() {
        let base = BUILTIN[1].1;
        let err = Scenario::from_toml_str("x", &base.replace("at_s = 10.0", "at_s = -1.0"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("controls[1].at_s"), "{err}");
        let err =
            Scenario::from_toml_str("x", &base.replace("duration_s = 30.0", "duration_s = 0"))
                .unwrap_err()
                .to_string();
        assert!(err.contains("duration_s"), "{err}");
        // The parser's report is the error's source, printed once by an error chain.
        let err = Scenario::from_toml_str("x", &format!("{base}\nbogus = 1\n")).unwrap_err();
        let source = std::error::Error::source(&err)
            .map(ToString::to_string)
            .unwrap_or_default();
        assert!(source.contains("bogus"), "{source}");
        assert!(!err.to_string().contains("bogus"), "{err}");
    }

    #[test]
    fn named_main_line_positions_resolve_to_the_travel() {
        let s = Scenario::builtin("spiral-exit").unwrap();
        assert_eq!(s.controls_at(3.0, 0.03).main_line_m, 0.03);
        assert_eq!(s.controls_at(10.0, 0.03).main_line_m, 0.0);
        assert_eq!(s.control_change_times(), vec![10.0]);
    }
}
