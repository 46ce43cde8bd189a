//! Operators' requests and their outcomes: request ids, what goes on the link, the answers
//! that come back (COMMAND_ACK, PARAM_VALUE, MISSION_ACK) turned into `command_result`s, the
//! parameter table, and the cutdown's arm-then-confirm.

use std::collections::{BTreeMap, HashMap};

use nalgebra::Vector3;
use stx_gnc::control::Localizer;
use stx_gnc::geo::LocalFrame;
use stx_gnc::mission::FlightMode;
use stx_gnc::plan_upload::PlanPoint;
use stx_link::command::{Command, CommandEvent, CommandOutcome, CommandResult, RequestId};
use stx_link::param::{ParamEvent, ParamValue};
use stx_link::plan::{PlanEvent, PlanItem};

use crate::messages::{CommandResultMsg, Outcome};

/// An operator's request, checked.
#[derive(Debug, Clone, PartialEq)]
pub enum CommandRequest {
    /// Select a mode.
    Mode(FlightMode),
    /// Heading for heading mode, degrees.
    Heading { heading_deg: f64 },
    /// Course for course mode, degrees.
    Course { course_deg: f64 },
    /// Localizer through a point with a course and optional glide slope (sink over ground
    /// speed).
    Localizer {
        lat_deg: f64,
        lon_deg: f64,
        course_deg: f64,
        glide_slope: Option<f64>,
    },
    /// Landing target.
    Target {
        lat_deg: f64,
        lon_deg: f64,
        alt_msl_m: f64,
        approach_course_deg: Option<f64>,
    },
    /// A guidance plan (waypoints and a landing).
    Plan(Vec<PlanItem>),
    /// Set a parameter.
    ParamSet { name: String, value: f64 },
}

/// What the daemon must do on the link.
#[derive(Debug, Clone, PartialEq)]
pub enum LinkAction {
    /// Send a command (retried by the link until acknowledged).
    Command {
        request_id: RequestId,
        command: Command,
    },
    /// Set a parameter (retried until echoed).
    ParamSet { name: String, value: f32 },
    /// Upload a plan.
    PlanUpload(Vec<PlanItem>),
    /// Read the plan the drone holds (the station's own initiative, no request id).
    PlanDownload,
}

/// A refusal of a request, as the HTTP layer answers it.
#[derive(Debug, Clone, PartialEq)]
pub struct ApiError {
    /// HTTP status.
    pub status: u16,
    /// Machine-readable kind.
    pub error: &'static str,
    /// For people.
    pub reason: String,
}

impl ApiError {
    /// 400 with a reason naming the field.
    pub fn bad_request(reason: impl Into<String>) -> Self {
        Self {
            status: 400,
            error: "bad_request",
            reason: reason.into(),
        }
    }
}

/// An armed cutdown, as `POST /api/cutdown/arm` answers it.
#[derive(Debug, Clone, PartialEq, serde::Serialize, schemars::JsonSchema)]
pub struct CutdownArm {
    /// The id to confirm with.
    pub arm_id: String,
    /// Seconds left to confirm.
    pub expires_in_s: f64,
}

/// A plan change the guidance replica adopts once the drone accepts it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum PlanChange {
    Target {
        target_ned_m: Vector3<f64>,
        approach_course_rad: Option<f64>,
    },
    Heading(f64),
    Course(f64),
    Localizer {
        line: Localizer,
        glide_slope: Option<f64>,
    },
    /// An uploaded plan, applied with the drone's own mapping (`stx_gnc::plan_upload`).
    Upload(Vec<PlanPoint>),
}

#[derive(Debug, Clone)]
struct Record {
    result: CommandResultMsg,
    plan_change: Option<PlanChange>,
}

#[derive(Debug, Clone)]
struct Armed {
    arm_id: String,
    until_s: f64,
    by: String,
}

/// Parameter metadata the station knows (the wire only carries names and values).
#[derive(Debug, Clone, Default)]
pub(crate) struct Table {
    pub values: BTreeMap<String, ParamValue>,
    pub complete: bool,
}

/// Every request and the parameter table.
#[derive(Debug)]
pub(crate) struct Commands {
    next: u64,
    records: HashMap<String, Record>,
    by_link_id: HashMap<u64, String>,
    param_sets: HashMap<String, String>,
    plan_request: Option<(String, Option<PlanChange>)>,
    pub table: Table,
    armed: Option<Armed>,
    window_s: f64,
    next_arm: u64,
}

fn check_finite(name: &str, v: f64) -> Result<f64, super::ApiError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(ApiError::bad_request(format!(
            "{name} must be a finite number"
        )))
    }
}

