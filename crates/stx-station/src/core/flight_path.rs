//! The unsteered flight path on the station, live: while the balloon rises (and on the pad)
//! and while the stack falls under its round chute, every [`FLIGHT_PATH_EVERY_S`] of the
//! drone's clock the pure
//! [`stx_gnc::flight_path::propagate`] flies the stack from the latest 3-D GPS fix through the
//! wind profile every descent prediction uses ([`StationCore::wind_profile`]: the ascent's
//! measured bands, the forecast outside them) to the burst, the deploy point and the landing
//! with neutral servos. Under the parafoil the landing predictions and the footprint take over.
//!
//! The stack's settings come from the station config (`[flight_path]`), except those the
//! drone holds as parameters, which win once its table is read: `MIS_DEPLOY_M` (the deploy
//! height), `MIS_CUTDOWN_M` (a cutdown below the burst altitude ends the ascent there), and the
//! launch profile loaded before launch, `MIS_BURST_M` and `MIS_ASCENT_MPS` (0: not loaded).
//! The launch profile is never a silent default: the view says where the burst altitude and
//! the ascent rate came from (`drone` or `station_config`), and with neither a loaded parameter
//! nor a value in the configuration file there is no path, and the operators are told why.
//!
//! A path costs well under a millisecond (10 m altitude steps to 35 km, a 0.5 s glide), so
//! it runs on the core's tick rather than as a detached job.

use nalgebra::Vector3;
use stx_dynamics::atmosphere::StandardAtmosphere;
use stx_gnc::flight_path::{Air, FlightPath, PathPoint, StackConfig, Start, propagate};
use stx_gnc::mission::FlightStage;

use super::StationCore;
use crate::messages::{FlightPathView, Level, PathPointView};

/// Seconds of the drone's clock between two flight paths, s.
pub const FLIGHT_PATH_EVERY_S: f64 = 2.0;

/// Where a launch-profile setting the path flies comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum LaunchSource {
    /// The drone's parameter, loaded before launch.
    Drone,
    /// The station config's `[flight_path]`.
    StationConfig,
}

impl LaunchSource {
    fn name(self) -> &'static str {
        match self {
            Self::Drone => "drone",
            Self::StationConfig => "station_config",
        }
    }
}

/// Where the path's burst altitude and ascent rate come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct LaunchSources {
    burst: LaunchSource,
    ascent_rate: LaunchSource,
}

/// The latest path and when the next is due.
#[derive(Debug, Clone, Default)]
pub(crate) struct LivePath {
    next_s: f64,
    view: Option<FlightPathView>,
    /// The last failure logged, so that one cause is said once.
    said: Option<String>,
}

impl StationCore {
    /// The stack as the path flies it: the configured one, with the drone's parameters, and
    /// where its burst altitude and ascent rate come from; the reason when one is known to
    /// neither the drone nor the configuration.
    pub(crate) fn stack_config(&self) -> Result<(StackConfig, LaunchSources), String> {
        let mut stack = self.config.flight_path;
        let param = |name: &str| {
            self.params
                .values
                .get(name)
                .map(|p| f64::from(p.value))
                .filter(|v| v.is_finite())
        };
        if let Some(deploy) = param("MIS_DEPLOY_M").filter(|v| *v >= 0.0) {
            stack.deploy_height_m = deploy;
        }
        let configured = |key: &str| !self.config.flight_path_unset.contains(&key);
        let mut unknown = Vec::new();
        let mut pick = |name: &str, key: &str, what: &str, value: &mut f64| {
            if let Some(v) = param(name).filter(|v| *v > 0.0) {
                *value = v;
                return LaunchSource::Drone;
            }
            if !configured(key) {
                unknown.push(format!(
                    "{what} (the drone's {name}, or [flight_path] {key})"
                ));
            }
            LaunchSource::StationConfig
        };
        let burst = pick(
            "MIS_BURST_M",
            "burst_altitude_msl_m",
            "the burst altitude",
            &mut stack.burst_altitude_msl_m,
        );
        let ascent_rate = pick(
            "MIS_ASCENT_MPS",
            "mean_ascent_rate_mps",
            "the ascent rate",
            &mut stack.mean_ascent_rate_mps,
        );
        if !unknown.is_empty() {
            return Err(format!(
                "neither the drone nor the station config gives {}",
                unknown.join(" nor ")
            ));
        }
        if let Some(cutdown) = param("MIS_CUTDOWN_M").filter(|v| *v > 0.0) {
            stack.burst_altitude_msl_m = stack.burst_altitude_msl_m.min(cutdown);
        }
        Ok((stack, LaunchSources { burst, ascent_rate }))
    }

