//! The GPS-loss policy (see the parent module's "GPS loss"): the loss announced, the action
//! of `FS_GPS_ACTION` taken after `FS_GPS_LOSS_S`, the return announced.

use stx_gnc::estimate::Estimate;
use stx_gnc::mission::FlightStage;
use stx_gnc::params::GpsLossAction;
use stx_link::telemetry::Severity;

use super::{GpsState, Onboard, mode_name, steers_on_position};

impl Onboard {
    /// Follows the GPS: announces its loss, takes the GPS-loss action after `FS_GPS_LOSS_S`,
    /// and announces its return. Called every control period with the age of the last fix
    /// that reached the drone (∞ before the first), the age beyond which the GPS counts as
    /// lost (the estimator's GPS timeout) and the latest estimate.
    pub fn update_gps(
        &mut self,
        time_s: f64,
        stage: FlightStage,
        gps_age_s: f64,
        timeout_s: f64,
        est: Option<&Estimate>,
    ) {
        let gps_ok = gps_age_s <= timeout_s;
        if gps_ok {
            self.had_fix = true;
        }
        match self.gps {
            GpsState::Ok => {
                if self.had_fix && !gps_ok && stage != FlightStage::Landed {
                    self.gps = GpsState::Lost {
                        since_s: time_s - gps_age_s.min(time_s),
                        acted: false,
                    };
                    self.say(
                        Severity::Warning,
                        "GPS lost: navigating by dead reckoning".into(),
                    );
                }
            }
            GpsState::Lost { since_s, acted } => {
                if gps_ok {
                    self.gps = GpsState::Ok;
                    self.say(
                        Severity::Notice,
                        format!("GPS back after {:.0} s", time_s - since_s),
                    );
                } else if (!acted || self.gps_action_pending())
                    && stage == FlightStage::Parafoil
                    && time_s - since_s >= self.settings.failsafe.gps_loss_s
                    && let Some(est) = est
                {
                    self.act_on_gps_loss(time_s, since_s, est);
                }
            }
            GpsState::IntoWind { since_s, .. } | GpsState::Neutral { since_s } => {
                if gps_ok {
                    self.gps = GpsState::Ok;
                    let mode = self.mode();
                    // A spiral under way replans from where the fixes say the vehicle is.
                    let plan = *self.guidance.plan();
                    self.guidance.set_plan(plan, time_s);
                    self.say(
                        Severity::Notice,
                        format!(
                            "GPS back after {:.0} s: resuming {}",
                            time_s - since_s,
                            mode_name(mode)
                        ),
                    );
                }
            }
        }
    }

    /// After the loss was flown through in a mode that does not need the GPS: whether the
    /// mode now steers on position and the policy has an action for that.
    fn gps_action_pending(&self) -> bool {
        steers_on_position(self.mode())
            && self.settings.failsafe.gps_loss_action != GpsLossAction::Continue
    }

    fn act_on_gps_loss(&mut self, time_s: f64, since_s: f64, est: &Estimate) {
        let mode = self.mode();
        let lost_s = time_s - since_s;
        let action = self.settings.failsafe.gps_loss_action;
        if action == GpsLossAction::Uncontrolled && steers_on_position(mode) {
            self.gps = GpsState::Neutral { since_s };
            self.say(
                Severity::Critical,
                format!("GPS lost {lost_s:.0} s: servos neutral, gliding straight"),
            );
        } else if action == GpsLossAction::IntoWind && steers_on_position(mode) {
            let wind = est.wind_ned_mps;
            let speed = wind.x.hypot(wind.y);
            let heading_rad = if speed > 0.5 {
                (-wind.y).atan2(-wind.x)
            } else {
                est.heading_rad
            };
            self.gps = GpsState::IntoWind {
                since_s,
                heading_rad,
            };
            self.say(
                Severity::Critical,
                format!(
                    "GPS lost {lost_s:.0} s: holding heading {:.0}° into the wind ({speed:.1} m/s), flare by barometer",
                    heading_rad.to_degrees().rem_euclid(360.0)
                ),
            );
        } else {
            self.gps = GpsState::Lost {
                since_s,
                acted: true,
            };
            self.say(
                Severity::Warning,
                format!(
                    "GPS lost {lost_s:.0} s: continuing {} on dead reckoning",
                    mode_name(mode)
                ),
            );
        }
    }
}
