//! The core with telemetry, plan reads and link events, on the fake clock.

use nalgebra::Vector3;
use stx_dynamics::atmosphere::{Atmosphere, StandardAtmosphere};
use stx_gnc::mission::FlightMode;
use stx_link::telemetry::{
    AirData, Attitude, GpsFix as Fix, GpsRaw, SystemState, Telemetry, VehicleStatus,
};

use super::*;
use crate::config::DEFAULT_STATION_TOML;

pub(super) fn core() -> StationCore {
    StationCore::new(
        StationConfig::from_toml_str(DEFAULT_STATION_TOML).expect("config"),
        0,
    )
}

/// The link actions due at `now_s`, each reported applied by the link.
pub(super) fn sent_ops(core: &mut StationCore, now_s: f64) -> Vec<LinkOp> {
    core.take_link_actions(now_s)
        .into_iter()
        .map(|a| {
            core.on_action_outcome(now_s, a.id, Ok(()));
            a.op
        })
        .collect()
}

/// A level, still attitude at `ms` on the drone's clock (it moves the drone's clock on).
pub(super) fn level_attitude(ms: u32) -> Telemetry {
    Telemetry::Attitude(Attitude {
        time_boot_ms: ms,
        roll_rad: 0.0,
        pitch_rad: 0.0,
        yaw_rad: 0.0,
        roll_rate_radps: 0.0,
        pitch_rate_radps: 0.0,
        yaw_rate_radps: 0.0,
    })
}

/// A 3-D GPS fix at `ms` on the drone's clock, at latitude, longitude (degrees) and altitude
/// (m MSL), moving at `[north, east]` m/s.
pub(super) fn gps_raw(ms: u32, [lat, lon, alt]: [f64; 3], [north, east]: [f64; 2]) -> GpsRaw {
    GpsRaw {
        time_usec: u64::from(ms) * 1000,
        fix: Fix::Fix3d,
        lat_deg: lat,
        lon_deg: lon,
        alt_msl_m: alt,
        ground_speed_mps: Some(north.hypot(east)),
        course_deg: Some(east.atan2(north).to_degrees().rem_euclid(360.0)),
        satellites: Some(10),
        h_acc_m: Some(1.5),
        v_acc_m: Some(3.0),
    }
}

/// The drone's heartbeat `status` heard at `now_s`.
fn hear_status(core: &mut StationCore, now_s: f64, status: VehicleStatus) {
    let telemetry = Telemetry::Status(status);
    core.on_link_event(
        now_s,
        GroundEvent::Telemetry {
            from: (1, 1),
            telemetry,
        },
    );
}

/// The drone reports `stage` (heading mode, guidance idle) at `now_s`.
pub(super) fn hear_stage(core: &mut StationCore, now_s: f64, stage: stx_gnc::mission::FlightStage) {
    let status = VehicleStatus {
        mode: FlightMode::Heading,
        stage,
        phase: stx_gnc::mission::GuidancePhase::Idle,
        state: SystemState::Active,
    };
    hear_status(core, now_s, status);
}

/// The drone reports it has landed (its guidance landed, standing by) at `now_s`.
fn hear_landed(core: &mut StationCore, now_s: f64) {
    let status = VehicleStatus {
        mode: FlightMode::Heading,
        stage: stx_gnc::mission::FlightStage::Landed,
        phase: stx_gnc::mission::GuidancePhase::Landed,
        state: SystemState::Standby,
    };
    hear_status(core, now_s, status);
}

/// Telemetry of a parafoil gliding north in still air at 6 m/s, sinking 3 m/s, from 800 m
/// above the origin, as the drone sends it at 4 Hz.
fn glide(core: &mut StationCore, from_s: f64, to_s: f64) -> Vector3<f64> {
    glide_at_speed(core, from_s, to_s, 1.0)
}

