//! Keeping the guidance replica on the plan the drone actually flies.
//!
//! The replica is only as good as its plan: a station that starts after the drone, restarts,
//! or shares the drone with another ground station does not know the target the drone was
//! loaded with. So the drone is the authority:
//! - its plan is downloaded (MAVLink mission protocol) when its heartbeat (re)appears, after
//!   every accepted plan-changing command, and whenever its guidance telemetry disagrees with
//!   the replica; the download is applied with the same mapping the drone applies to an upload
//!   (`stx_gnc::plan_upload`);
//! - NAV_CONTROLLER_OUTPUT (bearing and distance to the target, whole degrees and metres, from
//!   the drone's own position in GLOBAL_POSITION_INT) gives the target at once, to within
//!   about 1 % of the distance: the replica uses it until a download succeeds, and when
//!   downloads keep failing; in heading and course modes its desired heading is the plan's
//!   heading or course;
//! - until one of them has spoken, the target is unknown and shown as such (never as the
//!   station's origin).
//!
//! Failed downloads are retried with a growing delay so a drone that does not hold plans is
//! not asked at every telemetry burst.

use nalgebra::Vector3;
use stx_gnc::guidance::Plan;
use stx_gnc::mission::FlightMode;
use stx_gnc::plan_upload::{LineChange, apply};
use stx_link::plan::PlanItem;
use stx_link::telemetry::GuidanceStatus;

use super::StationCore;
use super::actions::{APPLY_WITHIN_S, ActionId, LinkOp, Purpose};
use crate::messages::Level;

/// Where the replica's landing target comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TargetSource {
    /// Downloaded from the drone: exactly what it flies.
    DronePlan,
    /// Worked out from the drone's guidance telemetry (bearing and distance to its target).
    DroneTelemetry,
    /// An operator's command the drone acknowledged (a download confirms it).
    Operator,
}

impl TargetSource {
    /// The name in the `state` message.
    pub fn name(self) -> &'static str {
        match self {
            Self::DronePlan => "drone_plan",
            Self::DroneTelemetry => "drone_telemetry",
            Self::Operator => "operator",
        }
    }
}

/// Seconds before a download is asked again after the guidance telemetry disagreed.
const MISMATCH_RETRY_S: f64 = 10.0;
/// First delay after a failed download, s; doubled at each failure up to [`MAX_RETRY_S`].
const FIRST_RETRY_S: f64 = 5.0;
const MAX_RETRY_S: f64 = 60.0;
/// A download not answered in this long is taken as lost, s (the link's own retries end
/// well before).
const DOWNLOAD_LOST_S: f64 = 30.0;
/// Failed downloads after which the guidance telemetry's target is adopted over a
/// downloaded one.
const TRUST_TELEMETRY_AFTER_FAILURES: u32 = 2;
/// GLOBAL_POSITION_INT older than this is not used with NAV_CONTROLLER_OUTPUT, s.
const POSITION_FRESH_S: f64 = 1.0;

/// The plan download's progress and what the replica knows.
#[derive(Debug, Clone, Default)]
pub(crate) struct PlanSync {
    /// A download is due.
    wanted: bool,
    /// Not before this mission time, s.
    not_before_s: f64,
    /// The running download's link action and the mission time it was asked, s.
    in_flight: Option<(ActionId, f64)>,
    /// Downloads failed in a row.
    failures: u32,
    /// Mission time of the last download asked because of a telemetry mismatch, s.
    last_mismatch_s: Option<f64>,
    /// Where the target comes from; `None`: unknown.
    pub target: Option<TargetSource>,
    /// The localizer line is the drone's (downloaded or acknowledged).
    pub line_known: bool,
    /// At least one download succeeded.
    pub downloaded: bool,
}

fn close(a: f64, b: f64, tolerance: f64) -> bool {
    (a - b).abs() <= tolerance
}

fn close_angle(a: f64, b: f64, tolerance_rad: f64) -> bool {
    stx_dynamics::rotation::wrap_pi(a - b).abs() <= tolerance_rad
}

