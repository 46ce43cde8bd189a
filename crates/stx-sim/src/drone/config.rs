//! Mission scenario files (`config/scenarios/mission*.toml`, `rehearsal.toml`): everything the
//! simulated drone needs to fly a whole STRAPLEX mission — the launch site, the balloon, the
//! round chute, the parafoil's deployment, the onboard plan and settings (the parameters of
//! [`stx_gnc::params`]), the wind, the sensors and estimator, the battery and the failures to
//! inject.
//!
//! Staged like the rest of stx: the TOML text is parsed into [`MissionConfig`] (unknown keys
//! refused), [`MissionConfig::validate`] checks every number before anything runs, and only
//! then does [`crate::drone::Drone::new`] build the running drone. Every field has a default,
//! so a file names only what it changes.

use serde::Deserialize;
use stx_dynamics::wind::WindConfig;
use stx_gnc::estimator::EstimatorConfig;
use stx_gnc::flight_path::StackConfig;
use stx_gnc::geo::LocalFrame;
use stx_gnc::mission::{FlightMode, FlightStage};
use stx_gnc::params::OnboardSettings;

pub use crate::drone::config_error::MissionError;
use crate::drone::failures::FailureConfig;
use crate::scenario::LocalizerSpec;
use crate::sensors::SensorConfig;

/// The mission scenarios shipped with stx, by name (`stx drone --scenario NAME`).
pub const BUILTIN: &[(&str, &str)] = &[
    (
        "mission",
        include_str!("../../../../config/scenarios/mission.toml"),
    ),
    (
        "mission-short",
        include_str!("../../../../config/scenarios/mission-short.toml"),
    ),
    (
        "rehearsal",
        include_str!("../../../../config/scenarios/rehearsal.toml"),
    ),
];

fn invalid(field: &str, value: impl ToString, rule: &'static str) -> MissionError {
    MissionError::Invalid {
        field: field.to_string(),
        value: value.to_string(),
        rule,
    }
}

/// Where and how the mission starts.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StartConfig {
    /// Stage the drone starts in: `pre_launch` (on the pad, the whole mission), `ascent`,
    /// `round_chute` or `parafoil_deploy` (rehearsals that skip what comes before).
    pub stage: FlightStage,
    /// Time on the pad before the balloon is released, s (pre_launch only).
    pub launch_delay_s: f64,
    /// Drone position at the start, local NED from the launch site, m (z ≤ 0; for
    /// `pre_launch` it must be on the ground, z = 0).
    pub position_ned_m: [f64; 3],
}

impl Default for StartConfig {
    fn default() -> Self {
        Self {
            stage: FlightStage::PreLaunch,
            launch_delay_s: 10.0,
            position_ned_m: [0.0, 0.0, 0.0],
        }
    }
}

/// The balloon (see `mission.rs`, "Ascent"): a constant free lift on an envelope that grows
/// as the air thins gives an ascent rate `v = v₀·(ρ₀/ρ)^k`, with `v₀` such that the climb
/// from the launch site to the burst altitude takes `(burst − site) / mean_ascent_rate_mps`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BalloonConfig {
    /// Mean ascent rate from launch to burst (climb over time), m/s (> 0; ≈ 5 for STRAPLEX).
    /// The rate at launch is lower and the rate near burst higher (by `ascent_density_exponent`).
    pub mean_ascent_rate_mps: f64,
    /// Exponent `k` of the density ratio, 0…0.5: 1/6 for drag balance with the volume growing
    /// as 1/ρ and a constant drag coefficient; 0 for a constant ascent rate.
    pub ascent_density_exponent: f64,
    /// Altitude at which the balloon bursts, m above mean sea level (> the site's altitude).
    pub burst_altitude_msl_m: f64,
}

impl Default for BalloonConfig {
    fn default() -> Self {
        Self {
            mean_ascent_rate_mps: 5.0,
            ascent_density_exponent: 1.0 / 6.0,
            burst_altitude_msl_m: 35_000.0,
        }
    }
}

/// The round parachute the stack falls under after burst or cutdown.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RoundChuteConfig {
    /// Drag coefficient times reference area, Cd·A, m² (> 0). 4 m² lets the 9-kg stack land at
    /// about 6 m/s and fall at about 70 m/s (250 km/h) at 35 km.
    pub drag_area_m2: f64,
    /// Mass hanging under the round chute besides the parafoil stack (the chute itself, the
    /// balloon's remains), kg (≥ 0).
    pub extra_mass_kg: f64,
}

