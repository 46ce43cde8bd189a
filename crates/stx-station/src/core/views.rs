//! The dashboard's view of the station's state: the `state` and `params` messages.

use stx_dynamics::rotation::wrap_pi;
use stx_gnc::mission::FlightStage;
use stx_gnc::mission::GuidancePhase;
use stx_gnc::params::ParamKind;
use stx_gnc::predict::PredictedTouchdown;

use super::StationCore;
use crate::messages::{
    AirView, AttitudeView, CommandsView, EstimateView, GpsView, GuidanceView, LatLonAlt,
    LearnedView, LinkView, LocalizerView, MissionView, OnboardLandingView, ParamView, ParamsMsg,
    PatternView, PowerView, PredictionView, RadioView, ReadinessView, ServosView, StateMsg,
    TouchdownView, VehicleView,
};

pub(crate) fn snake<T: serde::Serialize + std::fmt::Debug>(v: T) -> String {
    serde_json::to_value(&v)
        .ok()
        .and_then(|j| j.as_str().map(String::from))
        .unwrap_or_else(|| format!("{v:?}"))
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

impl StationCore {
    /// The `state` message for `now_s` from what the station knows (no side effects).
    pub fn state_msg_now(&self, now_s: f64) -> StateMsg {
        let stale_after = self.config.link.stale_after_s;
        let age = |since: Option<f64>| since.map(|t| (now_s - t).max(0.0));
        // One rule for every block derived from the drone's data.
        let stale =
            |age_s: Option<f64>| age_s.is_none_or(|a| a > stale_after) || !self.link.connected;
        let age_s = age(self.latest.any_s);
        let link = LinkView {
            connected: self.link.connected,
            stale: stale(age_s),
            age_s,
            rate_hz: self.link.messages_per_s,
            loss_percent: self.link.packet_loss_pct,
            crc_errors: self.link.crc_errors,
            parse_errors: self.link.parse_errors,
            signature_errors: self.link.signature_failures,
            ages_s: self.link.last_message_age_s.clone(),
            radios: self
                .config
                .link
                .addresses()
                .zip(&self.link.paths)
                .map(|(address, p)| RadioView {
                    address: address.clone(),
                    transmitting: p.transmitting,
                    stale: p.last_heard_age_s.is_none_or(|a| a > stale_after),
                    age_s: p.last_heard_age_s,
                    rate_hz: p.messages_per_s,
                    loss_percent: p.packet_loss_pct,
                    duplicates: p.duplicates,
                })
                .collect(),
        };
        let l = &self.latest;
        let vehicle = l.any_s.map(|any_s| VehicleView {
            age_s: (now_s - any_s).max(0.0),
            stale: stale(age(Some(any_s))),
            predicted_landing: l.predicted_landing.map(|(p, at)| OnboardLandingView {
                lat_deg: p.lat_deg,
                lon_deg: p.lon_deg,
                alt_msl_m: p.alt_msl_m,
                age_s: (now_s - at).max(0.0),
                stale: stale(age(Some(at))),
            }),
            mode: l.status.map(|(s, _)| snake(s.mode)),
            stage: l.status.map(|(s, _)| snake(s.stage)),
            phase: l.status.map(|(s, _)| snake(s.phase)),
            final_approaches: l.final_approaches,
            gps: l.gps.map(|(g, _)| {
                let speed = g.ground_speed_mps.unwrap_or(0.0);
                let course = g.course_deg.unwrap_or(0.0).to_radians();
                let down = l.position.map_or(0.0, |(p, _)| p.v_down_mps);
                GpsView {
                    fix: snake(g.fix),
                    satellites: g.satellites,
                    lat_deg: g.lat_deg,
                    lon_deg: g.lon_deg,
                    alt_msl_m: g.alt_msl_m,
                    velocity_ned_mps: [speed * course.cos(), speed * course.sin(), down],
                    h_acc_m: g.h_acc_m,
                }
            }),
            attitude: l.attitude.map(|(a, _)| AttitudeView {
                time_boot_ms: a.time_boot_ms,
                roll_deg: a.roll_rad.to_degrees(),
                pitch_deg: a.pitch_rad.to_degrees(),
                yaw_deg: a.yaw_rad.to_degrees(),
            }),
            air: l.air.map(|(a, _)| {
                let sample = stx_gnc::measurement::AirDataSample {
                    time_s: 0.0,
                    differential_pressure_pa: a.diff_pressure_pa,
                    static_pressure_pa: a.abs_pressure_pa,
                    temperature_k: a.temperature_c + 273.15,
                };
                AirView {
                    static_pressure_pa: a.abs_pressure_pa,
                    differential_pressure_pa: a.diff_pressure_pa,
                    temperature_c: a.temperature_c,
                    airspeed_mps: sample.indicated_airspeed_mps(),
                }
            }),
            servos: l.actuators.map(|(a, _)| ServosView {
                main_line: a.main_line,
                brake_right: a.brake_right,
                brake_left: a.brake_left,
            }),
            power: l
                .battery
                .map(|(b, _)| PowerView {
                    voltage_v: b.voltage_v,
                    current_a: b.current_a,
                    remaining_percent: b.remaining_pct,
                })
                .or_else(|| {
                    l.system.map(|(s, _)| PowerView {
                        voltage_v: s.battery_voltage_v,
                        current_a: s.battery_current_a,
                        remaining_percent: s.battery_remaining_pct,
                    })
                }),
            onboard_wind_ned_mps: l.wind.and_then(|(w, _)| {
                Some([
                    w.wind_north_mps?,
                    w.wind_east_mps?,
                    w.wind_down_mps.unwrap_or(0.0),
                ])
            }),
        });
        let estimate_age_s = self.estimate.and(age(self.latest.sensors_s));
        // A glide ratio is a canopy's: on the pad, under the balloon, under the round chute
        // and on the ground the estimator's quotient of noise reads as "24.67 : 1".
        let stage = self.latest.status.map(|(s, _)| s.stage);
        let gliding = !matches!(
            stage,
            Some(
                FlightStage::PreLaunch
                    | FlightStage::Ascent
                    | FlightStage::RoundChute
                    | FlightStage::Landed
            )
        );
        let glide = |v: f64| finite(v).filter(|_| gliding);
        let estimate = self.estimate.map(|e| {
            let (lat, lon, alt) = self.frame.to_geodetic(&e.position_ned_m);
            let w = e.wind_ned_mps;
            EstimateView {
                lat_deg: lat,
                lon_deg: lon,
                alt_msl_m: alt,
                height_m: e.height_m(),
                velocity_ned_mps: [
                    e.velocity_ned_mps.x,
                    e.velocity_ned_mps.y,
                    e.velocity_ned_mps.z,
                ],
                ground_speed_mps: e.ground_speed_mps(),
                course_deg: e.course_rad.to_degrees(),
                heading_deg: e.heading_rad.to_degrees(),
                heading_rate_dps: e.heading_rate_rad_s.to_degrees(),
                airspeed_mps: e.airspeed_mps,
                sink_rate_mps: e.sink_rate_mps,
                glide_ratio_air: glide(e.glide_ratio_air),
                glide_ratio_ground: glide(e.glide_ratio_ground),
                wind_ned_mps: [w.x, w.y, w.z],
                wind_speed_mps: e.wind_speed_mps(),
                wind_from_deg: (-w.y).atan2(-w.x).to_degrees().rem_euclid(360.0),
                wind_sigma_mps: e.wind_sigma_mps.x.max(e.wind_sigma_mps.y),
                position_sigma_m: e.position_sigma_m.x.hypot(e.position_sigma_m.y),
                gps_ok: e.gps_ok,
                age_s: estimate_age_s.unwrap_or(0.0),
                stale: stale(estimate_age_s),
            }
        });
        let plan = self.guidance.plan();
        let to_pair = |ne: [f64; 2]| {
            let (lat, lon, _) = self
                .frame
                .to_geodetic(&nalgebra::Vector3::new(ne[0], ne[1], 0.0));
            [lat, lon]
        };
        let target = self.sync.target.map(|_| {
            let (lat, lon, alt) = self.frame.to_geodetic(&plan.target_ned_m);
            LatLonAlt {
                lat_deg: lat,
                lon_deg: lon,
                alt_msl_m: alt,
            }
        });
        let mode = self.guidance.mode();
        let plan_known = self.plan_known_for(mode);
        let flying = self.replica_flies();
        // The replica flies only under the parafoil; before and after, the phase is the
        // drone's (idle, landed), as the onboard guidance reports it.
        let phase = match self.latest.status {
            Some((s, _)) if !flying => s.phase,
            _ => self.guidance.phase(),
        };
        let spiral = self.guidance.spiral_status();
        let guidance = Some(GuidanceView {
            mode: snake(mode),
            phase: snake(phase),
            target,
            target_source: self.sync.target.map(|s| s.name()),
            localizer: self.sync.line_known.then(|| LocalizerView {
                point: to_pair(plan.localizer.point_ne_m),
                course_deg: plan.localizer.course_rad.to_degrees().rem_euclid(360.0),
                glide_slope: plan.localizer_glide_slope,
            }),
            age_s: estimate_age_s,
            stale: stale(estimate_age_s),
            disagreement: self.disagreement_view(self.drone_time_s),
            // Before its first update under the parafoil the spiral has planned nothing: its
            // status would put the pattern at the origin.
            pattern: (flying
                && plan_known
                && phase != GuidancePhase::Idle
                && self.guidance.spiral_has_run())
            .then(|| PatternView {
                corners: spiral.corners_ne_m.iter().map(|c| to_pair(*c)).collect(),
                final_entry: to_pair(spiral.final_entry_ne_m),
                final_course_deg: wrap_pi(spiral.final_course_rad)
                    .to_degrees()
                    .rem_euclid(360.0),
                final_approach_height_m: spiral.final_approach_height_m,
                target_reachable: spiral.target_reachable,
                reach_ratio: if spiral.reach_ratio.is_finite() {
                    spiral.reach_ratio
                } else {
                    -1.0
                },
            }),
            // Kept after the landing: what this flight learned is what the debrief (and the
            // next flight's vehicle file) wants.
            learned: self.guidance.spiral_has_run().then(|| {
                let l = self.guidance.learned_polar();
                LearnedView {
                    brake: l.brake,
                    airspeed_scale: l.airspeed_scale,
                    sink_scale: l.sink_scale,
                    airspeed_sigma: l.airspeed_sigma,
                    sink_sigma: l.sink_sigma,
                    learned_s: l.learned_s,
                    turn_scale: l.turn_scale,
                    turn_sigma: l.turn_sigma,
                    turn_learned_s: l.turn_learned_s,
                    flying,
                }
            }),
            commands: CommandsView {
                main_line: (self.replica_command.main_line_m / self.main_line_travel_m)
                    .clamp(-1.0, 1.0),
                brake: 0.5 * (self.replica_command.brake_right + self.replica_command.brake_left),
            },
        });
        let touchdown = |t: &PredictedTouchdown| {
            let (lat, lon, _) = self.frame.to_geodetic(&nalgebra::Vector3::new(
                t.position_ne_m[0],
                t.position_ne_m[1],
                0.0,
            ));
            TouchdownView {
                lat_deg: lat,
                lon_deg: lon,
                time_to_land_s: t.time_to_land_s,
                semi_major_m: t.semi_major_m,
                semi_minor_m: t.semi_minor_m,
                major_axis_deg: t.major_axis_rad.to_degrees().rem_euclid(180.0),
            }
        };
        let prediction_age_s = age(self.prediction_data_s);
        let prediction = self.prediction.map(|p| PredictionView {
            planned: plan_known.then(|| touchdown(&p.planned)),
            uncontrolled: touchdown(&p.uncontrolled),
            age_s: prediction_age_s,
            stale: stale(prediction_age_s),
        });
        let mut msg = StateMsg {
            kind: "state",
            time_s: now_s,
            mission_time_s: self.mission_clock.at(now_s),
            wall_ms: self.wall_ms(now_s),
            link,
            vehicle,
            estimate,
            // On the ground the bodies lie where they fell, not where the rigging hangs them.
            stack: self
                .latest
                .attitude
                .filter(|_| {
                    self.latest
                        .status
                        .is_none_or(|(st, _)| st.stage != FlightStage::Landed)
                })
                .map(|(a, at)| {
                    let euler = nalgebra::Vector3::new(a.roll_rad, a.pitch_rad, a.yaw_rad);
                    let canopy_out = self.latest.status.is_some_and(|(st, _)| {
                        matches!(
                            st.stage,
                            FlightStage::ParafoilDeploy | FlightStage::Parafoil
                        )
                    });
                    super::stack::stack_view(
                        &self.rigging,
                        euler,
                        (now_s - at).max(0.0),
                        &self.body_attitudes,
                        now_s,
                        canopy_out,
                    )
                }),
            guidance,
            prediction,
            footprint: self.footprint_view(now_s),
            flight_path: self.flight_path_view_now(),
            forecast_wind: self.config.forecast_wind.clone(),
            mission: MissionView {
                stage: self.latest.status.map(|(s, _)| snake(s.stage)),
                cutdown_armed_until_s: self.cutdown.armed_until(),
                landing: self.landing.landing.clone(),
            },
            keep_out_alarms: self.keep_out_alarms(),
            recording: None,
            readiness: ReadinessView::default(),
            replay: None,
            surface_wind: self.surface_wind_view(now_s),
        };
        msg.readiness = self.readiness_view(&msg);
        msg
    }

    /// The parameter table as the dashboard shows it.
    pub fn params_msg(&self, now_s: f64) -> ParamsMsg {
        let params = self
            .params
            .values
            .values()
            .map(|p| {
                let spec = stx_gnc::params::find(&p.name);
                ParamView {
                    name: p.name.clone(),
                    value: f64::from(p.value),
                    min: spec.map(|s| s.min),
                    max: spec.map(|s| s.max),
                    units: spec.map_or(String::new(), |s| s.units.to_string()),
                    description: spec.map_or(String::new(), |s| s.description.to_string()),
                    group: spec.map(|s| snake(s.group)),
                    choices: match spec.map(|s| s.kind) {
                        Some(ParamKind::Choice(names)) => names.to_vec(),
                        Some(ParamKind::Flag) => vec!["off", "on"],
                        _ => Vec::new(),
                    },
                }
            })
            .collect();
        ParamsMsg {
            kind: "params",
            params,
            complete: self.params.complete,
            time_s: now_s,
        }
    }
}