fn check_lat_lon(lat: f64, lon: f64) -> Result<(), super::ApiError> {
    if !(lat.is_finite() && lat.abs() <= 90.0) {
        return Err(ApiError::bad_request("lat_deg must be within ±90°"));
    }
    if !(lon.is_finite() && lon.abs() <= 180.0) {
        return Err(ApiError::bad_request("lon_deg must be within ±180°"));
    }
    Ok(())
}

fn mode_name(mode: FlightMode) -> String {
    serde_json::to_value(mode)
        .ok()
        .and_then(|v| v.as_str().map(String::from))
        .unwrap_or_else(|| format!("{mode:?}"))
}

impl Commands {
    pub fn new(window_s: f64) -> Self {
        Self {
            next: 1,
            records: HashMap::new(),
            by_link_id: HashMap::new(),
            param_sets: HashMap::new(),
            plan_request: None,
            table: Table::default(),
            armed: None,
            window_s,
            next_arm: 1,
        }
    }

    fn new_id(&mut self) -> (String, RequestId) {
        let n = self.next;
        self.next += 1;
        (format!("r{n}"), RequestId(n))
    }

    fn record(&mut self, id: &str, command: &str, plan_change: Option<PlanChange>) {
        self.records.insert(
            id.to_string(),
            Record {
                result: CommandResultMsg {
                    kind: "command_result",
                    request_id: id.to_string(),
                    command: command.to_string(),
                    outcome: Outcome::InProgress,
                    attempts: 0,
                    detail: "sent".into(),
                    value: None,
                },
                plan_change,
            },
        );
    }

    /// Checks a request and turns it into a link action; returns the request id, the action
    /// and a sentence for the log.
    pub fn request(
        &mut self,
        _now_s: f64,
        frame: &LocalFrame,
        request: CommandRequest,
    ) -> Result<(String, LinkAction, String), ApiError> {
        let (command, change, name, text) = match request {
            CommandRequest::ParamSet { name, value } => {
                let value = check_finite("value", value)?;
                if name.is_empty() || name.len() > 16 || !name.is_ascii() {
                    return Err(ApiError::bad_request(
                        "parameter names are 1–16 ASCII characters",
                    ));
                }
                // The drone would refuse it too, but saying so here spares a round trip
                // over a slow radio and names the range.
                if let Some(def) = stx_gnc::params::find(&name) {
                    def.check(value)
                        .map_err(|e| ApiError::bad_request(e.to_string()))?;
                }
                if !self.table.values.is_empty() && !self.table.values.contains_key(&name) {
                    return Err(ApiError {
                        status: 404,
                        error: "not_found",
                        reason: format!("the drone has no parameter `{name}`"),
                    });
                }
                let (id, _) = self.new_id();
                self.record(&id, "set_param", None);
                self.param_sets.insert(name.clone(), id.clone());
                let text = format!("set parameter {name} = {value}");
                return Ok((
                    id,
                    LinkAction::ParamSet {
                        name,
                        value: value as f32,
                    },
                    text,
                ));
            }
            CommandRequest::Plan(items) => {
                if items.is_empty() {
                    return Err(ApiError::bad_request("items must not be empty"));
                }
                if items.len() > usize::from(stx_link::plan::MAX_PLAN_ITEMS) {
                    return Err(ApiError::bad_request(format!(
                        "items: at most {} items",
                        stx_link::plan::MAX_PLAN_ITEMS
                    )));
                }
                for item in &items {
                    let (lat, lon, alt, approach) = match *item {
                        PlanItem::Waypoint {
                            lat_deg,
                            lon_deg,
                            alt_msl_m,
                        } => (lat_deg, lon_deg, alt_msl_m, None),
                        PlanItem::Land {
                            lat_deg,
                            lon_deg,
                            alt_msl_m,
                            approach_heading_deg,
                        } => (lat_deg, lon_deg, alt_msl_m, approach_heading_deg),
                    };
                    check_lat_lon(lat, lon)?;
                    check_finite("alt_msl_m", alt)?;
                    if let Some(a) = approach {
                        check_finite("approach_course_deg", a)?;
                    }
                }
                let change = Some(PlanChange::Upload(
                    items.iter().map(|i| i.to_local(frame)).collect(),
                ));
                let (id, _) = self.new_id();
                self.record(&id, "set_plan", None);
                let text = format!("upload a plan of {} items", items.len());
                self.plan_request = Some((id.clone(), change));
                return Ok((id, LinkAction::PlanUpload(items), text));
            }
            CommandRequest::Mode(mode) => (
                Command::SetMode(mode),
                None,
                "set_mode",
                format!("mode → {}", mode_name(mode)),
            ),
            CommandRequest::Heading { heading_deg } => {
                let h = check_finite("heading_deg", heading_deg)?.rem_euclid(360.0);
                (
                    Command::HoldHeading { heading_deg: h },
                    Some(PlanChange::Heading(h.to_radians())),
                    "set_heading",
                    format!("heading → {h:.0}°"),
                )
            }
            CommandRequest::Course { course_deg } => {
                let c = check_finite("course_deg", course_deg)?.rem_euclid(360.0);
                (
                    Command::HoldCourse { course_deg: c },
                    Some(PlanChange::Course(c.to_radians())),
                    "set_course",
                    format!("course → {c:.0}°"),
                )
            }
            CommandRequest::Localizer {
                lat_deg,
                lon_deg,
                course_deg,
                glide_slope,
            } => {
                check_lat_lon(lat_deg, lon_deg)?;
                let c = check_finite("course_deg", course_deg)?.rem_euclid(360.0);
                if let Some(s) = glide_slope
                    && !(s > 0.0 && s < 10.0)
                {
                    return Err(ApiError::bad_request("glide_slope must be in (0, 10)"));
                }
                let p = frame.to_ned(lat_deg, lon_deg, frame.alt_msl_m);
                (
                    Command::SetLocalizer {
                        lat_deg,
                        lon_deg,
                        course_deg: c,
                        glide_slope_deg: glide_slope.map(|s| s.atan().to_degrees()),
                    },
                    Some(PlanChange::Localizer {
                        line: Localizer {
                            point_ne_m: [p.x, p.y],
                            course_rad: c.to_radians(),
                        },
                        glide_slope,
                    }),
                    "set_localizer",
                    format!("localizer → {c:.0}° through {lat_deg:.5}, {lon_deg:.5}"),
                )
            }
            CommandRequest::Target {
                lat_deg,
                lon_deg,
                alt_msl_m,
                approach_course_deg,
            } => {
                check_lat_lon(lat_deg, lon_deg)?;
                check_finite("alt_msl_m", alt_msl_m)?;
                if let Some(a) = approach_course_deg {
                    check_finite("approach_course_deg", a)?;
                }
                (
                    Command::SetLandingTarget {
                        lat_deg,
                        lon_deg,
                        alt_msl_m,
                        approach_heading_deg: approach_course_deg.map(|a| a.rem_euclid(360.0)),
                    },
                    Some(PlanChange::Target {
                        target_ned_m: frame.to_ned(lat_deg, lon_deg, alt_msl_m),
                        approach_course_rad: approach_course_deg.map(f64::to_radians),
                    }),
                    "set_target",
                    format!(
                        "landing target → {lat_deg:.5}, {lon_deg:.5}, approach {}",
                        approach_course_deg
                            .map_or("into the wind".to_string(), |a| format!("{a:.0}°"))
                    ),
                )
            }
        };
        let (id, link_id) = self.new_id();
        self.record(&id, name, change);
        self.by_link_id.insert(link_id.0, id.clone());
        Ok((
            id,
            LinkAction::Command {
                request_id: link_id,
                command,
            },
            text,
        ))
    }

