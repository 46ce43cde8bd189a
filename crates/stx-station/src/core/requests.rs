//! What operators may ask, checked before anything goes on the link: every number finite,
//! positions on the Earth, parameters within the onboard catalogue's ranges and known to the
//! drone, plans within the protocol's size. A checked request says what to send, what the
//! guidance replica adopts once the drone accepts it, and a sentence for the log.

use nalgebra::Vector3;
use stx_gnc::control::Localizer;
use stx_gnc::geo::LocalFrame;
use stx_gnc::keep_out::KeepOutZones;
use stx_gnc::mission::FlightMode;
use stx_gnc::plan_upload::PlanPoint;
use stx_link::command::Command;
use stx_link::plan::PlanItem;

use super::params::Table;

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

/// What a request sends.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Payload {
    Command(Command),
    ParamSet { name: String, value: f32 },
    Plan(Vec<PlanItem>),
}

/// A request ready to record and send.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Checked {
    /// The name in `command_result`.
    pub command: &'static str,
    pub payload: Payload,
    /// What the replica adopts once the drone accepts.
    pub change: Option<PlanChange>,
    /// For the log.
    pub text: String,
}

fn check_finite(name: &str, v: f64) -> Result<f64, ApiError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(ApiError::bad_request(format!(
            "{name} must be a finite number"
        )))
    }
}

fn check_lat_lon(lat: f64, lon: f64) -> Result<(), ApiError> {
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

/// A landing point inside a keep-out zone is refused, naming the zone.
fn check_clear(
    zones: &KeepOutZones,
    what: &str,
    frame: &LocalFrame,
    lat_deg: f64,
    lon_deg: f64,
) -> Result<(), ApiError> {
    let p = frame.to_ned(lat_deg, lon_deg, frame.alt_msl_m);
    match zones.zone_at([p.x, p.y]) {
        Some(zone) => Err(ApiError::bad_request(format!(
            "{what} inside keep-out zone '{}'",
            zone.name
        ))),
        None => Ok(()),
    }
}

/// Checks `request` against the frame, the keep-out zones and the drone's parameter table.
pub(crate) fn check(
    frame: &LocalFrame,
    zones: &KeepOutZones,
    table: &Table,
    request: CommandRequest,
) -> Result<Checked, ApiError> {
    let checked = |command, payload, change, text| Checked {
        command,
        payload,
        change,
        text,
    };
    Ok(match request {
        CommandRequest::ParamSet { name, value } => check_param_set(table, name, value)?,
        CommandRequest::Plan(items) => check_plan(frame, zones, items)?,
        CommandRequest::Mode(mode) => checked(
            "set_mode",
            Payload::Command(Command::SetMode(mode)),
            None,
            format!("mode → {}", mode_name(mode)),
        ),
        CommandRequest::Heading { heading_deg } => {
            let h = check_finite("heading_deg", heading_deg)?.rem_euclid(360.0);
            checked(
                "set_heading",
                Payload::Command(Command::HoldHeading { heading_deg: h }),
                Some(PlanChange::Heading(h.to_radians())),
                format!("heading → {h:.0}°"),
            )
        }
        CommandRequest::Course { course_deg } => {
            let c = check_finite("course_deg", course_deg)?.rem_euclid(360.0);
            checked(
                "set_course",
                Payload::Command(Command::HoldCourse { course_deg: c }),
                Some(PlanChange::Course(c.to_radians())),
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
            checked(
                "set_localizer",
                Payload::Command(Command::SetLocalizer {
                    lat_deg,
                    lon_deg,
                    course_deg: c,
                    glide_slope_deg: glide_slope.map(|s| s.atan().to_degrees()),
                }),
                Some(PlanChange::Localizer {
                    line: Localizer {
                        point_ne_m: [p.x, p.y],
                        course_rad: c.to_radians(),
                    },
                    glide_slope,
                }),
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
            check_clear(zones, "target", frame, lat_deg, lon_deg)?;
            checked(
                "set_target",
                Payload::Command(Command::SetLandingTarget {
                    lat_deg,
                    lon_deg,
                    alt_msl_m,
                    approach_heading_deg: approach_course_deg.map(|a| a.rem_euclid(360.0)),
                }),
                Some(PlanChange::Target {
                    target_ned_m: frame.to_ned(lat_deg, lon_deg, alt_msl_m),
                    approach_course_rad: approach_course_deg.map(f64::to_radians),
                }),
                format!(
                    "landing target → {lat_deg:.5}, {lon_deg:.5}, approach {}",
                    approach_course_deg.map_or("into the wind".to_string(), |a| format!("{a:.0}°"))
                ),
            )
        }
    })
}

fn check_param_set(table: &Table, name: String, value: f64) -> Result<Checked, ApiError> {
    let value = check_finite("value", value)?;
    if name.is_empty() || name.len() > 16 || !name.is_ascii() {
        return Err(ApiError::bad_request(
            "parameter names are 1–16 ASCII characters",
        ));
    }
    // The drone would refuse it too, but saying so here spares a round trip over a slow
    // radio and names the range.
    if let Some(def) = stx_gnc::params::find(&name) {
        def.check(value)
            .map_err(|e| ApiError::bad_request(e.to_string()))?;
    }
    if !table.values.is_empty() && !table.values.contains_key(&name) {
        return Err(ApiError {
            status: 404,
            error: "not_found",
            reason: format!("the drone has no parameter `{name}`"),
        });
    }
    Ok(Checked {
        command: "set_param",
        text: format!("set parameter {name} = {value}"),
        payload: Payload::ParamSet {
            name,
            value: value as f32,
        },
        change: None,
    })
}

fn check_plan(
    frame: &LocalFrame,
    zones: &KeepOutZones,
    items: Vec<PlanItem>,
) -> Result<Checked, ApiError> {
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
        // Flying over a zone is guidance's to avoid where it can; landing in one is refused.
        if matches!(item, PlanItem::Land { .. }) {
            check_clear(zones, "the plan's landing point", frame, lat, lon)?;
        }
    }
    Ok(Checked {
        command: "set_plan",
        text: format!("upload a plan of {} items", items.len()),
        change: Some(PlanChange::Upload(
            items.iter().map(|i| i.to_local(frame)).collect(),
        )),
        payload: Payload::Plan(items),
    })
}
