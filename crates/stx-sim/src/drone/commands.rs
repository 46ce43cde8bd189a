//! What the station asks of the drone: commands, parameter sets, plan uploads, sticks and the
//! link's coming and going. Each is applied at once, between two control periods; refusals
//! carry their reason to the operator's log.

use stx_gnc::params::ParamError;
use stx_link::command::{Command, CommandResult};
use stx_link::manual::Sticks;
use stx_link::plan::{FenceItem, PlanItem};
use stx_link::telemetry::Severity;

use super::Drone;
use super::onboard::mode_name;
use super::summary::stage_name;

impl Drone {
    /// Whether `name` may take `value` now (range, kind, the rules between parameters, the
    /// servo travel), without changing anything: the link's table asks this before it takes a
    /// set from the station or echoes it.
    pub fn check_param(&self, name: &str, value: f32) -> Result<(), ParamError> {
        self.onboard.check_param(name, value).map(drop)
    }

    /// Sets a parameter from the station (checked against the shared catalog); effective at
    /// the next period. On refusal nothing changes and the reason goes to the operator's log.
    pub fn set_param(&mut self, name: &str, value: f32) -> Result<(), ParamError> {
        match self.onboard.set_param(name, value) {
            Ok(()) => {
                self.physics.settle_s = self.onboard.settings().mission.settle_s;
                self.say(Severity::Info, format!("parameter {name} = {value}"));
                Ok(())
            }
            Err(e) => {
                self.say(Severity::Warning, format!("parameter refused: {e}"));
                Err(e)
            }
        }
    }

    /// The sticks as the link's receiver has them (`None` when stale): call before every
    /// [`step`](Self::step) and whenever they change.
    pub fn set_sticks(&mut self, sticks: Option<Sticks>) {
        self.onboard.set_sticks(self.time_s(), sticks);
        self.drain_onboard_texts();
    }

    /// An uploaded plan.
    pub fn handle_plan(&mut self, items: &[PlanItem]) {
        self.onboard.handle_plan(self.time_s(), items);
        self.drain_onboard_texts();
    }

    /// An uploaded keep-out fence (checked whole by the link): the onboard guidance's zones.
    pub fn handle_fence(&mut self, items: &[FenceItem]) {
        self.onboard.handle_fence(items);
        self.drain_onboard_texts();
    }

    /// The plan held, as mission items.
    pub fn plan_items(&self) -> Vec<PlanItem> {
        self.onboard.plan_items()
    }

    /// The station's heartbeats stopped (`false`) or came back (`true`). Nothing changes in
    /// flight: the drone keeps flying its plan; when the link returns it says what it did.
    pub fn link_changed(&mut self, connected: bool) {
        let now = self.time_s();
        if !connected {
            self.link_lost_at_s.get_or_insert(now);
        } else if let Some(lost) = self.link_lost_at_s.take() {
            let stage = self.stage();
            self.say(
                Severity::Notice,
                format!(
                    "link back after {:.0} s: {}, {}, {:.0} m",
                    now - lost,
                    stage_name(stage),
                    mode_name(self.onboard.mode()),
                    self.estimate.map_or(f64::NAN, |e| e.height_m()),
                ),
            );
        }
    }

    /// Executes an operator command; every command gets a result (COMMAND_ACK), refusals
    /// with a reason in the log.
    pub fn handle_command(&mut self, command: &Command) -> CommandResult {
        let result = match *command {
            Command::Cutdown => match self.physics.cutdown() {
                Ok(event) => {
                    self.stage_event(event);
                    CommandResult::Accepted
                }
                Err(why) => {
                    self.say(Severity::Warning, format!("cutdown refused: {why}"));
                    CommandResult::Denied
                }
            },
            Command::RequestMessage { message_id } => self.streams.request(message_id),
            Command::SetMessageInterval {
                message_id,
                interval_us,
            } => self.streams.set_interval(message_id, interval_us),
            _ => self.onboard.handle_command(self.time_s(), command),
        };
        self.drain_onboard_texts();
        result
    }
}
