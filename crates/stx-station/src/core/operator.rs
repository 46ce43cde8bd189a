//! The core's side of commanding: operators' requests, the cutdown, and the station's own
//! reads of the drone become link actions ([`super::actions`]); the link's outcomes and the
//! drone's answers settle them as `command_result`s ([`super::commands`]); retries and
//! deadlines run as timers on the `now_s` passed in. The daemon only carries actions to the
//! link driver and outcomes back.

use std::collections::HashMap;

use stx_gnc::guidance::Plan;

use super::StationCore;
use super::actions::{ActionError, ActionId, LinkAction, Purpose};
use super::cutdown::CutdownArm;
use super::requests::{ApiError, Checked, CommandRequest, Payload, PlanChange, check};
use super::sync::TargetSource;
use crate::messages::{CommandResultMsg, Level, Outcome};
use crate::recording::station::CommandRecord;

impl StationCore {
    /// Checks and records an operator's request and queues its link action; the request id,
    /// under which its `command_result` will come.
    pub fn request(
        &mut self,
        now_s: f64,
        who: &str,
        request: CommandRequest,
    ) -> Result<String, ApiError> {
        let Checked {
            command,
            payload,
            change,
            text,
        } = check(&self.frame, &self.keep_out.zones, &self.params, request)?;
        let id = self
            .commands
            .open(now_s, &mut self.outbox, command, payload, change);
        self.outbound.push(super::Outbound::Command(CommandRecord {
            time_s: now_s,
            request_id: id.clone(),
            by: who.to_owned(),
            text: text.clone(),
        }));
        self.log(now_s, Level::Info, "command", format!("{who}: {text}"));
        Ok(id)
    }

    /// Arms the cutdown for the window of the configuration.
    pub fn arm_cutdown(&mut self, now_s: f64, who: &str) -> CutdownArm {
        let arm = self.cutdown.arm(now_s, who);
        self.log(
            now_s,
            Level::Warning,
            "command",
            format!(
                "{who} armed the cutdown ({} s to confirm)",
                arm.expires_in_s
            ),
        );
        arm
    }

    /// Confirms an armed cutdown and queues the command: its request id.
    pub fn confirm_cutdown(
        &mut self,
        now_s: f64,
        who: &str,
        arm_id: &str,
    ) -> Result<String, ApiError> {
        self.cutdown.confirm(now_s, who, arm_id)?;
        let cutdown = Payload::Command(stx_link::command::Command::Cutdown);
        let id = self
            .commands
            .open(now_s, &mut self.outbox, "cutdown", cutdown, None);
        self.log(
            now_s,
            Level::Warning,
            "command",
            format!("{who} confirmed the CUTDOWN"),
        );
        Ok(id)
    }

    /// Runs the timers due at `now_s`, then takes the link actions queued since the last
    /// call, oldest first, for the link driver. Each action's outcome must come back through
    /// [`StationCore::on_action_outcome`].
    pub fn take_link_actions(&mut self, now_s: f64) -> Vec<LinkAction> {
        self.handle_timeout(now_s);
        self.outbox.take()
    }

    /// The core's timers: link actions whose outcome is overdue, busy plan uploads offered
    /// again, requests with no answer by their deadline, the cutdown's arming, silent sticks,
    /// and the read of the drone's plan.
    pub fn handle_timeout(&mut self, now_s: f64) {
        for (id, purpose, error) in self.outbox.overdue(now_s) {
            self.settle_action(now_s, id, purpose, false, Err(error));
        }
        for msg in self.commands.handle_timeout(now_s, &mut self.outbox) {
            self.after_command_result(now_s, &msg);
        }
        if let Some(expired) = self.cutdown.expire(now_s) {
            self.log(now_s, Level::Info, "command", expired);
        }
        self.manual_timeout(now_s);
        self.fence_timeout(now_s);
        self.surface_wind_timeout(now_s);
        let upload_waiting = self.commands.upload_waiting();
        self.schedule_plan_download(now_s, upload_waiting);
    }

