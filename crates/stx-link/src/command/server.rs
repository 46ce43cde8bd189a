//! Vehicle side of the command protocol: [`CommandServer`] decodes each command, refuses
//! what it cannot decode with the matching MAV_RESULT, recognises retries (by content within
//! [`CommandServer::dedup_window`]) so a command is executed once, and acknowledges with the
//! application's answer.

use std::collections::VecDeque;
use std::time::Duration;

use mavlink::dialects::common as mc;
use mavlink::dialects::common::{MavCmd, MavMessage};
use serde::{Deserialize, Serialize};

use super::encoding::{Command, CommandResult};

/// Handle for answering one received command.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct IncomingId(u64);

/// A command received by the vehicle, waiting for the application's answer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IncomingCommand {
    /// Pass to [`CommandServer::respond`].
    pub id: IncomingId,
    /// Sender (system, component).
    pub from: (u8, u8),
    /// The decoded command.
    pub command: Command,
}

#[derive(Debug)]
struct Recent {
    id: IncomingId,
    from: (u8, u8),
    command: MavCmd,
    /// Message id and wire payload with `confirmation` zeroed: retries compare equal even
    /// when a parameter is NaN (as in a landing target "into the wind").
    content: Vec<u8>,
    confirmation: u8,
    received: Duration,
    answer: Option<CommandResult>,
}

/// Counters of the vehicle side.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct CommandServerStats {
    /// Commands delivered to the application.
    pub delivered: u64,
    /// Retries recognised and not delivered again.
    pub duplicates: u64,
    /// Commands refused while decoding (unsupported, invalid parameter, frame).
    pub refused: u64,
}

/// Vehicle side of the command protocol (sans-io).
#[derive(Debug)]
pub struct CommandServer {
    /// Our system id (commands for others are ignored; 0 = broadcast accepted).
    pub system_id: u8,
    /// Our component id.
    pub component_id: u8,
    /// How long a command is remembered to recognise its retries.
    pub dedup_window: Duration,
    next_id: u64,
    recent: VecDeque<Recent>,
    events: VecDeque<IncomingCommand>,
    transmit: VecDeque<MavMessage>,
    stats: CommandServerStats,
}

impl CommandServer {
    /// Most commands remembered for de-duplication.
    pub const MAX_RECENT: usize = 32;

    /// A server for `system_id`/`component_id`, remembering commands for 5 s.
    pub fn new(system_id: u8, component_id: u8) -> Self {
        Self {
            system_id,
            component_id,
            dedup_window: Duration::from_secs(5),
            next_id: 0,
            recent: VecDeque::new(),
            events: VecDeque::new(),
            transmit: VecDeque::new(),
            stats: CommandServerStats::default(),
        }
    }

    /// Counters.
    pub fn stats(&self) -> CommandServerStats {
        self.stats
    }

    fn ack(&mut self, to: (u8, u8), command: MavCmd, result: CommandResult) {
        self.transmit
            .push_back(MavMessage::COMMAND_ACK(mc::COMMAND_ACK_DATA {
                command,
                result: result.to_mav(),
                progress: if result == CommandResult::InProgress {
                    u8::MAX
                } else {
                    0
                },
                result_param2: 0,
                target_system: to.0,
                target_component: to.1,
            }));
    }

    /// Feeds a received message from `from` (system, component). Returns whether it was a
    /// command for us.
    pub fn handle_message(&mut self, now: Duration, from: (u8, u8), msg: &MavMessage) -> bool {
        let (target_system, target_component, confirmation, mav_cmd) = match msg {
            MavMessage::COMMAND_LONG(c) => (
                c.target_system,
                c.target_component,
                Some(c.confirmation),
                c.command,
            ),
            MavMessage::COMMAND_INT(c) => (c.target_system, c.target_component, None, c.command),
            _ => return false,
        };
        if (target_system != 0 && target_system != self.system_id)
            || (target_component != 0 && target_component != self.component_id)
        {
            return false;
        }
        while self
            .recent
            .front()
            .is_some_and(|r| now.saturating_sub(r.received) > self.dedup_window)
        {
            self.recent.pop_front();
        }
        // A retry: same sender, same content (confirmation aside), newer confirmation (or any
        // copy for COMMAND_INT, which has none).
        let canonical = canonical(msg);
        if let Some(r) = self
            .recent
            .iter_mut()
            .find(|r| r.from == from && r.content == canonical)
        {
            let is_retry = match confirmation {
                Some(c) => c > r.confirmation,
                None => true,
            };
            if is_retry {
                r.confirmation = confirmation.unwrap_or(0);
                r.received = now;
                self.stats.duplicates += 1;
                tracing::debug!(?mav_cmd, ?from, "command retry recognised");
                if let Some(answer) = r.answer {
                    self.ack(from, mav_cmd, answer);
                }
                return true;
            }
        }
        match Command::from_mavlink(msg) {
            Some(Ok(command)) => {
                let id = IncomingId(self.next_id);
                self.next_id += 1;
                if self.recent.len() >= Self::MAX_RECENT {
                    self.recent.pop_front();
                }
                self.recent.push_back(Recent {
                    id,
                    from,
                    command: mav_cmd,
                    content: canonical,
                    confirmation: confirmation.unwrap_or(0),
                    received: now,
                    answer: None,
                });
                self.stats.delivered += 1;
                self.events.push_back(IncomingCommand { id, from, command });
            }
            Some(Err(e)) => {
                tracing::warn!(error = %e, ?from, "command refused");
                self.stats.refused += 1;
                self.ack(from, mav_cmd, e.result());
            }
            None => return false,
        }
        true
    }

