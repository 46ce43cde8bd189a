//! Vehicle side of the parameter protocol: [`ParamTable`] holds the named parameters of
//! their [`ParamSpec`]s, answers list / read / set, refuses out-of-range sets and those the
//! application's [`ParamValidator`] refuses (answering with the value in force and a text
//! saying why), and reports [`ParamChange`]s and [`ParamRefusal`]s to the application.

use std::collections::VecDeque;

use mavlink::dialects::common::MavMessage;
use serde::{Deserialize, Serialize};

use super::value::{ParamRequestError, ParamValue, check_name, name_from_wire, param_value_msg};
use crate::telemetry::Severity;

/// Definition of one vehicle parameter.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParamSpec {
    /// Name, 1..=16 ASCII bytes.
    pub name: String,
    /// Value at start.
    pub default: f32,
    /// Smallest accepted value.
    pub min: f32,
    /// Largest accepted value.
    pub max: f32,
    /// What it does, with its unit.
    pub description: String,
    /// Whole numbers only (a choice, a flag): advertised as `MAV_PARAM_TYPE_INT32`, and a set
    /// with a fraction is refused.
    #[serde(default)]
    pub integer: bool,
}

impl ParamSpec {
    /// A parameter definition taking any number in its range.
    pub fn new(name: &str, default: f32, min: f32, max: f32, description: &str) -> Self {
        Self {
            name: name.to_string(),
            default,
            min,
            max,
            description: description.to_string(),
            integer: false,
        }
    }

    /// The same definition, taking whole numbers only.
    pub fn whole(self) -> Self {
        Self {
            integer: true,
            ..self
        }
    }
}

/// Why a parameter table could not be built or changed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParamTableError {
    /// Bad name.
    #[error(transparent)]
    Name(#[from] ParamRequestError),
    /// Two parameters with one name.
    #[error("duplicate parameter {name:?}")]
    Duplicate { name: String },
    /// Default outside [min, max], or non-finite bounds.
    #[error("parameter {name:?}: default {default} outside [{min}, {max}]")]
    BadDefault {
        name: String,
        default: f32,
        min: f32,
        max: f32,
    },
    /// More parameters than PARAM_VALUE can index.
    #[error("{count} parameters is more than the protocol can index")]
    TooMany { count: usize },
    /// Set of an unknown parameter.
    #[error("unknown parameter {name:?}")]
    Unknown { name: String },
    /// Set outside the range (or not finite).
    #[error("{name} = {value} outside [{min}, {max}]")]
    OutOfRange {
        name: String,
        value: f32,
        min: f32,
        max: f32,
    },
    /// Set of a fraction to a parameter that takes whole numbers only.
    #[error("{name} = {value} refused: it takes whole numbers only")]
    NotWhole { name: String, value: f32 },
    /// Set refused by the application's validator.
    #[error("{name} = {value} refused: {reason}")]
    Refused {
        name: String,
        value: f32,
        reason: String,
    },
}

/// The application's check of a parameter set from the station, run by [`ParamTable`] after
/// its own range check and before anything changes or is echoed. `Err(reason)` refuses the
/// value; the reason goes to the station in a STATUSTEXT and to the application as a
/// [`ParamRefusal`].
pub trait ParamValidator {
    /// Whether `name` may take `value` now.
    fn validate(&mut self, name: &str, value: f32) -> Result<(), String>;
}

impl<F: FnMut(&str, f32) -> Result<(), String>> ParamValidator for F {
    fn validate(&mut self, name: &str, value: f32) -> Result<(), String> {
        self(name, value)
    }
}

/// A validator that accepts every value within the table's ranges.
#[derive(Debug, Clone, Copy, Default)]
pub struct RangeOnly;

impl ParamValidator for RangeOnly {
    fn validate(&mut self, _name: &str, _value: f32) -> Result<(), String> {
        Ok(())
    }
}

/// A set from the station that was refused (the table still holds the old value).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParamRefusal {
    /// Name.
    pub name: String,
    /// The value asked for.
    pub value: f32,
    /// The value still in force.
    pub in_force: f32,
    /// Why.
    pub reason: String,
}

/// A change of a vehicle parameter, for the application to apply.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParamChange {
    /// Name.
    pub name: String,
    /// Value before.
    pub old: f32,
    /// Value now.
    pub new: f32,
}