    /// What became of link action `id`: applied (`Ok`) or not, and why.
    pub fn on_action_outcome(&mut self, now_s: f64, id: ActionId, result: Result<(), ActionError>) {
        match self.outbox.settle(id) {
            Some((purpose, late)) => self.settle_action(now_s, id, purpose, late, result),
            None => tracing::warn!(?id, ?result, "outcome of a link action never issued"),
        }
    }

    fn settle_action(
        &mut self,
        now_s: f64,
        id: ActionId,
        purpose: Purpose,
        late: bool,
        result: Result<(), ActionError>,
    ) {
        match purpose {
            Purpose::Request(n) => {
                if let Some(msg) = self.commands.on_applied(now_s, n, id, result) {
                    self.after_command_result(now_s, &msg);
                }
            }
            Purpose::PlanDownload => {
                if let Err(e) = result
                    && !late
                {
                    self.plan_download_refused(now_s, id, &e.to_string());
                }
            }
            Purpose::ParamList => {
                if let Err(e) = result {
                    tracing::warn!(error = %e, "parameter list not requested");
                }
            }
            Purpose::Manual => {
                if let Err(e) = result {
                    tracing::debug!(error = %e, "sticks not sent");
                }
            }
            Purpose::FenceUpload => {
                if !late {
                    self.fence_applied(now_s, result);
                }
            }
            Purpose::SurfaceWind => {
                if !late {
                    self.surface_wind_applied(now_s, result);
                }
            }
        }
    }

    /// Logs a settled result, lets the replica adopt what the drone accepted, and queues the
    /// `command_result` for the dashboards.
    pub(crate) fn after_command_result(&mut self, now_s: f64, msg: &CommandResultMsg) {
        let level = match msg.outcome {
            Outcome::Accepted | Outcome::InProgress => Level::Info,
            _ => Level::Warning,
        };
        if msg.outcome != Outcome::InProgress {
            self.log(
                now_s,
                level,
                "command",
                format!("{} {:?}: {}", msg.command, msg.outcome, msg.detail),
            );
        }
        // The replica flies the plan the drone accepted.
        if msg.outcome == Outcome::Accepted
            && let Some(plan_change) = self.commands.take_accepted_change(&msg.request_id)
        {
            self.apply_plan_change(now_s, plan_change);
        }
        self.outbound
            .push(super::Outbound::CommandResult(msg.clone()));
    }

    fn apply_plan_change(&mut self, now_s: f64, change: PlanChange) {
        let mut plan: Plan = *self.guidance.plan();
        let mut read_back = true;
        match change {
            PlanChange::Target {
                target_ned_m,
                approach_course_rad,
            } => {
                plan.target_ned_m = target_ned_m;
                plan.approach_course_rad = approach_course_rad;
                self.sync.target = Some(TargetSource::Operator);
            }
            PlanChange::Heading(h) => {
                plan.heading_rad = h;
                read_back = false;
            }
            PlanChange::Course(c) => {
                plan.course_rad = c;
                read_back = false;
            }
            PlanChange::Localizer { line, glide_slope } => {
                plan.localizer = line;
                plan.localizer_glide_slope = glide_slope;
                self.sync.line_known = true;
            }
            PlanChange::Upload(points) => {
                // The drone's own mapping of an upload.
                let update = stx_gnc::plan_upload::apply(&plan, &points);
                plan = update.plan;
                if update.target_set {
                    self.sync.target = Some(TargetSource::Operator);
                }
                if update.line == stx_gnc::plan_upload::LineChange::Set {
                    self.sync.line_known = true;
                }
            }
        }
        self.set_replica_plan(now_s, plan);
        if read_back {
            // What the drone holds now is the truth: read it back.
            self.want_plan_download(now_s);
        }
    }

    /// The outcome of a request, if it is known.
    pub fn command_result(&self, request_id: &str) -> Option<CommandResultMsg> {
        self.commands.result(request_id)
    }

    /// Requests still in progress, by id, with their command.
    pub fn pending_requests(&self) -> HashMap<String, String> {
        self.commands.pending()
    }
}

