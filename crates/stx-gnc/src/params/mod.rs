//! The onboard parameters: every setting of the drone's software that the ground station may
//! read and write over the link, described once, here, for both ends.
//!
//! The drone builds its MAVLink parameter table (`stx_link::param::ParamTable`) from
//! [`CATALOG`] and applies every accepted set with [`OnboardSettings::apply`]; the station uses
//! the same catalog to show units, ranges and meanings in its parameter editor and to keep its
//! replica of guidance in step ([`OnboardSettings::guidance`] is a [`GuidanceConfig`]).
//!
//! Each [`ParamDef`] says where its value lives in [`OnboardSettings`]: the control gains and
//! spiral settings of [`GuidanceConfig`], the failsafes ([`FailsafeSettings`]) and the mission's
//! onboard decisions ([`MissionSettings`]). Values travel as `f32` (MAVLink's `REAL32`); flags
//! are 0/1 and choices are small integers, both refused when not whole.
//!
//! Names follow one pattern: a group prefix (`GN_` control gains, `SP_` spiral landing, `FS_`
//! failsafes, `MAN_` manual control, `MIS_` mission), then the quantity, at most 16 ASCII
//! characters (MAVLink's `param_id`).

use serde::{Deserialize, Serialize};

use crate::guidance::GuidanceConfig;

mod catalog;

pub use catalog::CATALOG;

/// What the drone does when its GPS has been silent for [`FailsafeSettings::gps_loss_s`]
/// under the parafoil (parameter `FS_GPS_ACTION`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[repr(u8)]
pub enum GpsLossAction {
    /// Keep flying the plan on the estimator's dead reckoning (pitot, AHRS, barometer and the
    /// last wind): good for short outages; the position error grows with the wind error
    /// (about 20 m a minute at 0.3 m/s).
    Continue = 0,
    /// Turn into the last estimated wind and hold that heading on the AHRS, brakes off, full
    /// brakes at the flare height by the barometer: the slowest drift over the ground and the
    /// softest touchdown for a vehicle that no longer knows where it is. In calm air the
    /// heading at the loss is held.
    IntoWind = 1,
    /// Servos neutral: the parafoil glides straight and lands unflared.
    Uncontrolled = 2,
}

impl GpsLossAction {
    /// Every action, in code order.
    pub const ALL: &'static [GpsLossAction] = &[Self::Continue, Self::IntoWind, Self::Uncontrolled];

    /// The parameter value.
    pub fn code(self) -> u8 {
        self as u8
    }

    /// The action for a parameter value.
    pub fn from_code(code: u8) -> Option<Self> {
        Self::ALL.iter().copied().find(|a| a.code() == code)
    }
}

/// Failsafe settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FailsafeSettings {
    /// Seconds without a GPS fix before the GPS-loss action is taken, s.
    pub gps_loss_s: f64,
    /// The GPS-loss action.
    pub gps_loss_action: GpsLossAction,
    /// Sticks go stale after this long without a MANUAL_CONTROL, s; manual mode then falls
    /// back to the autonomous mode flown before it.
    pub manual_timeout_s: f64,
}

impl Default for FailsafeSettings {
    fn default() -> Self {
        Self {
            gps_loss_s: 3.0,
            gps_loss_action: GpsLossAction::IntoWind,
            manual_timeout_s: 0.5,
        }
    }
}

/// The onboard decisions of a STRAPLEX mission before guidance starts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MissionSettings {
    /// Estimated height above the launch site's ground at which the round chute is released
    /// and the parafoil deploys, m.
    pub deploy_height_m: f64,
    /// Time the parafoil is left to inflate and settle with neutral servos before guidance
    /// steers, s.
    pub settle_s: f64,
    /// Estimated altitude above mean sea level at which the drone cuts the balloon away
    /// itself if it has not burst, m; 0 = no automatic cutdown.
    pub cutdown_altitude_msl_m: f64,
    /// Expected burst altitude above mean sea level, m, as loaded before launch; 0 = not
    /// loaded. For the station's predictions only: the drone does nothing at it.
    pub expected_burst_msl_m: f64,
    /// Expected mean ascent rate from launch to burst, m/s, as loaded before launch; 0 = not
    /// loaded. For the station's predictions only.
    pub expected_ascent_rate_mps: f64,
}