/// As [`glide`], with the drone's clock running `speed` times faster than the station's
/// (an accelerated rehearsal).
fn glide_at_speed(core: &mut StationCore, from_s: f64, to_s: f64, speed: f64) -> Vector3<f64> {
    let air = StandardAtmosphere;
    let mut t = from_s;
    let mut truth = Vector3::zeros();
    while t < to_s {
        truth = Vector3::new(6.0 * t, 0.0, -800.0 + 3.0 * t);
        let (lat, lon, alt) = core.frame.to_geodetic(&truth);
        let ms = (t * 1000.0) as u32;
        let state = air.air_at(alt);
        let airspeed = (6.0_f64.powi(2) + 3.0_f64.powi(2)).sqrt();
        let pitch = -(3.0_f64 / 6.0).atan();
        for telemetry in [
            Telemetry::Status(VehicleStatus {
                mode: FlightMode::Heading,
                stage: stx_gnc::mission::FlightStage::Parafoil,
                phase: stx_gnc::mission::GuidancePhase::Idle,
                state: SystemState::Active,
            }),
            Telemetry::Position(stx_link::telemetry::GlobalPosition {
                time_boot_ms: ms,
                lat_deg: lat,
                lon_deg: lon,
                alt_msl_m: alt,
                alt_rel_m: alt - core.frame.alt_msl_m,
                v_north_mps: 6.0,
                v_east_mps: 0.0,
                v_down_mps: 3.0,
                heading_deg: Some(0.0),
            }),
            Telemetry::GpsRaw(gps_raw(ms, [lat, lon, alt], [6.0, 0.0])),
            Telemetry::Attitude(Attitude {
                time_boot_ms: ms,
                roll_rad: 0.0,
                pitch_rad: pitch,
                yaw_rad: 0.0,
                roll_rate_radps: 0.0,
                pitch_rate_radps: 0.0,
                yaw_rate_radps: 0.0,
            }),
            Telemetry::AirData(AirData {
                time_boot_ms: ms,
                abs_pressure_pa: state.pressure_pa,
                diff_pressure_pa: 0.5 * state.density_kg_per_m3 * airspeed * airspeed,
                temperature_c: state.temperature_k - 273.15,
                diff_temperature_c: None,
            }),
        ] {
            core.on_link_event(
                t,
                GroundEvent::Telemetry {
                    from: (1, 1),
                    telemetry,
                },
            );
        }
        core.set_link_stats(
            t,
            LinkStats {
                connected: true,
                ..LinkStats::default()
            },
        );
        core.tick(t / speed);
        t += 0.25;
    }
    truth
}

#[test]
fn live_telemetry_becomes_an_estimate_with_still_air_and_a_prediction() {
    let mut core = core();
    assert!(
        core.tick(0.0).estimate.is_none(),
        "no estimate before telemetry"
    );
    let truth = glide(&mut core, 0.0, 40.0);
    let est = core.estimate.expect("an estimate");
    assert!(
        (est.position_ned_m - truth).norm() < 5.0,
        "{:?} vs {truth:?}",
        est.position_ned_m
    );
    assert!(
        est.wind_ned_mps.xy().norm() < 0.5,
        "still air: {:?}",
        est.wind_ned_mps
    );
    let state = core.state_msg_now(40.0);
    assert_eq!(
        state
            .vehicle
            .as_ref()
            .and_then(|v| v.mode.clone())
            .as_deref(),
        Some("heading")
    );
    assert!(
        state.prediction.is_none(),
        "the prediction runs only when asked"
    );
    let job = core.prediction_job().expect("a prediction can run");
    core.set_prediction(job.run());
    let prediction = core.state_msg_now(40.0).prediction.expect("a prediction");
    // Uncontrolled, straight north: lands north of where it is now, about 2:1 further on.
    let uncontrolled = prediction.uncontrolled;
    let (lat_now, _, _) = core.frame.to_geodetic(&truth);
    assert!(uncontrolled.lat_deg > lat_now, "{uncontrolled:?}");
}

#[test]
fn navigation_runs_on_the_drones_clock_in_accelerated_rehearsals() {
    let mut core = core();
    let truth = glide_at_speed(&mut core, 0.0, 40.0, 20.0);
    let est = core.estimate.expect("an estimate");
    assert!(
        (est.position_ned_m - truth).norm() < 5.0,
        "{:?} vs {truth:?}",
        est.position_ned_m
    );
    assert!(
        (est.velocity_ned_mps - Vector3::new(6.0, 0.0, 3.0)).norm() < 0.5,
        "{:?}",
        est.velocity_ned_mps
    );
    assert!(
        (core.track.len() as f64 - 40.0).abs() <= 1.0,
        "one track point per flight second"
    );
}

