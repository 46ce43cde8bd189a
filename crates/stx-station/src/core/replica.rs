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
//! Where the replica's own decisions part from the drone's, [`super::phase_sync`] brings it back.

use stx_gnc::guidance::Guidance;
use stx_gnc::mission::FlightStage;
use stx_gnc::params::{OnboardSettings, find};
use stx_link::telemetry::VehicleStatus;

use super::StationCore;
use super::navigation::new_estimator;
use crate::messages::Level;

impl StationCore {
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
            self.estimator = new_estimator(self.frame.alt_msl_m);
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
        if config.gains != settings.guidance.gains || config.spiral != settings.guidance.spiral {
            self.guidance.set_gains(settings.guidance.gains);
            self.guidance.set_spiral_config(settings.guidance.spiral);
        }
    }
}
