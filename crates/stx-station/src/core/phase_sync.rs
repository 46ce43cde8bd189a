//! Keeping the replica's guidance phase on the drone's, and saying so when they part.
//!
//! The replica runs the onboard guidance on the station's estimate, which, fed the drone's own
//! measurements (GPS_INPUT, ATTITUDE, SCALED_PRESSURE), is the onboard estimate to within the
//! wire's rounding. Its phase then changes with the drone's, a control period later (the
//! telemetry's delay). A decision taken right at its threshold can still fall the other way,
//! and a lossy link starves the station's estimator; the replica would then fly its own story
//! for a whole loop while the map draws it. So, while the drone's heartbeat is fresh:
//! - a disagreement of the phases is shown at once as an alarm on every page (which phases,
//!   since when on the mission clock, for how long) once it has lasted [`ALARM_AFTER_S`];
//! - after [`ADOPT_AFTER_S`] the replica takes the drone's phase (`Guidance::adopt_phase`) and
//!   the log says so; the alarm stays up, marked re-synchronised, for [`SHOW_RESOLVED_S`].
//!
//! With a stale link the drone's phase is old news: the replica flies on by itself, which is
//! the station's best guess of what the drone does, and nothing is compared.

use stx_gnc::mission::{FlightMode, GuidancePhase};

use super::StationCore;
use crate::messages::{DisagreementView, Level};

/// A disagreement shorter than this is a transition seen a control period apart: not shown, s
/// of the drone's clock.
pub const ALARM_AFTER_S: f64 = 1.0;
/// The replica takes the drone's phase after they have disagreed this long, s.
pub const ADOPT_AFTER_S: f64 = 2.0;
/// A resolved disagreement stays on the pages this long, s of the drone's clock.
pub const SHOW_RESOLVED_S: f64 = 10.0;

/// One disagreement of the phases.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Apart {
    /// The replica's phase.
    pub replica: GuidancePhase,
    /// The drone's.
    pub drone: GuidancePhase,
    /// The drone's clock when it began, s.
    pub since_s: f64,
    /// The drone's clock when it ended (the replica caught up or adopted), s.
    pub until_s: Option<f64>,
    /// It ended with the replica taking the drone's phase.
    pub adopted: bool,
}

/// Where the replica's phase stands against the drone's.
#[derive(Debug, Clone, Default)]
pub(crate) struct PhaseSync {
    /// The current disagreement, or the last one.
    pub apart: Option<Apart>,
    /// Times the replica took the drone's phase.
    pub adopted: u32,
}

fn name(p: GuidancePhase) -> String {
    crate::core::views::snake(p)
}

impl StationCore {
    /// Compares the replica's phase with the drone's at the drone's clock `drone_s`, after the
    /// replica's update; `fresh` says whether the drone's heartbeat is current.
    pub(crate) fn sync_phase(&mut self, now_s: f64, drone_s: f64, fresh: bool) {
        let drone = match self.latest.status {
            Some((s, _)) if fresh && s.mode == FlightMode::SpiralLanding => s.phase,
            _ => {
                self.close_disagreement(now_s, drone_s, false);
                return;
            }
        };
        let replica = self.guidance.phase();
        if replica == drone {
            self.close_disagreement(now_s, drone_s, false);
            return;
        }
        let open = self
            .phase_sync
            .apart
            .filter(|a| a.until_s.is_none() && a.replica == replica && a.drone == drone);
        let since_s = match open {
            Some(a) => a.since_s,
            None => {
                self.close_disagreement(now_s, drone_s, false);
                self.phase_sync.apart = Some(Apart {
                    replica,
                    drone,
                    since_s: drone_s,
                    until_s: None,
                    adopted: false,
                });
                drone_s
            }
        };
        if drone_s - since_s >= ADOPT_AFTER_S {
            self.guidance.adopt_phase(drone, drone_s);
            self.phase_sync.adopted += 1;
            self.close_disagreement(now_s, drone_s, true);
        }
    }

    /// Ends the open disagreement at `drone_s`, logging it if it was long enough to be shown.
    fn close_disagreement(&mut self, now_s: f64, drone_s: f64, adopted: bool) {
        let Some(a) = self.phase_sync.apart.as_mut() else {
            return;
        };
        if a.until_s.is_some() {
            return;
        }
        a.until_s = Some(drone_s);
        a.adopted = adopted;
        let a = *a;
        let lasted = drone_s - a.since_s;
        if lasted < ALARM_AFTER_S {
            // A transition seen a control period apart: nothing to show.
            self.phase_sync.apart = None;
            return;
        }
        let (level, outcome) = if adopted {
            (Level::Warning, "the replica takes the drone's phase")
        } else {
            (Level::Info, "they agree again")
        };
        self.log(
            now_s,
            level,
            "station",
            format!(
                "guidance replica and drone disagreed for {lasted:.1} s (replica {}, drone {}, \
                 since T+{:.1} s): {outcome}",
                name(a.replica),
                name(a.drone),
                a.since_s
            ),
        );
    }

    /// The disagreement the pages show at the drone's clock `drone_s`: an open one that has
    /// lasted [`ALARM_AFTER_S`], or a resolved one for [`SHOW_RESOLVED_S`].
    pub(crate) fn disagreement_view(&self, drone_s: Option<f64>) -> Option<DisagreementView> {
        let a = self.phase_sync.apart?;
        let now = drone_s?;
        let end = a.until_s.unwrap_or(now);
        let lasted = end - a.since_s;
        if lasted < ALARM_AFTER_S || a.until_s.is_some_and(|u| now - u > SHOW_RESOLVED_S) {
            return None;
        }
        Some(DisagreementView {
            what: "phase".into(),
            replica: name(a.replica),
            drone: name(a.drone),
            since_s: a.since_s,
            for_s: lasted,
            resolved: a.until_s.is_some(),
            adopted: a.adopted,
        })
    }
}
