//! The parameter micro-protocol (PARAM_*): the station reads and edits the drone's tuning
//! parameters (gains, geometry, limits) with the retries the protocol needs over a lossy link.
//!
//! - [`ParamClient`] (ground): list all parameters (PARAM_REQUEST_LIST, then PARAM_VALUEs
//!   collected by index; missing indices re-requested with PARAM_REQUEST_READ after a quiet
//!   timeout), read one, set one (PARAM_SET, the echoed PARAM_VALUE is the value actually
//!   set). Outcomes are [`ParamEvent`]s.
//! - [`ParamTable`] (vehicle): named `f32` parameters with min / max / default and a
//!   description; answers list / read / set, refuses out-of-range or non-finite sets and
//!   those the application's [`ParamValidator`] refuses (the rules between parameters only
//!   the application knows), replying with the unchanged value and a text saying why, and
//!   reports changes to the application as [`ParamChange`]s. The validator runs inside the
//!   set, before the echo, so the only PARAM_VALUE a set produces is the value in force: a
//!   station never sees a value that is put back a moment later.
//!
//! Every value travels as `MAV_PARAM_TYPE_REAL32`.

use std::collections::{BTreeMap, VecDeque};
use std::time::Duration;

use mavlink::dialects::common as mc;
use mavlink::dialects::common::MavMessage;
use serde::{Deserialize, Serialize};

use crate::telemetry::Severity;

/// Longest parameter name, bytes.
pub const PARAM_NAME_LEN: usize = 16;

/// A parameter name and value as seen on the wire.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParamValue {
    /// Name (≤ 16 ASCII bytes).
    pub name: String,
    /// Value.
    pub value: f32,
    /// Index in the vehicle's table.
    pub index: u16,
    /// Number of parameters in the vehicle's table.
    pub count: u16,
}

fn name_to_wire(name: &str) -> mavlink::types::CharArray<16> {
    let mut bytes = [0_u8; PARAM_NAME_LEN];
    for (b, s) in bytes.iter_mut().zip(name.bytes()) {
        *b = s;
    }
    bytes.into()
}

fn name_from_wire(id: &mavlink::types::CharArray<16>) -> String {
    let raw: &[u8] = &id[..];
    let end = raw.iter().position(|&b| b == 0).unwrap_or(raw.len());
    String::from_utf8_lossy(raw.get(..end).unwrap_or(&[])).into_owned()
}

fn param_value_msg(p: &ParamValue) -> MavMessage {
    MavMessage::PARAM_VALUE(mc::PARAM_VALUE_DATA {
        param_value: p.value,
        param_count: p.count,
        param_index: p.index,
        param_id: name_to_wire(&p.name),
        param_type: mc::MavParamType::MAV_PARAM_TYPE_REAL32,
    })
}

/// Retry policy of the ground side.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ParamConfig {
    /// Quiet time before re-requesting.
    pub timeout: Duration,
    /// Re-request rounds before giving up.
    pub retries: u8,
    /// Most PARAM_REQUEST_READs sent per re-request round of a list.
    pub max_rereads_per_round: usize,
}

impl Default for ParamConfig {
    fn default() -> Self {
        Self {
            timeout: Duration::from_secs(1),
            retries: 3,
            max_rereads_per_round: 32,
        }
    }
}

/// Outcome of a parameter operation on the ground side.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ParamEvent {
    /// Every parameter of the list, by index.
    ListComplete { params: Vec<ParamValue> },
    /// The list could not be completed; what arrived and which indices are missing.
    ListFailed {
        received: Vec<ParamValue>,
        missing: Vec<u16>,
        expected_count: Option<u16>,
    },
    /// A read answered.
    ReadDone { param: ParamValue },
    /// A read unanswered after all retries.
    ReadFailed { name: String, attempts: u8 },
    /// A set answered: `actual` is the value the vehicle now holds (differs from
    /// `requested` when the vehicle refused it).
    SetDone {
        name: String,
        requested: f32,
        actual: f32,
        accepted: bool,
    },
    /// A set unanswered after all retries.
    SetFailed {
        name: String,
        requested: f32,
        attempts: u8,
    },
    /// A PARAM_VALUE outside any operation (another station's change, or a late echo).
    Value { param: ParamValue },
}

