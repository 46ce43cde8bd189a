//! Upload and download of the guidance plan (landing target and localizer points) with the
//! MAVLink mission protocol, so the station can send the plan the drone flies and read back
//! what it actually holds.
//!
//! Upload: station MISSION_COUNT → drone MISSION_REQUEST_INT(seq) → station
//! MISSION_ITEM_INT(seq) … → drone MISSION_ACK. Download: station MISSION_REQUEST_LIST →
//! drone MISSION_COUNT → station MISSION_REQUEST_INT(seq) → drone MISSION_ITEM_INT(seq) … →
//! station MISSION_ACK. Both sides re-send their last message after a quiet timeout and give up
//! after a number of retries; progress resets the retry count.
//!
//! Items: [`PlanItem::Waypoint`] ↔ `MAV_CMD_NAV_WAYPOINT`, [`PlanItem::Land`] ↔
//! `MAV_CMD_NAV_LAND` (param4 = approach heading in degrees, NaN = into the wind), both in
//! `MAV_FRAME_GLOBAL` (altitude MSL), latitude/longitude in degE7.

use std::collections::VecDeque;
use std::time::Duration;

use mavlink::dialects::common as mc;
use mavlink::dialects::common::{MavCmd, MavMessage, MavMissionResult};
use serde::{Deserialize, Serialize};

/// Largest plan accepted, items.
pub const MAX_PLAN_ITEMS: u16 = 512;

/// One element of the guidance plan.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PlanItem {
    /// A localizer point.
    Waypoint {
        lat_deg: f64,
        lon_deg: f64,
        alt_msl_m: f64,
    },
    /// The landing target; `approach_heading_deg: None` lands into the wind.
    Land {
        lat_deg: f64,
        lon_deg: f64,
        alt_msl_m: f64,
        approach_heading_deg: Option<f64>,
    },
}

impl PlanItem {
    /// The item in the mission's local frame, for [`stx_gnc::plan_upload::apply`] (the one
    /// mapping the drone and the station's replica share).
    pub fn to_local(&self, frame: &stx_gnc::geo::LocalFrame) -> stx_gnc::plan_upload::PlanPoint {
        use stx_gnc::plan_upload::PlanPoint;
        match *self {
            Self::Waypoint {
                lat_deg,
                lon_deg,
                alt_msl_m,
            } => PlanPoint::Waypoint {
                position_ned_m: frame.to_ned(lat_deg, lon_deg, alt_msl_m),
            },
            Self::Land {
                lat_deg,
                lon_deg,
                alt_msl_m,
                approach_heading_deg,
            } => PlanPoint::Land {
                position_ned_m: frame.to_ned(lat_deg, lon_deg, alt_msl_m),
                approach_course_rad: approach_heading_deg.map(f64::to_radians),
            },
        }
    }
}

/// Why a MISSION_ITEM_INT is not a [`PlanItem`], as the MISSION_ACK result to answer with.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum PlanItemError {
    /// Not a waypoint or land command.
    #[error("unsupported mission command {command:?}")]
    Unsupported { command: MavCmd },
    /// Not `MAV_FRAME_GLOBAL`.
    #[error("unsupported frame {frame:?}")]
    UnsupportedFrame { frame: mc::MavFrame },
    /// Latitude, longitude, altitude or heading out of range.
    #[error("invalid value in parameter {param}")]
    Invalid { param: u8 },
}

impl PlanItemError {
    fn result(self) -> MavMissionResult {
        match self {
            Self::Unsupported { .. } => MavMissionResult::MAV_MISSION_UNSUPPORTED,
            Self::UnsupportedFrame { .. } => MavMissionResult::MAV_MISSION_UNSUPPORTED_FRAME,
            Self::Invalid { param: 4 } => MavMissionResult::MAV_MISSION_INVALID_PARAM4,
            Self::Invalid { param: 5 } => MavMissionResult::MAV_MISSION_INVALID_PARAM5_X,
            Self::Invalid { param: 6 } => MavMissionResult::MAV_MISSION_INVALID_PARAM6_Y,
            Self::Invalid { param: 7 } => MavMissionResult::MAV_MISSION_INVALID_PARAM7,
            Self::Invalid { .. } => MavMissionResult::MAV_MISSION_INVALID,
        }
    }
}