impl Default for RoundChuteConfig {
    fn default() -> Self {
        Self {
            drag_area_m2: 4.0,
            extra_mass_kg: 0.3,
        }
    }
}

/// How the parafoil comes out when the onboard software releases the round chute (the height
/// is the onboard decision `onboard.mission.deploy_height_m`).
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ParafoilStageConfig {
    /// Heading of the canopy at deployment, degrees from north; absent: along the drift.
    pub deploy_heading_deg: Option<f64>,
}

/// The onboard plan: what the drone flies with no operator.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlanConfig {
    /// Mode flown once the parafoil is up (`spiral_landing`, `heading`, `course`, `localizer`,
    /// `uncontrolled`; not `manual`).
    pub mode: FlightMode,
    /// Landing target, latitude and longitude in degrees (on the site's ground level).
    pub target_lat_lon_deg: Option<[f64; 2]>,
    /// Landing target, north and east of the launch site, m (instead of latitude/longitude).
    pub target_ne_m: Option<[f64; 2]>,
    /// Course of the final approach, degrees; absent: into the wind.
    pub approach_course_deg: Option<f64>,
    /// Heading held in heading mode, degrees.
    pub heading_deg: f64,
    /// Course held in course mode, degrees.
    pub course_deg: f64,
    /// Line followed in localizer mode.
    pub localizer: Option<LocalizerSpec>,
    /// Glide slope (sink over ground speed) down the localizer, if any.
    pub glide_slope: Option<f64>,
}

impl Default for PlanConfig {
    fn default() -> Self {
        Self {
            mode: FlightMode::SpiralLanding,
            target_lat_lon_deg: None,
            target_ne_m: None,
            approach_course_deg: None,
            heading_deg: 0.0,
            course_deg: 0.0,
            localizer: None,
            glide_slope: None,
        }
    }
}

/// The drone's battery (see [`crate::drone::telemetry::Battery`]).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BatteryConfig {
    /// Capacity, mAh (> 0).
    pub capacity_mah: f64,
    /// Charge at the start, % (0…100).
    pub initial_pct: f64,
    /// Open-circuit voltage when full, V.
    pub full_v: f64,
    /// Open-circuit voltage when empty, V (< full).
    pub empty_v: f64,
    /// Internal resistance, Ω (≥ 0).
    pub internal_resistance_ohm: f64,
    /// Current of the avionics and radio, A (≥ 0).
    pub base_current_a: f64,
    /// Extra current with all three servos at full deflection, A (≥ 0).
    pub servo_current_a: f64,
}

impl Default for BatteryConfig {
    fn default() -> Self {
        Self {
            capacity_mah: 5000.0,
            initial_pct: 100.0,
            full_v: 12.6,
            empty_v: 10.5,
            internal_resistance_ohm: 0.05,
            base_current_a: 0.45,
            servo_current_a: 1.5,
        }
    }
}

/// Telemetry settings.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TelemetryConfig {
    /// Time between landing predictions, s of mission time (≥ 1: one costs milliseconds).
    pub prediction_period_s: f64,
}

impl Default for TelemetryConfig {
    fn default() -> Self {
        Self {
            prediction_period_s: 2.0,
        }
    }
}

/// A mission scenario file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MissionConfig {
    /// Short name, as given on the command line.
    pub name: String,
    /// What it rehearses.
    pub description: String,
    /// Seed of everything random: sensor noise, turbulence is seeded in the wind itself,
    /// packet loss, the swing of the flight train.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Longest mission, s of mission time; a run still flying then stops with an error.
    #[serde(default = "default_max_duration_s")]
    pub max_duration_s: f64,
    /// Launch site: origin of the local NED frame and ground level of the whole mission.
    #[serde(default)]
    pub site: LocalFrame,
    /// Start.
    #[serde(default)]
    pub start: StartConfig,
    /// Balloon ascent.
    #[serde(default)]
    pub balloon: BalloonConfig,
    /// Round-chute descent.
    #[serde(default)]
    pub round_chute: RoundChuteConfig,
    /// Parafoil deployment.
    #[serde(default)]
    pub parafoil: ParafoilStageConfig,
    /// Onboard plan.
    #[serde(default)]
    pub plan: PlanConfig,
    /// Onboard settings: the initial values of the drone's parameters (gains, spiral,
    /// failsafes, mission decisions; see `stx_gnc::params::CATALOG`).
    #[serde(default)]
    pub onboard: OnboardSettings,
    /// Wind over the whole height of the mission (a profile up to the burst altitude); calm
    /// if absent. Its mean (without turbulence) is also the forecast loaded onboard for the
    /// round-chute landing prediction.
    pub wind: Option<WindConfig>,
    /// The drone's sensors.
    #[serde(default)]
    pub sensors: SensorConfig,
    /// The onboard estimator (its `ground_altitude_msl_m` is taken from `site`).
    #[serde(default)]
    pub estimator: EstimatorConfig,
    /// Battery.
    #[serde(default)]
    pub battery: BatteryConfig,
    /// Telemetry.
    #[serde(default)]
    pub telemetry: TelemetryConfig,
    /// Failures to inject (rehearsals).
    #[serde(default)]
    pub failures: FailureConfig,
}