    /// Recomputes the path when one is due.
    pub(crate) fn update_flight_path(&mut self, now_s: f64) {
        // On the drone's clock, as navigation: an accelerated rehearsal refreshes as often
        // per second of flight as a real one. A clock that went back is a restarted drone.
        let Some(t) = self.drone_time_s else {
            self.live_path.view = None;
            return;
        };
        if t < self.live_path.next_s && t >= self.live_path.next_s - 2.0 * FLIGHT_PATH_EVERY_S {
            return;
        }
        self.live_path.next_s = t + FLIGHT_PATH_EVERY_S;
        let stage = self.latest.status.map(|(s, _)| s.stage);
        let fix = self.latest.gps.filter(|(g, _)| g.has_3d_fix());
        let (Some(stage), Some((gps, _))) = (stage, fix) else {
            self.live_path.view = None;
            return;
        };
        let mut p = self.frame.to_ned(gps.lat_deg, gps.lon_deg, gps.alt_msl_m);
        // On the pad the fix may read a little below the origin's altitude.
        p.z = p.z.min(0.0);
        let start = match stage {
            FlightStage::PreLaunch | FlightStage::Ascent => Start::Ascending(p),
            FlightStage::RoundChute => Start::UnderRoundChute(p),
            _ => {
                self.live_path.view = None;
                return;
            }
        };
        let Some(profile) = self.wind_profile() else {
            self.flight_path_failed(now_s, "no wind: neither a measured band nor a forecast");
            return;
        };
        let air = Air {
            wind: &profile,
            atmosphere: &StandardAtmosphere,
            ground_msl_m: self.frame.alt_msl_m,
        };
        let (stack, sources) = match self.stack_config() {
            Ok(s) => s,
            Err(reason) => {
                self.flight_path_failed(now_s, &reason);
                return;
            }
        };
        match propagate(start, &stack, air, &self.config.guidance.performance) {
            Ok(path) => {
                let view = self.flight_path_view([now_s, t], stage, &path, sources);
                self.live_path.view = Some(view);
                self.live_path.said = None;
            }
            Err(e) => self.flight_path_failed(now_s, &e.to_string()),
        }
    }

    fn flight_path_failed(&mut self, now_s: f64, reason: &str) {
        self.live_path.view = None;
        if self.live_path.said.as_deref() != Some(reason) {
            self.live_path.said = Some(reason.to_string());
            self.log(
                now_s,
                Level::Warning,
                "station",
                format!("no flight-path prediction: {reason}"),
            );
        }
    }

    /// The view of `path`, computed at the station's `now_s` from a fix of the mission clock
    /// `mission_s` (`[now_s, mission_s]`).
    fn flight_path_view(
        &self,
        [now_s, mission_s]: [f64; 2],
        stage: FlightStage,
        path: &FlightPath,
        sources: LaunchSources,
    ) -> FlightPathView {
        let point = |p: &PathPoint| {
            let ned = Vector3::from(p.position_ned_m);
            let (lat_deg, lon_deg, alt_msl_m) = self.frame.to_geodetic(&ned);
            PathPointView {
                lat_deg,
                lon_deg,
                alt_msl_m,
                in_s: p.time_s,
            }
        };
        let [n, e] = path.reach.centre_ne_m;
        let (lat, lon, _) = self.frame.to_geodetic(&Vector3::new(n, e, 0.0));
        let bands: Vec<_> = self
            .ascent
            .bands()
            .iter()
            .filter(|b| b.is_believed())
            .collect();
        FlightPathView {
            computed_s: now_s,
            computed_mission_s: mission_s,
            stage: match stage {
                FlightStage::PreLaunch => "pre_launch",
                FlightStage::RoundChute => "round_chute",
                _ => "ascent",
            }
            .to_string(),
            burst: path.burst.as_ref().map(point),
            deploy: point(&path.deploy),
            landing: point(&path.landing),
            round_chute_landing: point(&path.round_chute_landing),
            reach_centre_lat_lon_deg: [lat, lon],
            reach_radius_m: path.reach.radius_m,
            measured_bands: u32::try_from(bands.len()).unwrap_or(u32::MAX),
            measured_to_msl_m: bands
                .iter()
                .map(|b| b.altitude_max_m + self.frame.alt_msl_m)
                .reduce(f64::max),
            burst_source: sources.burst.name().to_string(),
            ascent_rate_source: sources.ascent_rate.name().to_string(),
        }
    }

    /// The latest flight path, for the `state` message.
    pub(crate) fn flight_path_view_now(&self) -> Option<FlightPathView> {
        self.live_path.view.clone()
    }
}

