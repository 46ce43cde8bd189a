//! Ground side of a list transfer: [`MissionClient`] uploads a list or downloads the one the
//! vehicle holds, re-sending its last message after a quiet timeout, and reports each
//! outcome as a [`TransferEvent`]. One client per mission type: [`PlanClient`] for the
//! guidance plan, [`FenceClient`](super::FenceClient) for the keep-out fence.

use std::collections::VecDeque;
use std::time::Duration;

use mavlink::dialects::common as mc;
use mavlink::dialects::common::{MavMessage, MavMissionResult};
use serde::{Deserialize, Serialize};

use super::item::PlanItem;
use super::mission::{
    MAX_PLAN_ITEMS, MissionItem, PlanConfig, mission_ack, mission_count, mission_request,
};

/// Outcome of a plan transfer on the ground side.
pub type PlanEvent = TransferEvent<PlanItem>;
/// Ground side of the plan transfer.
pub type PlanClient = MissionClient<PlanItem>;

/// Outcome of a list transfer on the ground side.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum TransferEvent<I> {
    /// The vehicle acknowledged the whole list.
    UploadDone { items: usize },
    /// The vehicle refused the list (`result` is the MAV_MISSION_RESULT code) or stopped
    /// answering (`result: None`).
    UploadFailed { result: Option<u8>, reason: String },
    /// The list the vehicle holds.
    DownloadDone { items: Vec<I> },
    /// Download failed.
    DownloadFailed { reason: String },
}

/// Why a transfer could not start.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PlanRequestError {
    /// Another transfer is running.
    #[error("a plan transfer is already in progress")]
    Busy,
    /// More items than [`MAX_PLAN_ITEMS`].
    #[error("plan of {count} items exceeds {max}")]
    TooLong { count: usize, max: u16 },
}

#[derive(Debug)]
enum ClientOp<I> {
    Upload {
        items: Vec<I>,
        acked_through: Option<u16>,
    },
    Download {
        count: Option<u16>,
        items: Vec<I>,
    },
}

#[derive(Debug)]
struct ClientState<I> {
    target: (u8, u8),
    op: ClientOp<I>,
    last_sent: MavMessage,
    attempts: u8,
    deadline: Duration,
}

/// Ground side of the transfer of one mission type's list (sans-io).
#[derive(Debug)]
pub struct MissionClient<I: MissionItem> {
    /// Timing.
    pub config: PlanConfig,
    state: Option<ClientState<I>>,
    transmit: VecDeque<MavMessage>,
    events: VecDeque<TransferEvent<I>>,
}

impl<I: MissionItem> Default for MissionClient<I> {
    fn default() -> Self {
        Self::new(PlanConfig::default())
    }
}

impl<I: MissionItem> MissionClient<I> {
    /// A client with the given timing.
    pub fn new(config: PlanConfig) -> Self {
        Self {
            config,
            state: None,
            transmit: VecDeque::new(),
            events: VecDeque::new(),
        }
    }

    /// Whether a transfer is running.
    pub fn busy(&self) -> bool {
        self.state.is_some()
    }

    fn send(&mut self, now: Duration, msg: MavMessage, progress: bool) {
        if let Some(s) = self.state.as_mut() {
            s.last_sent = msg.clone();
            s.deadline = now + self.config.timeout;
            if progress {
                s.attempts = 1;
            }
        }
        self.transmit.push_back(msg);
    }

    /// Starts uploading `items` to `target`.
    pub fn upload(
        &mut self,
        now: Duration,
        target: (u8, u8),
        items: Vec<I>,
    ) -> Result<(), PlanRequestError> {
        if self.state.is_some() {
            return Err(PlanRequestError::Busy);
        }
        let count = u16::try_from(items.len())
            .ok()
            .filter(|&c| c <= MAX_PLAN_ITEMS)
            .ok_or(PlanRequestError::TooLong {
                count: items.len(),
                max: MAX_PLAN_ITEMS,
            })?;
        let msg = mission_count(target, count, I::MISSION_TYPE);
        self.state = Some(ClientState {
            target,
            op: ClientOp::Upload {
                items,
                acked_through: None,
            },
            last_sent: msg.clone(),
            attempts: 1,
            deadline: now,
        });
        self.send(now, msg, true);
        Ok(())
    }

    /// Starts downloading the plan `target` holds.
    pub fn download(&mut self, now: Duration, target: (u8, u8)) -> Result<(), PlanRequestError> {
        if self.state.is_some() {
            return Err(PlanRequestError::Busy);
        }
        let msg = MavMessage::MISSION_REQUEST_LIST(mc::MISSION_REQUEST_LIST_DATA {
            target_system: target.0,
            target_component: target.1,
            mission_type: I::MISSION_TYPE,
        });
        self.state = Some(ClientState {
            target,
            op: ClientOp::Download {
                count: None,
                items: Vec::new(),
            },
            last_sent: msg.clone(),
            attempts: 1,
            deadline: now,
        });
        self.send(now, msg, true);
        Ok(())
    }