impl PlanItem {
    /// The MISSION_ITEM_INT carrying this item at `seq`.
    pub fn to_mavlink(&self, target: (u8, u8), seq: u16) -> MavMessage {
        let (command, lat, lon, alt, p4) = match *self {
            Self::Waypoint {
                lat_deg,
                lon_deg,
                alt_msl_m,
            } => (
                MavCmd::MAV_CMD_NAV_WAYPOINT,
                lat_deg,
                lon_deg,
                alt_msl_m,
                0.0,
            ),
            Self::Land {
                lat_deg,
                lon_deg,
                alt_msl_m,
                approach_heading_deg,
            } => (
                MavCmd::MAV_CMD_NAV_LAND,
                lat_deg,
                lon_deg,
                alt_msl_m,
                approach_heading_deg.map_or(f32::NAN, |h| h as f32),
            ),
        };
        MavMessage::MISSION_ITEM_INT(mc::MISSION_ITEM_INT_DATA {
            param1: 0.0,
            param2: 0.0,
            param3: 0.0,
            param4: p4,
            x: (lat * 1e7).round() as i32,
            y: (lon * 1e7).round() as i32,
            z: alt as f32,
            seq,
            command,
            target_system: target.0,
            target_component: target.1,
            frame: mc::MavFrame::MAV_FRAME_GLOBAL,
            current: u8::from(seq == 0),
            autocontinue: 1,
            mission_type: mc::MavMissionType::MAV_MISSION_TYPE_MISSION,
        })
    }

    /// The item a MISSION_ITEM_INT carries.
    pub fn from_mavlink(m: &mc::MISSION_ITEM_INT_DATA) -> Result<PlanItem, PlanItemError> {
        #[allow(deprecated)] // MAV_FRAME_GLOBAL_INT: deprecated synonym older senders use.
        let frame_ok = m.frame == mc::MavFrame::MAV_FRAME_GLOBAL
            || m.frame == mc::MavFrame::MAV_FRAME_GLOBAL_INT;
        if !matches!(
            m.command,
            MavCmd::MAV_CMD_NAV_WAYPOINT | MavCmd::MAV_CMD_NAV_LAND
        ) {
            return Err(PlanItemError::Unsupported { command: m.command });
        }
        if !frame_ok {
            return Err(PlanItemError::UnsupportedFrame { frame: m.frame });
        }
        let (lat_deg, lon_deg) = (f64::from(m.x) / 1e7, f64::from(m.y) / 1e7);
        if !(-90.0..=90.0).contains(&lat_deg) {
            return Err(PlanItemError::Invalid { param: 5 });
        }
        if !(-180.0..=180.0).contains(&lon_deg) {
            return Err(PlanItemError::Invalid { param: 6 });
        }
        if !m.z.is_finite() {
            return Err(PlanItemError::Invalid { param: 7 });
        }
        let alt_msl_m = f64::from(m.z);
        Ok(match m.command {
            MavCmd::MAV_CMD_NAV_LAND => {
                let approach_heading_deg = if m.param4.is_nan() {
                    None
                } else if m.param4.is_finite() && (-360.0..=360.0).contains(&m.param4) {
                    Some(f64::from(m.param4).rem_euclid(360.0))
                } else {
                    return Err(PlanItemError::Invalid { param: 4 });
                };
                PlanItem::Land {
                    lat_deg,
                    lon_deg,
                    alt_msl_m,
                    approach_heading_deg,
                }
            }
            _ => PlanItem::Waypoint {
                lat_deg,
                lon_deg,
                alt_msl_m,
            },
        })
    }
}

/// Timing of either side.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PlanConfig {
    /// Quiet time before re-sending.
    pub timeout: Duration,
    /// Re-sends without progress before giving up.
    pub retries: u8,
}

impl Default for PlanConfig {
    fn default() -> Self {
        Self {
            timeout: Duration::from_millis(1500),
            retries: 4,
        }
    }
}

/// Outcome of a plan transfer on the ground side.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PlanEvent {
    /// The vehicle acknowledged the whole plan.
    UploadDone { items: usize },
    /// The vehicle refused the plan (`result` is the MAV_MISSION_RESULT code) or stopped
    /// answering (`result: None`).
    UploadFailed { result: Option<u8>, reason: String },
    /// The plan the vehicle holds.
    DownloadDone { items: Vec<PlanItem> },
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
enum ClientOp {
    Upload {
        items: Vec<PlanItem>,
        acked_through: Option<u16>,
    },
    Download {
        count: Option<u16>,
        items: Vec<PlanItem>,
    },
}