/// Whether two plans fly the same within the wire's quantisation (degE7, f32 altitude).
fn same_plan(a: &Plan, b: &Plan) -> bool {
    let optional = |x: Option<f64>, y: Option<f64>, f: &dyn Fn(f64, f64) -> bool| match (x, y) {
        (None, None) => true,
        (Some(x), Some(y)) => f(x, y),
        _ => false,
    };
    (a.target_ned_m - b.target_ned_m).norm() < 0.5
        && optional(a.approach_course_rad, b.approach_course_rad, &|x, y| {
            close_angle(x, y, 1e-3)
        })
        && close_angle(a.heading_rad, b.heading_rad, 1e-3)
        && close_angle(a.course_rad, b.course_rad, 1e-3)
        && close(a.localizer.point_ne_m[0], b.localizer.point_ne_m[0], 0.5)
        && close(a.localizer.point_ne_m[1], b.localizer.point_ne_m[1], 0.5)
        && close_angle(a.localizer.course_rad, b.localizer.course_rad, 1e-3)
        && optional(a.localizer_glide_slope, b.localizer_glide_slope, &|x, y| {
            close(x, y, 1e-3)
        })
}

impl StationCore {
    /// Asks for the drone's plan as soon as the link allows.
    pub(crate) fn want_plan_download(&mut self, now_s: f64) {
        let s = &mut self.sync;
        s.wanted = true;
        s.not_before_s = s.not_before_s.min(now_s);
    }

    /// Queues the download when it is due (not while an operator's upload waits for the
    /// link: the operator goes first).
    pub(crate) fn schedule_plan_download(&mut self, now_s: f64, upload_waiting: bool) {
        let s = &mut self.sync;
        if let Some((_, since)) = s.in_flight
            && now_s - since > DOWNLOAD_LOST_S
        {
            s.in_flight = None;
        }
        if s.wanted && s.in_flight.is_none() && now_s >= s.not_before_s && !upload_waiting {
            s.wanted = false;
            let id = self.outbox.issue(
                now_s,
                LinkOp::PlanDownload,
                Purpose::PlanDownload,
                APPLY_WITHIN_S,
            );
            self.sync.in_flight = Some((id, now_s));
        }
    }

    /// The link did not start download `id` (another plan transfer is running): try again
    /// shortly.
    pub(crate) fn plan_download_refused(&mut self, now_s: f64, id: ActionId, reason: &str) {
        let s = &mut self.sync;
        if s.in_flight.is_none_or(|(running, _)| running != id) {
            return;
        }
        tracing::debug!(reason, "plan download postponed");
        s.in_flight = None;
        s.wanted = true;
        s.not_before_s = now_s + 1.0;
    }

    pub(crate) fn on_plan_download_failed(&mut self, now_s: f64, reason: &str) {
        let s = &mut self.sync;
        s.in_flight = None;
        s.failures += 1;
        let delay = (FIRST_RETRY_S * 2_f64.powi(s.failures as i32 - 1)).min(MAX_RETRY_S);
        s.wanted = true;
        s.not_before_s = now_s + delay;
        let failures = s.failures;
        if failures == 1 {
            self.log(
                now_s,
                Level::Warning,
                "station",
                format!(
                    "the drone's plan could not be read ({reason}): the map's target and \
                     pattern follow its guidance telemetry; retrying"
                ),
            );
        }
    }

    /// The plan the drone holds: the replica adopts it with the drone's own mapping.
    pub(crate) fn on_plan_downloaded(&mut self, now_s: f64, items: &[PlanItem]) {
        let points: Vec<_> = items.iter().map(|i| i.to_local(&self.frame)).collect();
        let update = apply(self.guidance.plan(), &points);
        let s = &mut self.sync;
        s.in_flight = None;
        s.failures = 0;
        s.downloaded = true;
        let was = (s.target, s.line_known);
        s.target = update.target_set.then_some(TargetSource::DronePlan);
        s.line_known = update.line == LineChange::Set;
        let changed = !same_plan(self.guidance.plan(), &update.plan);
        if changed {
            self.set_replica_plan(now_s, update.plan);
        }
        if changed || was.0.is_none() != update.target_set {
            let t = update.plan.target_ned_m;
            let target = if update.target_set {
                format!("target {:.0} m N {:.0} m E of the origin", t.x, t.y)
            } else {
                "no landing target".to_string()
            };
            self.log(
                now_s,
                Level::Info,
                "station",
                format!(
                    "read the drone's plan ({} items): {target}{}",
                    items.len(),
                    if update.line == LineChange::Set {
                        ", a localizer line"
                    } else {
                        ""
                    }
                ),
            );
        }
    }

