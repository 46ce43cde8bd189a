//! What the core asks of the drone link, and how each ask is followed until its outcome.
//!
//! Every [`LinkAction`] carries an [`ActionId`] and a deadline on the mission clock. The link
//! driver applies it to the ground endpoint ([`crate::link::StationLink`]), or refuses it
//! once its deadline has passed, and the outcome comes back to the core under the same id
//! ([`super::StationCore::on_action_outcome`]). The [`Outbox`] remembers every action until
//! then; one whose outcome has not come [`OUTCOME_GRACE_S`] after its deadline is settled by
//! the core itself as [`ActionError::Expired`], so nothing waits forever on an outcome that
//! never came.

use std::collections::{BTreeMap, VecDeque};

use stx_link::command::{Command, RequestId};
use stx_link::manual::Sticks;
use stx_link::plan::PlanItem;

/// Seconds the link driver has to apply an action before it must not any more.
pub const APPLY_WITHIN_S: f64 = 5.0;
/// Seconds past an action's deadline its outcome may still arrive (it travels through the
/// driver's event queue) before the core settles it as expired.
pub const OUTCOME_GRACE_S: f64 = 2.0;
/// Expired actions remembered, so that an outcome arriving after all is still recognised.
const EXPIRED_KEPT: usize = 256;

/// Names one link action; its outcome comes back under it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ActionId(pub u64);

/// What the link driver does on the ground endpoint.
#[derive(Debug, Clone, PartialEq)]
pub enum LinkOp {
    /// Send a command (retried by the link until acknowledged).
    Command {
        request_id: RequestId,
        command: Command,
    },
    /// Set a parameter (retried until echoed).
    ParamSet { name: String, value: f32 },
    /// Upload a plan.
    PlanUpload(Vec<PlanItem>),
    /// Read the plan the drone holds (the station's own initiative).
    PlanDownload,
    /// Read the drone's parameter table (whenever the drone (re)appears).
    ParamList,
    /// Hold the sticks (MANUAL_CONTROL streamed until released).
    ManualHold(Sticks),
    /// Stop the sticks.
    ManualRelease,
    /// Send the keep-out zones as the drone's fence (the station's own initiative).
    FenceUpload(Vec<stx_link::plan::FenceItem>),
}

/// A [`LinkOp`] for the link driver, with the id its outcome comes back under and the
/// mission time after which it must not be applied any more (the core will have told the
/// operator it was not sent).
#[derive(Debug, Clone, PartialEq)]
pub struct LinkAction {
    /// Its id.
    pub id: ActionId,
    /// What to do.
    pub op: LinkOp,
    /// Apply it no later than this, mission time, s.
    pub deadline_s: f64,
}

/// Why the link did not take an action.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ActionError {
    /// Another transfer of the same kind is running (a plan transfer, the same command or
    /// parameter): it might be taken later.
    #[error("{0}")]
    Busy(String),
    /// The link cannot take it.
    #[error("{0}")]
    Refused(String),
    /// Its deadline passed before the link driver got to it, or its outcome never came: not
    /// sent.
    #[error("not sent: the link did not take it in time")]
    Expired,
}

/// What the core does with an action's outcome.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Purpose {
    /// An operator's request (its id).
    Request(u64),
    /// The station's own read of the drone's plan.
    PlanDownload,
    /// The station's own read of the parameter table.
    ParamList,
    /// Sticks.
    Manual,
    /// The station's own transfer of the keep-out fence.
    FenceUpload,
    /// The station's own uplink of the surface wind.
    SurfaceWind,
}

#[derive(Debug)]
struct Pending {
    purpose: Purpose,
    deadline_s: f64,
}

/// Actions waiting for the link driver, and those it has not reported on yet.
#[derive(Debug, Default)]
pub(crate) struct Outbox {
    next: u64,
    queued: Vec<LinkAction>,
    pending: BTreeMap<ActionId, Pending>,
    /// Settled as expired, newest last.
    expired: VecDeque<(ActionId, Purpose)>,
}

impl Outbox {
    /// Queues `op` for the driver, to be applied within `within_s`.
    pub fn issue(&mut self, now_s: f64, op: LinkOp, purpose: Purpose, within_s: f64) -> ActionId {
        self.next += 1;
        let id = ActionId(self.next);
        let deadline_s = now_s + within_s;
        self.queued.push(LinkAction { id, op, deadline_s });
        self.pending.insert(
            id,
            Pending {
                purpose,
                deadline_s,
            },
        );
        id
    }

    /// The actions queued since the last call, oldest first.
    pub fn take(&mut self) -> Vec<LinkAction> {
        std::mem::take(&mut self.queued)
    }

    /// The action `id` has its outcome: what it was for, and whether the core had settled it
    /// as expired already (`None`: unknown).
    pub fn settle(&mut self, id: ActionId) -> Option<(Purpose, bool)> {
        if let Some(p) = self.pending.remove(&id) {
            return Some((p.purpose, false));
        }
        let at = self.expired.iter().position(|(e, _)| *e == id)?;
        self.expired.remove(at).map(|(_, purpose)| (purpose, true))
    }

    /// Removes the actions whose outcome is overdue at `now_s` (queued ones too: they are
    /// never handed out), with the error they settle with.
    pub fn overdue(&mut self, now_s: f64) -> Vec<(ActionId, Purpose, ActionError)> {
        let late: Vec<ActionId> = self
            .pending
            .iter()
            .filter(|(_, p)| now_s > p.deadline_s + OUTCOME_GRACE_S)
            .map(|(id, _)| *id)
            .collect();
        self.queued.retain(|a| !late.contains(&a.id));
        late.into_iter()
            .filter_map(|id| {
                let p = self.pending.remove(&id)?;
                if self.expired.len() >= EXPIRED_KEPT {
                    self.expired.pop_front();
                }
                self.expired.push_back((id, p.purpose.clone()));
                Some((id, p.purpose, ActionError::Expired))
            })
            .collect()
    }

    /// Actions handed out or queued whose outcome has not come.
    #[cfg(test)]
    pub fn unsettled(&self) -> usize {
        self.pending.len()
    }
}