/// Counters of the vehicle side.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct ParamTableStats {
    /// Sets refused (out of range, not finite, or by the application's validator).
    pub sets_refused: u64,
    /// Requests naming a parameter or index we do not have.
    pub unknown_requests: u64,
}

/// Vehicle side of the parameter protocol (sans-io).
#[derive(Debug)]
pub struct ParamTable {
    /// Our system id.
    pub system_id: u8,
    /// Our component id.
    pub component_id: u8,
    specs: Vec<ParamSpec>,
    values: Vec<f32>,
    transmit: VecDeque<MavMessage>,
    changes: VecDeque<ParamChange>,
    refusals: VecDeque<ParamRefusal>,
    texts: VecDeque<(Severity, String)>,
    stats: ParamTableStats,
}

impl ParamTable {
    /// A table of `specs`, every value at its default.
    pub fn new(
        system_id: u8,
        component_id: u8,
        specs: Vec<ParamSpec>,
    ) -> Result<Self, ParamTableError> {
        if specs.len() >= usize::from(u16::MAX) {
            return Err(ParamTableError::TooMany { count: specs.len() });
        }
        for (i, s) in specs.iter().enumerate() {
            check_name(&s.name)?;
            if specs.iter().take(i).any(|o| o.name == s.name) {
                return Err(ParamTableError::Duplicate {
                    name: s.name.clone(),
                });
            }
            if !(s.min.is_finite() && s.max.is_finite() && s.min <= s.default && s.default <= s.max)
                || (s.integer && s.default.fract() != 0.0)
            {
                return Err(ParamTableError::BadDefault {
                    name: s.name.clone(),
                    default: s.default,
                    min: s.min,
                    max: s.max,
                });
            }
        }
        let values = specs.iter().map(|s| s.default).collect();
        Ok(Self {
            system_id,
            component_id,
            specs,
            values,
            transmit: VecDeque::new(),
            changes: VecDeque::new(),
            refusals: VecDeque::new(),
            texts: VecDeque::new(),
            stats: ParamTableStats::default(),
        })
    }

    /// Definitions, in index order.
    pub fn specs(&self) -> &[ParamSpec] {
        &self.specs
    }

    /// Current value of `name`.
    pub fn get(&self, name: &str) -> Option<f32> {
        let i = self.specs.iter().position(|s| s.name == name)?;
        self.values.get(i).copied()
    }

    /// Counters.
    pub fn stats(&self) -> ParamTableStats {
        self.stats
    }

    fn value_at(&self, index: usize) -> Option<ParamValue> {
        Some(ParamValue {
            name: self.specs.get(index)?.name.clone(),
            value: *self.values.get(index)?,
            index: u16::try_from(index).ok()?,
            count: u16::try_from(self.specs.len()).ok()?,
        })
    }

    /// The PARAM_VALUE announcing the parameter at `index`, typed as its spec says.
    fn announce(&mut self, index: usize) {
        let integer = self.specs.get(index).is_some_and(|s| s.integer);
        if let Some(v) = self.value_at(index) {
            self.transmit.push_back(param_value_msg(&v, integer));
        }
    }

    /// Sets a value locally (from the application, which has checked it), announcing it to
    /// the station. Only the table's range is checked.
    pub fn set(&mut self, name: &str, value: f32) -> Result<(), ParamTableError> {
        self.set_validated(name, value, &mut RangeOnly)
    }

    /// The index of `name` if `value` is within its range.
    fn check_range(&self, name: &str, value: f32) -> Result<usize, ParamTableError> {
        let unknown = || ParamTableError::Unknown {
            name: name.to_string(),
        };
        let i = self
            .specs
            .iter()
            .position(|s| s.name == name)
            .ok_or_else(unknown)?;
        let spec = self.specs.get(i).ok_or_else(unknown)?;
        if !(value.is_finite() && spec.min <= value && value <= spec.max) {
            return Err(ParamTableError::OutOfRange {
                name: name.to_string(),
                value,
                min: spec.min,
                max: spec.max,
            });
        }
        if spec.integer && value.fract() != 0.0 {
            return Err(ParamTableError::NotWhole {
                name: name.to_string(),
                value,
            });
        }
        Ok(i)
    }