/// Every path of a request's life on the fake clock: the core's link actions are "applied"
/// by hand and the drone's answers fed in as the endpoint reports them.
#[cfg(test)]
mod tests {
    use stx_gnc::mission::FlightMode;
    use stx_link::command::{Command, CommandEvent, CommandOutcome, CommandResult, RequestId};
    use stx_link::endpoint::{GroundConfig, GroundEvent};
    use stx_link::manual::Sticks;
    use stx_link::param::ParamEvent;
    use stx_link::plan::{PlanEvent, PlanItem};
    use stx_link::telemetry::Severity;

    use super::super::actions::{APPLY_WITHIN_S, LinkOp, OUTCOME_GRACE_S};
    use super::super::commands::{
        ANSWER_PER_PLAN_ITEM_S, ANSWER_WITHIN_S, UPLOAD_RETRY_S, UPLOAD_TRIES,
    };
    use super::super::manual::MANUAL_SILENCE_S;
    use super::super::tests::{core, sent_ops};
    use super::super::{Outbound, StationCore};
    use super::*;

    /// The `command_result`s queued for the dashboards since the last call.
    fn results(core: &mut StationCore) -> Vec<CommandResultMsg> {
        core.drain_outbound()
            .into_iter()
            .filter_map(|o| match o {
                Outbound::CommandResult(r) => Some(r),
                _ => None,
            })
            .collect()
    }

    fn heading(core: &mut StationCore, now_s: f64, heading_deg: f64) -> String {
        core.request(now_s, "ops", CommandRequest::Heading { heading_deg })
            .expect("a valid request")
    }

    /// The drone's answer to command request `n`, as the endpoint reports it.
    fn answer(core: &mut StationCore, now_s: f64, n: u64, outcome: CommandOutcome) {
        core.on_link_event(
            now_s,
            GroundEvent::Command(CommandEvent {
                request_id: RequestId(n),
                command: Command::SetMode(FlightMode::Heading),
                outcome,
                attempts: 1,
            }),
        );
    }

    fn plan() -> Vec<PlanItem> {
        vec![PlanItem::Land {
            lat_deg: 38.54,
            lon_deg: -7.88,
            alt_msl_m: 245.0,
            approach_heading_deg: Some(90.0),
        }]
    }

    fn only(results: Vec<CommandResultMsg>) -> CommandResultMsg {
        assert_eq!(results.len(), 1, "{results:?}");
        results.into_iter().next().expect("one result")
    }

    #[test]
    fn a_command_is_sent_then_acknowledged_and_the_replica_adopts_it() {
        let mut core = core();
        let id = heading(&mut core, 1.0, 120.0);
        assert_eq!(
            core.command_result(&id).expect("known").detail,
            "queued for the link"
        );
        let actions = core.take_link_actions(1.0);
        assert_eq!(actions.len(), 1);
        let action = &actions[0];
        assert_eq!(action.deadline_s, 1.0 + APPLY_WITHIN_S);
        assert!(matches!(
            action.op,
            LinkOp::Command {
                request_id: RequestId(1),
                command: Command::HoldHeading { .. }
            }
        ));
        core.on_action_outcome(1.05, action.id, Ok(()));
        assert!(results(&mut core).is_empty(), "sent is not a result yet");
        let sent = core.command_result(&id).expect("known");
        assert_eq!(
            (sent.outcome, sent.detail.as_str()),
            (Outcome::InProgress, "sent")
        );
        assert!(core.pending_requests().contains_key(&id));
        answer(&mut core, 1.5, 1, CommandOutcome::Accepted);
        let r = only(results(&mut core));
        assert_eq!(
            (r.request_id.as_str(), r.outcome),
            (id.as_str(), Outcome::Accepted)
        );
        assert!((core.replica_plan().heading_rad - 120_f64.to_radians()).abs() < 1e-9);
        assert!(core.pending_requests().is_empty());
        // Settled: no deadline fires later.
        core.handle_timeout(100.0);
        assert!(results(&mut core).is_empty());
    }

    #[test]
    fn a_denied_command_says_so_and_changes_nothing() {
        let mut core = core();
        let before = core.replica_plan().heading_rad;
        let id = heading(&mut core, 0.0, 45.0);
        sent_ops(&mut core, 0.0);
        answer(
            &mut core,
            0.5,
            1,
            CommandOutcome::Rejected {
                result: CommandResult::Denied,
            },
        );
        let r = only(results(&mut core));
        assert_eq!((r.request_id, r.outcome), (id, Outcome::Denied));
        assert_eq!(core.replica_plan().heading_rad, before);
    }