#[test]
fn a_drone_restart_starts_navigation_over() {
    let mut core = core();
    glide(&mut core, 30.0, 60.0);
    assert!(core.estimate.is_some());
    glide(&mut core, 0.0, 0.5);
    assert!(core.events.iter().any(|e| e.text.contains("restarted")));
    let est = core.estimate.expect("estimate after restart");
    assert!(
        est.time_s < 1.0,
        "navigation on the new clock: {}",
        est.time_s
    );
}

#[test]
fn silence_turns_the_vehicle_stale_and_the_stage_change_is_logged() {
    let mut core = core();
    glide(&mut core, 0.0, 5.0);
    assert!(!core.state_msg_now(5.0).link.stale);
    let stale_after = core.config.link.stale_after_s;
    assert!(core.state_msg_now(5.0 + stale_after + 0.5).link.stale);
    hear_landed(&mut core, 6.0);
    assert!(core.events.iter().any(|e| e.text.contains("Landed")));
}

#[test]
fn every_final_approach_the_drone_reports_is_counted_for_pages_that_skip_states() {
    use stx_gnc::mission::GuidancePhase as P;
    let mut core = core();
    let heard = |core: &mut StationCore, now_s: f64, phase: P| {
        let stage = stx_gnc::mission::FlightStage::Parafoil;
        let (mode, state) = (FlightMode::SpiralLanding, SystemState::Active);
        hear_status(
            core,
            now_s,
            VehicleStatus {
                mode,
                stage,
                phase,
                state,
            },
        );
    };
    let count = |core: &StationCore, now_s: f64| {
        core.state_msg_now(now_s)
            .vehicle
            .map(|v| v.final_approaches)
    };
    // A page sent the state at 1 s and at 5 s sees branch 4, then the flare: the final approach
    // between shows in the count. A repeated status is the same approach; a second is counted.
    heard(&mut core, 1.0, P::Branch4);
    assert_eq!(count(&core, 1.0), Some(0));
    for (t, phase) in [
        (2.0, P::FinalApproach),
        (3.0, P::FinalApproach),
        (4.0, P::Flare),
    ] {
        heard(&mut core, t, phase);
    }
    assert_eq!(count(&core, 5.0), Some(1));
    for (t, phase) in [(6.0, P::Approximation), (7.0, P::FinalApproach)] {
        heard(&mut core, t, phase);
    }
    assert_eq!(count(&core, 8.0), Some(2));
}

#[test]
fn guidance_telemetry_gives_the_drones_target_until_its_plan_is_read() {
    let mut core = core();
    glide(&mut core, 0.0, 5.0);
    assert!(
        core.state_msg_now(5.0)
            .guidance
            .and_then(|g| g.target)
            .is_none()
    );
    // The drone's NAV_CONTROLLER_OUTPUT towards its target 300 m N, 2,500 m E.
    let (p, _) = core.latest.position.expect("a position");
    let here = core.frame.to_ned(p.lat_deg, p.lon_deg, p.alt_msl_m);
    let to = Vector3::new(300.0, 2500.0, 0.0) - here;
    let status = stx_link::telemetry::GuidanceStatus {
        desired_roll_deg: 0.0,
        desired_heading_deg: 0.0,
        bearing_to_target_deg: to.y.atan2(to.x).to_degrees().rem_euclid(360.0).round(),
        distance_to_target_m: to.xy().norm().round(),
        alt_error_m: 0.0,
        xtrack_error_m: 0.0,
    };
    let guidance = |core: &mut StationCore, t: f64| {
        core.on_link_event(
            t,
            GroundEvent::Telemetry {
                from: (1, 1),
                telemetry: Telemetry::Guidance(status),
            },
        );
    };
    guidance(&mut core, 5.0);
    let g = core.state_msg_now(5.0).guidance.expect("guidance");
    assert_eq!(g.target_source, Some("drone_telemetry"));
    let t = g.target.expect("a target");
    let ne = core.frame.to_ned(t.lat_deg, t.lon_deg, t.alt_msl_m);
    // Whole degrees of bearing at 2.5 km: within about 22 m.
    assert!(
        (ne.xy() - nalgebra::Vector2::new(300.0, 2500.0)).norm() < 25.0,
        "{ne:?}"
    );
    assert_eq!(sent_ops(&mut core, 5.0), vec![LinkOp::PlanDownload]);
    assert!(sent_ops(&mut core, 5.1).is_empty(), "asked once");
    // The plan read back is exact, and agreeing telemetry changes nothing.
    let (lat, lon, alt) = core.frame.to_geodetic(&Vector3::new(300.0, 2500.0, 0.0));
    core.on_link_event(
        6.0,
        GroundEvent::Plan(stx_link::plan::PlanEvent::DownloadDone {
            items: vec![stx_link::plan::PlanItem::Land {
                lat_deg: lat,
                lon_deg: lon,
                alt_msl_m: alt,
                approach_heading_deg: None,
            }],
        }),
    );
    guidance(&mut core, 6.5);
    let g = core.state_msg_now(6.5).guidance.expect("guidance");
    assert_eq!(g.target_source, Some("drone_plan"));
    assert!(
        (core.replica_plan().target_ned_m.xy() - nalgebra::Vector2::new(300.0, 2500.0)).norm()
            < 0.5
    );
    assert!(sent_ops(&mut core, 20.0).is_empty(), "no new download");
}

