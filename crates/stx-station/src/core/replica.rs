//! The guidance replica follows the drone through its mission.
//!
//! The replica is the station's copy of the onboard guidance, run on the station's own
//! estimate, so that the map can draw the pattern and the final line and the predictor can fly
//! the plan. It is only a copy if it starts, stops and is configured as the original is:
//! - **stages**: the drone steers only under its parafoil, and its guidance is first updated
//!   there; before (on the pad, under the balloon and the round chute) it holds the servos
//!   neutral and reports the phase `idle`, and on the ground `landed`. The replica does the
//!   same: it runs only while the drone reports the `parafoil` stage. When the round chute is
//!   released (`parafoil_deploy`) the drone restarts its estimator, so that guidance starts from
//!   a filter that has only seen parafoil flight; the station restarts its own then too. When
//!   the parafoil flies, the replica starts afresh with the plan, mode, zones and parameters in
//!   force, as the onboard guidance starts its first update. (Run from the pad, the replica
//!   decided "flare" two seconds after the station started — its height above the ground was
//!   below the flare height — and never left it: the flare is the spiral's last phase.)
//! - **parameters**: the replica flies with the drone's gains and spiral settings, read from its
//!   parameter table (`GN_*`, `SP_*`), not with the station's configured defaults.
//!
//! - **instants**: the drone updates its guidance at each control instant (whole multiples of
//!   [`CONTROL_PERIOD_S`] on its boot clock), with every measurement that reached it by then,
//!   and what guidance learns (the main-line trim, the glide) is summed per update. The replica
//!   updates at the same instants with the same measurements, whenever the telemetry arrives:
//!   an instant is flown as soon as a message shows the drone has passed it (its periodic
//!   telemetry, sent after the update and stamped with the instant, or a measurement taken
//!   after it), before that message is taken in. (Updated once per telemetry burst, the replica
//!   skipped instants whenever a loaded station read two control periods' telemetry at once —
//!   at 20× in one live rehearsal in three or so — and its trim drifted from the drone's until
//!   its predicted landing lay 10–40 m from the drone's through the whole final approach.)
//!
//! Where the replica's own decisions part from the drone's, [`super::phase_sync`] brings it back.

use stx_dynamics::atmosphere::{Atmosphere, StandardAtmosphere};
use stx_gnc::guidance::{CONTROL_PERIOD_S, Guidance};
use stx_gnc::mission::FlightStage;
use stx_gnc::params::{OnboardSettings, find};
use stx_link::telemetry::VehicleStatus;

use super::StationCore;
use super::navigation::Stamp;
use crate::messages::Level;

/// The drone's control period in its clock's unit (ms).
const CONTROL_PERIOD_MS: u32 = (CONTROL_PERIOD_S * 1000.0) as u32;

/// Control instants passed unheard that the replica still flies one by one: past this (a
/// silent link), it flies only the newest, since the drone's own updates in the gap were made
/// with measurements the station never got.
const MAX_CATCH_UP: u32 = 8;

impl StationCore {
    /// Flies the replica through the drone's control instants that a message stamped
    /// `stamp_ms` (drone clock) shows it has passed, before the message is taken in.
    pub(crate) fn replica_catch_up(&mut self, now_s: f64, stamp_ms: u32, stamp: Stamp) {
        let last = match stamp {
            Stamp::AfterControl => stamp_ms / CONTROL_PERIOD_MS,
            Stamp::Measured if stamp_ms == 0 => return,
            Stamp::Measured => (stamp_ms - 1) / CONTROL_PERIOD_MS,
        };
        let instant_s = |k: u32| f64::from(k) * CONTROL_PERIOD_S;
        let first = match self.guided_at_s {
            // The next instant after the last one flown.
            Some(t) if t >= 0.0 => (t / CONTROL_PERIOD_S + 1e-6).floor() as u32 + 1,
            _ => last,
        };
        if first > last {
            // Nothing passed (or the first stamp from a drone that restarted).
            return;
        }
        let first = first.max(last.saturating_sub(MAX_CATCH_UP - 1));
        for k in first..=last {
            self.guide_replica_at(now_s, instant_s(k));
        }
    }

