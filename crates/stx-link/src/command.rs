//! The command micro-protocol: the operator's [`Command`]s, their MAVLink encoding, the
//! ground side that retries until acknowledged ([`CommandClient`]) and the vehicle side that
//! decodes, de-duplicates and acknowledges ([`CommandServer`]).
//!
//! Every command is acknowledged (COMMAND_ACK) or retried and reported as failed, and the
//! operator sees which: each request carries the operator's [`RequestId`] into its final
//! [`CommandEvent`].
//!
//! ## Encoding
//! | [`Command`] | MAVLink | parameters |
//! |---|---|---|
//! | `SetMode` | COMMAND_LONG `MAV_CMD_DO_SET_MODE` | p1 = `MAV_MODE_FLAG_CUSTOM_MODE_ENABLED`, p2 = custom mode = the mode code (stage and phase bits zero: the vehicle decides those) |
//! | `HoldHeading` | COMMAND_LONG `MAV_CMD_CONDITION_YAW` | p1 = heading deg, p2 = 0 (default rate), p3 = 0 (shortest way), p4 = 0 (absolute) |
//! | `HoldCourse` | COMMAND_LONG `MAV_CMD_GUIDED_CHANGE_HEADING` | p1 = `HEADING_TYPE_COURSE_OVER_GROUND`, p2 = course deg, p3 = 0 (default rate) |
//! | `SetLandingTarget` | COMMAND_INT `MAV_CMD_NAV_LAND`, `MAV_FRAME_GLOBAL` | p4 = approach heading deg, NaN = into the wind (the vehicle's default yaw mode); x/y degE7, z m MSL |
//! | `SetLocalizer` | COMMAND_INT `MAV_CMD_DO_REPOSITION`, `MAV_FRAME_GLOBAL` | p1 = −1 (default speed), p2 = 0, p3 = glide-slope angle deg or NaN (p3 is the loiter radius, meaningless for a parafoil: documented re-use), p4 = course of the localizer line in **rad** (DO_REPOSITION's yaw unit), x/y = a point on the line, z = NaN (no altitude change) |
//! | `Cutdown` | COMMAND_LONG `MAV_CMD_DO_FLIGHTTERMINATION` | p1 = 1 |
//! | `RequestMessage` | COMMAND_LONG `MAV_CMD_REQUEST_MESSAGE` | p1 = message id |
//! | `SetMessageInterval` | COMMAND_LONG `MAV_CMD_SET_MESSAGE_INTERVAL` | p1 = message id, p2 = interval µs (−1 stop, 0 default) |
//!
//! COMMAND_LONG retries carry an incremented `confirmation`; COMMAND_INT has no such field, so
//! its retries are identical copies, which the vehicle recognises by content within
//! [`CommandServer::dedup_window`].

use std::collections::VecDeque;
use std::time::Duration;

use mavlink::dialects::common as mc;
use mavlink::dialects::common::{MavCmd, MavMessage};
use serde::{Deserialize, Serialize};
use stx_gnc::mission::FlightMode;

/// What the operator asks the drone to do.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Command {
    /// Select a control mode.
    SetMode(FlightMode),
    /// Hold a heading (Heading mode target), degrees true 0…360.
    HoldHeading { heading_deg: f64 },
    /// Hold a course over the ground (Course mode target), degrees true 0…360.
    HoldCourse { course_deg: f64 },
    /// Landing target; `approach_heading_deg: None` lands into the wind.
    SetLandingTarget {
        lat_deg: f64,
        lon_deg: f64,
        alt_msl_m: f64,
        approach_heading_deg: Option<f64>,
    },
    /// Localizer line through a point with a course, optionally with a glide slope (degrees
    /// below the horizon).
    SetLocalizer {
        lat_deg: f64,
        lon_deg: f64,
        course_deg: f64,
        glide_slope_deg: Option<f64>,
    },
    /// Flight termination: cut the payload loose.
    Cutdown,
    /// Ask for one message to be sent now.
    RequestMessage { message_id: u32 },
    /// Set the rate of a message: interval µs, −1 stops it, 0 restores the default.
    SetMessageInterval { message_id: u32, interval_us: i32 },
}