#[test]
fn failed_plan_reads_are_retried_later_and_later_and_said_once() {
    let mut core = core();
    core.on_link_event(
        0.0,
        GroundEvent::Link(LinkEvent::Connected {
            system_id: 1,
            component_id: 1,
        }),
    );
    assert_eq!(
        sent_ops(&mut core, 0.0),
        vec![LinkOp::ParamList, LinkOp::PlanDownload],
        "a drone heard: its parameters and its plan are read"
    );
    let fail = |core: &mut StationCore, t: f64| {
        core.on_link_event(
            t,
            GroundEvent::Plan(stx_link::plan::PlanEvent::DownloadFailed {
                reason: "no answer".into(),
            }),
        );
    };
    fail(&mut core, 1.0);
    assert!(sent_ops(&mut core, 5.9).is_empty(), "not before 5 s");
    assert_eq!(sent_ops(&mut core, 6.0), vec![LinkOp::PlanDownload]);
    fail(&mut core, 7.0);
    assert!(sent_ops(&mut core, 16.9).is_empty(), "then 10 s");
    assert_eq!(sent_ops(&mut core, 17.0), vec![LinkOp::PlanDownload]);
    let said = core
        .events
        .iter()
        .filter(|e| e.text.contains("plan could not be read"))
        .count();
    assert_eq!(said, 1);
}

#[test]
fn derived_values_turn_stale_with_the_link() {
    let mut core = core();
    glide(&mut core, 0.0, 10.0);
    let job = core.prediction_job().expect("a prediction");
    core.set_prediction(job.run());
    let fresh = core.state_msg_now(10.0);
    assert!(!fresh.estimate.as_ref().expect("estimate").stale);
    assert!(!fresh.vehicle.as_ref().expect("vehicle").stale);
    assert!(!fresh.prediction.as_ref().expect("prediction").stale);
    assert!(!fresh.guidance.as_ref().expect("guidance").stale);
    let later = 10.0 + core.config.link.stale_after_s + 1.0;
    let old = core.state_msg_now(later);
    let estimate = old.estimate.expect("the last estimate is still shown");
    assert!(estimate.stale && estimate.age_s > core.config.link.stale_after_s);
    assert!(old.vehicle.expect("vehicle").stale);
    assert!(old.prediction.expect("prediction").stale);
    assert!(old.guidance.expect("guidance").stale);
    assert!(old.link.stale);
}

#[test]
fn kml_predicted_landings_lie_on_the_ground_not_at_sea_level() {
    let mut core = core();
    glide(&mut core, 0.0, 10.0);
    let job = core.prediction_job().expect("a prediction");
    core.set_prediction(job.run());
    core.on_link_event(
        10.0,
        GroundEvent::Telemetry {
            from: (1, 1),
            telemetry: Telemetry::PredictedLanding(stx_link::telemetry::PredictedLanding {
                time_boot_ms: 10_000,
                lat_deg: 38.54,
                lon_deg: -7.88,
                alt_msl_m: 245.0,
            }),
        },
    );
    let doc = crate::kml::live("test", &core.track(1.0), &core.state_msg_now(10.0));
    let predicted: Vec<&str> = doc
        .lines()
        .filter(|l| l.contains("predicted landing"))
        .collect();
    assert_eq!(
        predicted.len(),
        3,
        "station plan, uncontrolled, drone's own: {doc}"
    );
    for p in predicted {
        // The site is 245 m above the sea: altitude 0 absolute would be underground.
        assert!(
            p.contains("<altitudeMode>clampToGround</altitudeMode>"),
            "{p}"
        );
        assert!(!p.contains("absolute"), "{p}");
    }
    // The name as XML text: its apostrophe escaped, as every XML writer of stx escapes it.
    assert!(
        doc.contains("predicted landing (drone&apos;s own)"),
        "{doc}"
    );
}

