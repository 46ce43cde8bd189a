//! What a command is and how it travels: [`Command`], the vehicle's answer
//! ([`CommandResult`], MAV_RESULT), why a received command is refused
//! ([`CommandDecodeError`]), and the COMMAND_LONG / COMMAND_INT mapping tabled in the
//! [module documentation](super).

use mavlink::dialects::common as mc;
use mavlink::dialects::common::{MavCmd, MavMessage};
use serde::{Deserialize, Serialize};
use stx_types::mission::FlightMode;

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
    /// The wind measured at the ground by the landing target (a mast anemometer's mean, or
    /// the operator's reading): its speed, m/s, where it blows from, degrees true, and how
    /// long ago it was measured when sent, s.
    SetSurfaceWind {
        speed_mps: f64,
        from_deg: f64,
        age_s: f64,
    },
}

/// Most surface wind a command carries, m/s: far beyond what a parafoil lands in, so only a
/// broken value is refused.
pub const SURFACE_WIND_MAX_MPS: f64 = 60.0;
/// Oldest surface wind a command carries, s.
pub const SURFACE_WIND_MAX_AGE_S: f64 = 3600.0;

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
            Self::SetSurfaceWind { .. } => MavCmd::MAV_CMD_USER_1,
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
            Self::SetSurfaceWind {
                speed_mps,
                from_deg,
                age_s,
            } => long([
                speed_mps as f32,
                from_deg as f32,
                age_s as f32,
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
            MavCmd::MAV_CMD_USER_1 => {
                let speed = c.param1;
                if !(speed.is_finite() && (0.0..=SURFACE_WIND_MAX_MPS as f32).contains(&speed)) {
                    return Err(bad(1, speed));
                }
                let age = c.param3;
                if !(age.is_finite() && (0.0..=SURFACE_WIND_MAX_AGE_S as f32).contains(&age)) {
                    return Err(bad(3, age));
                }
                Ok(Command::SetSurfaceWind {
                    speed_mps: f64::from(speed),
                    from_deg: finite_angle(command, 2, c.param2)?,
                    age_s: f64::from(age),
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
            Command::SetSurfaceWind {
                speed_mps: 3.5,
                from_deg: 247.5,
                age_s: 4.0,
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
    fn a_surface_wind_out_of_range_is_refused_naming_the_parameter() {
        let refused = |speed_mps, from_deg, age_s| {
            let c = Command::SetSurfaceWind {
                speed_mps,
                from_deg,
                age_s,
            };
            match Command::from_mavlink(&c.to_mavlink(1, 1, 0)) {
                Some(Err(CommandDecodeError::InvalidParam { param, .. })) => param,
                other => panic!("{c:?} decoded as {other:?}"),
            }
        };
        assert_eq!(refused(-1.0, 90.0, 0.0), 1);
        assert_eq!(refused(f64::NAN, 90.0, 0.0), 1);
        assert_eq!(refused(SURFACE_WIND_MAX_MPS + 1.0, 90.0, 0.0), 1);
        assert_eq!(refused(3.0, f64::INFINITY, 0.0), 2);
        assert_eq!(refused(3.0, 400.0, 0.0), 2);
        assert_eq!(refused(3.0, 90.0, -5.0), 3);
        assert_eq!(refused(3.0, 90.0, SURFACE_WIND_MAX_AGE_S + 1.0), 3);
        // A direction of −90° is where 270° is.
        let back = Command::from_mavlink(
            &Command::SetSurfaceWind {
                speed_mps: 2.0,
                from_deg: -90.0,
                age_s: 0.0,
            }
            .to_mavlink(1, 1, 0),
        );
        assert!(
            matches!(back, Some(Ok(Command::SetSurfaceWind { from_deg, .. })) if from_deg == 270.0)
        );
    }
}