impl Default for MissionSettings {
    fn default() -> Self {
        Self {
            deploy_height_m: 2500.0,
            settle_s: 8.0,
            cutdown_altitude_msl_m: 0.0,
            expected_burst_msl_m: 0.0,
            expected_ascent_rate_mps: 0.0,
        }
    }
}

/// Every setting of the onboard software that is a parameter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct OnboardSettings {
    /// Control gains, planning performance and spiral settings.
    pub guidance: GuidanceConfig,
    /// Failsafes.
    pub failsafe: FailsafeSettings,
    /// Mission decisions.
    pub mission: MissionSettings,
}

/// Which part of the onboard software a parameter belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "snake_case")]
pub enum ParamGroup {
    /// Control-law gains ([`crate::control::ControlGains`]).
    Gains,
    /// Spiral landing ([`crate::guidance::SpiralConfig`]).
    Spiral,
    /// Failsafes and manual control ([`FailsafeSettings`]).
    Failsafe,
    /// Mission decisions ([`MissionSettings`]).
    Mission,
    /// The glide and turn guidance plans with ([`crate::performance::GlidePerformance`]): a
    /// vehicle file's trimmed table (`stx polar`), so what one flight identified serves the next.
    Polar,
}

/// What values a parameter takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind", content = "choices")]
pub enum ParamKind {
    /// Any number in [min, max].
    Real,
    /// 0 (off) or 1 (on).
    Flag,
    /// A whole number in [min, max]; the choices' names in code order.
    Choice(&'static [&'static str]),
}

/// One parameter: its wire name, units, range and meaning, and where its value lives.
#[derive(Clone, Copy)]
pub struct ParamDef {
    /// Name on the wire, 1..=16 ASCII characters.
    pub name: &'static str,
    /// Units ("1" for a pure number, "" for flags and choices).
    pub units: &'static str,
    /// Smallest accepted value.
    pub min: f64,
    /// Largest accepted value.
    pub max: f64,
    /// Kind of value.
    pub kind: ParamKind,
    /// Part of the software it tunes.
    pub group: ParamGroup,
    /// What it does.
    pub description: &'static str,
    get: fn(&OnboardSettings) -> f64,
    set: fn(&mut OnboardSettings, f64),
}

impl std::fmt::Debug for ParamDef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ParamDef")
            .field("name", &self.name)
            .field("units", &self.units)
            .field("min", &self.min)
            .field("max", &self.max)
            .field("kind", &self.kind)
            .field("group", &self.group)
            .finish_non_exhaustive()
    }
}

/// Why a parameter value was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// No parameter has this name.
    #[error("unknown parameter {name:?}")]
    Unknown { name: String },
    /// Outside [min, max] or not finite.
    #[error("{name} = {value} is outside [{min}, {max}]")]
    OutOfRange {
        name: &'static str,
        value: f64,
        min: f64,
        max: f64,
    },
    /// A flag or choice that is not a whole number.
    #[error("{name} = {value} is not a whole number")]
    NotWhole { name: &'static str, value: f64 },
    /// Two parameters that contradict each other.
    #[error("{rule} ({a} = {a_value}, {b} = {b_value})")]
    Inconsistent {
        a: &'static str,
        a_value: f64,
        b: &'static str,
        b_value: f64,
        rule: &'static str,
    },
}

impl ParamDef {
    /// The value in `settings`.
    pub fn get(&self, settings: &OnboardSettings) -> f64 {
        (self.get)(settings)
    }

    /// The value in the default settings.
    pub fn default_value(&self) -> f64 {
        (self.get)(&OnboardSettings::default())
    }