    /// Range check, then `validator`, then the change and its announcement.
    fn set_validated(
        &mut self,
        name: &str,
        value: f32,
        validator: &mut impl ParamValidator,
    ) -> Result<(), ParamTableError> {
        let i = self.check_range(name, value)?;
        validator
            .validate(name, value)
            .map_err(|reason| ParamTableError::Refused {
                name: name.to_string(),
                value,
                reason,
            })?;
        if let Some(slot) = self.values.get_mut(i) {
            let old = *slot;
            *slot = value;
            if old.to_bits() != value.to_bits() {
                self.changes.push_back(ParamChange {
                    name: name.to_string(),
                    old,
                    new: value,
                });
            }
        }
        self.announce(i);
        Ok(())
    }

    /// Feeds a received message, sets checked against the range only. Returns whether it was
    /// a parameter request for us.
    pub fn handle_message(&mut self, msg: &MavMessage) -> bool {
        self.handle_message_with(msg, &mut RangeOnly)
    }

    /// Feeds a received message; a PARAM_SET within its range is then put to `validator`
    /// before anything changes or is echoed. Returns whether it was a parameter request for
    /// us.
    pub fn handle_message_with(
        &mut self,
        msg: &MavMessage,
        validator: &mut impl ParamValidator,
    ) -> bool {
        let for_us = |ts: u8, tc: u8| {
            (ts == 0 || ts == self.system_id) && (tc == 0 || tc == self.component_id)
        };
        match msg {
            MavMessage::PARAM_REQUEST_LIST(r) if for_us(r.target_system, r.target_component) => {
                for i in 0..self.specs.len() {
                    self.announce(i);
                }
                true
            }
            MavMessage::PARAM_REQUEST_READ(r) if for_us(r.target_system, r.target_component) => {
                let index = if r.param_index >= 0 {
                    usize::try_from(r.param_index)
                        .ok()
                        .filter(|&i| i < self.specs.len())
                } else {
                    let name = name_from_wire(&r.param_id);
                    self.specs.iter().position(|s| s.name == name)
                };
                match index.filter(|&i| i < self.specs.len()) {
                    Some(i) => self.announce(i),
                    None => {
                        self.stats.unknown_requests += 1;
                        tracing::debug!(index = r.param_index, name = %name_from_wire(&r.param_id), "read of unknown parameter");
                    }
                }
                true
            }
            MavMessage::PARAM_SET(s) if for_us(s.target_system, s.target_component) => {
                let name = name_from_wire(&s.param_id);
                match self.set_validated(&name, s.param_value, validator) {
                    Ok(()) => {}
                    Err(ParamTableError::Unknown { .. }) => {
                        self.stats.unknown_requests += 1;
                        self.texts
                            .push_back((Severity::Warning, format!("PARAM {name}: unknown")));
                    }
                    Err(e) => {
                        self.stats.sets_refused += 1;
                        tracing::warn!(error = %e, "parameter set refused");
                        // The value in force answers the set: the station's client reads it
                        // as the outcome.
                        if let Some(i) = self.specs.iter().position(|sp| sp.name == name)
                            && let Some(v) = self.value_at(i)
                        {
                            self.announce(i);
                            self.refusals.push_back(ParamRefusal {
                                name: name.clone(),
                                value: s.param_value,
                                in_force: v.value,
                                reason: match &e {
                                    ParamTableError::Refused { reason, .. } => reason.clone(),
                                    other => other.to_string(),
                                },
                            });
                        }
                        self.texts
                            .push_back((Severity::Warning, format!("PARAM {e}")));
                    }
                }
                true
            }
            _ => false,
        }
    }

    /// Next change for the application.
    pub fn poll_change(&mut self) -> Option<ParamChange> {
        self.changes.pop_front()
    }

    /// Next refused set, for the application.
    pub fn poll_refusal(&mut self) -> Option<ParamRefusal> {
        self.refusals.pop_front()
    }

    /// Next text for the station (why a set was refused), to send as STATUSTEXT (split when
    /// longer than one chunk).
    pub fn poll_text(&mut self) -> Option<(Severity, String)> {
        self.texts.pop_front()
    }