#[cfg(test)]
mod tests {
    use stx_gnc::mission::{FlightMode, GuidancePhase};
    use stx_link::endpoint::GroundEvent;
    use stx_link::param::ParamValue;
    use stx_link::telemetry::{SystemState, Telemetry, VehicleStatus};

    use super::super::tests::{gps_raw, level_attitude};
    use super::*;
    use crate::config::{DEFAULT_STATION_TOML, ForecastRow, StationConfig};

    /// A station whose forecast is 10 m/s from the west at every height and whose balloon
    /// climbs at a constant 5 m/s (no density exponent), so that the burst lies where a
    /// closed form puts it.
    fn core() -> StationCore {
        let mut config = StationConfig::from_toml_str(DEFAULT_STATION_TOML).expect("config");
        let origin_msl = config.origin.alt_msl_m;
        config.forecast_wind = [0.0, 20_000.0, 40_000.0]
            .into_iter()
            .map(|h| ForecastRow {
                alt_msl_m: origin_msl + h,
                speed_mps: 10.0,
                from_deg: 270.0,
                sigma_mps: None,
            })
            .collect();
        config.flight_path.ascent_density_exponent = 0.0;
        config.flight_path.mean_ascent_rate_mps = 5.0;
        config.flight_path.burst_altitude_msl_m = 30_000.0;
        // Set here rather than in the file: the station's config gives both.
        config.flight_path_unset.clear();
        StationCore::new(config, 0)
    }

    fn set_param(core: &mut StationCore, name: &str, value: f32) {
        core.on_link_event(
            0.0,
            GroundEvent::Param(stx_link::param::ParamEvent::Value {
                param: ParamValue {
                    name: name.into(),
                    value,
                    index: 0,
                    count: 50,
                },
            }),
        );
    }

    fn hear(core: &mut StationCore, now_s: f64, stage: FlightStage, height_m: f64) {
        let (lat, lon, alt) = core.frame.to_geodetic(&Vector3::new(0.0, 0.0, -height_m));
        let ms = (now_s * 1000.0) as u32;
        for telemetry in [
            Telemetry::Status(VehicleStatus {
                mode: FlightMode::Heading,
                stage,
                phase: GuidancePhase::Idle,
                state: SystemState::Active,
            }),
            Telemetry::GpsRaw(gps_raw(ms, [lat, lon, alt], [0.0, 10.0])),
            // Time-stamped on the drone's clock, which the path's refresh runs on.
            level_attitude(ms),
        ] {
            core.on_link_event(
                now_s,
                GroundEvent::Telemetry {
                    from: (1, 1),
                    telemetry,
                },
            );
        }
        core.tick(now_s);
    }

    fn east_of_origin(core: &StationCore, p: &PathPointView) -> f64 {
        core.frame.to_ned(p.lat_deg, p.lon_deg, p.alt_msl_m).y
    }

    #[test]
    fn during_the_ascent_the_burst_lies_where_the_wind_carries_the_balloon() {
        let mut core = core();
        hear(&mut core, 10.0, FlightStage::Ascent, 5_000.0);
        let path = core
            .flight_path_view_now()
            .expect("a path during the ascent");
        assert_eq!(path.stage, "ascent");
        let burst = path.burst.as_ref().expect("a burst point");
        // 25 km to climb at 5 m/s: 5000 s in a 10 m/s west wind, 50 km east.
        let climb_s = (30_000.0 - (core.frame.alt_msl_m + 5_000.0)) / 5.0;
        assert!((burst.in_s - climb_s).abs() < 1.0, "{} s", burst.in_s);
        let east = east_of_origin(&core, burst);
        assert!(
            (east - 10.0 * climb_s).abs() < 10.0,
            "burst {east:.0} m east"
        );
        assert!((burst.alt_msl_m - 30_000.0).abs() < 1.0);
        // The fall goes on east, the parafoil's deploy height as the config says.
        let deploy = east_of_origin(&core, &path.deploy);
        assert!(deploy > east + 1_000.0, "deploy {deploy:.0} m east");
        let deploy_height = path.deploy.alt_msl_m - core.frame.alt_msl_m;
        assert!((deploy_height - core.config.flight_path.deploy_height_m).abs() < 11.0);
        assert!(east_of_origin(&core, &path.round_chute_landing) > deploy);
        assert_eq!(path.measured_bands, 0, "the forecast alone");
        assert_eq!(
            (path.burst_source.as_str(), path.ascent_rate_source.as_str()),
            ("station_config", "station_config")
        );
    }

