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

#[cfg(test)]
mod tests {
    use stx_gnc::mission::{FlightMode, FlightStage, GuidancePhase as P};
    use stx_link::telemetry::{SystemState, VehicleStatus};

    use super::*;
    use crate::core::tests::core;

    /// A station whose replica flies spiral landing, in the approximation, and a drone whose
    /// heartbeat says `phase`.
    fn apart(phase: P) -> StationCore {
        let mut c = core();
        c.guidance.set_mode(FlightMode::SpiralLanding, 0.0);
        says(&mut c, phase);
        c
    }

    fn says(c: &mut StationCore, phase: P) {
        let status = VehicleStatus {
            mode: FlightMode::SpiralLanding,
            stage: FlightStage::Parafoil,
            phase,
            state: SystemState::Active,
        };
        c.latest.status = Some((status, 0.0));
    }

    #[test]
    fn a_disagreement_is_shown_after_a_second_and_the_drones_phase_adopted_after_two() {
        let mut c = apart(P::Branch2);
        assert_eq!(c.guidance.phase(), P::Approximation);
        c.sync_phase(100.0, 500.0, true);
        c.sync_phase(100.5, 500.5, true);
        assert_eq!(
            c.disagreement_view(Some(500.5)),
            None,
            "a transition is not an alarm"
        );
        c.sync_phase(101.2, 501.2, true);
        let shown = c.disagreement_view(Some(501.2)).expect("the alarm");
        assert_eq!(
            (shown.replica.as_str(), shown.drone.as_str(), shown.resolved),
            ("approximation", "branch2", false)
        );
        assert!(
            shown.since_s == 500.0 && (shown.for_s - 1.2).abs() < 1e-9,
            "{shown:?}"
        );
        c.sync_phase(102.0, 502.0, true);
        assert_eq!(
            c.guidance.phase(),
            P::Branch2,
            "the replica takes the drone's phase"
        );
        let shown = c.disagreement_view(Some(503.0)).expect("still shown");
        assert!(shown.resolved && shown.adopted && shown.for_s == 2.0);
        let said: Vec<String> = c.events_since(0.0).into_iter().map(|e| e.text).collect();
        assert!(
            said.iter().any(|t| t.contains("disagreed for 2.0 s (replica approximation, drone branch2, since T+500.0 s): the replica takes the drone's phase")),
            "{said:?}"
        );
        assert_eq!(
            c.disagreement_view(Some(502.0 + SHOW_RESOLVED_S + 0.1)),
            None
        );
    }

    #[test]
    fn a_transition_seen_a_period_apart_is_neither_shown_nor_logged() {
        let mut c = apart(P::Branch2);
        c.sync_phase(10.0, 50.0, true);
        says(&mut c, P::Approximation);
        c.sync_phase(10.1, 50.2, true);
        assert_eq!(c.disagreement_view(Some(50.2)), None);
        assert!(c.phase_sync.apart.is_none());
        assert_eq!(c.phase_sync.adopted, 0);
        assert!(
            !c.events_since(0.0)
                .iter()
                .any(|e| e.text.contains("disagreed")),
        );
    }

    #[test]
    fn with_a_stale_link_the_replica_flies_on_by_itself() {
        let mut c = apart(P::Branch2);
        for i in 0..50 {
            c.sync_phase(f64::from(i), 100.0 + f64::from(i), false);
        }
        assert_eq!(c.guidance.phase(), P::Approximation);
        assert_eq!(c.disagreement_view(Some(150.0)), None);
    }
}