/// Outcome of a command as reported by the vehicle (MAV_RESULT).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CommandResult {
    Accepted,
    TemporarilyRejected,
    Denied,
    Unsupported,
    Failed,
    InProgress,
    Cancelled,
    CommandLongOnly,
    CommandIntOnly,
    UnsupportedFrame,
    NotInControl,
}

impl CommandResult {
    /// The MAV_RESULT value.
    pub fn to_mav(self) -> mc::MavResult {
        use mc::MavResult as R;
        match self {
            Self::Accepted => R::MAV_RESULT_ACCEPTED,
            Self::TemporarilyRejected => R::MAV_RESULT_TEMPORARILY_REJECTED,
            Self::Denied => R::MAV_RESULT_DENIED,
            Self::Unsupported => R::MAV_RESULT_UNSUPPORTED,
            Self::Failed => R::MAV_RESULT_FAILED,
            Self::InProgress => R::MAV_RESULT_IN_PROGRESS,
            Self::Cancelled => R::MAV_RESULT_CANCELLED,
            Self::CommandLongOnly => R::MAV_RESULT_COMMAND_LONG_ONLY,
            Self::CommandIntOnly => R::MAV_RESULT_COMMAND_INT_ONLY,
            Self::UnsupportedFrame => R::MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME,
            Self::NotInControl => R::MAV_RESULT_NOT_IN_CONTROL,
        }
    }
    /// From a MAV_RESULT value.
    pub fn from_mav(r: mc::MavResult) -> Self {
        use mc::MavResult as R;
        match r {
            R::MAV_RESULT_ACCEPTED => Self::Accepted,
            R::MAV_RESULT_TEMPORARILY_REJECTED => Self::TemporarilyRejected,
            R::MAV_RESULT_DENIED => Self::Denied,
            R::MAV_RESULT_UNSUPPORTED => Self::Unsupported,
            R::MAV_RESULT_FAILED => Self::Failed,
            R::MAV_RESULT_IN_PROGRESS => Self::InProgress,
            R::MAV_RESULT_CANCELLED => Self::Cancelled,
            R::MAV_RESULT_COMMAND_LONG_ONLY => Self::CommandLongOnly,
            R::MAV_RESULT_COMMAND_INT_ONLY => Self::CommandIntOnly,
            R::MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME => Self::UnsupportedFrame,
            R::MAV_RESULT_NOT_IN_CONTROL => Self::NotInControl,
        }
    }
}

/// Why a received command could not be turned into a [`Command`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CommandDecodeError {
    /// The MAV_CMD is not one stx implements (answered `MAV_RESULT_UNSUPPORTED`).
    #[error("unsupported command {command:?}")]
    Unsupported { command: MavCmd },
    /// A parameter is out of range (answered `MAV_RESULT_DENIED`).
    #[error("command {command:?}: parameter {param} = {value} is invalid")]
    InvalidParam {
        command: MavCmd,
        param: u8,
        value: f64,
    },
    /// The coordinate frame is not `MAV_FRAME_GLOBAL` (answered `MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME`).
    #[error("command {command:?}: unsupported frame {frame:?}")]
    UnsupportedFrame {
        command: MavCmd,
        frame: mc::MavFrame,
    },
    /// Sent as COMMAND_LONG but must be COMMAND_INT (positions need integer lat/lon).
    #[error("command {command:?} must be sent as COMMAND_INT")]
    IntOnly { command: MavCmd },
}

impl CommandDecodeError {
    /// The MAV_RESULT the vehicle answers with.
    pub fn result(&self) -> CommandResult {
        match self {
            Self::Unsupported { .. } => CommandResult::Unsupported,
            Self::InvalidParam { .. } => CommandResult::Denied,
            Self::UnsupportedFrame { .. } => CommandResult::UnsupportedFrame,
            Self::IntOnly { .. } => CommandResult::CommandIntOnly,
        }
    }
}