    /// Issue 28: the map said "burst in 1 h 45 min at 35.0 km" while the drone, loaded for
    /// mission-short, bursts at 3,000 m. The drone's MIS_BURST_M and MIS_ASCENT_MPS win over
    /// the station config's, and the view says so.
    #[test]
    fn regression_the_drones_burst_altitude_and_ascent_rate_win_and_the_view_says_so() {
        let mut core = core();
        set_param(&mut core, "MIS_BURST_M", 3_000.0);
        set_param(&mut core, "MIS_ASCENT_MPS", 4.0);
        hear(&mut core, 10.0, FlightStage::Ascent, 1_000.0);
        let path = core.flight_path_view_now().expect("path");
        let burst = path.burst.as_ref().expect("burst");
        assert!(
            (burst.alt_msl_m - 3_000.0).abs() < 1.0,
            "{}",
            burst.alt_msl_m
        );
        let climb_s = (3_000.0 - (core.frame.alt_msl_m + 1_000.0)) / 4.0;
        assert!((burst.in_s - climb_s).abs() < 1.0, "{} s", burst.in_s);
        assert_eq!(
            (path.burst_source.as_str(), path.ascent_rate_source.as_str()),
            ("drone", "drone")
        );
        // 0 is "not loaded": the station config's value again.
        set_param(&mut core, "MIS_BURST_M", 0.0);
        hear(
            &mut core,
            10.0 + FLIGHT_PATH_EVERY_S,
            FlightStage::Ascent,
            1_000.0,
        );
        let path = core.flight_path_view_now().expect("path");
        assert!((path.burst.expect("burst").alt_msl_m - 30_000.0).abs() < 1.0);
        assert_eq!(path.burst_source, "station_config");
    }

    #[test]
    fn with_no_burst_altitude_from_the_drone_or_the_config_file_there_is_no_path_and_it_is_said() {
        let mut config = StationConfig::from_toml_str(DEFAULT_STATION_TOML).expect("config");
        // The shipped file has a forecast-free [flight_path]-free station: give it a wind.
        config.forecast_wind = vec![ForecastRow {
            alt_msl_m: 0.0,
            speed_mps: 5.0,
            from_deg: 270.0,
            sigma_mps: None,
        }];
        assert_eq!(
            config.flight_path_unset,
            vec!["burst_altitude_msl_m", "mean_ascent_rate_mps"]
        );
        let mut core = StationCore::new(config, 0);
        hear(&mut core, 10.0, FlightStage::Ascent, 1_000.0);
        assert!(core.flight_path_view_now().is_none(), "no silent default");
        let said: Vec<String> = core.events_since(0.0).into_iter().map(|e| e.text).collect();
        assert!(
            said.iter().any(|t| t
                .contains("neither the drone nor the station config gives the burst altitude")
                && t.contains("MIS_BURST_M")
                && t.contains("the ascent rate")),
            "{said:?}"
        );
        // The drone's parameters are enough.
        set_param(&mut core, "MIS_BURST_M", 3_000.0);
        set_param(&mut core, "MIS_ASCENT_MPS", 5.0);
        hear(
            &mut core,
            10.0 + FLIGHT_PATH_EVERY_S,
            FlightStage::Ascent,
            1_000.0,
        );
        let path = core
            .flight_path_view_now()
            .expect("a path from the drone's launch profile");
        assert_eq!(path.burst_source, "drone");
    }

    #[test]
    fn the_drones_deploy_and_cutdown_parameters_win_and_the_round_chute_has_no_burst() {
        let mut core = core();
        for (name, value) in [("MIS_DEPLOY_M", 1_500.0), ("MIS_CUTDOWN_M", 20_000.0)] {
            set_param(&mut core, name, value);
        }
        hear(&mut core, 10.0, FlightStage::Ascent, 5_000.0);
        let path = core.flight_path_view_now().expect("path");
        let burst = path.burst.expect("burst");
        assert!(
            (burst.alt_msl_m - 20_000.0).abs() < 1.0,
            "cut down at MIS_CUTDOWN_M"
        );
        let deploy_height = path.deploy.alt_msl_m - core.frame.alt_msl_m;
        assert!((deploy_height - 1_500.0).abs() < 11.0, "{deploy_height}");
        // Under the round chute: no burst ahead; the next path comes after the period.
        hear(&mut core, 11.0, FlightStage::RoundChute, 4_000.0);
        assert!(
            core.flight_path_view_now().expect("path").burst.is_some(),
            "not due yet"
        );
        hear(
            &mut core,
            10.0 + FLIGHT_PATH_EVERY_S,
            FlightStage::RoundChute,
            4_000.0,
        );
        let path = core.flight_path_view_now().expect("path");
        assert_eq!(path.stage, "round_chute");
        assert!(path.burst.is_none());
        // Under the parafoil the landing predictions take over.
        hear(&mut core, 20.0, FlightStage::Parafoil, 1_000.0);
        assert!(core.flight_path_view_now().is_none());
    }
}