    #[test]
    fn a_refusal_carries_the_reason_the_drone_said_just_before_it_once() {
        let mut core = core();
        let said = |core: &mut StationCore, now_s: f64, text: &str| {
            core.on_link_event(
                now_s,
                GroundEvent::StatusText {
                    from: (1, 1),
                    severity: Severity::Warning,
                    text: text.into(),
                },
            );
        };
        let denied = CommandOutcome::Rejected {
            result: CommandResult::TemporarilyRejected,
        };
        heading(&mut core, 0.0, 45.0);
        sent_ops(&mut core, 0.0);
        said(
            &mut core,
            0.4,
            "manual refused: no stick input (hold the dead-man first)",
        );
        answer(&mut core, 0.5, 1, denied);
        let r = only(results(&mut core));
        assert_eq!(r.outcome, Outcome::Denied);
        assert_eq!(
            r.detail,
            "the drone answered TemporarilyRejected: manual refused: no stick input (hold the dead-man first)"
        );
        // The next refusal has no reason of its own: it does not borrow the last one.
        heading(&mut core, 1.0, 50.0);
        sent_ops(&mut core, 1.0);
        answer(&mut core, 1.5, 2, denied);
        assert_eq!(
            only(results(&mut core)).detail,
            "the drone answered TemporarilyRejected"
        );
        // Nor one said long before.
        said(&mut core, 2.0, "GPS glitch");
        heading(&mut core, 9.0, 55.0);
        sent_ops(&mut core, 9.0);
        answer(&mut core, 9.5, 3, denied);
        assert_eq!(
            only(results(&mut core)).detail,
            "the drone answered TemporarilyRejected"
        );
    }

    #[test]
    fn the_links_own_time_out_ends_the_request() {
        let mut core = core();
        let id = heading(&mut core, 0.0, 45.0);
        sent_ops(&mut core, 0.0);
        answer(&mut core, 4.0, 1, CommandOutcome::TimedOut { attempts: 4 });
        let r = only(results(&mut core));
        assert_eq!((r.request_id, r.outcome), (id, Outcome::TimedOut));
        assert!(r.detail.contains("4 attempts"), "{}", r.detail);
    }

    #[test]
    fn no_answer_at_all_times_out_at_the_deadline_and_progress_extends_it() {
        let mut core = core();
        let id = heading(&mut core, 0.0, 45.0);
        sent_ops(&mut core, 0.0);
        answer(
            &mut core,
            10.0,
            1,
            CommandOutcome::InProgress {
                progress_pct: Some(50),
            },
        );
        let progress = only(results(&mut core));
        assert_eq!(progress.outcome, Outcome::InProgress);
        // The deadline counts from the last sign of progress.
        core.handle_timeout(10.0 + ANSWER_WITHIN_S);
        assert!(results(&mut core).is_empty());
        assert!(core.pending_requests().contains_key(&id));
        core.handle_timeout(10.0 + ANSWER_WITHIN_S + 0.1);
        let r = only(results(&mut core));
        assert_eq!((r.request_id, r.outcome), (id, Outcome::TimedOut));
        assert!(
            r.detail.contains("no answer from the drone"),
            "{}",
            r.detail
        );
        assert!(core.pending_requests().is_empty());
    }

    #[test]
    fn an_action_the_link_never_reports_on_times_out_as_not_sent() {
        let mut core = core();
        let id = heading(&mut core, 0.0, 45.0);
        let actions = core.take_link_actions(0.0);
        assert_eq!(actions.len(), 1);
        core.handle_timeout(APPLY_WITHIN_S + OUTCOME_GRACE_S);
        assert!(results(&mut core).is_empty(), "still within the grace");
        core.handle_timeout(APPLY_WITHIN_S + OUTCOME_GRACE_S + 0.1);
        let r = only(results(&mut core));
        assert_eq!(
            (r.request_id.as_str(), r.outcome),
            (id.as_str(), Outcome::TimedOut)
        );
        assert!(r.detail.contains("not sent"), "{}", r.detail);
        // It was sent after all, and the drone accepted it: the truth replaces the time-out.
        core.on_action_outcome(8.0, actions[0].id, Ok(()));
        let reopened = only(results(&mut core));
        assert_eq!(reopened.outcome, Outcome::InProgress);
        assert!(reopened.detail.contains("sent late"), "{}", reopened.detail);
        answer(&mut core, 8.5, 1, CommandOutcome::Accepted);
        assert_eq!(only(results(&mut core)).outcome, Outcome::Accepted);
    }