/// Why a parameter operation could not start.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ParamRequestError {
    /// Name longer than 16 bytes or not ASCII.
    #[error("parameter name {name:?} is not 1..=16 ASCII bytes")]
    BadName { name: String },
    /// A list is already running.
    #[error("a parameter list is already in progress")]
    ListInProgress,
    /// An operation on the same name is already running.
    #[error("an operation on {name:?} is already in progress")]
    Busy { name: String },
}

fn check_name(name: &str) -> Result<(), ParamRequestError> {
    if name.is_empty() || name.len() > PARAM_NAME_LEN || !name.is_ascii() || name.contains('\0') {
        return Err(ParamRequestError::BadName {
            name: name.to_string(),
        });
    }
    Ok(())
}

#[derive(Debug)]
struct ListOp {
    target: (u8, u8),
    received: BTreeMap<u16, ParamValue>,
    count: Option<u16>,
    attempts: u8,
    deadline: Duration,
}

#[derive(Debug)]
struct NamedOp {
    target: (u8, u8),
    name: String,
    /// `Some(value)` for a set, `None` for a read.
    set: Option<f32>,
    attempts: u8,
    deadline: Duration,
}

/// Ground side of the parameter protocol (sans-io).
#[derive(Debug, Default)]
pub struct ParamClient {
    /// Retry policy.
    pub config: ParamConfig,
    list: Option<ListOp>,
    named: Vec<NamedOp>,
    transmit: VecDeque<MavMessage>,
    events: VecDeque<ParamEvent>,
}

impl ParamClient {
    /// A client with the given retry policy.
    pub fn new(config: ParamConfig) -> Self {
        Self {
            config,
            ..Default::default()
        }
    }

    /// Starts fetching the whole table of `target`.
    pub fn list(&mut self, now: Duration, target: (u8, u8)) -> Result<(), ParamRequestError> {
        if self.list.is_some() {
            return Err(ParamRequestError::ListInProgress);
        }
        self.transmit.push_back(request_list(target));
        self.list = Some(ListOp {
            target,
            received: BTreeMap::new(),
            count: None,
            attempts: 1,
            deadline: now + self.config.timeout,
        });
        Ok(())
    }

    /// Reads one parameter by name.
    pub fn read(
        &mut self,
        now: Duration,
        target: (u8, u8),
        name: &str,
    ) -> Result<(), ParamRequestError> {
        self.start_named(now, target, name, None)
    }

    /// Sets one parameter; the outcome reports the value the vehicle holds afterwards.
    pub fn set(
        &mut self,
        now: Duration,
        target: (u8, u8),
        name: &str,
        value: f32,
    ) -> Result<(), ParamRequestError> {
        self.start_named(now, target, name, Some(value))
    }

    fn start_named(
        &mut self,
        now: Duration,
        target: (u8, u8),
        name: &str,
        set: Option<f32>,
    ) -> Result<(), ParamRequestError> {
        check_name(name)?;
        if self
            .named
            .iter()
            .any(|o| o.name == name && o.target.0 == target.0)
        {
            return Err(ParamRequestError::Busy {
                name: name.to_string(),
            });
        }
        let op = NamedOp {
            target,
            name: name.to_string(),
            set,
            attempts: 1,
            deadline: now + self.config.timeout,
        };
        self.transmit.push_back(named_request(&op));
        self.named.push(op);
        Ok(())
    }

