//! Stage and guidance-phase changes: what the drone records of them (its stage log, the
//! balloon's end, the deployment, the landing) and what it tells the operator.

use nalgebra::Vector3;
use stx_gnc::guidance::PhaseEvent;
use stx_link::telemetry::Severity;

use super::mission::StageEvent;
use super::onboard::mode_name;
use super::summary::{BalloonEnd, Landing};
use super::{Drone, PHASE_TEXT_INTERVAL_S};
use crate::closed_loop::phase_name;

impl Drone {
    /// Tells the operator of a guidance phase change, with its reason. Changes closer than
    /// [`PHASE_TEXT_INTERVAL_S`] to the last one told are counted and told with the next, so a
    /// guidance that hesitates between phases cannot flood the link (the heartbeat carries
    /// the phase in any case).
    pub(super) fn announce_phase(&mut self, event: &PhaseEvent) {
        let now = event.time_s;
        if self
            .last_phase_text_s
            .is_some_and(|last| now - last < PHASE_TEXT_INTERVAL_S)
        {
            self.phase_texts_held += 1;
            return;
        }
        let held = std::mem::take(&mut self.phase_texts_held);
        let more = if held > 0 {
            format!(" (+{held} changes in the last {PHASE_TEXT_INTERVAL_S:.0} s)")
        } else {
            String::new()
        };
        self.last_phase_text_s = Some(now);
        self.say(
            Severity::Info,
            format!("phase {}: {}{more}", phase_name(event.to), event.reason),
        );
    }

    pub(super) fn stage_event(&mut self, event: StageEvent) {
        let now = self.time_s();
        let stage = self.stage();
        if self.stage_log.last().map(|s| s.0) != Some(stage) {
            self.stage_log.push((stage, now));
        }
        let (severity, text) = match event {
            StageEvent::Launched => (
                Severity::Notice,
                format!(
                    "launched: ascending at {:.1} m/s on average ({:.1} m/s now) to burst at {:.0} m",
                    self.config.balloon.mean_ascent_rate_mps,
                    self.physics.balloon().launch_rate_mps(),
                    self.physics.burst_altitude_msl_m()
                ),
            ),
            StageEvent::Burst { altitude_msl_m } => {
                self.balloon_end = Some((BalloonEnd::Burst, now, altitude_msl_m));
                (
                    Severity::Notice,
                    format!("balloon burst at {altitude_msl_m:.0} m MSL: round chute"),
                )
            }
            StageEvent::CutDown { altitude_msl_m } => {
                self.balloon_end = Some((BalloonEnd::Cutdown, now, altitude_msl_m));
                (
                    Severity::Notice,
                    format!("cutdown at {altitude_msl_m:.0} m MSL: balloon released, round chute"),
                )
            }
            StageEvent::Deployed {
                height_m,
                heading_rad,
            } => {
                self.deployment = Some((now, height_m));
                // Guidance starts from a filter that has only seen the parafoil fly, with what
                // was learnt of the sensors kept.
                self.estimator = self.estimator.restarted();
                self.estimate = None;
                (
                    Severity::Notice,
                    format!(
                        "round chute released at {height_m:.0} m: parafoil deploying, heading {:.0}°",
                        heading_rad.to_degrees().rem_euclid(360.0)
                    ),
                )
            }
            StageEvent::Flying => (
                Severity::Notice,
                format!("parafoil flying: {}", mode_name(self.onboard.mode())),
            ),
            StageEvent::Landed(t) => {
                let target = self.target_ned_m();
                let miss =
                    target.map(|p| (t.position_ne_m[0] - p.x).hypot(t.position_ne_m[1] - p.y));
                let (lat_deg, lon_deg, _) = self.frame.to_geodetic(&Vector3::new(
                    t.position_ne_m[0],
                    t.position_ne_m[1],
                    0.0,
                ));
                self.landing = Some(Landing {
                    time_s: t.time_s,
                    position_ne_m: t.position_ne_m,
                    miss_m: miss,
                    vertical_speed_mps: t.vertical_speed_mps,
                    under_parafoil: self.physics.parafoil().is_some(),
                    lat_deg,
                    lon_deg,
                });
                // What the drone itself knows of where it is: its estimate (the truth's
                // distance from the target is the simulator's, not the drone's, to tell).
                let place = self
                    .estimate
                    .map(|e| {
                        format!(
                            " at {:.0} m N {:.0} m E of the site by its estimate",
                            e.position_ned_m.x, e.position_ned_m.y
                        )
                    })
                    .unwrap_or_default();
                (
                    Severity::Notice,
                    format!("landed{place}, {:.1} m/s down", t.vertical_speed_mps),
                )
            }
        };
        self.say(severity, text);
    }
}