    #[test]
    fn an_action_the_link_driver_got_too_late_is_not_sent() {
        let mut core = core();
        let id = heading(&mut core, 0.0, 45.0);
        let action = core.take_link_actions(0.0).remove(0);
        core.on_action_outcome(6.0, action.id, Err(ActionError::Expired));
        let r = only(results(&mut core));
        assert_eq!((r.request_id, r.outcome), (id, Outcome::TimedOut));
        assert!(r.detail.contains("not sent"), "{}", r.detail);
    }

    #[test]
    fn a_request_the_link_refuses_fails_with_the_links_reason() {
        let mut core = core();
        let first = heading(&mut core, 0.0, 45.0);
        let second = heading(&mut core, 0.1, 90.0);
        let actions = core.take_link_actions(0.1);
        core.on_action_outcome(0.1, actions[0].id, Ok(()));
        core.on_action_outcome(
            0.1,
            actions[1].id,
            Err(ActionError::Busy("command already in flight".into())),
        );
        let r = only(results(&mut core));
        assert_eq!(
            (r.request_id.as_str(), r.outcome),
            (second.as_str(), Outcome::Failed)
        );
        assert_eq!(r.detail, "command already in flight");
        assert!(
            core.take_link_actions(5.0).is_empty(),
            "a command is not retried"
        );
        assert!(core.pending_requests().contains_key(&first));
        let id = core
            .request(
                1.0,
                "ops",
                CommandRequest::ParamSet {
                    name: "ZZ_NOT_KNOWN".into(),
                    value: 1.0,
                },
            )
            .expect("unknown to the catalogue, and no table yet");
        let action = core.take_link_actions(1.0).remove(0);
        core.on_action_outcome(1.0, action.id, Err(ActionError::Refused("bad name".into())));
        let r = only(results(&mut core));
        assert_eq!((r.request_id, r.outcome), (id, Outcome::Failed));
    }

    #[test]
    fn a_busy_plan_upload_is_retried_on_the_clock_then_sent_and_accepted() {
        let mut core = core();
        let id = core
            .request(2.0, "ops", CommandRequest::Plan(plan()))
            .expect("a valid plan");
        let first = core.take_link_actions(2.0).remove(0);
        assert_eq!(first.op, LinkOp::PlanUpload(plan()));
        core.on_action_outcome(
            2.0,
            first.id,
            Err(ActionError::Busy(
                "a plan transfer is already in progress".into(),
            )),
        );
        assert!(results(&mut core).is_empty(), "busy is not the end");
        assert!(core.pending_requests().contains_key(&id));
        assert!(
            core.take_link_actions(2.0 + UPLOAD_RETRY_S - 0.01)
                .is_empty()
        );
        let again = core.take_link_actions(2.0 + UPLOAD_RETRY_S);
        assert_eq!(again.len(), 1);
        assert_ne!(again[0].id, first.id, "a new action");
        assert_eq!(again[0].op, LinkOp::PlanUpload(plan()));
        core.on_action_outcome(2.3, again[0].id, Ok(()));
        assert_eq!(core.command_result(&id).expect("known").detail, "sent");
        core.on_link_event(3.0, GroundEvent::Plan(PlanEvent::UploadDone { items: 1 }));
        let r = only(results(&mut core));
        assert_eq!((r.request_id, r.outcome), (id, Outcome::Accepted));
        assert!(
            core.replica_plan().target_ned_m.norm() > 100.0,
            "the replica flies it"
        );
        assert_eq!(
            sent_ops(&mut core, 3.0),
            vec![LinkOp::PlanDownload],
            "and reads it back"
        );
    }

