//! Each operator's request through its whole life, on the mission clock:
//!
//! 1. opened: recorded `in_progress`, its link action queued in the [`Outbox`];
//! 2. the link driver reports the action applied (`sent`), refused (`failed`: e.g. the same
//!    command is still waiting for its answer) or not applied in time (`timed_out`). A plan
//!    upload that meets another plan transfer (the station's own read of the drone's plan) is
//!    offered again every [`UPLOAD_RETRY_S`], [`UPLOAD_TRIES`] times in all, then `failed`;
//! 3. the drone's answer (COMMAND_ACK, PARAM_VALUE, MISSION_ACK), or the link's own give-up
//!    after its retries, settles it; IN_PROGRESS acknowledgements keep it open;
//! 4. with no answer by its deadline, well past the link's own retries, it times out: nothing
//!    stays `in_progress` for ever because an answer was lost.
//!
//! Every step that settles a request yields its `command_result`; an answer from the drone
//! that comes after the station gave up still corrects it (the drone's word is the truth).

use std::collections::{BTreeMap, HashMap};

use stx_link::command::{CommandEvent, CommandOutcome, CommandResult, RequestId};
use stx_link::param::ParamEvent;
use stx_link::plan::PlanEvent;

use super::actions::{APPLY_WITHIN_S, ActionError, ActionId, LinkOp, Outbox, Purpose};
use super::requests::{Payload, PlanChange};
use crate::messages::{CommandResultMsg, Outcome};

/// Seconds an upload that met another plan transfer waits before it is offered again …
pub const UPLOAD_RETRY_S: f64 = 0.25;
/// … and how many times in all it is offered (a plan read is over within a few round trips).
pub const UPLOAD_TRIES: u32 = 40;
/// Seconds after sending by which the drone's answer to a command or a parameter write must
/// have come; an IN_PROGRESS acknowledgement starts it again. The link itself gives up after
/// 4 transmissions 1 s apart (`stx_link` defaults): this only catches an answer that was lost.
pub const ANSWER_WITHIN_S: f64 = 30.0;
/// For a plan upload, this much more per item: the link re-sends each item up to 5 times
/// 1.5 s apart before it gives up, and progress starts its count again.
pub const ANSWER_PER_PLAN_ITEM_S: f64 = 8.0;
/// A refusal's reason comes as a STATUSTEXT just before the COMMAND_ACK (which has no room for
/// text); a warning older than this belongs to something else.
pub const REASON_WITHIN_S: f64 = 2.0;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Stage {
    /// Its action is with the link driver.
    Sending(ActionId),
    /// The link took it; the drone's answer is due by `deadline_s`.
    Answering { deadline_s: f64 },
    /// The link was busy with another plan transfer: offered again at `at_s`.
    Retrying { at_s: f64 },
    /// Settled.
    Done,
}

#[derive(Debug, Clone)]
struct Record {
    result: CommandResultMsg,
    op: LinkOp,
    /// What the replica adopts once the drone accepts (taken then).
    change: Option<PlanChange>,
    stage: Stage,
    /// Times its action was handed to the link driver.
    tries: u32,
}

fn answer_within_s(op: &LinkOp) -> f64 {
    match op {
        LinkOp::PlanUpload(items) => ANSWER_WITHIN_S + ANSWER_PER_PLAN_ITEM_S * items.len() as f64,
        _ => ANSWER_WITHIN_S,
    }
}

/// `r12` → 12.
fn number(request_id: &str) -> Option<u64> {
    request_id.strip_prefix('r')?.parse().ok()
}

/// Every request, by number (its link request id too).
#[derive(Debug, Default)]
pub(crate) struct Commands {
    last: u64,
    records: BTreeMap<u64, Record>,
    /// Parameter writes the link took, by name.
    param_sets: HashMap<String, u64>,
    /// The plan upload the link took.
    plan_upload: Option<u64>,
    /// The drone's last warning (or worse) and when it came: the reason of the next refusal.
    last_warning: Option<(f64, String)>,
}

impl Commands {
    /// Records a request for `command` and queues its link action; its id.
    pub fn open(
        &mut self,
        now_s: f64,
        outbox: &mut Outbox,
        command: &'static str,
        payload: Payload,
        change: Option<PlanChange>,
    ) -> String {
        self.last += 1;
        let n = self.last;
        let op = match payload {
            Payload::Command(command) => LinkOp::Command {
                request_id: RequestId(n),
                command,
            },
            Payload::ParamSet { name, value } => LinkOp::ParamSet { name, value },
            Payload::Plan(items) => LinkOp::PlanUpload(items),
        };
        let action = outbox.issue(now_s, op.clone(), Purpose::Request(n), APPLY_WITHIN_S);
        let request_id = format!("r{n}");
        self.records.insert(
            n,
            Record {
                result: CommandResultMsg {
                    kind: "command_result",
                    request_id: request_id.clone(),
                    command: command.to_string(),
                    outcome: Outcome::InProgress,
                    attempts: 0,
                    detail: "queued for the link".into(),
                    value: None,
                },
                op,
                change,
                stage: Stage::Sending(action),
                tries: 1,
            },
        );
        request_id
    }

