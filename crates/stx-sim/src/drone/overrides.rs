//! What a command line changes in a mission before it flies: the seed, failures on top of the
//! scenario's own `[failures]`, and the onboard guidance's gains. [`MissionOverrides::apply`]
//! returns the mission validated with them, so a bad combination is refused before anything
//! starts.

use stx_gnc::control::ControlGains;

use crate::drone::config::MissionConfig;
use crate::drone::config_error::MissionError;
use crate::drone::failures::StuckServo;

/// Failures to inject on top of the scenario's own (`[failures]`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FailureFlags {
    /// Random loss of datagrams each way, % (replaces the scenario's).
    pub packet_loss_pct: Option<f64>,
    /// Link-drop windows, s of mission time (added to the scenario's).
    pub link_drop_s: Vec<[f64; 2]>,
    /// GPS-loss windows, s of mission time (added to the scenario's).
    pub gps_loss_s: Vec<[f64; 2]>,
    /// A stuck servo (replaces the scenario's).
    pub stuck_servo: Option<StuckServo>,
}

/// Everything a command line may change in a mission.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MissionOverrides {
    /// Seed of everything random; `None` keeps the scenario's.
    pub seed: Option<u64>,
    /// Failures to inject.
    pub failures: FailureFlags,
    /// Control gains replacing the mission's (the onboard guidance's parameters).
    pub gains: Option<ControlGains>,
}

impl MissionOverrides {
    /// `config` with these changes, validated again (a window or a loss the scenario's rules
    /// refuse is an error naming the field).
    pub fn apply(&self, mut config: MissionConfig) -> Result<MissionConfig, MissionError> {
        if let Some(seed) = self.seed {
            config.seed = seed;
        }
        let f = &self.failures;
        if let Some(pct) = f.packet_loss_pct {
            config.failures.packet_loss_pct = pct;
        }
        config.failures.link_drop_s.extend(&f.link_drop_s);
        config.failures.gps_loss_s.extend(&f.gps_loss_s);
        if let Some(stuck) = f.stuck_servo {
            config.failures.stuck_servo = Some(stuck);
        }
        if let Some(gains) = self.gains {
            config.onboard.guidance.gains = gains;
        }
        config.validate()?;
        Ok(config)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::drone::failures::Servo;

    #[test]
    fn overrides_replace_or_add_to_the_scenarios_and_bad_ones_are_refused() {
        let overrides = MissionOverrides {
            seed: Some(9),
            failures: FailureFlags {
                packet_loss_pct: Some(20.0),
                link_drop_s: vec![[100.0, 160.0]],
                gps_loss_s: vec![[300.0, 330.0]],
                stuck_servo: Some(StuckServo {
                    servo: Servo::Left,
                    at_s: 400.0,
                }),
            },
            gains: Some(ControlGains {
                hk1_m_per_rad: 0.0123,
                ..ControlGains::default()
            }),
        };
        let base = MissionConfig::builtin("rehearsal").expect("built-in");
        let config = overrides.apply(base.clone()).expect("valid");
        assert_eq!(config.seed, 9);
        assert_eq!(config.failures.packet_loss_pct, 20.0);
        assert_eq!(config.failures.link_drop_s, vec![[100.0, 160.0]]);
        assert_eq!(config.failures.gps_loss_s, vec![[300.0, 330.0]]);
        assert_eq!(config.failures.stuck_servo, overrides.failures.stuck_servo);
        assert_eq!(config.onboard.guidance.gains.hk1_m_per_rad, 0.0123);
        // Nothing asked, nothing changed.
        let same = MissionOverrides::default()
            .apply(base.clone())
            .expect("valid");
        assert_eq!(same.seed, base.seed);
        assert_eq!(same.failures, base.failures);

        let too_lossy = MissionOverrides {
            failures: FailureFlags {
                packet_loss_pct: Some(120.0),
                ..FailureFlags::default()
            },
            ..MissionOverrides::default()
        };
        let err = too_lossy.apply(base).expect_err("120 % refused");
        assert!(err.to_string().contains("packet_loss_pct"), "{err}");
    }
}