    /// Feeds a received message from `from_system`.
    pub fn handle_message(&mut self, now: Duration, from_system: u8, msg: &MavMessage) {
        let MavMessage::PARAM_VALUE(v) = msg else {
            return;
        };
        let param = ParamValue {
            name: name_from_wire(&v.param_id),
            value: v.param_value,
            index: v.param_index,
            count: v.param_count,
        };
        let mut used = false;
        if let Some(i) = self
            .named
            .iter()
            .position(|o| o.target.0 == from_system && o.name == param.name)
        {
            let op = self.named.remove(i);
            used = true;
            self.events.push_back(match op.set {
                Some(requested) => ParamEvent::SetDone {
                    name: op.name,
                    requested,
                    actual: param.value,
                    accepted: param.value.to_bits() == requested.to_bits(),
                },
                None => ParamEvent::ReadDone {
                    param: param.clone(),
                },
            });
        }
        let mut list_done = false;
        if let Some(list) = self.list.as_mut().filter(|l| l.target.0 == from_system) {
            // PARAM_VALUE index 65535 answers a read by name outside the table order.
            if param.index != u16::MAX && param.index < param.count {
                used = true;
                list.count.get_or_insert(param.count);
                list.received.insert(param.index, param.clone());
                list.deadline = now + self.config.timeout;
                list_done = list
                    .count
                    .is_some_and(|c| list.received.len() >= usize::from(c));
            }
        }
        if list_done && let Some(list) = self.list.take() {
            self.events.push_back(ParamEvent::ListComplete {
                params: list.received.into_values().collect(),
            });
        }
        if !used {
            self.events.push_back(ParamEvent::Value { param });
        }
    }

    /// Re-requests or gives up on operations whose deadline passed.
    pub fn handle_timeout(&mut self, now: Duration) {
        let (timeout, retries) = (self.config.timeout, self.config.retries);
        if let Some(list) = self.list.as_mut().filter(|l| l.deadline <= now) {
            if list.attempts > retries {
                if let Some(list) = self.list.take() {
                    let missing = missing_indices(&list);
                    tracing::warn!(missing = missing.len(), "parameter list failed");
                    self.events.push_back(ParamEvent::ListFailed {
                        received: list.received.into_values().collect(),
                        missing,
                        expected_count: list.count,
                    });
                }
            } else {
                list.attempts += 1;
                list.deadline = now + timeout;
                if list.count.is_none() {
                    self.transmit.push_back(request_list(list.target));
                } else {
                    for index in missing_indices(list)
                        .into_iter()
                        .take(self.config.max_rereads_per_round)
                    {
                        self.transmit.push_back(MavMessage::PARAM_REQUEST_READ(
                            mc::PARAM_REQUEST_READ_DATA {
                                param_index: i16::try_from(index).unwrap_or(i16::MAX),
                                target_system: list.target.0,
                                target_component: list.target.1,
                                param_id: name_to_wire(""),
                            },
                        ));
                    }
                }
            }
        }
        let mut i = 0;
        while let Some(op) = self.named.get_mut(i) {
            if op.deadline > now {
                i += 1;
                continue;
            }
            if op.attempts > retries {
                let op = self.named.remove(i);
                self.events.push_back(match op.set {
                    Some(requested) => ParamEvent::SetFailed {
                        name: op.name,
                        requested,
                        attempts: op.attempts,
                    },
                    None => ParamEvent::ReadFailed {
                        name: op.name,
                        attempts: op.attempts,
                    },
                });
                continue;
            }
            op.attempts += 1;
            op.deadline = now + timeout;
            let msg = named_request(op);
            self.transmit.push_back(msg);
            i += 1;
        }
    }

    /// Earliest deadline.
    pub fn poll_timeout(&self) -> Option<Duration> {
        self.list
            .iter()
            .map(|l| l.deadline)
            .chain(self.named.iter().map(|o| o.deadline))
            .min()
    }

    /// Next message to send.
    pub fn poll_transmit(&mut self) -> Option<MavMessage> {
        self.transmit.pop_front()
    }

    /// Next outcome.
    pub fn poll_event(&mut self) -> Option<ParamEvent> {
        self.events.pop_front()
    }
}

fn missing_indices(list: &ListOp) -> Vec<u16> {
    (0..list.count.unwrap_or(0))
        .filter(|i| !list.received.contains_key(i))
        .collect()
}