    #[test]
    fn a_plan_upload_busy_every_time_gives_up_after_its_tries() {
        let mut core = core();
        let id = core
            .request(0.0, "ops", CommandRequest::Plan(plan()))
            .expect("a valid plan");
        let mut now = 0.0;
        let mut tries = 0;
        while tries < UPLOAD_TRIES + 5 {
            for a in core.take_link_actions(now) {
                assert_eq!(a.op, LinkOp::PlanUpload(plan()));
                tries += 1;
                core.on_action_outcome(now, a.id, Err(ActionError::Busy("busy".into())));
            }
            if !results(&mut core).is_empty() || now > 60.0 {
                break;
            }
            // Exact in binary: the retry falls on a step.
            now += 0.0625;
        }
        assert_eq!(tries, UPLOAD_TRIES, "offered {UPLOAD_TRIES} times in all");
        let r = core.command_result(&id).expect("known");
        assert_eq!(r.outcome, Outcome::Failed);
        assert!(
            r.detail.contains(&format!("tried {UPLOAD_TRIES} times")),
            "{}",
            r.detail
        );
        let spent = now;
        let expected = f64::from(UPLOAD_TRIES - 1) * UPLOAD_RETRY_S;
        assert_eq!(spent, expected);
        assert!(core.take_link_actions(100.0).is_empty());
    }

    #[test]
    fn the_stations_own_plan_read_waits_for_an_operators_upload() {
        let mut core = core();
        core.want_plan_download(0.0);
        assert_eq!(sent_ops(&mut core, 0.0), vec![LinkOp::PlanDownload]);
        // The upload meets the read on the link: busy, it waits.
        let id = core
            .request(0.1, "ops", CommandRequest::Plan(plan()))
            .expect("a valid plan");
        let upload = core.take_link_actions(0.1).remove(0);
        core.on_action_outcome(0.1, upload.id, Err(ActionError::Busy("busy".into())));
        core.on_link_event(
            0.2,
            GroundEvent::Plan(PlanEvent::DownloadDone { items: vec![] }),
        );
        // Something asks for another read while the upload waits: the upload goes first.
        core.want_plan_download(0.2);
        assert!(sent_ops(&mut core, 0.3).is_empty());
        let ops = sent_ops(&mut core, 0.1 + UPLOAD_RETRY_S);
        assert_eq!(ops, vec![LinkOp::PlanUpload(plan())]);
        core.on_link_event(0.5, GroundEvent::Plan(PlanEvent::UploadDone { items: 1 }));
        assert_eq!(only(results(&mut core)).request_id, id);
        assert_eq!(sent_ops(&mut core, 0.5), vec![LinkOp::PlanDownload]);
    }

    #[test]
    fn overlapping_plan_uploads_each_get_their_own_answer() {
        let mut core = core();
        let first = core
            .request(0.0, "ops", CommandRequest::Plan(plan()))
            .expect("valid");
        sent_ops(&mut core, 0.0);
        let second = core
            .request(0.1, "ops", CommandRequest::Plan(plan()))
            .expect("valid");
        let busy = core.take_link_actions(0.1).remove(0);
        core.on_action_outcome(0.1, busy.id, Err(ActionError::Busy("busy".into())));
        core.on_link_event(0.2, GroundEvent::Plan(PlanEvent::UploadDone { items: 1 }));
        let r = only(results(&mut core));
        assert_eq!(
            (r.request_id.as_str(), r.outcome),
            (first.as_str(), Outcome::Accepted)
        );
        assert_eq!(
            core.command_result(&second).expect("known").outcome,
            Outcome::InProgress
        );
        let ops = sent_ops(&mut core, 0.1 + UPLOAD_RETRY_S);
        assert!(ops.contains(&LinkOp::PlanUpload(plan())), "{ops:?}");
        core.on_link_event(
            0.6,
            GroundEvent::Plan(PlanEvent::UploadFailed {
                result: Some(1),
                reason: "refused".into(),
            }),
        );
        let r = only(results(&mut core));
        assert_eq!((r.request_id, r.outcome), (second, Outcome::Denied));
    }