    /// Next command for the application to execute and answer.
    pub fn poll_event(&mut self) -> Option<IncomingCommand> {
        self.events.pop_front()
    }

    /// Sends the application's answer for `id` (and remembers it for retries). Returns
    /// `false` if `id` is unknown (already forgotten).
    pub fn respond(&mut self, id: IncomingId, result: CommandResult) -> bool {
        let Some(r) = self.recent.iter_mut().find(|r| r.id == id) else {
            return false;
        };
        r.answer = Some(result);
        let (from, cmd) = (r.from, r.command);
        self.ack(from, cmd, result);
        true
    }

    /// Next message to send.
    pub fn poll_transmit(&mut self) -> Option<MavMessage> {
        self.transmit.pop_front()
    }
}

/// Message id and wire payload with the confirmation zeroed, to compare retries by content
/// (bit-exact, so NaN parameters compare equal).
fn canonical(msg: &MavMessage) -> Vec<u8> {
    use mavlink::{MavlinkVersion, Message};
    let zeroed;
    let msg = match msg {
        MavMessage::COMMAND_LONG(c) => {
            zeroed = MavMessage::COMMAND_LONG(mc::COMMAND_LONG_DATA {
                confirmation: 0,
                ..c.clone()
            });
            &zeroed
        }
        other => other,
    };
    let mut payload = [0_u8; 255];
    let n = msg.ser(MavlinkVersion::V2, &mut payload);
    let mut out = msg.message_id().to_le_bytes().to_vec();
    out.extend_from_slice(payload.get(..n).unwrap_or(&[]));
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use stx_types::mission::FlightMode;

    #[test]
    fn unsupported_and_invalid_commands_are_refused_with_the_right_result() {
        let mut srv = CommandServer::new(1, 1);
        let arm = MavMessage::COMMAND_LONG(mc::COMMAND_LONG_DATA {
            command: MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            target_system: 1,
            target_component: 1,
            ..Default::default()
        });
        assert!(srv.handle_message(Duration::ZERO, (255, 190), &arm));
        let Some(MavMessage::COMMAND_ACK(a)) = srv.poll_transmit() else {
            panic!("no ack")
        };
        assert_eq!(a.result, mc::MavResult::MAV_RESULT_UNSUPPORTED);
        let bad_mode = Command::SetMode(FlightMode::Manual).to_mavlink(1, 1, 0);
        let MavMessage::COMMAND_LONG(mut c) = bad_mode else {
            panic!()
        };
        c.param2 = 42.0;
        srv.handle_message(Duration::ZERO, (255, 190), &MavMessage::COMMAND_LONG(c));
        let Some(MavMessage::COMMAND_ACK(a)) = srv.poll_transmit() else {
            panic!("no ack")
        };
        assert_eq!(a.result, mc::MavResult::MAV_RESULT_DENIED);
        assert_eq!(srv.stats().refused, 2);
        assert!(srv.poll_event().is_none());
    }

    #[test]
    fn retry_is_acked_again_but_delivered_once() {
        let mut srv = CommandServer::new(1, 1);
        let gcs = (255, 190);
        let c = Command::Cutdown;
        srv.handle_message(Duration::ZERO, gcs, &c.to_mavlink(1, 1, 0));
        let inc = srv.poll_event().expect("delivered");
        assert!(srv.respond(inc.id, CommandResult::Accepted));
        assert!(matches!(
            srv.poll_transmit(),
            Some(MavMessage::COMMAND_ACK(_))
        ));
        srv.handle_message(Duration::from_millis(1000), gcs, &c.to_mavlink(1, 1, 1));
        assert!(srv.poll_event().is_none());
        let Some(MavMessage::COMMAND_ACK(a)) = srv.poll_transmit() else {
            panic!("no re-ack")
        };
        assert_eq!(a.result, mc::MavResult::MAV_RESULT_ACCEPTED);
        assert_eq!(srv.stats().duplicates, 1);
        // A fresh request (confirmation 0) later is delivered again.
        srv.handle_message(Duration::from_millis(2000), gcs, &c.to_mavlink(1, 1, 0));
        assert!(srv.poll_event().is_some());
    }

    /// Regression: retries were compared with `PartialEq`, and a NaN parameter (landing target
    /// "into the wind") never equals itself, so each COMMAND_INT retry was executed again.
    #[test]
    fn command_int_retry_with_nan_parameter_is_recognised() {
        let mut srv = CommandServer::new(1, 1);
        let c = Command::SetLandingTarget {
            lat_deg: 41.0,
            lon_deg: -8.0,
            alt_msl_m: 90.0,
            approach_heading_deg: None,
        };
        srv.handle_message(Duration::ZERO, (255, 190), &c.to_mavlink(1, 1, 0));
        let inc = srv.poll_event().expect("delivered");
        srv.respond(inc.id, CommandResult::Accepted);
        srv.handle_message(Duration::from_secs(1), (255, 190), &c.to_mavlink(1, 1, 0));
        assert!(srv.poll_event().is_none(), "retry delivered again");
        assert_eq!(srv.stats().duplicates, 1);
    }
}