#[test]
fn waiting_for_the_drone_is_said_once() {
    let mut core = core();
    for queued in 1..10 {
        core.on_io_event(
            f64::from(queued as u32),
            0,
            IoEvent::QueuedWithoutPeer { queued },
        );
    }
    assert_eq!(core.events.len(), 1);
}

#[test]
fn glide_ratios_are_shown_under_the_canopy_and_not_once_landed() {
    let mut core = core();
    glide(&mut core, 0.0, 20.0);
    let gliding = core.state_msg_now(20.0).estimate.expect("an estimate");
    // 6 m/s forward for 3 m/s down.
    let air = gliding.glide_ratio_air.expect("a glide ratio in flight");
    assert!((air - 2.0).abs() < 0.2, "{air}");
    hear_landed(&mut core, 20.1);
    let landed = core.state_msg_now(20.2).estimate.expect("an estimate");
    assert_eq!(
        (landed.glide_ratio_air, landed.glide_ratio_ground),
        (None, None)
    );
}

/// The chase cars' summaries (`crate::chase`) from a live state: the payload where its GPS
/// says, its speed in km/h and course, Horus's fields and nothing else; then the landing.
#[test]
fn chase_summaries_carry_the_gps_fix_and_the_predicted_landing_in_horus_fields() {
    use crate::chase::{ChaseConfig, summaries};
    let config: ChaseConfig = toml::from_str("callsign = \"STRAPLEX1\"").expect("config");
    let mut core = core();
    assert!(
        summaries(&config, 240.0, &core.state_msg_now(0.0)).is_empty(),
        "no fix, nothing"
    );
    glide(&mut core, 0.0, 40.0);
    let job = core.prediction_job().expect("a prediction can run");
    core.set_prediction(job.run());
    let state = core.state_msg_now(40.0);
    let sent = summaries(&config, 240.0, &state);
    let gps = state
        .vehicle
        .as_ref()
        .and_then(|v| v.gps.clone())
        .expect("a fix");
    let payload = &sent[0];
    assert_eq!(payload.callsign, "STRAPLEX1");
    assert_eq!(
        (payload.latitude, payload.longitude),
        (gps.lat_deg, gps.lon_deg)
    );
    assert!(
        (payload.speed - 6.0 * 3.6).abs() < 1e-6,
        "{}",
        payload.speed
    );
    assert!(payload.heading.abs() < 1e-6, "north: {}", payload.heading);
    assert_eq!(
        (payload.sats, payload.comment.as_str()),
        (10, "stx: parafoil")
    );
    let json = serde_json::to_value(payload).expect("json");
    let mut keys: Vec<&str> = json
        .as_object()
        .expect("object")
        .keys()
        .map(String::as_str)
        .collect();
    keys.sort_unstable();
    // What horusdemodlib's send_payload_summary sends (without its optional snr/frequency).
    assert_eq!(
        keys,
        [
            "altitude",
            "batt_voltage",
            "callsign",
            "comment",
            "heading",
            "latitude",
            "longitude",
            "sats",
            "speed",
            "temp",
            "time",
            "type"
        ]
    );
    let landing = &sent[1];
    let predicted = state.prediction.as_ref().expect("a prediction");
    let touchdown = predicted
        .planned
        .as_ref()
        .unwrap_or(&predicted.uncontrolled);
    assert_eq!(landing.callsign, "STRAPLEX1_LANDING");
    assert_eq!(
        (landing.latitude, landing.longitude),
        (touchdown.lat_deg, touchdown.lon_deg)
    );
    assert!(
        landing.comment.starts_with("stx predicted landing"),
        "{}",
        landing.comment
    );
}