#[derive(Debug)]
struct ClientState {
    target: (u8, u8),
    op: ClientOp,
    last_sent: MavMessage,
    attempts: u8,
    deadline: Duration,
}

/// Ground side of the plan transfer (sans-io).
#[derive(Debug, Default)]
pub struct PlanClient {
    /// Timing.
    pub config: PlanConfig,
    state: Option<ClientState>,
    transmit: VecDeque<MavMessage>,
    events: VecDeque<PlanEvent>,
}

fn mission_ack(target: (u8, u8), result: MavMissionResult) -> MavMessage {
    MavMessage::MISSION_ACK(mc::MISSION_ACK_DATA {
        target_system: target.0,
        target_component: target.1,
        mavtype: result,
        mission_type: mc::MavMissionType::MAV_MISSION_TYPE_MISSION,
        opaque_id: 0,
    })
}

fn mission_request(target: (u8, u8), seq: u16) -> MavMessage {
    MavMessage::MISSION_REQUEST_INT(mc::MISSION_REQUEST_INT_DATA {
        seq,
        target_system: target.0,
        target_component: target.1,
        mission_type: mc::MavMissionType::MAV_MISSION_TYPE_MISSION,
    })
}

fn mission_count(target: (u8, u8), count: u16) -> MavMessage {
    MavMessage::MISSION_COUNT(mc::MISSION_COUNT_DATA {
        count,
        target_system: target.0,
        target_component: target.1,
        mission_type: mc::MavMissionType::MAV_MISSION_TYPE_MISSION,
        opaque_id: 0,
    })
}

fn is_mission(t: mc::MavMissionType) -> bool {
    t == mc::MavMissionType::MAV_MISSION_TYPE_MISSION
}