    /// Next message to send.
    pub fn poll_transmit(&mut self) -> Option<MavMessage> {
        self.transmit.pop_front()
    }
}

#[cfg(test)]
mod tests {
    use mavlink::dialects::common::MavParamType;

    use super::*;

    #[test]
    fn table_refuses_bad_definitions() {
        assert!(matches!(
            ParamTable::new(
                1,
                1,
                vec![ParamSpec::new("A_NAME_TOO_LONG_X", 0.0, 0.0, 1.0, "")]
            ),
            Err(ParamTableError::Name(_))
        ));
        assert!(matches!(
            ParamTable::new(1, 1, vec![ParamSpec::new("A", 2.0, 0.0, 1.0, "")]),
            Err(ParamTableError::BadDefault { .. })
        ));
        assert!(matches!(
            ParamTable::new(
                1,
                1,
                vec![
                    ParamSpec::new("A", 0.0, 0.0, 1.0, ""),
                    ParamSpec::new("A", 0.0, 0.0, 1.0, "")
                ]
            ),
            Err(ParamTableError::Duplicate { .. })
        ));
        assert!(matches!(
            ParamTable::new(1, 1, vec![ParamSpec::new("A", 0.5, 0.0, 1.0, "").whole()]),
            Err(ParamTableError::BadDefault { .. })
        ));
    }

    fn answers(t: &mut ParamTable) -> Vec<(String, f32, MavParamType)> {
        std::iter::from_fn(|| t.poll_transmit())
            .filter_map(|m| match m {
                MavMessage::PARAM_VALUE(v) => {
                    Some((name_from_wire(&v.param_id), v.param_value, v.param_type))
                }
                _ => None,
            })
            .collect()
    }

    fn set(name: &str, value: f32) -> MavMessage {
        MavMessage::PARAM_SET(mavlink::dialects::common::PARAM_SET_DATA {
            param_value: value,
            target_system: 1,
            target_component: 1,
            param_id: super::super::value::name_to_wire(name),
            param_type: MavParamType::MAV_PARAM_TYPE_REAL32,
        })
    }

    /// Regression (issue 17 item 3): a parameter of whole numbers was advertised as REAL32,
    /// so a generic ground station offered a float editor, and its write of 1.05 was answered
    /// with the old value and no word why.
    #[test]
    fn whole_numbers_are_advertised_as_int32_and_a_fraction_is_refused_with_a_reason() {
        let mut t = ParamTable::new(
            1,
            1,
            vec![
                ParamSpec::new("FS_GPS_ACTION", 1.0, 0.0, 2.0, "choice").whole(),
                ParamSpec::new("SP_FLARE_H", 6.0, 0.0, 30.0, "m"),
            ],
        )
        .expect("table");
        t.handle_message(&MavMessage::PARAM_REQUEST_LIST(
            mavlink::dialects::common::PARAM_REQUEST_LIST_DATA {
                target_system: 1,
                target_component: 1,
            },
        ));
        assert_eq!(
            answers(&mut t),
            vec![
                (
                    "FS_GPS_ACTION".into(),
                    1.0,
                    MavParamType::MAV_PARAM_TYPE_INT32
                ),
                (
                    "SP_FLARE_H".into(),
                    6.0,
                    MavParamType::MAV_PARAM_TYPE_REAL32
                ),
            ]
        );
        t.handle_message(&set("FS_GPS_ACTION", 1.05));
        assert_eq!(
            answers(&mut t),
            vec![(
                "FS_GPS_ACTION".into(),
                1.0,
                MavParamType::MAV_PARAM_TYPE_INT32
            )],
            "the value in force answers"
        );
        let (_, text) = t.poll_text().expect("a text says why");
        assert!(text.contains("whole numbers"), "{text}");
        assert_eq!(t.poll_refusal().map(|r| r.in_force), Some(1.0));
        t.handle_message(&set("FS_GPS_ACTION", 2.0));
        assert_eq!(
            answers(&mut t),
            vec![(
                "FS_GPS_ACTION".into(),
                2.0,
                MavParamType::MAV_PARAM_TYPE_INT32
            )]
        );
        // A fraction is fine where fractions are.
        t.handle_message(&set("SP_FLARE_H", 6.5));
        assert_eq!(t.get("SP_FLARE_H"), Some(6.5));
    }
}
