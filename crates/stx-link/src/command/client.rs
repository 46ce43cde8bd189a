//! Ground side of the command protocol: [`CommandClient`] sends each command, retries it
//! until acknowledged (COMMAND_LONG retries carry an incremented `confirmation`) and reports
//! its outcome as a [`CommandEvent`] carrying the operator's [`RequestId`].

use std::collections::VecDeque;
use std::time::Duration;

use mavlink::dialects::common::{MavCmd, MavMessage};
use serde::{Deserialize, Serialize};

use super::encoding::{Command, CommandResult};

/// The operator's id for one command request, echoed in its [`CommandEvent`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct RequestId(pub u64);

/// Retry policy of the ground side.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CommandConfig {
    /// Wait for an ACK before re-sending.
    pub timeout: Duration,
    /// Re-sends after the first transmission before giving up (3 → 4 attempts in all).
    pub retries: u8,
    /// Extra wait granted by each `MAV_RESULT_IN_PROGRESS`.
    pub in_progress_timeout: Duration,
}

impl Default for CommandConfig {
    fn default() -> Self {
        Self {
            timeout: Duration::from_secs(1),
            retries: 3,
            in_progress_timeout: Duration::from_secs(5),
        }
    }
}

/// Final (or progress) outcome of a command request.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "outcome", rename_all = "snake_case")]
pub enum CommandOutcome {
    /// The vehicle accepted and executed the command.
    Accepted,
    /// The vehicle answered with a refusal or failure (any MAV_RESULT but ACCEPTED and
    /// IN_PROGRESS).
    Rejected { result: CommandResult },
    /// The vehicle is executing it (not final).
    InProgress { progress_pct: Option<u8> },
    /// No ACK after `attempts` transmissions.
    TimedOut { attempts: u8 },
}

/// What the ground side reports about a request.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CommandEvent {
    /// The operator's id of the request.
    pub request_id: RequestId,
    /// The command.
    pub command: Command,
    /// Outcome.
    pub outcome: CommandOutcome,
    /// Transmissions so far.
    pub attempts: u8,
}

/// Why a command could not be queued.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CommandSendError {
    /// A command with the same MAV_CMD to the same target is already waiting for its ACK
    /// (MAVLink matches ACKs by command id, so two would be ambiguous).
    #[error(
        "command {command:?} to system {target_system} already in flight (request {in_flight:?})"
    )]
    Busy {
        command: MavCmd,
        target_system: u8,
        in_flight: RequestId,
    },
}

#[derive(Debug)]
struct InFlight {
    request_id: RequestId,
    command: Command,
    target: (u8, u8),
    attempts: u8,
    deadline: Duration,
}

/// Ground side of the command protocol (sans-io).
#[derive(Debug, Default)]
pub struct CommandClient {
    /// Retry policy.
    pub config: CommandConfig,
    in_flight: Vec<InFlight>,
    transmit: VecDeque<MavMessage>,
    events: VecDeque<CommandEvent>,
}

impl CommandClient {
    /// A client with the given retry policy.
    pub fn new(config: CommandConfig) -> Self {
        Self {
            config,
            ..Default::default()
        }
    }

    /// Sends `command` to `target` (system, component) now; the outcome comes back as a
    /// [`CommandEvent`] carrying `request_id`.
    pub fn send(
        &mut self,
        now: Duration,
        request_id: RequestId,
        target: (u8, u8),
        command: Command,
    ) -> Result<(), CommandSendError> {
        let mav = command.mav_cmd();
        if let Some(f) = self
            .in_flight
            .iter()
            .find(|f| f.target.0 == target.0 && f.command.mav_cmd() == mav)
        {
            return Err(CommandSendError::Busy {
                command: mav,
                target_system: target.0,
                in_flight: f.request_id,
            });
        }
        tracing::debug!(?request_id, ?command, "command sent");
        self.transmit
            .push_back(command.to_mavlink(target.0, target.1, 0));
        self.in_flight.push(InFlight {
            request_id,
            command,
            target,
            attempts: 1,
            deadline: now + self.config.timeout,
        });
        Ok(())
    }

    /// Requests still waiting for their final ACK.
    pub fn pending(&self) -> usize {
        self.in_flight.len()
    }