impl PlanClient {
    /// A client with the given timing.
    pub fn new(config: PlanConfig) -> Self {
        Self {
            config,
            ..Default::default()
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
        items: Vec<PlanItem>,
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
        let msg = mission_count(target, count);
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
            mission_type: mc::MavMissionType::MAV_MISSION_TYPE_MISSION,
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
                if !is_mission(*mission_type) {
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
                if is_mission(a.mission_type) =>
            {
                let n = items.len();
                self.state = None;
                self.events
                    .push_back(if a.mavtype == MavMissionResult::MAV_MISSION_ACCEPTED {
                        PlanEvent::UploadDone { items: n }
                    } else {
                        PlanEvent::UploadFailed {
                            result: Some(a.mavtype as u8),
                            reason: format!("vehicle answered {:?}", a.mavtype),
                        }
                    });
            }
            (ClientOp::Download { count, items }, MavMessage::MISSION_COUNT(c))
                if is_mission(c.mission_type) =>
            {
                if count.is_some() {
                    return; // a duplicate COUNT; our request for the next item is out already
                }
                if c.count > MAX_PLAN_ITEMS {
                    self.state = None;
                    self.events.push_back(PlanEvent::DownloadFailed {
                        reason: format!("plan of {} items exceeds {MAX_PLAN_ITEMS}", c.count),
                    });
                    return;
                }
                *count = Some(c.count);
                if c.count == 0 {
                    self.state = None;
                    self.transmit
                        .push_back(mission_ack(target, MavMissionResult::MAV_MISSION_ACCEPTED));
                    self.events
                        .push_back(PlanEvent::DownloadDone { items: Vec::new() });
                    return;
                }
                items.clear();
                self.send(now, mission_request(target, 0), true);
            }
            (
                ClientOp::Download {
                    count: Some(count),
                    items,
                },
                MavMessage::MISSION_ITEM_INT(m),
            ) if is_mission(m.mission_type) => {
                if usize::from(m.seq) != items.len() {
                    return; // late duplicate; the current request is re-sent on timeout
                }
                match PlanItem::from_mavlink(m) {
                    Ok(item) => items.push(item),
                    Err(e) => {
                        self.state = None;
                        self.transmit.push_back(mission_ack(target, e.result()));
                        self.events.push_back(PlanEvent::DownloadFailed {
                            reason: format!("item {}: {e}", m.seq),
                        });
                        return;
                    }
                }
                let count = *count;
                if items.len() >= usize::from(count) {
                    let items = std::mem::take(items);
                    self.state = None;
                    self.transmit
                        .push_back(mission_ack(target, MavMissionResult::MAV_MISSION_ACCEPTED));
                    self.events.push_back(PlanEvent::DownloadDone { items });
                } else {
                    let next = items.len() as u16;
                    self.send(now, mission_request(target, next), true);
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
                PlanEvent::UploadFailed {
                    result: None,
                    reason,
                }
            } else {
                PlanEvent::DownloadFailed { reason }
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
    pub fn poll_event(&mut self) -> Option<PlanEvent> {
        self.events.pop_front()
    }
}

#[derive(Debug)]
struct Receiving {
    from: (u8, u8),
    count: u16,
    items: Vec<PlanItem>,
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

/// Vehicle side of the plan transfer (sans-io).
#[derive(Debug)]
pub struct PlanServer {
    /// Our system id.
    pub system_id: u8,
    /// Our component id.
    pub component_id: u8,
    /// Timing.
    pub config: PlanConfig,
    plan: Vec<PlanItem>,
    receiving: Option<Receiving>,
    /// Sender and size of the last completed upload, to re-ACK a re-sent last item.
    last_upload: Option<((u8, u8), u16)>,
    transmit: VecDeque<MavMessage>,
    received: VecDeque<Vec<PlanItem>>,
    stats: PlanServerStats,
}

impl PlanServer {
    /// A server holding an empty plan.
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

    /// The plan held now.
    pub fn plan(&self) -> &[PlanItem] {
        &self.plan
    }

    /// Replaces the plan (e.g. loaded onboard); served to later downloads.
    pub fn set_plan(&mut self, plan: Vec<PlanItem>) {
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
                    && is_mission(c.mission_type) =>
            {
                if self
                    .receiving
                    .as_ref()
                    .is_some_and(|r| r.from == from && r.count == c.count && r.items.is_empty())
                {
                    // Re-sent COUNT: our request for item 0 was lost.
                    self.transmit.push_back(mission_request(from, 0));
                    return true;
                }
                if c.count > MAX_PLAN_ITEMS {
                    self.transmit
                        .push_back(mission_ack(from, MavMissionResult::MAV_MISSION_NO_SPACE));
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
                self.transmit.push_back(mission_request(from, 0));
                true
            }
            MavMessage::MISSION_ITEM_INT(m)
                if self.for_us(m.target_system, m.target_component)
                    && is_mission(m.mission_type) =>
            {
                let Some(rx) = self.receiving.as_mut().filter(|r| r.from == from) else {
                    // The last item again after we finished: our ACK was lost.
                    if self
                        .last_upload
                        .is_some_and(|(f, n)| f == from && m.seq.checked_add(1) == Some(n))
                    {
                        self.transmit
                            .push_back(mission_ack(from, MavMissionResult::MAV_MISSION_ACCEPTED));
                    }
                    return true;
                };
                let expected = rx.items.len() as u16;
                if m.seq != expected {
                    self.transmit.push_back(mission_request(from, expected));
                    return true;
                }
                match PlanItem::from_mavlink(m) {
                    Ok(item) => rx.items.push(item),
                    Err(e) => {
                        tracing::warn!(error = %e, seq = m.seq, "plan item refused");
                        self.receiving = None;
                        self.stats.uploads_failed += 1;
                        self.transmit.push_back(mission_ack(from, e.result()));
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
                    self.transmit.push_back(mission_request(from, next));
                }
                true
            }
            MavMessage::MISSION_REQUEST_LIST(r)
                if self.for_us(r.target_system, r.target_component)
                    && is_mission(r.mission_type) =>
            {
                self.stats.downloads += 1;
                self.transmit
                    .push_back(mission_count(from, self.plan.len() as u16));
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
            }) if self.for_us(*target_system, *target_component) && is_mission(*mission_type) => {
                match self.plan.get(usize::from(*seq)) {
                    Some(item) => self.transmit.push_back(item.to_mavlink(from, *seq)),
                    None => self.transmit.push_back(mission_ack(
                        from,
                        MavMissionResult::MAV_MISSION_INVALID_SEQUENCE,
                    )),
                }
                true
            }
            MavMessage::MISSION_ACK(a) if self.for_us(a.target_system, a.target_component) => true,
            _ => false,
        }
    }

    fn finish_upload(&mut self, from: (u8, u8), items: Vec<PlanItem>) {
        self.last_upload = Some((from, items.len() as u16));
        self.plan = items.clone();
        self.stats.uploads += 1;
        self.transmit
            .push_back(mission_ack(from, MavMissionResult::MAV_MISSION_ACCEPTED));
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
            ));
            return;
        }
        rx.attempts += 1;
        rx.deadline = now + self.config.timeout;
        let (from, next) = (rx.from, rx.items.len() as u16);
        self.transmit.push_back(mission_request(from, next));
    }

    /// Deadline of a running upload.
    pub fn poll_timeout(&self) -> Option<Duration> {
        self.receiving.as_ref().map(|r| r.deadline)
    }

    /// A newly received plan, for the application.
    pub fn poll_plan(&mut self) -> Option<Vec<PlanItem>> {
        self.received.pop_front()
    }

    /// Next message to send.
    pub fn poll_transmit(&mut self) -> Option<MavMessage> {
        self.transmit.pop_front()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan() -> Vec<PlanItem> {
        vec![
            PlanItem::Waypoint {
                lat_deg: 41.1,
                lon_deg: -8.6,
                alt_msl_m: 300.0,
            },
            PlanItem::Waypoint {
                lat_deg: 41.2,
                lon_deg: -8.5,
                alt_msl_m: 200.0,
            },
            PlanItem::Land {
                lat_deg: 41.15,
                lon_deg: -8.55,
                alt_msl_m: 90.0,
                approach_heading_deg: Some(270.0),
            },
        ]
    }

    fn pump(cl: &mut PlanClient, srv: &mut PlanServer) {
        loop {
            let mut moved = false;
            while let Some(m) = cl.poll_transmit() {
                srv.handle_message(Duration::ZERO, (255, 190), &m);
                moved = true;
            }
            while let Some(m) = srv.poll_transmit() {
                cl.handle_message(Duration::ZERO, 1, &m);
                moved = true;
            }
            if !moved {
                break;
            }
        }
    }

    #[test]
    fn upload_then_download_returns_the_plan() {
        let mut cl = PlanClient::default();
        let mut srv = PlanServer::new(1, 1, PlanConfig::default());
        cl.upload(Duration::ZERO, (1, 1), plan()).expect("started");
        pump(&mut cl, &mut srv);
        assert_eq!(cl.poll_event(), Some(PlanEvent::UploadDone { items: 3 }));
        assert_eq!(srv.poll_plan().map(|p| p.len()), Some(3));
        cl.download(Duration::ZERO, (1, 1)).expect("started");
        pump(&mut cl, &mut srv);
        let Some(PlanEvent::DownloadDone { items }) = cl.poll_event() else {
            panic!("no download")
        };
        assert_eq!(items.len(), 3);
        for (a, b) in items.iter().zip(plan()) {
            let (PlanItem::Waypoint { lat_deg: x, .. } | PlanItem::Land { lat_deg: x, .. }) = *a;
            let (PlanItem::Waypoint { lat_deg: y, .. } | PlanItem::Land { lat_deg: y, .. }) = b;
            assert!((x - y).abs() < 1e-7);
        }
        assert!(
            matches!(items[2], PlanItem::Land { approach_heading_deg: Some(h), .. } if h == 270.0)
        );
    }

    #[test]
    fn unsupported_item_is_refused() {
        let mut srv = PlanServer::new(1, 1, PlanConfig::default());
        srv.handle_message(Duration::ZERO, (255, 190), &mission_count((1, 1), 1));
        let _ = srv.poll_transmit();
        let MavMessage::MISSION_ITEM_INT(mut m) = plan()[0].to_mavlink((1, 1), 0) else {
            panic!()
        };
        m.command = MavCmd::MAV_CMD_NAV_TAKEOFF;
        srv.handle_message(Duration::ZERO, (255, 190), &MavMessage::MISSION_ITEM_INT(m));
        let Some(MavMessage::MISSION_ACK(a)) = srv.poll_transmit() else {
            panic!("no ack")
        };
        assert_eq!(a.mavtype, MavMissionResult::MAV_MISSION_UNSUPPORTED);
        assert_eq!(srv.stats().uploads_failed, 1);
    }
}
