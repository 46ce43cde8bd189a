//! The operator's commands and plan uploads (see the parent module's table), and the plan
//! held, as mission items.

use nalgebra::Vector3;
use stx_dynamics::rotation::wrap_pi;
use stx_gnc::control::Localizer;
use stx_gnc::guidance::SurfaceWind;
use stx_gnc::mission::FlightMode;
use stx_link::command::{Command, CommandResult};
use stx_link::plan::{FenceItem, PlanItem, fence_to_zones};
use stx_link::telemetry::Severity;

use super::{Onboard, mode_name};

impl Onboard {
    /// Executes an operator command (all but cutdown and the telemetry requests, which the
    /// drone handles itself); the result goes back in COMMAND_ACK, the reason of a refusal to
    /// the operator's log.
    pub fn handle_command(&mut self, time_s: f64, command: &Command) -> CommandResult {
        match *command {
            Command::SetMode(mode) => {
                let refusal = match mode {
                    FlightMode::Manual if self.sticks.is_none() => Some((
                        CommandResult::TemporarilyRejected,
                        "manual refused: no stick input (hold the dead-man first)",
                    )),
                    FlightMode::SpiralLanding if !self.has_target => Some((
                        CommandResult::Denied,
                        "spiral landing refused: no landing target",
                    )),
                    FlightMode::Localizer if !self.has_localizer => Some((
                        CommandResult::Denied,
                        "localizer refused: no localizer line",
                    )),
                    _ => None,
                };
                if let Some((result, why)) = refusal {
                    self.say(Severity::Warning, why.to_string());
                    return result;
                }
                if mode != self.mode() {
                    self.say(Severity::Info, format!("mode {}", mode_name(mode)));
                }
                self.select(mode, time_s);
                CommandResult::Accepted
            }
            Command::HoldHeading { heading_deg } => {
                let mut plan = *self.guidance.plan();
                plan.heading_rad = wrap_pi(heading_deg.to_radians());
                self.guidance.set_plan(plan, time_s);
                self.select(FlightMode::Heading, time_s);
                self.say(Severity::Info, format!("heading {heading_deg:.0}°"));
                CommandResult::Accepted
            }
            Command::HoldCourse { course_deg } => {
                let mut plan = *self.guidance.plan();
                plan.course_rad = wrap_pi(course_deg.to_radians());
                self.guidance.set_plan(plan, time_s);
                self.select(FlightMode::Course, time_s);
                self.say(Severity::Info, format!("course {course_deg:.0}°"));
                CommandResult::Accepted
            }
            Command::SetLandingTarget {
                lat_deg,
                lon_deg,
                alt_msl_m,
                approach_heading_deg,
            } => {
                let target = self.frame.to_ned(lat_deg, lon_deg, alt_msl_m);
                if !(target.iter().all(|v| v.is_finite()) && target.x.hypot(target.y) < 1.0e6) {
                    self.say(
                        Severity::Warning,
                        "landing target refused: more than 1000 km away".into(),
                    );
                    return CommandResult::Denied;
                }
                let mut plan = *self.guidance.plan();
                plan.target_ned_m = target;
                plan.approach_course_rad = approach_heading_deg.map(|d| wrap_pi(d.to_radians()));
                if let Err(e) = self.guidance.try_set_plan(plan, time_s) {
                    self.say(Severity::Warning, format!("landing target refused: {e}"));
                    return CommandResult::Denied;
                }
                self.has_target = true;
                self.say(
                    Severity::Info,
                    format!(
                        "landing target {lat_deg:.6} {lon_deg:.6} ({:.0} m N, {:.0} m E)",
                        target.x, target.y
                    ),
                );
                CommandResult::Accepted
            }
            Command::SetLocalizer {
                lat_deg,
                lon_deg,
                course_deg,
                glide_slope_deg,
            } => {
                let point = self.frame.to_ned(lat_deg, lon_deg, self.frame.alt_msl_m);
                if !(point.iter().all(|v| v.is_finite()) && point.x.hypot(point.y) < 1.0e6) {
                    self.say(
                        Severity::Warning,
                        "localizer refused: more than 1000 km away".into(),
                    );
                    return CommandResult::Denied;
                }
                let mut plan = *self.guidance.plan();
                plan.localizer = Localizer {
                    point_ne_m: [point.x, point.y],
                    course_rad: wrap_pi(course_deg.to_radians()),
                };
                plan.localizer_glide_slope = glide_slope_deg.map(|d| d.to_radians().tan());
                self.guidance.set_plan(plan, time_s);
                self.has_localizer = true;
                self.select(FlightMode::Localizer, time_s);
                self.say(Severity::Info, format!("localizer course {course_deg:.0}°"));
                CommandResult::Accepted
            }
            Command::SetSurfaceWind {
                speed_mps,
                from_deg,
                age_s,
            } => {
                let (north, east) = stx_types::wind::blowing_north_east_mps(speed_mps, from_deg);
                let wind = SurfaceWind {
                    ne_mps: [north, east],
                    time_s: time_s - age_s,
                };
                // Said once: the station sends a fresh mean every few seconds.
                if self.guidance.surface_wind().is_none() {
                    self.say(
                        Severity::Info,
                        format!("surface wind {speed_mps:.1} m/s from {from_deg:.0}°"),
                    );
                }
                self.guidance.set_surface_wind(Some(wind));
                CommandResult::Accepted
            }
            Command::Cutdown
            | Command::RequestMessage { .. }
            | Command::SetMessageInterval { .. } => CommandResult::Unsupported,
        }
    }