fn default_seed() -> u64 {
    1
}

fn default_max_duration_s() -> f64 {
    6.0 * 3600.0
}

impl MissionConfig {
    /// The stack as the flight-path planner models it: this mission's balloon, round chute
    /// and deploy height, with `vehicle`'s mass and gravity.
    pub fn stack_config(&self, vehicle: &stx_dynamics::vehicle::Vehicle) -> StackConfig {
        StackConfig {
            mean_ascent_rate_mps: self.balloon.mean_ascent_rate_mps,
            ascent_density_exponent: self.balloon.ascent_density_exponent,
            burst_altitude_msl_m: self.balloon.burst_altitude_msl_m,
            chute_drag_area_m2: self.round_chute.drag_area_m2,
            chute_mass_kg: vehicle.total_mass_kg() + self.round_chute.extra_mass_kg,
            gravity_mps2: vehicle.gravity_mps2,
            deploy_height_m: self.onboard.mission.deploy_height_m,
            ..StackConfig::default()
        }
    }

    /// Parses and validates a mission; `name` is used in errors.
    pub fn from_toml_str(name: &str, text: &str) -> Result<Self, MissionError> {
        let mut config: MissionConfig =
            toml::from_str(text).map_err(|source| MissionError::Parse {
                name: name.to_string(),
                source,
            })?;
        config.estimator.ground_altitude_msl_m = config.site.alt_msl_m;
        config.validate()?;
        // The drone is loaded with its balloon's expected burst and ascent rate before launch
        // (MIS_BURST_M, MIS_ASCENT_MPS), unless the scenario loads other values.
        let (balloon, mission) = (&config.balloon, &mut config.onboard.mission);
        if mission.expected_burst_msl_m == 0.0 {
            mission.expected_burst_msl_m = balloon.burst_altitude_msl_m;
        }
        if mission.expected_ascent_rate_mps == 0.0 {
            mission.expected_ascent_rate_mps = balloon.mean_ascent_rate_mps;
        }
        config.validate()?;
        Ok(config)
    }

    /// A built-in mission by name.
    pub fn builtin(name: &str) -> Result<Self, MissionError> {
        match crate::scenario::find_builtin(BUILTIN, name) {
            Ok((n, text)) => Self::from_toml_str(n, text),
            Err(known) => Err(MissionError::Unknown {
                name: name.to_string(),
                known,
            }),
        }
    }

    /// The landing target, local NED (z = 0: the site's ground), if the plan has one.
    pub fn target_ned_m(&self) -> Option<nalgebra::Vector3<f64>> {
        match (self.plan.target_lat_lon_deg, self.plan.target_ne_m) {
            (Some([lat, lon]), _) => {
                let mut p = self.site.to_ned(lat, lon, self.site.alt_msl_m);
                p.z = 0.0;
                Some(p)
            }
            (None, Some([n, e])) => Some(nalgebra::Vector3::new(n, e, 0.0)),
            (None, None) => None,
        }
    }