    #[test]
    fn a_parameter_write_is_answered_with_the_value_read_back() {
        let mut core = core();
        let set = |core: &mut StationCore, now: f64| {
            core.request(
                now,
                "ops",
                CommandRequest::ParamSet {
                    name: "HK1".into(),
                    value: 0.02,
                },
            )
            .expect("valid")
        };
        let first = set(&mut core, 0.0);
        sent_ops(&mut core, 0.0);
        // The same parameter again while the first is under way: the link refuses it, and
        // the first one's answer still goes to the first.
        let second = set(&mut core, 0.1);
        let busy = core.take_link_actions(0.1).remove(0);
        core.on_action_outcome(0.1, busy.id, Err(ActionError::Busy("busy".into())));
        assert_eq!(only(results(&mut core)).request_id, second);
        core.on_link_event(
            0.5,
            GroundEvent::Param(ParamEvent::SetDone {
                name: "HK1".into(),
                requested: 0.02,
                actual: 0.02,
                accepted: true,
            }),
        );
        let r = only(results(&mut core));
        assert_eq!(
            (r.request_id.as_str(), r.outcome),
            (first.as_str(), Outcome::Accepted)
        );
        assert_eq!(r.value, Some(f64::from(0.02_f32)));
        let third = set(&mut core, 1.0);
        sent_ops(&mut core, 1.0);
        core.on_link_event(
            5.0,
            GroundEvent::Param(ParamEvent::SetFailed {
                name: "HK1".into(),
                requested: 0.02,
                attempts: 4,
            }),
        );
        let r = only(results(&mut core));
        assert_eq!((r.request_id, r.outcome), (third, Outcome::TimedOut));
    }

    #[test]
    fn a_confirmed_cutdown_goes_out_as_a_command_with_its_own_result() {
        let mut core = core();
        let arm = core.arm_cutdown(0.0, "ops");
        let id = core
            .confirm_cutdown(1.0, "ops", &arm.arm_id)
            .expect("armed");
        let ops = sent_ops(&mut core, 1.0);
        assert!(matches!(
            ops[..],
            [LinkOp::Command {
                command: Command::Cutdown,
                ..
            }]
        ));
        answer(&mut core, 1.5, 1, CommandOutcome::Accepted);
        let r = only(results(&mut core));
        assert_eq!((r.request_id, r.command.as_str()), (id, "cutdown"));
        // Confirming again needs a new arming.
        assert_eq!(
            core.confirm_cutdown(2.0, "ops", &arm.arm_id)
                .expect_err("used up")
                .status,
            409
        );
        // An arming nobody confirms lapses on the core's timer.
        core.arm_cutdown(10.0, "ops");
        core.handle_timeout(10.0 + core.config.cutdown_window_s + 0.1);
        assert!(
            core.events
                .iter()
                .any(|e| e.text.contains("expired unconfirmed"))
        );
    }

    #[test]
    fn sticks_are_clamped_stale_ones_expire_and_silence_releases_them() {
        let mut core = core();
        core.manual_hold(
            1.0,
            Sticks {
                x: 3.0,
                y: f64::NAN,
                z: -0.5,
                r: 0.0,
                buttons: 1,
            },
        );
        let hold = core.take_link_actions(1.0).remove(0);
        assert_eq!(hold.deadline_s, 1.0 + MANUAL_SILENCE_S);
        let LinkOp::ManualHold(sticks) = hold.op else {
            panic!("{hold:?}")
        };
        assert_eq!((sticks.x, sticks.y, sticks.z), (1.0, 0.0, -0.5));
        core.on_action_outcome(1.0, hold.id, Ok(()));
        assert!(core.take_link_actions(1.0 + MANUAL_SILENCE_S).is_empty());
        assert_eq!(
            sent_ops(&mut core, 1.0 + MANUAL_SILENCE_S + 0.1),
            vec![LinkOp::ManualRelease],
            "silent sticks are released"
        );
        assert!(sent_ops(&mut core, 3.0).is_empty(), "once");
        core.manual_hold(4.0, Sticks::default());
        core.manual_release(4.05);
        let ops = sent_ops(&mut core, 4.05);
        assert_eq!(ops.last(), Some(&LinkOp::ManualRelease));
        assert!(
            sent_ops(&mut core, 6.0).is_empty(),
            "released: nothing more"
        );
    }