fn request_list(target: (u8, u8)) -> MavMessage {
    MavMessage::PARAM_REQUEST_LIST(mc::PARAM_REQUEST_LIST_DATA {
        target_system: target.0,
        target_component: target.1,
    })
}

fn named_request(op: &NamedOp) -> MavMessage {
    match op.set {
        Some(value) => MavMessage::PARAM_SET(mc::PARAM_SET_DATA {
            param_value: value,
            target_system: op.target.0,
            target_component: op.target.1,
            param_id: name_to_wire(&op.name),
            param_type: mc::MavParamType::MAV_PARAM_TYPE_REAL32,
        }),
        None => MavMessage::PARAM_REQUEST_READ(mc::PARAM_REQUEST_READ_DATA {
            param_index: -1,
            target_system: op.target.0,
            target_component: op.target.1,
            param_id: name_to_wire(&op.name),
        }),
    }
}

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
}

impl ParamSpec {
    /// A parameter definition.
    pub fn new(name: &str, default: f32, min: f32, max: f32, description: &str) -> Self {
        Self {
            name: name.to_string(),
            default,
            min,
            max,
            description: description.to_string(),
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
        if let Some(v) = self.value_at(i) {
            self.transmit.push_back(param_value_msg(&v));
        }
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
                    if let Some(v) = self.value_at(i) {
                        self.transmit.push_back(param_value_msg(&v));
                    }
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
                match index.and_then(|i| self.value_at(i)) {
                    Some(v) => self.transmit.push_back(param_value_msg(&v)),
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
                            self.transmit.push_back(param_value_msg(&v));
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
    use super::*;

    fn table() -> ParamTable {
        ParamTable::new(
            1,
            1,
            vec![
                ParamSpec::new("HDG_KP", 0.8, 0.0, 5.0, "heading P gain, 1/s"),
                ParamSpec::new("HDG_KD", 0.1, 0.0, 2.0, "heading D gain, s"),
                ParamSpec::new("FLARE_ALT_M", 8.0, 0.0, 50.0, "flare height, m"),
            ],
        )
        .expect("valid table")
    }

    fn pump(cl: &mut ParamClient, tb: &mut ParamTable) {
        loop {
            let mut moved = false;
            while let Some(m) = cl.poll_transmit() {
                tb.handle_message(&m);
                moved = true;
            }
            while let Some(m) = tb.poll_transmit() {
                cl.handle_message(Duration::ZERO, 1, &m);
                moved = true;
            }
            if !moved {
                break;
            }
        }
    }

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
    }

    #[test]
    fn list_read_set_and_refused_set() {
        let mut tb = table();
        let mut cl = ParamClient::default();
        cl.list(Duration::ZERO, (1, 1)).expect("started");
        pump(&mut cl, &mut tb);
        let Some(ParamEvent::ListComplete { params }) = cl.poll_event() else {
            panic!("no list")
        };
        assert_eq!(
            params.iter().map(|p| p.name.as_str()).collect::<Vec<_>>(),
            ["HDG_KP", "HDG_KD", "FLARE_ALT_M"]
        );

        cl.set(Duration::ZERO, (1, 1), "HDG_KP", 1.5)
            .expect("started");
        pump(&mut cl, &mut tb);
        assert_eq!(
            cl.poll_event(),
            Some(ParamEvent::SetDone {
                name: "HDG_KP".into(),
                requested: 1.5,
                actual: 1.5,
                accepted: true
            })
        );
        assert_eq!(
            tb.poll_change(),
            Some(ParamChange {
                name: "HDG_KP".into(),
                old: 0.8,
                new: 1.5
            })
        );

        // Out of range: the unchanged value comes back, with a STATUSTEXT saying why.
        cl.set(Duration::ZERO, (1, 1), "HDG_KP", 99.0)
            .expect("started");
        let m = cl.poll_transmit().expect("PARAM_SET");
        tb.handle_message(&m);
        while let Some(m) = tb.poll_transmit() {
            cl.handle_message(Duration::ZERO, 1, &m);
        }
        let (_, text) = tb.poll_text().expect("a text saying why");
        assert!(
            text.contains("HDG_KP") && text.contains("outside"),
            "{text}"
        );
        assert_eq!(
            cl.poll_event(),
            Some(ParamEvent::SetDone {
                name: "HDG_KP".into(),
                requested: 99.0,
                actual: 1.5,
                accepted: false
            })
        );
        assert_eq!(tb.poll_change(), None);
        assert_eq!(tb.stats().sets_refused, 1);

        cl.read(Duration::ZERO, (1, 1), "FLARE_ALT_M")
            .expect("started");
        pump(&mut cl, &mut tb);
        assert!(
            matches!(cl.poll_event(), Some(ParamEvent::ReadDone { param }) if param.value == 8.0 && param.index == 2)
        );
    }

    /// Regression: a value within its range but refused by the application used to be
    /// echoed first (the client reported it accepted) and put back afterwards.
    #[test]
    fn a_set_the_validator_refuses_is_answered_only_with_the_value_in_force() {
        let mut tb = table();
        let mut cl = ParamClient::default();
        // The application's rule: the D gain at most a quarter of the P gain.
        let kp = tb.get("HDG_KP").expect("KP");
        let mut validator = |name: &str, value: f32| {
            if name == "HDG_KD" && value > kp / 4.0 {
                Err(format!("HDG_KD must not exceed HDG_KP/4 = {}", kp / 4.0))
            } else {
                Ok(())
            }
        };
        cl.set(Duration::ZERO, (1, 1), "HDG_KD", 1.0)
            .expect("started");
        let m = cl.poll_transmit().expect("PARAM_SET");
        assert!(tb.handle_message_with(&m, &mut validator));
        let mut values = Vec::new();
        while let Some(m) = tb.poll_transmit() {
            if let MavMessage::PARAM_VALUE(v) = &m {
                values.push(v.param_value);
            }
            cl.handle_message(Duration::ZERO, 1, &m);
        }
        assert_eq!(values, [0.1], "only the value in force goes out");
        assert_eq!(
            cl.poll_event(),
            Some(ParamEvent::SetDone {
                name: "HDG_KD".into(),
                requested: 1.0,
                actual: 0.1,
                accepted: false
            })
        );
        assert_eq!(cl.poll_event(), None);
        assert_eq!(tb.get("HDG_KD"), Some(0.1));
        assert_eq!(tb.poll_change(), None);
        let refusal = tb.poll_refusal().expect("the application hears of it");
        assert_eq!((refusal.value, refusal.in_force), (1.0, 0.1));
        assert!(refusal.reason.contains("HDG_KP/4"), "{refusal:?}");
        let (_, text) = tb.poll_text().expect("the station hears why");
        assert!(
            text.contains("HDG_KD") && text.contains("HDG_KP/4"),
            "{text}"
        );
        assert_eq!(tb.stats().sets_refused, 1);

        // Within the rule: taken and echoed once.
        cl.set(Duration::ZERO, (1, 1), "HDG_KD", 0.15)
            .expect("started");
        let m = cl.poll_transmit().expect("PARAM_SET");
        tb.handle_message_with(&m, &mut validator);
        while let Some(m) = tb.poll_transmit() {
            cl.handle_message(Duration::ZERO, 1, &m);
        }
        assert!(matches!(
            cl.poll_event(),
            Some(ParamEvent::SetDone { accepted: true, .. })
        ));
        assert_eq!(tb.get("HDG_KD"), Some(0.15));
    }

    #[test]
    fn read_times_out_after_retries() {
        let mut cl = ParamClient::new(ParamConfig {
            retries: 2,
            ..Default::default()
        });
        cl.read(Duration::ZERO, (1, 1), "X").expect("started");
        let mut sent = 0;
        let mut t = Duration::ZERO;
        while cl.poll_event().is_none() {
            while cl.poll_transmit().is_some() {
                sent += 1;
            }
            t = cl.poll_timeout().expect("a deadline");
            cl.handle_timeout(t);
        }
        assert_eq!(sent, 3);
        assert_eq!(t, Duration::from_secs(3));
    }
}