    /// Feeds a received message from `from_system`.
    // The deprecated MISSION_REQUEST is still sent by older vehicles; it is answered like
    // MISSION_REQUEST_INT, as MAVLink asks.
    #[allow(deprecated)]
    pub fn handle_message(&mut self, now: Duration, from_system: u8, msg: &MavMessage) {
        let Some(state) = self.state.as_mut() else {
            return;
        };
        if state.target.0 != from_system {
            return;
        }
        let target = state.target;
        match (&mut state.op, msg) {
            (
                ClientOp::Upload {
                    items,
                    acked_through,
                },
                MavMessage::MISSION_REQUEST_INT(mc::MISSION_REQUEST_INT_DATA {
                    seq,
                    mission_type,
                    ..
                }),
            )
            | (
                ClientOp::Upload {
                    items,
                    acked_through,
                },
                MavMessage::MISSION_REQUEST(mc::MISSION_REQUEST_DATA {
                    seq, mission_type, ..
                }),
            ) => {
                if *mission_type != I::MISSION_TYPE {
                    return;
                }
                let Some(item) = items.get(usize::from(*seq)) else {
                    tracing::warn!(seq, "vehicle requested a plan item out of range");
                    return;
                };
                let progress = acked_through.is_none_or(|a| *seq > a);
                if progress {
                    *acked_through = Some(*seq);
                }
                let m = item.to_mavlink(target, *seq);
                self.send(now, m, progress);
            }
            (ClientOp::Upload { items, .. }, MavMessage::MISSION_ACK(a))
                if a.mission_type == I::MISSION_TYPE =>
            {
                let n = items.len();
                self.state = None;
                self.events
                    .push_back(if a.mavtype == MavMissionResult::MAV_MISSION_ACCEPTED {
                        TransferEvent::UploadDone { items: n }
                    } else {
                        TransferEvent::UploadFailed {
                            result: Some(a.mavtype as u8),
                            reason: format!("vehicle answered {:?}", a.mavtype),
                        }
                    });
            }
            (ClientOp::Download { count, items }, MavMessage::MISSION_COUNT(c))
                if c.mission_type == I::MISSION_TYPE =>
            {
                if count.is_some() {
                    return; // a duplicate COUNT; our request for the next item is out already
                }
                if c.count > MAX_PLAN_ITEMS {
                    self.state = None;
                    self.events.push_back(TransferEvent::DownloadFailed {
                        reason: format!("plan of {} items exceeds {MAX_PLAN_ITEMS}", c.count),
                    });
                    return;
                }
                *count = Some(c.count);
                if c.count == 0 {
                    self.state = None;
                    self.transmit.push_back(mission_ack(
                        target,
                        MavMissionResult::MAV_MISSION_ACCEPTED,
                        I::MISSION_TYPE,
                    ));
                    self.events
                        .push_back(TransferEvent::DownloadDone { items: Vec::new() });
                    return;
                }
                items.clear();
                self.send(now, mission_request(target, 0, I::MISSION_TYPE), true);
            }
            (
                ClientOp::Download {
                    count: Some(count),
                    items,
                },
                MavMessage::MISSION_ITEM_INT(m),
            ) if m.mission_type == I::MISSION_TYPE => {
                if usize::from(m.seq) != items.len() {
                    return; // late duplicate; the current request is re-sent on timeout
                }
                match I::from_mavlink(m) {
                    Ok(item) => items.push(item),
                    Err(e) => {
                        self.state = None;
                        self.transmit.push_back(mission_ack(
                            target,
                            I::refusal(&e),
                            I::MISSION_TYPE,
                        ));
                        self.events.push_back(TransferEvent::DownloadFailed {
                            reason: format!("item {}: {e}", m.seq),
                        });
                        return;
                    }
                }
                let count = *count;
                if items.len() >= usize::from(count) {
                    let items = std::mem::take(items);
                    self.state = None;
                    if let Err(reason) = I::check_list(&items) {
                        self.transmit.push_back(mission_ack(
                            target,
                            MavMissionResult::MAV_MISSION_INVALID,
                            I::MISSION_TYPE,
                        ));
                        self.events
                            .push_back(TransferEvent::DownloadFailed { reason });
                        return;
                    }
                    self.transmit.push_back(mission_ack(
                        target,
                        MavMissionResult::MAV_MISSION_ACCEPTED,
                        I::MISSION_TYPE,
                    ));
                    self.events.push_back(TransferEvent::DownloadDone { items });
                } else {
                    let next = items.len() as u16;
                    self.send(now, mission_request(target, next, I::MISSION_TYPE), true);
                }
            }
            _ => {}
        }
    }

    /// Re-sends, or gives up, when the deadline passed.
    pub fn handle_timeout(&mut self, now: Duration) {
        let Some(state) = self.state.as_mut() else {
            return;
        };
        if state.deadline > now {
            return;
        }
        if state.attempts > self.config.retries {
            let reason = format!("no answer after {} attempts", state.attempts);
            let upload = matches!(state.op, ClientOp::Upload { .. });
            self.state = None;
            tracing::warn!(%reason, upload, "plan transfer failed");
            self.events.push_back(if upload {
                TransferEvent::UploadFailed {
                    result: None,
                    reason,
                }
            } else {
                TransferEvent::DownloadFailed { reason }
            });
            return;
        }
        state.attempts += 1;
        state.deadline = now + self.config.timeout;
        self.transmit.push_back(state.last_sent.clone());
    }

    /// Deadline of the running transfer.
    pub fn poll_timeout(&self) -> Option<Duration> {
        self.state.as_ref().map(|s| s.deadline)
    }

    /// Next message to send.
    pub fn poll_transmit(&mut self) -> Option<MavMessage> {
        self.transmit.pop_front()
    }

    /// Next outcome.
    pub fn poll_event(&mut self) -> Option<TransferEvent<I>> {
        self.events.pop_front()
    }
}