    /// A command could not even be queued on the link (another of the same kind is waiting).
    pub fn refuse(&mut self, id: &str, reason: String) -> Option<CommandResultMsg> {
        let r = self.records.get_mut(id)?;
        r.result.outcome = Outcome::Failed;
        r.result.detail = reason;
        Some(r.result.clone())
    }

    pub fn on_command_event(&mut self, _now_s: f64, e: &CommandEvent) -> Option<CommandResultMsg> {
        let id = self.by_link_id.get(&e.request_id.0)?.clone();
        let r = self.records.get_mut(&id)?;
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
                (outcome, format!("the drone answered {result:?}"))
            }
        };
        r.result.outcome = outcome;
        r.result.detail = detail;
        if outcome != Outcome::InProgress {
            self.by_link_id.remove(&e.request_id.0);
        }
        Some(r.result.clone())
    }

    /// Parameter events: finished writes as results, and whether the table changed.
    pub fn on_param_event(&mut self, e: &ParamEvent) -> (Vec<CommandResultMsg>, bool) {
        let mut results = Vec::new();
        let mut changed = false;
        let store = |table: &mut Table, p: &ParamValue| {
            table.values.insert(p.name.clone(), p.clone());
            if table.values.len() >= usize::from(p.count) {
                table.complete = true;
            }
        };
        match e {
            ParamEvent::ListComplete { params } => {
                for p in params {
                    store(&mut self.table, p);
                }
                self.table.complete = true;
                changed = true;
            }
            ParamEvent::ListFailed { received, .. } => {
                for p in received {
                    store(&mut self.table, p);
                }
                changed = true;
            }
            ParamEvent::ReadDone { param } | ParamEvent::Value { param } => {
                store(&mut self.table, param);
                changed = true;
            }
            ParamEvent::ReadFailed { .. } => {}
            ParamEvent::SetDone {
                name,
                requested,
                actual,
                accepted,
            } => {
                if let Some(p) = self.table.values.get_mut(name) {
                    p.value = *actual;
                    changed = true;
                }
                if let Some(id) = self.param_sets.remove(name)
                    && let Some(r) = self.records.get_mut(&id)
                {
                    r.result.attempts = r.result.attempts.max(1);
                    r.result.value = Some(f64::from(*actual));
                    if *accepted {
                        r.result.outcome = Outcome::Accepted;
                        r.result.detail = format!("{name} = {actual} read back from the drone");
                    } else {
                        r.result.outcome = Outcome::Denied;
                        r.result.detail = format!(
                            "the drone kept {name} = {actual} (asked {requested}: out of range)"
                        );
                    }
                    results.push(r.result.clone());
                }
            }
            ParamEvent::SetFailed { name, attempts, .. } => {
                if let Some(id) = self.param_sets.remove(name)
                    && let Some(r) = self.records.get_mut(&id)
                {
                    r.result.attempts = u32::from(*attempts);
                    r.result.outcome = Outcome::TimedOut;
                    r.result.detail = format!("no PARAM_VALUE after {attempts} attempts");
                    results.push(r.result.clone());
                }
            }
        }
        (results, changed)
    }

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
        let (id, change) = self.plan_request.take()?;
        let r = self.records.get_mut(&id)?;
        r.result.outcome = outcome;
        r.result.detail = detail;
        r.result.attempts = r.result.attempts.max(1);
        if outcome == Outcome::Accepted {
            r.plan_change = change;
        }
        Some(r.result.clone())
    }

    /// The plan change of an accepted request, once.
    pub fn take_accepted_plan(&mut self, id: &str) -> Option<PlanChange> {
        self.records.get_mut(id)?.plan_change.take()
    }

    pub fn result(&self, id: &str) -> Option<CommandResultMsg> {
        self.records.get(id).map(|r| r.result.clone())
    }

    pub fn pending(&self) -> HashMap<String, String> {
        self.records
            .iter()
            .filter(|(_, r)| r.result.outcome == Outcome::InProgress)
            .map(|(id, r)| (id.clone(), r.result.command.clone()))
            .collect()
    }

    pub fn arm_cutdown(&mut self, now_s: f64, who: &str) -> CutdownArm {
        // Unpredictable enough that a stale page cannot confirm someone else's arming.
        let n = self.next_arm;
        self.next_arm += 1;
        let salt = (now_s.to_bits() ^ 0x9E37_79B9_7F4A_7C15).rotate_left((n % 63) as u32);
        let arm_id = format!("arm-{n}-{salt:016x}");
        self.armed = Some(Armed {
            arm_id: arm_id.clone(),
            until_s: now_s + self.window_s,
            by: who.to_string(),
        });
        CutdownArm {
            arm_id,
            expires_in_s: self.window_s,
        }
    }

    pub fn confirm_cutdown(
        &mut self,
        now_s: f64,
        who: &str,
        arm_id: &str,
    ) -> Result<(String, LinkAction), ApiError> {
        let not_armed = |reason: &str| ApiError {
            status: 409,
            error: "not_armed",
            reason: reason.to_string(),
        };
        let Some(armed) = self.armed.take() else {
            return Err(not_armed("the cutdown is not armed: arm it first"));
        };
        if now_s > armed.until_s {
            return Err(not_armed("the arming expired: arm it again"));
        }
        if armed.arm_id != arm_id {
            self.armed = Some(armed);
            return Err(not_armed("that is not the current arming"));
        }
        if armed.by != who {
            tracing::warn!(armed_by = %armed.by, confirmed_by = who, "cutdown confirmed by another operator");
        }
        let (id, link_id) = self.new_id();
        self.record(&id, "cutdown", None);
        self.by_link_id.insert(link_id.0, id.clone());
        Ok((
            id,
            LinkAction::Command {
                request_id: link_id,
                command: Command::Cutdown,
            },
        ))
    }

    /// Drops an arming whose window has passed; the sentence for the log.
    pub fn expire_cutdown(&mut self, now_s: f64) -> Option<String> {
        if self.armed.as_ref().is_some_and(|a| now_s > a.until_s) {
            let a = self.armed.take()?;
            return Some(format!("cutdown armed by {} expired unconfirmed", a.by));
        }
        None
    }

    pub fn armed_until(&self) -> Option<f64> {
        self.armed.as_ref().map(|a| a.until_s)
    }
}