    /// One update of the replica at the drone's control instant `t_s`, from the estimate then.
    fn guide_replica_at(&mut self, now_s: f64, t_s: f64) {
        self.guided_at_s = Some(t_s);
        let est = self.estimator.estimate(t_s);
        if !est.position_sigma_m.iter().all(|s| s.is_finite()) {
            return;
        }
        if !self.replica_flies() || !self.plan_known_for(self.guidance.mode()) {
            // Before its parafoil flies the drone holds its servos neutral; and flying towards
            // a target the drone may not have would draw and log a pattern that does not exist.
            self.replica_command = stx_dynamics::state::Controls::default();
            return;
        }
        let density = StandardAtmosphere
            .air_at(self.frame.alt_msl_m - est.position_ned_m.z)
            .density_kg_per_m3;
        self.replica_command = self.guidance.update(&est, density).controls;
        let fresh = self.latest.status.is_some_and(|(_, at)| {
            now_s - at <= self.config.link.stale_after_s && self.link.connected
        });
        self.sync_phase(now_s, est.time_s, fresh);
        self.log_guidance_events(now_s);
    }

    /// Logs the replica's phase changes since the last call.
    pub(crate) fn log_guidance_events(&mut self, now_s: f64) {
        for e in self.guidance.drain_events() {
            self.log(
                now_s,
                Level::Info,
                "guidance",
                format!("{:?} → {:?}: {}", e.from, e.to, e.reason),
            );
        }
    }

    /// The guidance replica (its plan, phase and spiral status).
    pub fn replica(&self) -> &Guidance {
        &self.guidance
    }

    /// The station's estimate as of its last tick.
    pub fn estimate_now(&self) -> Option<stx_gnc::estimate::Estimate> {
        self.estimate
    }

    /// The mission clock at the station's `now_s`: the drone's (s since its boot) carried
    /// forward from its newest time-stamped telemetry.
    pub fn mission_time_s(&self, now_s: f64) -> Option<f64> {
        self.mission_clock.at(now_s)
    }

    /// The stage the drone reports, if it has reported one.
    pub(crate) fn drone_stage(&self) -> Option<FlightStage> {
        self.latest.status.map(|(s, _)| s.stage)
    }

    /// Whether the replica flies now: the drone steers only under its parafoil.
    pub(crate) fn replica_flies(&self) -> bool {
        self.drone_stage() == Some(FlightStage::Parafoil)
    }

    /// The drone's stage went from `previous` (`None`: first heard) to `status.stage`.
    pub(crate) fn replica_on_stage(
        &mut self,
        now_s: f64,
        previous: Option<FlightStage>,
        status: VehicleStatus,
    ) {
        let stage = status.stage;
        if previous == Some(stage) {
            return;
        }
        if stage == FlightStage::ParafoilDeploy && previous.is_some() {
            // As the drone does when its round chute is released.
            self.estimator = self.estimator.restarted();
            self.estimate = None;
            self.guided_at_s = None;
        }
        if stage == FlightStage::Parafoil {
            self.restart_replica();
            self.log(
                now_s,
                Level::Info,
                "station",
                "the parafoil flies: the guidance replica starts with the drone's plan".into(),
            );
        }
        if !matches!(stage, FlightStage::ParafoilDeploy | FlightStage::Parafoil) {
            // A prediction of a parafoil's glide means nothing on the ground or before it.
            self.prediction = None;
            self.prediction_data_s = None;
            self.replica_command = stx_dynamics::state::Controls::default();
        }
    }

    /// A replica that has not flown yet, with everything in force kept: what the onboard
    /// guidance is at its first update under the parafoil.
    fn restart_replica(&mut self) {
        let at = self.drone_time_s.unwrap_or(0.0);
        let mut fresh = Guidance::new(*self.guidance.config());
        fresh.set_keep_out(self.guidance.keep_out().clone());
        fresh.set_plan(*self.guidance.plan(), at);
        fresh.set_mode(self.guidance.mode(), at);
        fresh.drain_events();
        self.guidance = fresh;
        // The drone's first update under the parafoil is at its next control period: the
        // replica's is with the first estimate after the one the news came with (one more
        // update would put every sum it learns a step ahead of the drone's).
        self.guided_at_s = self.drone_time_s;
        self.phase_sync = Default::default();
    }