    pub(crate) fn set_replica_plan(&mut self, now_s: f64, plan: Plan) {
        self.guidance
            .set_plan(plan, self.drone_time_s.unwrap_or(now_s));
    }

    /// NAV_CONTROLLER_OUTPUT: checks the replica against what the drone's guidance is after.
    pub(crate) fn on_guidance_status(&mut self, now_s: f64, g: GuidanceStatus) {
        let mode = self.vehicle_mode();
        let mut plan = *self.guidance.plan();
        let mut mismatch = false;
        match mode {
            FlightMode::Heading | FlightMode::Course => {
                let desired = g.desired_heading_deg.to_radians();
                let held = if mode == FlightMode::Heading {
                    &mut plan.heading_rad
                } else {
                    &mut plan.course_rad
                };
                // Whole degrees on the wire.
                if !close_angle(*held, desired, 0.6_f64.to_radians()) {
                    *held = desired;
                    self.set_replica_plan(now_s, plan);
                }
            }
            FlightMode::Localizer => {
                let desired = g.desired_heading_deg.to_radians();
                if !self.sync.line_known
                    || !close_angle(plan.localizer.course_rad, desired, 0.6_f64.to_radians())
                {
                    mismatch = true;
                }
            }
            _ => {}
        }
        if let Some(implied) = self.target_from_guidance(now_s, &g) {
            match implied {
                None => mismatch |= self.sync.target.is_some(),
                Some(target) => {
                    let distance = g.distance_to_target_m;
                    // Whole degrees of bearing (±0.5°), whole metres, and the vehicle's motion
                    // between the two messages of one burst.
                    let tolerance = 10.0 + distance * 0.6_f64.to_radians().tan();
                    let known = self.sync.target.is_some();
                    let off = (plan.target_ned_m.xy() - target.xy()).norm();
                    if !known || off > tolerance {
                        mismatch = true;
                        // A read plan is exact: only failing downloads make the coarser
                        // telemetry win over it.
                        let trust_telemetry = self.sync.target != Some(TargetSource::DronePlan)
                            || self.sync.failures >= TRUST_TELEMETRY_AFTER_FAILURES;
                        if trust_telemetry {
                            plan.target_ned_m = target;
                            self.sync.target = Some(TargetSource::DroneTelemetry);
                            self.set_replica_plan(now_s, plan);
                        }
                    }
                }
            }
        }
        if mismatch
            && self
                .sync
                .last_mismatch_s
                .is_none_or(|t| now_s - t >= MISMATCH_RETRY_S)
        {
            self.sync.last_mismatch_s = Some(now_s);
            self.want_plan_download(now_s);
        }
    }

    /// The target the guidance telemetry points at: `Some(None)` when the drone says it has
    /// none (distance 0), `None` when it cannot be worked out (no recent position).
    fn target_from_guidance(&self, now_s: f64, g: &GuidanceStatus) -> Option<Option<Vector3<f64>>> {
        if g.distance_to_target_m <= 0.0 {
            return Some(None);
        }
        let (p, at) = self.latest.position?;
        if now_s - at > POSITION_FRESH_S {
            return None;
        }
        let here = self.frame.to_ned(p.lat_deg, p.lon_deg, p.alt_msl_m);
        let bearing = g.bearing_to_target_deg.to_radians();
        let down = if self.sync.target.is_some() {
            self.guidance.plan().target_ned_m.z
        } else {
            0.0
        };
        Some(Some(Vector3::new(
            here.x + g.distance_to_target_m * bearing.cos(),
            here.y + g.distance_to_target_m * bearing.sin(),
            down,
        )))
    }

    /// Whether the replica knows what the drone's mode steers to.
    pub(crate) fn plan_known_for(&self, mode: FlightMode) -> bool {
        match mode {
            FlightMode::SpiralLanding => self.sync.target.is_some(),
            FlightMode::Localizer => self.sync.line_known,
            _ => true,
        }
    }
}