    /// Whether `value` is acceptable on its own (range and kind).
    pub fn check(&self, value: f64) -> Result<(), ParamError> {
        if !(value.is_finite() && self.min <= value && value <= self.max) {
            return Err(ParamError::OutOfRange {
                name: self.name,
                value,
                min: self.min,
                max: self.max,
            });
        }
        if !matches!(self.kind, ParamKind::Real) && value.fract() != 0.0 {
            return Err(ParamError::NotWhole {
                name: self.name,
                value,
            });
        }
        Ok(())
    }

    /// Writes `value` into `settings` after [`check`](Self::check).
    pub fn set(&self, settings: &mut OnboardSettings, value: f64) -> Result<(), ParamError> {
        self.check(value)?;
        (self.set)(settings, value);
        Ok(())
    }
}

/// The polar's airspeed parameters, by the table's brake setting.
pub const AIRSPEED_NAMES: [&str; crate::performance::BRAKE_POINTS] = [
    "PL_AS_0", "PL_AS_1", "PL_AS_2", "PL_AS_3", "PL_AS_4", "PL_AS_5",
];
/// The polar's sink-rate parameters, by the table's brake setting.
pub const SINK_NAMES: [&str; crate::performance::BRAKE_POINTS] = [
    "PL_SINK_0",
    "PL_SINK_1",
    "PL_SINK_2",
    "PL_SINK_3",
    "PL_SINK_4",
    "PL_SINK_5",
];

/// A planning polar as the parameters that carry it, in the drone's table order: what
/// `stx polar` writes and the station sends. The brake settings are not parameters: every
/// table guidance is given is over the shipped ones.
pub fn polar_params(perf: &crate::performance::GlidePerformance) -> Vec<(&'static str, f64)> {
    let mut settings = OnboardSettings::default();
    settings.guidance.performance = *perf;
    CATALOG
        .iter()
        .filter(|p| p.group == ParamGroup::Polar)
        .map(|p| (p.name, p.get(&settings)))
        .collect()
}

/// The parameter named `name`.
pub fn find(name: &str) -> Option<&'static ParamDef> {
    CATALOG.iter().find(|p| p.name == name)
}

impl OnboardSettings {
    /// Checks every parameter's value and the rules between them.
    pub fn check(&self) -> Result<(), ParamError> {
        for p in CATALOG {
            p.check(p.get(self))?;
        }
        let sp = &self.guidance.spiral;
        if sp.min_final_m > sp.max_final_m {
            return Err(ParamError::Inconsistent {
                a: "SP_MIN_FINAL",
                a_value: sp.min_final_m,
                b: "SP_MAX_FINAL",
                b_value: sp.max_final_m,
                rule: "the shortest final approach cannot be longer than the longest",
            });
        }
        let perf = &self.guidance.performance;
        for k in 0..perf.brake_points.len() {
            if perf.sink_rate_mps[k] >= perf.airspeed_mps[k] {
                return Err(ParamError::Inconsistent {
                    a: SINK_NAMES[k],
                    a_value: perf.sink_rate_mps[k],
                    b: AIRSPEED_NAMES[k],
                    b_value: perf.airspeed_mps[k],
                    rule: "a glide sinks slower than it flies through the air",
                });
            }
        }
        Ok(())
    }