fn finite_angle(command: MavCmd, param: u8, v: f32) -> Result<f64, CommandDecodeError> {
    let v = f64::from(v);
    if v.is_finite() && (-360.0..=360.0).contains(&v) {
        Ok(v.rem_euclid(360.0))
    } else {
        Err(CommandDecodeError::InvalidParam {
            command,
            param,
            value: v,
        })
    }
}

fn lat_lon(command: MavCmd, x: i32, y: i32) -> Result<(f64, f64), CommandDecodeError> {
    let (lat, lon) = (f64::from(x) / 1e7, f64::from(y) / 1e7);
    if !(-90.0..=90.0).contains(&lat) {
        return Err(CommandDecodeError::InvalidParam {
            command,
            param: 5,
            value: lat,
        });
    }
    if !(-180.0..=180.0).contains(&lon) {
        return Err(CommandDecodeError::InvalidParam {
            command,
            param: 6,
            value: lon,
        });
    }
    Ok((lat, lon))
}

impl Command {
    /// The MAV_CMD this command is sent as.
    pub fn mav_cmd(&self) -> MavCmd {
        match self {
            Self::SetMode(_) => MavCmd::MAV_CMD_DO_SET_MODE,
            Self::HoldHeading { .. } => MavCmd::MAV_CMD_CONDITION_YAW,
            Self::HoldCourse { .. } => MavCmd::MAV_CMD_GUIDED_CHANGE_HEADING,
            Self::SetLandingTarget { .. } => MavCmd::MAV_CMD_NAV_LAND,
            Self::SetLocalizer { .. } => MavCmd::MAV_CMD_DO_REPOSITION,
            Self::Cutdown => MavCmd::MAV_CMD_DO_FLIGHTTERMINATION,
            Self::RequestMessage { .. } => MavCmd::MAV_CMD_REQUEST_MESSAGE,
            Self::SetMessageInterval { .. } => MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
        }
    }