    /// Takes an uploaded plan (see the module documentation): the mapping of
    /// [`stx_gnc::plan_upload`], shared with the station's guidance replica.
    pub fn handle_plan(&mut self, time_s: f64, items: &[PlanItem]) {
        use stx_gnc::plan_upload::{LineChange, apply};
        let points: Vec<_> = items.iter().map(|i| i.to_local(&self.frame)).collect();
        let update = apply(self.guidance.plan(), &points);
        let plan = update.plan;
        if update.target_set
            && let Err(e) = plan.check_keep_out(self.guidance.keep_out())
        {
            // The upload is acknowledged (the protocol checks items, not their sense); the
            // plan in force is kept, and a download shows it.
            self.say(Severity::Warning, format!("plan refused: {e}"));
            return;
        }
        let mut said = Vec::new();
        if update.target_set {
            self.has_target = true;
            let target = plan.target_ned_m;
            said.push(format!("target {:.0} m N {:.0} m E", target.x, target.y));
        }
        match update.line {
            LineChange::Set => {
                self.has_localizer = true;
                said.push(format!(
                    "localizer course {:.0}°",
                    plan.localizer.course_rad.to_degrees().rem_euclid(360.0)
                ));
            }
            LineChange::PointsCoincide => {
                said.push("localizer points coincide: line ignored".into());
            }
            LineChange::None => {}
        }
        self.guidance.set_plan(plan, time_s);
        self.say(
            Severity::Info,
            format!("plan received ({} items): {}", items.len(), said.join(", ")),
        );
    }

    /// An uploaded keep-out fence: its polygons become guidance's zones in the mission's
    /// frame. A target already in force that now lies in a zone is kept (the operator is told
    /// and chooses another): dropping it would leave the drone without one.
    pub fn handle_fence(&mut self, items: &[FenceItem]) {
        let zones = match fence_to_zones(items, &self.frame) {
            Ok(zones) => zones,
            Err(e) => {
                self.say(Severity::Warning, format!("keep-out fence refused: {e}"));
                return;
            }
        };
        let n = zones.zones.len();
        let clash = self
            .has_target
            .then(|| self.guidance.plan().check_keep_out(&zones).err())
            .flatten();
        self.guidance.set_keep_out(zones);
        self.say(
            Severity::Info,
            format!("keep-out fence received: {n} zones"),
        );
        if let Some(e) = clash {
            self.say(Severity::Warning, format!("keep-out: {e}"));
        }
    }

    /// The plan held, as mission items (what a station's download returns).
    pub fn plan_items(&self) -> Vec<PlanItem> {
        let plan = self.guidance.plan();
        let mut items = Vec::new();
        if self.has_localizer {
            let l = plan.localizer;
            let along = Vector3::new(
                l.point_ne_m[0] + 1000.0 * l.course_rad.cos(),
                l.point_ne_m[1] + 1000.0 * l.course_rad.sin(),
                0.0,
            );
            let drop = plan.localizer_glide_slope.unwrap_or(0.0) * 1000.0;
            for (p, alt_offset) in [
                (Vector3::new(l.point_ne_m[0], l.point_ne_m[1], 0.0), drop),
                (along, 0.0),
            ] {
                let (lat_deg, lon_deg, alt_msl_m) = self.frame.to_geodetic(&p);
                items.push(PlanItem::Waypoint {
                    lat_deg,
                    lon_deg,
                    alt_msl_m: alt_msl_m + alt_offset,
                });
            }
        }
        if self.has_target {
            let (lat_deg, lon_deg, alt_msl_m) = self.frame.to_geodetic(&plan.target_ned_m);
            items.push(PlanItem::Land {
                lat_deg,
                lon_deg,
                alt_msl_m,
                approach_heading_deg: plan
                    .approach_course_rad
                    .map(|c| c.to_degrees().rem_euclid(360.0)),
            });
        }
        items
    }
}
