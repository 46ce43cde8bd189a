//! Vehicle side of a list transfer: [`MissionServer`] receives an upload item by item
//! (re-requesting the awaited one after a quiet timeout, refusing what it cannot fly), hands
//! the application each new list, and serves downloads of the list it holds. One server per
//! mission type: [`PlanServer`] for the guidance plan, [`FenceServer`](super::FenceServer)
//! for the keep-out fence.

use std::collections::VecDeque;
use std::time::Duration;

use mavlink::dialects::common as mc;
use mavlink::dialects::common::{MavMessage, MavMissionResult};
use serde::{Deserialize, Serialize};

use super::item::PlanItem;
use super::mission::{
    MAX_PLAN_ITEMS, MissionItem, PlanConfig, mission_ack, mission_count, mission_request,
};

#[derive(Debug)]
struct Receiving<I> {
    from: (u8, u8),
    count: u16,
    items: Vec<I>,
    attempts: u8,
    deadline: Duration,
}

/// Counters of the vehicle side.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct PlanServerStats {
    /// Uploads completed.
    pub uploads: u64,
    /// Uploads abandoned (station silent) or refused.
    pub uploads_failed: u64,
    /// Downloads served (MISSION_REQUEST_LIST answered).
    pub downloads: u64,
}

/// Vehicle side of the guidance plan's transfer.
pub type PlanServer = MissionServer<PlanItem>;

/// Vehicle side of the transfer of one mission type's list (sans-io).
#[derive(Debug)]
pub struct MissionServer<I: MissionItem> {
    /// Our system id.
    pub system_id: u8,
    /// Our component id.
    pub component_id: u8,
    /// Timing.
    pub config: PlanConfig,
    plan: Vec<I>,
    receiving: Option<Receiving<I>>,
    /// Sender and size of the last completed upload, to re-ACK a re-sent last item.
    last_upload: Option<((u8, u8), u16)>,
    transmit: VecDeque<MavMessage>,
    received: VecDeque<Vec<I>>,
    stats: PlanServerStats,
}

impl<I: MissionItem> MissionServer<I> {
    /// A server holding an empty list.
    pub fn new(system_id: u8, component_id: u8, config: PlanConfig) -> Self {
        Self {
            system_id,
            component_id,
            config,
            plan: Vec::new(),
            receiving: None,
            last_upload: None,
            transmit: VecDeque::new(),
            received: VecDeque::new(),
            stats: PlanServerStats::default(),
        }
    }

    /// The list held now.
    pub fn plan(&self) -> &[I] {
        &self.plan
    }

    /// Replaces the plan (e.g. loaded onboard); served to later downloads.
    pub fn set_plan(&mut self, plan: Vec<I>) {
        self.plan = plan;
    }

    /// Counters.
    pub fn stats(&self) -> PlanServerStats {
        self.stats
    }

    fn for_us(&self, ts: u8, tc: u8) -> bool {
        (ts == 0 || ts == self.system_id) && (tc == 0 || tc == self.component_id)
    }

