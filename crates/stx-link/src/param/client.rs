//! Ground side of the parameter protocol: [`ParamClient`] lists the vehicle's table
//! (re-requesting missing indices after a quiet timeout), reads and sets one parameter, and
//! reports each outcome as a [`ParamEvent`].

use std::collections::{BTreeMap, VecDeque};
use std::time::Duration;

use mavlink::dialects::common as mc;
use mavlink::dialects::common::MavMessage;
use serde::{Deserialize, Serialize};

use super::value::{ParamRequestError, ParamValue, check_name, name_from_wire, name_to_wire};

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

#[cfg(test)]
mod tests {
    use super::*;

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