    /// The link driver applied request `n`'s `action`, or did not: its result if that
    /// settles it (or reopens one the station had given up on).
    pub fn on_applied(
        &mut self,
        now_s: f64,
        n: u64,
        action: ActionId,
        result: Result<(), ActionError>,
    ) -> Option<CommandResultMsg> {
        let r = self.records.get_mut(&n)?;
        let late = match r.stage {
            Stage::Sending(current) if current == action => false,
            // Settled as not sent, and the outcome came after all.
            Stage::Done => true,
            _ => {
                tracing::warn!(
                    ?action,
                    request = n,
                    "outcome of an action the request no longer waits for"
                );
                return None;
            }
        };
        match result {
            Ok(()) => {
                r.stage = Stage::Answering {
                    deadline_s: now_s + answer_within_s(&r.op),
                };
                match &r.op {
                    LinkOp::ParamSet { name, .. } => {
                        self.param_sets.insert(name.clone(), n);
                    }
                    LinkOp::PlanUpload(_) => self.plan_upload = Some(n),
                    _ => {}
                }
                if late {
                    // Reported not sent, and sent after all: say so, and wait for the answer.
                    r.result.outcome = Outcome::InProgress;
                    r.result.detail = "sent late, after it was reported not sent".into();
                    return Some(r.result.clone());
                }
                r.result.detail = "sent".into();
                None
            }
            // Settled already; this changes nothing.
            Err(_) if late => None,
            Err(ActionError::Busy(reason))
                if matches!(r.op, LinkOp::PlanUpload(_)) && r.tries < UPLOAD_TRIES =>
            {
                r.stage = Stage::Retrying {
                    at_s: now_s + UPLOAD_RETRY_S,
                };
                r.result.detail = format!("waiting: {reason}");
                None
            }
            Err(e) => {
                r.stage = Stage::Done;
                r.result.outcome = match e {
                    ActionError::Expired => Outcome::TimedOut,
                    ActionError::Busy(_) | ActionError::Refused(_) => Outcome::Failed,
                };
                r.result.detail = match e {
                    ActionError::Busy(reason) if r.tries > 1 => {
                        format!("{reason} (tried {} times)", r.tries)
                    }
                    e => e.to_string(),
                };
                Some(r.result.clone())
            }
        }
    }

    /// Runs the timers at `now_s`: busy uploads offered again, answers overdue; the results
    /// this settles.
    pub fn handle_timeout(&mut self, now_s: f64, outbox: &mut Outbox) -> Vec<CommandResultMsg> {
        let mut settled = Vec::new();
        for (n, r) in &mut self.records {
            match r.stage {
                Stage::Retrying { at_s } if now_s >= at_s => {
                    r.tries += 1;
                    let action =
                        outbox.issue(now_s, r.op.clone(), Purpose::Request(*n), APPLY_WITHIN_S);
                    r.stage = Stage::Sending(action);
                }
                Stage::Answering { deadline_s } if now_s > deadline_s => {
                    r.stage = Stage::Done;
                    r.result.outcome = Outcome::TimedOut;
                    r.result.detail = format!(
                        "sent, but no answer from the drone within {:.0} s",
                        answer_within_s(&r.op)
                    );
                    settled.push(r.result.clone());
                }
                _ => {}
            }
        }
        settled
    }

    /// A warning the drone said (STATUSTEXT): kept to explain a refusal that follows it.
    pub fn on_vehicle_warning(&mut self, now_s: f64, text: &str) {
        self.last_warning = Some((now_s, text.to_string()));
    }