    /// Checks every rule; the first broken one is the error.
    pub fn validate(&self) -> Result<(), MissionError> {
        let finite_positive = |field: &str, v: f64| {
            if v > 0.0 && v.is_finite() {
                Ok(())
            } else {
                Err(invalid(field, v, "must be a finite number > 0"))
            }
        };
        let finite_non_negative = |field: &str, v: f64| {
            if v >= 0.0 && v.is_finite() {
                Ok(())
            } else {
                Err(invalid(field, v, "must be a finite number ≥ 0"))
            }
        };
        finite_positive("max_duration_s", self.max_duration_s)?;
        let site = &self.site;
        if !((-90.0..=90.0).contains(&site.lat_deg) && site.lat_deg.abs() < 89.0) {
            return Err(invalid("site.lat_deg", site.lat_deg, "must be within ±89°"));
        }
        if !(-180.0..=180.0).contains(&site.lon_deg) {
            return Err(invalid(
                "site.lon_deg",
                site.lon_deg,
                "must be within ±180°",
            ));
        }
        if !(-500.0..=5000.0).contains(&site.alt_msl_m) {
            return Err(invalid(
                "site.alt_msl_m",
                site.alt_msl_m,
                "must be within −500…5000 m",
            ));
        }
        let start = &self.start;
        finite_non_negative("start.launch_delay_s", start.launch_delay_s)?;
        if let Some(v) = start.position_ned_m.iter().find(|v| !v.is_finite()) {
            return Err(invalid("start.position_ned_m", v, "must be finite"));
        }
        match start.stage {
            FlightStage::PreLaunch if start.position_ned_m[2] != 0.0 => {
                return Err(invalid(
                    "start.position_ned_m",
                    start.position_ned_m[2],
                    "a pre_launch start is on the ground: z = 0",
                ));
            }
            FlightStage::Parafoil | FlightStage::Landed => {
                return Err(invalid(
                    "start.stage",
                    format!("{:?}", start.stage),
                    "must be pre_launch, ascent, round_chute or parafoil_deploy",
                ));
            }
            FlightStage::Ascent | FlightStage::RoundChute | FlightStage::ParafoilDeploy
                if start.position_ned_m[2] > -20.0 =>
            {
                return Err(invalid(
                    "start.position_ned_m",
                    start.position_ned_m[2],
                    "an airborne start must be at least 20 m up (z ≤ −20)",
                ));
            }
            _ => {}
        }
        let b = &self.balloon;
        finite_positive("balloon.mean_ascent_rate_mps", b.mean_ascent_rate_mps)?;
        if !(0.0..=0.5).contains(&b.ascent_density_exponent) {
            return Err(invalid(
                "balloon.ascent_density_exponent",
                b.ascent_density_exponent,
                "must be within 0…0.5",
            ));
        }
        finite_positive("round_chute.drag_area_m2", self.round_chute.drag_area_m2)?;
        finite_non_negative("round_chute.extra_mass_kg", self.round_chute.extra_mass_kg)?;
        let p = &self.parafoil;
        if let Some(h) = p.deploy_heading_deg
            && !h.is_finite()
        {
            return Err(invalid("parafoil.deploy_heading_deg", h, "must be finite"));
        }
        let plan = &self.plan;
        if plan.mode == FlightMode::Manual {
            return Err(invalid(
                "plan.mode",
                "manual",
                "the onboard plan must be autonomous: manual needs an operator",
            ));
        }
        if plan.target_lat_lon_deg.is_some() && plan.target_ne_m.is_some() {
            return Err(invalid(
                "plan.target_ne_m",
                "given with plan.target_lat_lon_deg",
                "give the target one way only",
            ));
        }
        if let Some([lat, lon]) = plan.target_lat_lon_deg
            && !((-90.0..=90.0).contains(&lat) && (-180.0..=180.0).contains(&lon))
        {
            return Err(invalid(
                "plan.target_lat_lon_deg",
                format!("[{lat}, {lon}]"),
                "latitude within ±90°, longitude within ±180°",
            ));
        }
        if let Some(t) = self.target_ned_m()
            && !(t.iter().all(|v| v.is_finite()) && t.x.hypot(t.y) < 1.0e6)
        {
            return Err(invalid(
                "plan.target",
                format!("{t:?}"),
                "must be within 1000 km of the site",
            ));
        }
        if plan.mode == FlightMode::SpiralLanding && self.target_ned_m().is_none() {
            return Err(invalid(
                "plan.target_lat_lon_deg",
                "absent",
                "spiral landing needs a target (target_lat_lon_deg or target_ne_m)",
            ));
        }
        if plan.mode == FlightMode::Localizer && plan.localizer.is_none() {
            return Err(invalid(
                "plan.localizer",
                "absent",
                "localizer mode needs a localizer",
            ));
        }
        for (field, v) in [
            ("plan.heading_deg", plan.heading_deg),
            ("plan.course_deg", plan.course_deg),
            (
                "plan.approach_course_deg",
                plan.approach_course_deg.unwrap_or(0.0),
            ),
        ] {
            if !v.is_finite() {
                return Err(invalid(field, v, "must be finite"));
            }
        }
        if let Some(slope) = plan.glide_slope
            && !(slope > 0.0 && slope.is_finite())
        {
            return Err(invalid(
                "plan.glide_slope",
                slope,
                "must be a finite number > 0",
            ));
        }
        if let Some(w) = &self.wind {
            w.build()?;
        }
        self.sensors.validate()?;
        self.estimator.validate()?;
        let b = &self.battery;
        finite_positive("battery.capacity_mah", b.capacity_mah)?;
        if !(0.0..=100.0).contains(&b.initial_pct) {
            return Err(invalid(
                "battery.initial_pct",
                b.initial_pct,
                "must be within 0…100",
            ));
        }
        finite_positive("battery.empty_v", b.empty_v)?;
        if !(b.full_v > b.empty_v && b.full_v < 65.0) {
            return Err(invalid(
                "battery.full_v",
                b.full_v,
                "must be above empty_v and below 65 V",
            ));
        }
        finite_non_negative("battery.internal_resistance_ohm", b.internal_resistance_ohm)?;
        finite_non_negative("battery.base_current_a", b.base_current_a)?;
        finite_non_negative("battery.servo_current_a", b.servo_current_a)?;
        if !(self.telemetry.prediction_period_s >= 1.0
            && self.telemetry.prediction_period_s.is_finite())
        {
            return Err(invalid(
                "telemetry.prediction_period_s",
                self.telemetry.prediction_period_s,
                "must be a finite number ≥ 1",
            ));
        }
        self.failures.validate()?;
        // The values that become parameters must lie in their parameters' ranges.
        self.onboard.check()?;
        let burst = self.balloon.burst_altitude_msl_m;
        if !(burst.is_finite() && burst > self.site.alt_msl_m + 20.0) {
            return Err(invalid(
                "balloon.burst_altitude_msl_m",
                self.balloon.burst_altitude_msl_m,
                "must be at least 20 m above site.alt_msl_m",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_mission_is_valid_and_named_as_listed() {
        for (name, text) in BUILTIN {
            let m =
                MissionConfig::from_toml_str(name, text).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(&m.name, name);
        }
    }

    #[test]
    fn the_drone_is_loaded_with_its_balloons_burst_and_ascent_rate() {
        let m = MissionConfig::builtin("mission-short").expect("built in");
        assert_eq!(m.onboard.mission.expected_burst_msl_m, 3000.0);
        assert_eq!(m.onboard.mission.expected_ascent_rate_mps, 5.0);
    }

    #[test]
    fn unknown_names_and_bad_fields_say_what_is_wrong() {
        let err = MissionConfig::builtin("misson").unwrap_err().to_string();
        assert!(
            err.contains("misson") && err.contains("mission-short"),
            "{err}"
        );
        let base = BUILTIN[0].1;
        let err = MissionConfig::from_toml_str("x", &format!("{base}\nbogus = 1\n"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("bogus"), "{err}");
        // Each broken field is named in the error.
        for (tables, field) in [
            ("[plan]\nmode = \"manual\"\n", "plan.mode"),
            (
                "[balloon]\nmean_ascent_rate_mps = -1\n[plan]\ntarget_ne_m = [0, 0]\n",
                "balloon.mean_ascent_rate_mps",
            ),
            (
                "[balloon]\nburst_altitude_msl_m = 100\n[plan]\ntarget_ne_m = [0, 0]\n",
                "balloon.burst_altitude_msl_m",
            ),
            (
                "[plan]\ntarget_ne_m = [0, 0]\n[onboard.mission]\ndeploy_height_m = 99999\n",
                "MIS_DEPLOY_M",
            ),
            (
                "[plan]\ntarget_ne_m = [0, 0]\n[failures]\nlink_drop_s = [[50, 10]]\n",
                "failures.link_drop_s[0]",
            ),
        ] {
            let text = format!("name = \"x\"\ndescription = \"x\"\n{tables}");
            let err = MissionConfig::from_toml_str("x", &text)
                .unwrap_err()
                .to_string();
            assert!(err.contains(field), "{field}: {err}");
        }
    }
}