    #[test]
    fn the_outcome_of_an_unknown_action_changes_nothing() {
        let mut core = core();
        core.on_action_outcome(1.0, ActionId(99), Ok(()));
        core.on_action_outcome(1.0, ActionId(98), Err(ActionError::Refused("x".into())));
        assert!(results(&mut core).is_empty());
        assert!(core.events.is_empty());
    }

    #[test]
    fn the_stations_deadlines_leave_the_link_its_own_retries() {
        let link = GroundConfig::default();
        let command_give_up =
            link.command.timeout.as_secs_f64() * f64::from(link.command.retries + 1);
        let progress_give_up = link.command.in_progress_timeout.as_secs_f64();
        let param_give_up = link.param.timeout.as_secs_f64() * f64::from(link.param.retries + 1);
        let plan_item_give_up = link.plan.timeout.as_secs_f64() * f64::from(link.plan.retries + 1);
        assert!(ANSWER_WITHIN_S > 2.0 * command_give_up.max(progress_give_up).max(param_give_up));
        assert!(ANSWER_PER_PLAN_ITEM_S > plan_item_give_up);
    }

    /// Seeded: requests of every kind, with the link and the drone answering, refusing, or
    /// saying nothing, at random. However it goes, each one ends in a final `command_result`
    /// and nothing stays in progress past the deadlines.
    #[test]
    fn every_request_ends_in_a_final_result_whatever_the_link_does() {
        let mut core = core();
        let mut seed: u64 = 0x5eed_1234_abcd_0001;
        let mut random = move |n: u64| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed % n
        };
        let mut ids = Vec::new();
        let mut finals: std::collections::HashMap<String, Outcome> = Default::default();
        let mut now = 0.0;
        let mut applied_commands = Vec::new();
        for step in 0..400 {
            now += 0.05;
            if step < 200 && random(4) == 0 {
                let request = match random(3) {
                    0 => CommandRequest::Heading {
                        heading_deg: random(360) as f64,
                    },
                    1 => CommandRequest::Plan(plan()),
                    _ => CommandRequest::ParamSet {
                        name: format!("P{}", random(3)),
                        value: 1.0,
                    },
                };
                ids.push(core.request(now, "ops", request).expect("valid"));
            }
            for a in core.take_link_actions(now) {
                let outcome = match random(6) {
                    0 => continue, // never reported
                    1 => Err(ActionError::Busy("busy".into())),
                    2 => Err(ActionError::Refused("no".into())),
                    _ => Ok(()),
                };
                let ok = outcome.is_ok();
                core.on_action_outcome(now, a.id, outcome);
                if ok && let LinkOp::Command { request_id, .. } = a.op {
                    applied_commands.push(request_id.0);
                }
            }
            if random(10) == 0
                && let Some(n) = applied_commands.pop()
            {
                answer(&mut core, now, n, CommandOutcome::Accepted);
            }
            if random(20) == 0 {
                core.on_link_event(now, GroundEvent::Plan(PlanEvent::UploadDone { items: 1 }));
            }
            for r in results(&mut core) {
                if r.outcome != Outcome::InProgress {
                    finals.insert(r.request_id.clone(), r.outcome);
                }
            }
        }
        // Past every deadline; then past the deadline of what that offered again (a busy
        // upload, a read of the drone's plan), which nobody reports on.
        let end = now + ANSWER_WITHIN_S + ANSWER_PER_PLAN_ITEM_S + APPLY_WITHIN_S + 10.0;
        core.take_link_actions(end);
        core.take_link_actions(end + APPLY_WITHIN_S + OUTCOME_GRACE_S + 0.1);
        for r in results(&mut core) {
            if r.outcome != Outcome::InProgress {
                finals.insert(r.request_id.clone(), r.outcome);
            }
        }
        assert!(ids.len() > 30, "{} requests", ids.len());
        assert!(
            core.pending_requests().is_empty(),
            "{:?}",
            core.pending_requests()
        );
        for id in &ids {
            assert!(finals.contains_key(id), "{id} never got a final result");
        }
        assert_eq!(core.outbox.unsettled(), 0);
    }
}