    /// Feeds a received message; COMMAND_ACKs from `from_system` settle matching requests.
    pub fn handle_message(
        &mut self,
        now: Duration,
        from_system: u8,
        our_system: u8,
        msg: &MavMessage,
    ) {
        let MavMessage::COMMAND_ACK(ack) = msg else {
            return;
        };
        // target_system 0 = broadcast or an older sender without the extension.
        if ack.target_system != 0 && ack.target_system != our_system {
            return;
        }
        let Some(i) = self
            .in_flight
            .iter()
            .position(|f| f.target.0 == from_system && f.command.mav_cmd() == ack.command)
        else {
            tracing::debug!(command = ?ack.command, from_system, "COMMAND_ACK for nothing in flight");
            return;
        };
        let result = CommandResult::from_mav(ack.result);
        if result == CommandResult::InProgress {
            if let Some(f) = self.in_flight.get_mut(i) {
                f.deadline = now + self.config.in_progress_timeout;
                self.events.push_back(CommandEvent {
                    request_id: f.request_id,
                    command: f.command,
                    outcome: CommandOutcome::InProgress {
                        progress_pct: (ack.progress <= 100).then_some(ack.progress),
                    },
                    attempts: f.attempts,
                });
            }
            return;
        }
        let f = self.in_flight.remove(i);
        let outcome = if result == CommandResult::Accepted {
            CommandOutcome::Accepted
        } else {
            CommandOutcome::Rejected { result }
        };
        tracing::info!(request_id = ?f.request_id, ?outcome, attempts = f.attempts, "command settled");
        self.events.push_back(CommandEvent {
            request_id: f.request_id,
            command: f.command,
            outcome,
            attempts: f.attempts,
        });
    }

    /// Re-sends or gives up on requests whose deadline passed.
    pub fn handle_timeout(&mut self, now: Duration) {
        let retries = self.config.retries;
        let timeout = self.config.timeout;
        let mut i = 0;
        while let Some(f) = self.in_flight.get_mut(i) {
            if f.deadline > now {
                i += 1;
                continue;
            }
            if f.attempts > retries {
                let f = self.in_flight.remove(i);
                tracing::warn!(request_id = ?f.request_id, attempts = f.attempts, "command timed out");
                self.events.push_back(CommandEvent {
                    request_id: f.request_id,
                    command: f.command,
                    outcome: CommandOutcome::TimedOut {
                        attempts: f.attempts,
                    },
                    attempts: f.attempts,
                });
                continue;
            }
            // Retry: confirmation counts previous transmissions.
            self.transmit
                .push_back(f.command.to_mavlink(f.target.0, f.target.1, f.attempts));
            f.attempts = f.attempts.saturating_add(1);
            f.deadline = now + timeout;
            i += 1;
        }
    }

    /// Earliest deadline.
    pub fn poll_timeout(&self) -> Option<Duration> {
        self.in_flight.iter().map(|f| f.deadline).min()
    }

    /// Next message to send.
    pub fn poll_transmit(&mut self) -> Option<MavMessage> {
        self.transmit.pop_front()
    }

    /// Next outcome.
    pub fn poll_event(&mut self) -> Option<CommandEvent> {
        self.events.pop_front()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn client_retries_with_confirmation_then_times_out() {
        let mut cl = CommandClient::new(CommandConfig {
            timeout: Duration::from_secs(1),
            retries: 2,
            ..Default::default()
        });
        cl.send(Duration::ZERO, RequestId(7), (1, 1), Command::Cutdown)
            .expect("queued");
        assert!(matches!(
            cl.send(Duration::ZERO, RequestId(8), (1, 1), Command::Cutdown),
            Err(CommandSendError::Busy { .. })
        ));
        let mut confirmations = Vec::new();
        let mut t = Duration::ZERO;
        for _ in 0..4 {
            while let Some(MavMessage::COMMAND_LONG(c)) = cl.poll_transmit() {
                confirmations.push(c.confirmation);
            }
            t = cl.poll_timeout().unwrap_or(t);
            cl.handle_timeout(t);
        }
        assert_eq!(confirmations, vec![0, 1, 2]);
        let ev = cl.poll_event().expect("outcome");
        assert_eq!(ev.request_id, RequestId(7));
        assert_eq!(ev.outcome, CommandOutcome::TimedOut { attempts: 3 });
        assert_eq!(cl.pending(), 0);
    }
}