    /// Sets parameter `name` to `value` if it and the settings it makes are valid; otherwise
    /// leaves the settings as they were.
    pub fn apply(&mut self, name: &str, value: f64) -> Result<(), ParamError> {
        let def = find(name).ok_or_else(|| ParamError::Unknown {
            name: name.to_string(),
        })?;
        let mut next = *self;
        def.set(&mut next, value)?;
        next.check()?;
        *self = next;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_fit_the_wire_and_are_unique() {
        for (i, p) in CATALOG.iter().enumerate() {
            assert!(
                !p.name.is_empty() && p.name.len() <= 16 && p.name.is_ascii(),
                "{}",
                p.name
            );
            assert!(
                CATALOG.iter().skip(i + 1).all(|o| o.name != p.name),
                "duplicate {}",
                p.name
            );
            assert!(p.min < p.max, "{}", p.name);
            assert!(!p.description.is_empty(), "{}", p.name);
        }
    }

    #[test]
    fn defaults_are_in_range_and_consistent() {
        OnboardSettings::default()
            .check()
            .expect("default settings are valid");
    }

    #[test]
    fn every_parameter_reads_back_what_was_set_into_its_own_field() {
        for p in CATALOG {
            let mut s = OnboardSettings::default();
            let value = match p.kind {
                ParamKind::Real => p.min + 0.37 * (p.max - p.min),
                ParamKind::Flag => 1.0 - p.default_value(),
                ParamKind::Choice(c) => ((p.default_value() as usize + 1) % c.len()) as f64,
            };
            p.set(&mut s, value).expect("in range");
            assert_eq!(p.get(&s), value, "{}", p.name);
            // Only this parameter moved.
            for other in CATALOG.iter().filter(|o| o.name != p.name) {
                assert_eq!(
                    other.get(&s),
                    other.default_value(),
                    "setting {} moved {}",
                    p.name,
                    other.name
                );
            }
        }
    }

    #[test]
    fn a_gain_set_reaches_the_guidance_configuration() {
        let mut s = OnboardSettings::default();
        s.apply("GN_HK1", 0.05).expect("valid");
        assert_eq!(s.guidance.gains.hk1_m_per_rad, 0.05);
        s.apply("FS_GPS_ACTION", 2.0).expect("valid");
        assert_eq!(s.failsafe.gps_loss_action, GpsLossAction::Uncontrolled);
    }

    #[test]
    fn bad_values_are_refused_and_change_nothing() {
        let mut s = OnboardSettings::default();
        let before = s;
        assert!(matches!(
            s.apply("GN_HK1", 5.0),
            Err(ParamError::OutOfRange { .. })
        ));
        assert!(matches!(
            s.apply("GN_HK1", f64::NAN),
            Err(ParamError::OutOfRange { .. })
        ));
        assert!(matches!(
            s.apply("FS_GPS_ACTION", 1.5),
            Err(ParamError::NotWhole { .. })
        ));
        assert!(matches!(
            s.apply("SP_MIN_FINAL", 1000.0),
            Err(ParamError::Inconsistent { .. })
        ));
        assert!(matches!(
            s.apply("NO_SUCH", 1.0),
            Err(ParamError::Unknown { .. })
        ));
        // In range on its own, but a sink rate above the airspeed is no glide.
        assert!(matches!(
            s.apply("PL_SINK_3", 6.0),
            Err(ParamError::Inconsistent {
                a: "PL_SINK_3",
                b: "PL_AS_3",
                ..
            })
        ));
        assert_eq!(s, before);
    }

    #[test]
    fn a_polar_sent_as_parameters_is_the_polar_guidance_plans_with() {
        let mut polar = crate::performance::GlidePerformance::default();
        for k in 0..polar.brake_points.len() {
            polar.airspeed_mps[k] *= 0.9;
            polar.sink_rate_mps[k] *= 1.1;
        }
        polar.turn_time_constant_s = 2.1;
        let params = polar_params(&polar);
        assert_eq!(params.len(), 2 * polar.brake_points.len() + 5);
        let mut s = OnboardSettings::default();
        for (name, value) in &params {
            s.apply(name, *value).expect(name);
        }
        assert_eq!(s.guidance.performance, polar);
        // Their names are the table's: the first is the airspeed released, in catalog order.
        assert_eq!(params[0].0, AIRSPEED_NAMES[0]);
        assert_eq!(params[6].0, SINK_NAMES[0]);
    }

    #[test]
    fn gps_loss_action_codes_round_trip() {
        for a in GpsLossAction::ALL {
            assert_eq!(GpsLossAction::from_code(a.code()), Some(*a));
        }
        assert_eq!(GpsLossAction::from_code(3), None);
    }
}