    /// The COMMAND_LONG / COMMAND_INT carrying this command to `target`.
    pub fn to_mavlink(
        &self,
        target_system: u8,
        target_component: u8,
        confirmation: u8,
    ) -> MavMessage {
        let command = self.mav_cmd();
        let long = |p: [f32; 7]| {
            MavMessage::COMMAND_LONG(mc::COMMAND_LONG_DATA {
                param1: p[0],
                param2: p[1],
                param3: p[2],
                param4: p[3],
                param5: p[4],
                param6: p[5],
                param7: p[6],
                command,
                target_system,
                target_component,
                confirmation,
            })
        };
        let int = |p: [f32; 4], lat: f64, lon: f64, z: f32| {
            MavMessage::COMMAND_INT(mc::COMMAND_INT_DATA {
                param1: p[0],
                param2: p[1],
                param3: p[2],
                param4: p[3],
                x: (lat * 1e7).round() as i32,
                y: (lon * 1e7).round() as i32,
                z,
                command,
                target_system,
                target_component,
                frame: mc::MavFrame::MAV_FRAME_GLOBAL,
                current: 0,
                autocontinue: 0,
            })
        };
        match *self {
            Self::SetMode(mode) => long([
                f32::from(mc::MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED.bits()),
                f32::from(mode.code()),
                0.0,
                0.0,
                0.0,
                0.0,
                0.0,
            ]),
            Self::HoldHeading { heading_deg } => {
                long([heading_deg as f32, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
            }
            Self::HoldCourse { course_deg } => long([
                mc::HeadingType::HEADING_TYPE_COURSE_OVER_GROUND as u8 as f32,
                course_deg as f32,
                0.0,
                0.0,
                0.0,
                0.0,
                0.0,
            ]),
            Self::SetLandingTarget {
                lat_deg,
                lon_deg,
                alt_msl_m,
                approach_heading_deg,
            } => int(
                [
                    0.0,
                    0.0,
                    0.0,
                    approach_heading_deg.map_or(f32::NAN, |h| h as f32),
                ],
                lat_deg,
                lon_deg,
                alt_msl_m as f32,
            ),
            Self::SetLocalizer {
                lat_deg,
                lon_deg,
                course_deg,
                glide_slope_deg,
            } => int(
                [
                    -1.0,
                    0.0,
                    glide_slope_deg.map_or(f32::NAN, |g| g as f32),
                    course_deg.to_radians() as f32,
                ],
                lat_deg,
                lon_deg,
                f32::NAN,
            ),
            Self::Cutdown => long([1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
            Self::RequestMessage { message_id } => {
                long([message_id as f32, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
            }
            Self::SetMessageInterval {
                message_id,
                interval_us,
            } => long([
                message_id as f32,
                interval_us as f32,
                0.0,
                0.0,
                0.0,
                0.0,
                0.0,
            ]),
        }
    }

    /// Decodes a COMMAND_LONG or COMMAND_INT; `None` for any other message.
    pub fn from_mavlink(msg: &MavMessage) -> Option<Result<Command, CommandDecodeError>> {
        match msg {
            MavMessage::COMMAND_LONG(c) => Some(Self::from_long(c)),
            MavMessage::COMMAND_INT(c) => Some(Self::from_int(c)),
            _ => None,
        }
    }

    fn from_long(c: &mc::COMMAND_LONG_DATA) -> Result<Command, CommandDecodeError> {
        let command = c.command;
        let bad = |param: u8, value: f32| CommandDecodeError::InvalidParam {
            command,
            param,
            value: f64::from(value),
        };
        match command {
            MavCmd::MAV_CMD_DO_SET_MODE => {
                let flags = c.param1;
                if flags != f32::from(mc::MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED.bits()) {
                    return Err(bad(1, flags));
                }
                let code = c.param2;
                if !(0.0..=255.0).contains(&code) || code.fract() != 0.0 {
                    return Err(bad(2, code));
                }
                FlightMode::from_code(code as u8)
                    .map(Command::SetMode)
                    .ok_or_else(|| bad(2, code))
            }
            MavCmd::MAV_CMD_CONDITION_YAW => {
                if c.param4 != 0.0 {
                    return Err(bad(4, c.param4));
                }
                Ok(Command::HoldHeading {
                    heading_deg: finite_angle(command, 1, c.param1)?,
                })
            }
            MavCmd::MAV_CMD_GUIDED_CHANGE_HEADING => {
                if c.param1 != mc::HeadingType::HEADING_TYPE_COURSE_OVER_GROUND as u8 as f32 {
                    return Err(bad(1, c.param1));
                }
                Ok(Command::HoldCourse {
                    course_deg: finite_angle(command, 2, c.param2)?,
                })
            }
            MavCmd::MAV_CMD_DO_FLIGHTTERMINATION => {
                if c.param1 >= 0.5 {
                    Ok(Command::Cutdown)
                } else {
                    Err(bad(1, c.param1))
                }
            }
            MavCmd::MAV_CMD_REQUEST_MESSAGE => {
                let id = c.param1;
                if !(0.0..=16_777_215.0).contains(&id) || id.fract() != 0.0 {
                    return Err(bad(1, id));
                }
                Ok(Command::RequestMessage {
                    message_id: id as u32,
                })
            }
            MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL => {
                let id = c.param1;
                if !(0.0..=16_777_215.0).contains(&id) || id.fract() != 0.0 {
                    return Err(bad(1, id));
                }
                if !c.param2.is_finite() || c.param2 < -1.0 {
                    return Err(bad(2, c.param2));
                }
                Ok(Command::SetMessageInterval {
                    message_id: id as u32,
                    interval_us: c.param2 as i32,
                })
            }
            MavCmd::MAV_CMD_NAV_LAND | MavCmd::MAV_CMD_DO_REPOSITION => {
                Err(CommandDecodeError::IntOnly { command })
            }
            _ => Err(CommandDecodeError::Unsupported { command }),
        }
    }

    fn from_int(c: &mc::COMMAND_INT_DATA) -> Result<Command, CommandDecodeError> {
        let command = c.command;
        // MAV_FRAME_GLOBAL_INT is the deprecated synonym older senders still use.
        #[allow(deprecated)]
        let check_frame = || {
            if c.frame == mc::MavFrame::MAV_FRAME_GLOBAL
                || c.frame == mc::MavFrame::MAV_FRAME_GLOBAL_INT
            {
                Ok(())
            } else {
                Err(CommandDecodeError::UnsupportedFrame {
                    command,
                    frame: c.frame,
                })
            }
        };
        match command {
            MavCmd::MAV_CMD_NAV_LAND => {
                check_frame()?;
                let (lat_deg, lon_deg) = lat_lon(command, c.x, c.y)?;
                if !c.z.is_finite() {
                    return Err(CommandDecodeError::InvalidParam {
                        command,
                        param: 7,
                        value: f64::from(c.z),
                    });
                }
                let approach_heading_deg = if c.param4.is_nan() {
                    None
                } else {
                    Some(finite_angle(command, 4, c.param4)?)
                };
                Ok(Command::SetLandingTarget {
                    lat_deg,
                    lon_deg,
                    alt_msl_m: f64::from(c.z),
                    approach_heading_deg,
                })
            }
            MavCmd::MAV_CMD_DO_REPOSITION => {
                check_frame()?;
                let (lat_deg, lon_deg) = lat_lon(command, c.x, c.y)?;
                let course = f64::from(c.param4);
                if !course.is_finite() || course.abs() > 2.0 * std::f64::consts::TAU {
                    return Err(CommandDecodeError::InvalidParam {
                        command,
                        param: 4,
                        value: course,
                    });
                }
                let glide_slope_deg = if c.param3.is_nan() {
                    None
                } else if (0.0..90.0).contains(&c.param3) {
                    Some(f64::from(c.param3))
                } else {
                    return Err(CommandDecodeError::InvalidParam {
                        command,
                        param: 3,
                        value: f64::from(c.param3),
                    });
                };
                Ok(Command::SetLocalizer {
                    lat_deg,
                    lon_deg,
                    course_deg: course.to_degrees().rem_euclid(360.0),
                    glide_slope_deg,
                })
            }
            _ => Self::from_long(&mc::COMMAND_LONG_DATA {
                param1: c.param1,
                param2: c.param2,
                param3: c.param3,
                param4: c.param4,
                param5: c.x as f32,
                param6: c.y as f32,
                param7: c.z,
                command,
                target_system: c.target_system,
                target_component: c.target_component,
                confirmation: 0,
            }),
        }
    }
}

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

    fn all_commands() -> Vec<Command> {
        vec![
            Command::SetMode(FlightMode::SpiralLanding),
            Command::HoldHeading { heading_deg: 270.5 },
            Command::HoldCourse { course_deg: 12.25 },
            Command::SetLandingTarget {
                lat_deg: 41.1779,
                lon_deg: -8.5977,
                alt_msl_m: 120.5,
                approach_heading_deg: None,
            },
            Command::SetLandingTarget {
                lat_deg: 41.1779,
                lon_deg: -8.5977,
                alt_msl_m: 120.5,
                approach_heading_deg: Some(250.0),
            },
            Command::SetLocalizer {
                lat_deg: 41.0,
                lon_deg: -8.0,
                course_deg: 90.0,
                glide_slope_deg: Some(12.0),
            },
            Command::SetLocalizer {
                lat_deg: 41.0,
                lon_deg: -8.0,
                course_deg: 90.0,
                glide_slope_deg: None,
            },
            Command::Cutdown,
            Command::RequestMessage { message_id: 242 },
            Command::SetMessageInterval {
                message_id: 33,
                interval_us: 200_000,
            },
        ]
    }

    #[test]
    fn every_command_round_trips() {
        for c in all_commands() {
            let back = Command::from_mavlink(&c.to_mavlink(1, 1, 0))
                .expect("a command")
                .expect("decodes");
            match (c, back) {
                (
                    Command::SetLocalizer { course_deg: a, .. },
                    Command::SetLocalizer { course_deg: b, .. },
                ) => {
                    assert!((a - b).abs() < 1e-4, "{a} {b}")
                }
                (
                    Command::SetLandingTarget { lat_deg: a, .. },
                    Command::SetLandingTarget { lat_deg: b, .. },
                ) => {
                    assert!((a - b).abs() < 1e-7);
                }
                _ => assert_eq!(c, back),
            }
        }
    }

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