    /// COMMAND_ACKs as the link reports them.
    pub fn on_command_event(&mut self, now_s: f64, e: &CommandEvent) -> Option<CommandResultMsg> {
        let r = self.records.get_mut(&e.request_id.0)?;
        if !matches!(r.op, LinkOp::Command { .. }) {
            return None;
        }
        r.result.attempts = u32::from(e.attempts);
        let (outcome, detail) = match e.outcome {
            CommandOutcome::Accepted => (Outcome::Accepted, "acknowledged by the drone".into()),
            CommandOutcome::InProgress { progress_pct } => (
                Outcome::InProgress,
                progress_pct.map_or("in progress".into(), |p| format!("{p} % done")),
            ),
            CommandOutcome::TimedOut { attempts } => (
                Outcome::TimedOut,
                format!("no acknowledgement after {attempts} attempts"),
            ),
            CommandOutcome::Rejected { result } => {
                let outcome = match result {
                    CommandResult::Unsupported => Outcome::Unsupported,
                    CommandResult::Failed => Outcome::Failed,
                    _ => Outcome::Denied,
                };
                // Taken once: two refusals in a row must not share one reason.
                let reason = self
                    .last_warning
                    .take()
                    .filter(|(at_s, _)| now_s - at_s <= REASON_WITHIN_S);
                let detail = match reason {
                    Some((_, why)) => format!("the drone answered {result:?}: {why}"),
                    None => format!("the drone answered {result:?}"),
                };
                (outcome, detail)
            }
        };
        r.result.outcome = outcome;
        r.result.detail = detail;
        r.stage = if outcome == Outcome::InProgress {
            Stage::Answering {
                deadline_s: now_s + ANSWER_WITHIN_S,
            }
        } else {
            Stage::Done
        };
        Some(r.result.clone())
    }

    /// Finished parameter writes as results.
    pub fn on_param_event(&mut self, e: &ParamEvent) -> Option<CommandResultMsg> {
        let (name, outcome, detail, attempts, value) = match e {
            ParamEvent::SetDone {
                name,
                requested,
                actual,
                accepted,
            } => {
                let (outcome, detail) = if *accepted {
                    (
                        Outcome::Accepted,
                        format!("{name} = {actual} read back from the drone"),
                    )
                } else {
                    (
                        Outcome::Denied,
                        format!(
                            "the drone kept {name} = {actual} (asked {requested}: out of range)"
                        ),
                    )
                };
                (name, outcome, detail, None, Some(f64::from(*actual)))
            }
            ParamEvent::SetFailed { name, attempts, .. } => (
                name,
                Outcome::TimedOut,
                format!("no PARAM_VALUE after {attempts} attempts"),
                Some(u32::from(*attempts)),
                None,
            ),
            _ => return None,
        };
        let n = self.param_sets.remove(name)?;
        let r = self.records.get_mut(&n)?;
        r.result.attempts = attempts.unwrap_or(r.result.attempts.max(1));
        if value.is_some() {
            r.result.value = value;
        }
        r.result.outcome = outcome;
        r.result.detail = detail;
        r.stage = Stage::Done;
        Some(r.result.clone())
    }

    /// The end of a plan upload as a result.
    pub fn on_plan_event(&mut self, e: &PlanEvent) -> Option<CommandResultMsg> {
        let (outcome, detail) = match e {
            PlanEvent::UploadDone { items } => (
                Outcome::Accepted,
                format!("the drone accepted {items} items"),
            ),
            PlanEvent::UploadFailed { result, reason } => (
                if result.is_some() {
                    Outcome::Denied
                } else {
                    Outcome::TimedOut
                },
                reason.clone(),
            ),
            PlanEvent::DownloadDone { .. } | PlanEvent::DownloadFailed { .. } => return None,
        };
        let n = self.plan_upload.take()?;
        let r = self.records.get_mut(&n)?;
        r.result.outcome = outcome;
        r.result.detail = detail;
        r.result.attempts = r.result.attempts.max(1);
        r.stage = Stage::Done;
        Some(r.result.clone())
    }

    /// The plan change of an accepted request, once.
    pub fn take_accepted_change(&mut self, request_id: &str) -> Option<PlanChange> {
        let r = self.records.get_mut(&number(request_id)?)?;
        if r.result.outcome != Outcome::Accepted {
            return None;
        }
        r.change.take()
    }

    pub fn result(&self, request_id: &str) -> Option<CommandResultMsg> {
        let n = number(request_id)?;
        self.records.get(&n).map(|r| r.result.clone())
    }

    /// Requests not settled, by id, with their command.
    pub fn pending(&self) -> HashMap<String, String> {
        self.records
            .values()
            .filter(|r| r.result.outcome == Outcome::InProgress)
            .map(|r| (r.result.request_id.clone(), r.result.command.clone()))
            .collect()
    }

    /// An operator's plan upload waits to be taken by the link (possibly for another plan
    /// transfer to end).
    pub fn upload_waiting(&self) -> bool {
        self.records.values().any(|r| {
            matches!(r.op, LinkOp::PlanUpload(_))
                && matches!(r.stage, Stage::Sending(_) | Stage::Retrying { .. })
        })
    }
}