    /// Feeds a received message from `from`. Returns whether it belonged to the protocol.
    // The deprecated MISSION_REQUEST is still sent by older stations; it is answered with
    // MISSION_ITEM_INT, as MAVLink asks.
    #[allow(deprecated)]
    pub fn handle_message(&mut self, now: Duration, from: (u8, u8), msg: &MavMessage) -> bool {
        match msg {
            MavMessage::MISSION_COUNT(c)
                if self.for_us(c.target_system, c.target_component)
                    && c.mission_type == I::MISSION_TYPE =>
            {
                if self
                    .receiving
                    .as_ref()
                    .is_some_and(|r| r.from == from && r.count == c.count && r.items.is_empty())
                {
                    // Re-sent COUNT: our request for item 0 was lost.
                    self.transmit
                        .push_back(mission_request(from, 0, I::MISSION_TYPE));
                    return true;
                }
                if c.count > MAX_PLAN_ITEMS {
                    self.transmit.push_back(mission_ack(
                        from,
                        MavMissionResult::MAV_MISSION_NO_SPACE,
                        I::MISSION_TYPE,
                    ));
                    self.stats.uploads_failed += 1;
                    return true;
                }
                if c.count == 0 {
                    self.finish_upload(from, Vec::new());
                    return true;
                }
                self.receiving = Some(Receiving {
                    from,
                    count: c.count,
                    items: Vec::new(),
                    attempts: 1,
                    deadline: now + self.config.timeout,
                });
                self.transmit
                    .push_back(mission_request(from, 0, I::MISSION_TYPE));
                true
            }
            MavMessage::MISSION_ITEM_INT(m)
                if self.for_us(m.target_system, m.target_component)
                    && m.mission_type == I::MISSION_TYPE =>
            {
                let Some(rx) = self.receiving.as_mut().filter(|r| r.from == from) else {
                    // The last item again after we finished: our ACK was lost.
                    if self
                        .last_upload
                        .is_some_and(|(f, n)| f == from && m.seq.checked_add(1) == Some(n))
                    {
                        self.transmit.push_back(mission_ack(
                            from,
                            MavMissionResult::MAV_MISSION_ACCEPTED,
                            I::MISSION_TYPE,
                        ));
                    }
                    return true;
                };
                let expected = rx.items.len() as u16;
                if m.seq != expected {
                    self.transmit
                        .push_back(mission_request(from, expected, I::MISSION_TYPE));
                    return true;
                }
                match I::from_mavlink(m) {
                    Ok(item) => rx.items.push(item),
                    Err(e) => {
                        tracing::warn!(error = %e, seq = m.seq, mission_type = ?I::MISSION_TYPE, "mission item refused");
                        self.receiving = None;
                        self.stats.uploads_failed += 1;
                        self.transmit
                            .push_back(mission_ack(from, I::refusal(&e), I::MISSION_TYPE));
                        return true;
                    }
                }
                rx.attempts = 1;
                rx.deadline = now + self.config.timeout;
                if rx.items.len() >= usize::from(rx.count) {
                    let items = std::mem::take(&mut rx.items);
                    self.receiving = None;
                    self.finish_upload(from, items);
                } else {
                    let next = rx.items.len() as u16;
                    self.transmit
                        .push_back(mission_request(from, next, I::MISSION_TYPE));
                }
                true
            }
            MavMessage::MISSION_REQUEST_LIST(r)
                if self.for_us(r.target_system, r.target_component)
                    && r.mission_type == I::MISSION_TYPE =>
            {
                self.stats.downloads += 1;
                self.transmit.push_back(mission_count(
                    from,
                    self.plan.len() as u16,
                    I::MISSION_TYPE,
                ));
                true
            }
            MavMessage::MISSION_REQUEST_INT(mc::MISSION_REQUEST_INT_DATA {
                seq,
                target_system,
                target_component,
                mission_type,
            })
            | MavMessage::MISSION_REQUEST(mc::MISSION_REQUEST_DATA {
                seq,
                target_system,
                target_component,
                mission_type,
            }) if self.for_us(*target_system, *target_component)
                && *mission_type == I::MISSION_TYPE =>
            {
                match self.plan.get(usize::from(*seq)) {
                    Some(item) => self.transmit.push_back(item.to_mavlink(from, *seq)),
                    None => self.transmit.push_back(mission_ack(
                        from,
                        MavMissionResult::MAV_MISSION_INVALID_SEQUENCE,
                        I::MISSION_TYPE,
                    )),
                }
                true
            }
            MavMessage::MISSION_ACK(a)
                if self.for_us(a.target_system, a.target_component)
                    && a.mission_type == I::MISSION_TYPE =>
            {
                true
            }
            _ => false,
        }
    }

    fn finish_upload(&mut self, from: (u8, u8), items: Vec<I>) {
        if let Err(reason) = I::check_list(&items) {
            tracing::warn!(%reason, mission_type = ?I::MISSION_TYPE, "upload refused");
            self.stats.uploads_failed += 1;
            self.transmit.push_back(mission_ack(
                from,
                MavMissionResult::MAV_MISSION_INVALID,
                I::MISSION_TYPE,
            ));
            return;
        }
        self.last_upload = Some((from, items.len() as u16));
        self.plan = items.clone();
        self.stats.uploads += 1;
        self.transmit.push_back(mission_ack(
            from,
            MavMissionResult::MAV_MISSION_ACCEPTED,
            I::MISSION_TYPE,
        ));
        self.received.push_back(items);
    }

    /// Re-requests the awaited item, or abandons the upload, when the deadline passed.
    pub fn handle_timeout(&mut self, now: Duration) {
        let Some(rx) = self.receiving.as_mut().filter(|r| r.deadline <= now) else {
            return;
        };
        if rx.attempts > self.config.retries {
            tracing::warn!(
                received = rx.items.len(),
                count = rx.count,
                "plan upload abandoned: station silent"
            );
            let from = rx.from;
            self.receiving = None;
            self.stats.uploads_failed += 1;
            self.transmit.push_back(mission_ack(
                from,
                MavMissionResult::MAV_MISSION_OPERATION_CANCELLED,
                I::MISSION_TYPE,
            ));
            return;
        }
        rx.attempts += 1;
        rx.deadline = now + self.config.timeout;
        let (from, next) = (rx.from, rx.items.len() as u16);
        self.transmit
            .push_back(mission_request(from, next, I::MISSION_TYPE));
    }

    /// Deadline of a running upload.
    pub fn poll_timeout(&self) -> Option<Duration> {
        self.receiving.as_ref().map(|r| r.deadline)
    }

    /// A newly received list, for the application.
    pub fn poll_plan(&mut self) -> Option<Vec<I>> {
        self.received.pop_front()
    }

    /// Next message to send.
    pub fn poll_transmit(&mut self) -> Option<MavMessage> {
        self.transmit.pop_front()
    }
}