    /// The drone's parameter table changed: the replica takes the drone's gains and spiral
    /// settings. A table that breaks the onboard rules (it cannot, from our drone) is logged and
    /// the settings in force are kept.
    pub(crate) fn replica_on_params(&mut self, now_s: f64) {
        let mut settings = OnboardSettings {
            guidance: *self.guidance.config(),
            ..OnboardSettings::default()
        };
        for (name, p) in &self.params.values {
            let Some(def) = find(name) else { continue };
            // The wire carries f32: a value that rounds to the one in force is that value (the
            // drone flies 0.00661, the wire says 0.0066100000403…), and taking the rounded one
            // would make the replica's sums part from the drone's.
            if def.get(&settings) as f32 == p.value {
                continue;
            }
            // One at a time each value is only range-checked: the rules between them are
            // checked on the whole table below.
            let _ = def.set(&mut settings, f64::from(p.value));
        }
        if let Err(e) = settings.check() {
            self.log(
                now_s,
                Level::Warning,
                "station",
                format!(
                    "the drone's parameters break the onboard rules ({e}): the guidance replica \
                     keeps its settings"
                ),
            );
            return;
        }
        let config = self.guidance.config();
        if config.gains != settings.guidance.gains
            || config.spiral != settings.guidance.spiral
            || config.performance != settings.guidance.performance
        {
            self.guidance.set_gains(settings.guidance.gains);
            self.guidance.set_spiral_config(settings.guidance.spiral);
            self.guidance.set_performance(settings.guidance.performance);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::tests::core;

    #[test]
    fn the_replica_flies_each_control_instant_the_drone_has_passed() {
        let mut c = core();
        // A measurement taken at 1.0 s: the drone updated at 0.75 s without it, and will at
        // 1.0 s with it.
        c.replica_catch_up(0.0, 1000, Stamp::Measured);
        assert_eq!(c.guided_at_s, Some(0.75));
        c.replica_catch_up(0.0, 1000, Stamp::AfterControl);
        assert_eq!(c.guided_at_s, Some(1.0));
        // Three periods' telemetry read at once: each instant is flown, none twice.
        let mut flown = Vec::new();
        for (stamp, kind) in [
            (1100, Stamp::Measured),
            (1250, Stamp::AfterControl),
            (1350, Stamp::Measured),
            (1500, Stamp::AfterControl),
            (1750, Stamp::Measured),
            (1750, Stamp::AfterControl),
            (1750, Stamp::AfterControl),
        ] {
            c.replica_catch_up(0.0, stamp, kind);
            flown.push(c.guided_at_s);
        }
        let expected = [1.0, 1.25, 1.25, 1.5, 1.5, 1.75, 1.75];
        assert_eq!(flown, expected.map(Some));
    }

    #[test]
    fn a_drone_that_restarted_does_not_fly_the_replica_back_in_time() {
        let mut c = core();
        c.replica_catch_up(0.0, 61_000, Stamp::AfterControl);
        assert_eq!(c.guided_at_s, Some(61.0));
        // Stamps from zero again: nothing is flown before the restart resets the replica's clock
        // (`observe_drone_clock`).
        c.replica_catch_up(0.0, 500, Stamp::AfterControl);
        assert_eq!(c.guided_at_s, Some(61.0));
    }

    fn drone_says(c: &mut crate::core::StationCore, name: &str, value: f32) {
        c.on_link_event(
            0.0,
            stx_link::endpoint::GroundEvent::Param(stx_link::param::ParamEvent::Value {
                param: stx_link::param::ParamValue {
                    name: name.into(),
                    value,
                    index: 0,
                    count: 1,
                },
            }),
        );
    }

    #[test]
    fn the_replica_plans_with_the_polar_the_drones_parameters_hold() {
        let mut c = core();
        let shipped = c.guidance.config().performance;
        // A slower canopy sent as parameters (`stx polar`): the replica plans with it, as the
        // drone's guidance does.
        drone_says(&mut c, "PL_AS_0", 6.1);
        drone_says(&mut c, "PL_SINK_0", 3.2);
        let perf = c.guidance.config().performance;
        assert_eq!(perf.airspeed_mps[0], f64::from(6.1_f32));
        assert_eq!(perf.sink_rate_mps[0], f64::from(3.2_f32));
        assert_eq!(perf.airspeed_mps[1..], shipped.airspeed_mps[1..]);
        // A table that is no glide (sink above airspeed) is the drone's mistake: logged, the
        // polar in force kept.
        drone_says(&mut c, "PL_SINK_2", 7.0);
        assert_eq!(c.guidance.config().performance, perf);
    }
}
