//! The simulated drone behind its MAVLink endpoint ([`LinkedDrone`]), flown in accelerated
//! time against a ground endpoint in the same process: every command, parameter, stick and
//! plan crosses the wire as MAVLink frames, and every failure of the link is injected on the
//! frames themselves. The link clock is the mission clock here (one clock, deterministic).
//!
//! `drone_core.rs` tests the drone's own logic through direct calls; this file tests what the
//! station sees and what reaches the drone over the link.

use std::time::Duration;

use stx_dynamics::vehicle::Vehicle;
use stx_gnc::mission::{FlightMode, FlightStage, GuidancePhase};
use stx_link::command::{Command, CommandOutcome, RequestId};
use stx_link::endpoint::{GroundConfig, GroundEndpoint, GroundEvent, LinkConfig};
use stx_link::manual::Sticks;
use stx_link::param::ParamEvent;
use stx_link::plan::{PlanEvent, PlanItem};
use stx_link::telemetry::{Actuators, Telemetry, VehicleStatus};
use stx_sim::drone::link::{DroneEvent, LinkedDrone};
use stx_sim::drone::{BalloonEnd, Drone, MissionConfig};
use stx_types::stack::BodyImu;

/// A linked drone and a ground endpoint exchanging every frame at once.
struct Bench {
    drone: LinkedDrone,
    ground: GroundEndpoint,
    /// Every ground event, with the mission time it arrived.
    ground_events: Vec<(f64, GroundEvent)>,
    /// Every drone event.
    drone_events: Vec<DroneEvent>,
    next_request: u64,
}

impl Bench {
    fn new(name: &str, tweak: impl FnOnce(&mut MissionConfig)) -> Self {
        let mut config = MissionConfig::builtin(name).expect("built-in mission");
        tweak(&mut config);
        let drone = Drone::new(&config, Vehicle::straplex()).expect("drone");
        let drone = LinkedDrone::new(drone, LinkConfig::vehicle(), Duration::ZERO).expect("linked");
        let mut bench = Self {
            drone,
            ground: GroundEndpoint::new(GroundConfig::default(), Duration::ZERO),
            ground_events: Vec::new(),
            drone_events: Vec::new(),
            next_request: 1,
        };
        bench.exchange();
        bench
    }

    fn time_s(&self) -> f64 {
        self.drone.drone().time_s()
    }

    fn now(&self) -> Duration {
        Duration::from_secs_f64(self.time_s())
    }

    /// Runs both ends' timers and delivers every frame each way until both are quiet.
    fn exchange(&mut self) {
        let now = self.now();
        self.drone.handle_timeout(now);
        self.ground.handle_timeout(now);
        loop {
            let mut moved = false;
            while let Some(frame) = self.drone.poll_transmit(now) {
                self.ground.handle_bytes(now, &frame);
                moved = true;
            }
            while let Some(frame) = self.ground.poll_transmit(now) {
                self.drone.handle_bytes(now, &frame);
                moved = true;
            }
            if !moved {
                break;
            }
        }
        let t = self.time_s();
        while let Some(e) = self.ground.poll_event() {
            self.ground_events.push((t, e));
        }
        while let Some(e) = self.drone.poll_event() {
            self.drone_events.push(e);
        }
    }

    fn step(&mut self) {
        let now = self.now();
        self.drone.step(now).expect("step");
        self.exchange();
    }

    /// Steps until `done` or `limit_s` of mission time; returns whether `done` was met.
    fn run_until(&mut self, limit_s: f64, mut done: impl FnMut(&Self) -> bool) -> bool {
        while self.time_s() < limit_s {
            if done(self) {
                return true;
            }
            self.step();
        }
        done(self)
    }

    fn run_for(&mut self, seconds: f64) {
        let end = self.time_s() + seconds;
        self.run_until(end, |_| false);
    }

    fn land(&mut self) {
        let limit = self.time_s() + 3600.0;
        assert!(
            self.run_until(limit, |b| b.drone.landed()),
            "not landed by {limit} s"
        );
    }

    fn command(&mut self, command: Command) -> RequestId {
        let id = RequestId(self.next_request);
        self.next_request += 1;
        let now = self.now();
        self.ground
            .send_command(now, id, command)
            .expect("command queued");
        self.exchange();
        id
    }

    /// The final outcome of request `id`, stepping until it arrives.
    fn outcome(&mut self, id: RequestId) -> CommandOutcome {
        let limit = self.time_s() + 30.0;
        let find = |b: &Self| {
            b.ground_events.iter().find_map(|(_, e)| match e {
                GroundEvent::Command(c)
                    if c.request_id == id
                        && !matches!(c.outcome, CommandOutcome::InProgress { .. }) =>
                {
                    Some(c.outcome)
                }
                _ => None,
            })
        };
        self.run_until(limit, |b| find(b).is_some());
        find(self).expect("command answered")
    }

    /// Every heartbeat the ground received, with its time.
    fn heartbeats(&self) -> Vec<(f64, VehicleStatus)> {
        self.ground_events
            .iter()
            .filter_map(|(t, e)| match e {
                GroundEvent::Telemetry {
                    telemetry: Telemetry::Status(s),
                    ..
                } => Some((*t, *s)),
                _ => None,
            })
            .collect()
    }

    fn last_status(&self) -> VehicleStatus {
        self.heartbeats().last().expect("a heartbeat").1
    }

    /// The last SERVO_OUTPUT_RAW the ground received.
    fn last_servos(&self) -> Actuators {
        self.ground_events
            .iter()
            .rev()
            .find_map(|(_, e)| match e {
                GroundEvent::Telemetry {
                    telemetry: Telemetry::Actuators(a),
                    ..
                } => Some(*a),
                _ => None,
            })
            .expect("SERVO_OUTPUT_RAW")
    }

    /// Every STATUSTEXT the ground re-assembled.
    fn texts(&self) -> Vec<String> {
        self.ground_events
            .iter()
            .filter_map(|(_, e)| match e {
                GroundEvent::StatusText { text, .. } => Some(text.clone()),
                _ => None,
            })
            .collect()
    }

    fn param_events(&self) -> Vec<ParamEvent> {
        self.ground_events
            .iter()
            .filter_map(|(_, e)| match e {
                GroundEvent::Param(p) => Some(p.clone()),
                _ => None,
            })
            .collect()
    }

    fn stage(&self) -> FlightStage {
        self.drone.drone().stage()
    }

    fn miss_m(&self) -> f64 {
        self.drone
            .drone()
            .landing()
            .and_then(|l| l.miss_m)
            .expect("landed with a target")
    }
}

#[test]
fn the_station_sees_every_stage_of_mission_short_in_order_and_the_landing_on_the_target() {
    let mut bench = Bench::new("mission-short", |_| {});
    bench.land();
    bench.run_for(2.0);
    let mut seen: Vec<FlightStage> = Vec::new();
    for (_, s) in bench.heartbeats() {
        if seen.last() != Some(&s.stage) {
            seen.push(s.stage);
        }
    }
    assert_eq!(
        seen,
        [
            FlightStage::PreLaunch,
            FlightStage::Ascent,
            FlightStage::RoundChute,
            FlightStage::ParafoilDeploy,
            FlightStage::Parafoil,
            FlightStage::Landed
        ],
        "{:#?}",
        bench.texts()
    );
    let texts = bench.texts();
    for needle in [
        "launched",
        "balloon burst at",
        "releasing the round chute",
        "parafoil flying",
        "landed at",
    ] {
        assert!(
            texts.iter().any(|t| t.contains(needle)),
            "no `{needle}` in {texts:#?}"
        );
    }
    let miss = bench.miss_m();
    println!(
        "mission-short through the link: landed at {:.0} s, {miss:.1} m from the target",
        bench.time_s()
    );
    assert!(miss < 60.0, "missed the target by {miss} m");

    // The summary tells the same story in figures.
    let summary = bench.drone.drone().summary();
    let (end, _, burst_msl_m) = summary.balloon_end.expect("the balloon went");
    assert_eq!(end, BalloonEnd::Burst);
    assert!((burst_msl_m - 3000.0).abs() < 10.0, "{burst_msl_m}");
    assert!((summary.max_altitude_msl_m - burst_msl_m).abs() < 10.0);
    // Released by the onboard estimate at MIS_DEPLOY_M: the truth within 30 m of it.
    let (_, deploy_m) = summary.deployment.expect("deployed");
    assert!((deploy_m - 1200.0).abs() < 30.0, "{deploy_m}");
    // The round chute's terminal speed for 9 kg on 4 m² of Cd·A, 6–7 m/s in this air.
    assert!(
        (5.5..8.0).contains(&summary.peak_descent_mps),
        "{}",
        summary.peak_descent_mps
    );
    let landing = summary.landing.expect("landing");
    let site = bench.drone.drone().config().site;
    let back = site.to_ned(landing.lat_deg, landing.lon_deg, site.alt_msl_m);
    assert!((back.x - landing.position_ne_m[0]).abs() < 0.01);
    assert!((back.y - landing.position_ne_m[1]).abs() < 0.01);
    let stages: Vec<&str> = summary.stages.iter().map(|s| s.stage.as_str()).collect();
    assert_eq!(stages[0], "pre_launch");
    assert_eq!(stages.last(), Some(&"landed"));
    assert!(summary.phases.iter().any(|p| p.stage == "final_approach"));
}

#[test]
fn heartbeats_come_at_1_hz_of_link_time_and_sensors_at_4_hz_of_mission_time() {
    let mut bench = Bench::new("rehearsal", |_| {});
    bench.run_for(30.0);
    // Per second, from component `component` of the drone's system (1: the autopilot).
    let count_from = |component: u8, name: &str| {
        bench
            .ground_events
            .iter()
            .filter(|(t, e)| {
                *t > 10.0
                    && matches!(e, GroundEvent::Telemetry { from: (1, c), telemetry } if *c == component && telemetry.message_name() == name)
            })
            .count() as f64
            / (bench.time_s() - 10.0)
    };
    let count = |name: &str| count_from(1, name);
    // One heartbeat a second, plus one at each change of guidance phase.
    assert!(
        (1.0..1.5).contains(&count("HEARTBEAT")),
        "{}",
        count("HEARTBEAT")
    );
    for name in [
        "GPS_RAW_INT",
        "ATTITUDE",
        "SCALED_PRESSURE",
        "SERVO_OUTPUT_RAW",
    ] {
        assert!((count(name) - 4.0).abs() < 0.25, "{name}: {}", count(name));
    }
    // The other bodies' IMUs, each from its own component at 2 Hz of mission time.
    for body in BodyImu::ALL {
        let rate = count_from(body.component_id(), "ATTITUDE");
        assert!((rate - 2.0).abs() < 0.15, "{body:?}: {rate}");
    }
    let now = bench.now();
    assert!(bench.ground.is_connected());
    assert_eq!(bench.ground.link_stats(now).packet_loss_pct, 0.0);
}

#[test]
fn a_heading_and_a_mode_command_are_acknowledged_shown_in_the_heartbeat_and_flown() {
    let mut bench = Bench::new("rehearsal", |_| {});
    assert!(bench.run_until(30.0, |b| b.stage() == FlightStage::Parafoil));
    let id = bench.command(Command::HoldHeading { heading_deg: 200.0 });
    assert_eq!(bench.outcome(id), CommandOutcome::Accepted);
    bench.run_for(0.5);
    assert_eq!(bench.last_status().mode, FlightMode::Heading);
    bench.run_for(40.0);
    let heading = bench
        .drone
        .drone()
        .estimate()
        .expect("estimate")
        .heading_rad
        .to_degrees()
        .rem_euclid(360.0);
    assert!((heading - 200.0).abs() < 25.0, "heading {heading}");
    let id = bench.command(Command::SetMode(FlightMode::SpiralLanding));
    assert_eq!(bench.outcome(id), CommandOutcome::Accepted);
    bench.run_for(0.5);
    assert_eq!(bench.last_status().mode, FlightMode::SpiralLanding);
    bench.land();
    assert!(bench.miss_m() < 80.0, "miss {}", bench.miss_m());
}

#[test]
fn a_parameter_set_over_the_link_changes_what_guidance_flies_and_reads_back() {
    let mut bench = Bench::new("rehearsal", |_| {});
    assert!(bench.run_until(30.0, |b| b.stage() == FlightStage::Parafoil));
    let peak_line = |b: &Bench, from_s: f64| {
        b.ground_events
            .iter()
            .filter(|(t, _)| *t > from_s)
            .filter_map(|(_, e)| match e {
                GroundEvent::Telemetry {
                    telemetry: Telemetry::Actuators(a),
                    ..
                } => Some(a.main_line.abs()),
                _ => None,
            })
            .fold(0.0, f64::max)
    };
    // Turning in the pattern, guidance moves the main line well past 0.002 m (1/15 of the
    // servo's 0.030 m travel). The approximation before it can be all straight.
    let in_pattern = |b: &Bench| {
        matches!(
            b.drone.drone().onboard().guidance().phase(),
            GuidancePhase::Branch1
                | GuidancePhase::Branch2
                | GuidancePhase::Branch3
                | GuidancePhase::Branch4
        )
    };
    assert!(
        bench.run_until(400.0, in_pattern),
        "never entered the pattern"
    );
    bench.run_for(30.0);
    let before = peak_line(&bench, 0.0);
    assert!(before > 0.1, "{before}");

    let now = bench.now();
    bench
        .ground
        .param_set(now, "GN_LINE_MAX", 0.002)
        .expect("set");
    bench.exchange();
    let now = bench.now();
    bench.ground.param_read(now, "GN_LINE_MAX").expect("read");
    bench.exchange();
    let events = bench.param_events();
    assert!(
        events.iter().any(
            |e| matches!(e, ParamEvent::SetDone { actual, accepted: true, .. } if *actual == 0.002)
        ),
        "{events:?}"
    );
    assert!(
        events
            .iter()
            .any(|e| matches!(e, ParamEvent::ReadDone { param } if param.value == 0.002)),
        "{events:?}"
    );
    let gains = bench.drone.drone().onboard().guidance().config().gains;
    assert!((gains.main_line_limit_m - 0.002).abs() < 1e-7);
    // And flown: once the servo has followed, it stays within 0.002 m (1/15 of its travel).
    let from = bench.time_s() + 3.0;
    bench.run_for(60.0);
    let after = peak_line(&bench, from);
    assert!(
        after <= 0.002 / 0.030 + 1e-3,
        "main line {after} after the limit"
    );

    // Regression: a value within its range that breaks a rule between parameters (the
    // shortest final longer than the longest) was echoed first (the station was told it was
    // accepted) and put back afterwards. Now the drone's rules run before the echo: the only
    // PARAM_VALUE is the value in force, and the set is reported refused, with the reason.
    bench.ground_events.clear();
    let in_force = bench
        .drone
        .drone()
        .onboard()
        .settings()
        .guidance
        .spiral
        .min_final_m as f32;
    let refused_before = bench.drone.counters().params_refused;
    let now = bench.now();
    bench
        .ground
        .param_set(now, "SP_MIN_FINAL", 1500.0)
        .expect("set");
    bench.exchange();
    bench.run_for(2.0);
    assert_eq!(
        bench.param_events(),
        [ParamEvent::SetDone {
            name: "SP_MIN_FINAL".into(),
            requested: 1500.0,
            actual: in_force,
            accepted: false
        }],
        "one answer, the value in force, and nothing after it"
    );
    assert_eq!(
        bench.drone.drone().param("SP_MIN_FINAL"),
        Some(in_force),
        "still flown"
    );
    assert_eq!(bench.drone.counters().params_refused, refused_before + 1);
    assert!(
        bench.drone_events.iter().any(|e| matches!(
            e,
            DroneEvent::Param { name, accepted: false, .. } if name == "SP_MIN_FINAL"
        )),
        "{:?}",
        bench.drone_events
    );
    assert!(
        bench
            .texts()
            .iter()
            .any(|t| t.contains("SP_MIN_FINAL") && t.contains("refused")),
        "{:?}",
        bench.texts()
    );
    // A read-back tells the same.
    let now = bench.now();
    bench.ground.param_read(now, "SP_MIN_FINAL").expect("read");
    bench.exchange();
    let events = bench.param_events();
    assert!(
        events
            .iter()
            .any(|e| matches!(e, ParamEvent::ReadDone { param } if param.value == in_force)),
        "{events:?}"
    );
}

#[test]
fn manual_control_moves_the_main_line_and_stale_sticks_fall_back_within_the_timeout() {
    let mut bench = Bench::new("rehearsal", |_| {});
    assert!(bench.run_until(30.0, |b| b.stage() == FlightStage::Parafoil));
    let now = bench.now();
    bench.ground.manual_hold(
        now,
        Sticks {
            y: -0.8,
            z: 0.5,
            ..Sticks::default()
        },
    );
    bench.run_for(0.5);
    let id = bench.command(Command::SetMode(FlightMode::Manual));
    assert_eq!(bench.outcome(id), CommandOutcome::Accepted);
    bench.run_for(4.0);
    assert_eq!(bench.last_status().mode, FlightMode::Manual);
    let a = bench.last_servos();
    assert!((a.main_line + 0.8).abs() < 0.03, "{a:?}");
    assert!((a.brake_left - 0.5).abs() < 0.03 && (a.brake_right - 0.5).abs() < 0.03);

    // The operator lets go: within the stick timeout (0.5 s of link time) and a control
    // period the drone is back in its spiral landing, and never held the stick.
    bench.ground.manual_release();
    let released_s = bench.time_s();
    assert!(bench.run_until(released_s + 2.0, |b| b.drone.drone().mode()
        == FlightMode::SpiralLanding));
    let took = bench.time_s() - released_s;
    assert!(took <= 0.5 + 0.25 + 1e-9, "fell back after {took} s");
    bench.run_for(0.5);
    assert_eq!(bench.last_status().mode, FlightMode::SpiralLanding);
    assert!(
        bench.texts().iter().any(|t| t.contains("stale")),
        "{:?}",
        bench.texts()
    );
    bench.run_for(15.0);
    let a = bench.last_servos();
    assert!(
        a.brake_left < 0.45,
        "brake held at the stick's value: {a:?}"
    );
    bench.land();
    assert!(bench.miss_m() < 80.0, "miss {}", bench.miss_m());
}

#[test]
fn a_cutdown_over_the_link_is_refused_on_the_pad_and_ends_the_ascent() {
    let mut bench = Bench::new("mission-short", |_| {});
    bench.run_for(3.0);
    let id = bench.command(Command::Cutdown);
    assert!(matches!(bench.outcome(id), CommandOutcome::Rejected { .. }));
    assert_eq!(bench.stage(), FlightStage::PreLaunch);
    assert!(
        bench.run_until(500.0, |b| b.drone.drone().physics().altitude_msl_m()
            > 1500.0)
    );
    let id = bench.command(Command::Cutdown);
    assert_eq!(bench.outcome(id), CommandOutcome::Accepted);
    bench.run_for(0.5);
    assert_eq!(bench.last_status().stage, FlightStage::RoundChute);
    let cut_at = bench.drone.drone().physics().altitude_msl_m();
    assert!(cut_at < 2000.0, "cut at {cut_at}");
    bench.run_for(20.0);
    assert!(bench.drone.drone().physics().altitude_msl_m() < cut_at - 80.0);
    bench.land();
    let texts = bench.texts();
    assert!(
        texts.iter().any(|t| t.starts_with("cutdown at")),
        "{texts:?}"
    );
    assert!(
        !texts.iter().any(|t| t.contains("balloon burst")),
        "{texts:?}"
    );
}

#[test]
fn a_link_drop_cuts_every_frame_both_ways_and_the_drone_flies_its_plan_as_without_it() {
    let landing_of = |drop: bool| {
        let mut bench = Bench::new("rehearsal", |c| {
            if drop {
                c.failures.link_drop_s = vec![[30.0, 90.0]];
            }
        });
        bench.land();
        bench
    };
    let calm = landing_of(false);
    let dropped = landing_of(true);
    assert_eq!(
        dropped.drone.drone().landing(),
        calm.drone.drone().landing(),
        "the drone did not fly its plan as it would have"
    );
    // Nothing reached the station inside the window.
    assert!(
        !dropped
            .ground_events
            .iter()
            .any(|(t, e)| (30.25..90.0).contains(t) && matches!(e, GroundEvent::Telemetry { .. }))
    );
    let lost = dropped.drone_events.iter().find_map(|e| match e {
        DroneEvent::Link {
            time_s,
            connected: false,
        } => Some(*time_s),
        _ => None,
    });
    assert!(lost.is_some_and(|t| (30.0..35.0).contains(&t)), "{lost:?}");
    assert!(
        dropped
            .texts()
            .iter()
            .any(|t| t.starts_with("link back after")),
        "{:?}",
        dropped.texts()
    );
    assert!(dropped.drone.counters().dropped_link_down > 200);
}

#[test]
fn with_packet_loss_the_station_measures_it_and_commands_get_through_by_retry() {
    let mut bench = Bench::new("rehearsal", |c| c.failures.packet_loss_pct = 20.0);
    assert!(bench.run_until(30.0, |b| b.stage() == FlightStage::Parafoil));
    let mut accepted = 0;
    for heading_deg in [90.0, 180.0, 270.0, 0.0, 90.0, 180.0] {
        let id = bench.command(Command::HoldHeading { heading_deg });
        if bench.outcome(id) == CommandOutcome::Accepted {
            accepted += 1;
        }
        bench.run_for(2.0);
    }
    assert_eq!(
        accepted, 6,
        "retries should carry every command through 20 % loss"
    );
    let now = bench.now();
    let loss = bench.ground.link_stats(now).packet_loss_pct;
    assert!((15.0..25.0).contains(&loss), "loss {loss} %");
    let random = bench.drone.counters().dropped_random;
    assert!(random > 50, "{random}");
}

#[test]
fn an_uploaded_plan_is_flown_and_downloads_as_the_drone_holds_it() {
    let mut bench = Bench::new("rehearsal", |_| {});
    assert!(bench.run_until(30.0, |b| b.stage() == FlightStage::Parafoil));
    let site = bench.drone.drone().config().site;
    let (lat_deg, lon_deg, alt_msl_m) =
        site.to_geodetic(&nalgebra::Vector3::new(-300.0, 250.0, 0.0));
    let now = bench.now();
    bench
        .ground
        .plan_upload(
            now,
            vec![PlanItem::Land {
                lat_deg,
                lon_deg,
                alt_msl_m,
                approach_heading_deg: None,
            }],
        )
        .expect("upload");
    assert!(bench.run_until(bench.time_s() + 10.0, |b| {
        b.ground_events
            .iter()
            .any(|(_, e)| matches!(e, GroundEvent::Plan(PlanEvent::UploadDone { .. })))
    }));
    let now = bench.now();
    bench.ground.plan_download(now).expect("download");
    assert!(bench.run_until(bench.time_s() + 10.0, |b| {
        b.ground_events
            .iter()
            .any(|(_, e)| matches!(e, GroundEvent::Plan(PlanEvent::DownloadDone { .. })))
    }));
    let downloaded = bench
        .ground_events
        .iter()
        .find_map(|(_, e)| match e {
            GroundEvent::Plan(PlanEvent::DownloadDone { items }) => Some(items.clone()),
            _ => None,
        })
        .expect("downloaded");
    assert!(
        matches!(downloaded.as_slice(), [PlanItem::Land { lat_deg: a, lon_deg: o, .. }]
            if (a - lat_deg).abs() < 1e-6 && (o - lon_deg).abs() < 1e-6),
        "{downloaded:?}"
    );
    bench.land();
    let landing = bench.drone.drone().landing().expect("landed");
    let miss = (landing.position_ne_m[0] + 300.0).hypot(landing.position_ne_m[1] - 250.0);
    assert!(miss < 80.0, "landed {miss} m from the uploaded target");
    assert_eq!(landing.miss_m.map(|m| (m - miss).abs() < 0.01), Some(true));
}

/// MAV_SYS_STATUS_GEOFENCE.
const GEOFENCE: u32 = 1 << 20;

/// The last SYS_STATUS's (present, enabled, health) bitmaps.
fn last_sys_status(bench: &Bench) -> (u32, u32, u32) {
    bench
        .ground_events
        .iter()
        .rev()
        .find_map(|(_, e)| match e {
            GroundEvent::Telemetry {
                telemetry: Telemetry::System(s),
                ..
            } => Some((s.sensors_present, s.sensors_enabled, s.sensors_health)),
            _ => None,
        })
        .expect("a SYS_STATUS")
}

#[test]
fn an_uploaded_fence_becomes_the_onboard_zones_and_sys_status_says_when_the_landing_is_in_one() {
    use stx_gnc::keep_out::{KeepOutZone, KeepOutZones};
    use stx_link::plan::{FenceEvent, zones_to_fence};
    let mut bench = Bench::new("rehearsal", |_| {});
    assert!(bench.run_until(30.0, |b| b.stage() == FlightStage::Parafoil));
    bench.run_for(5.0);
    let (present, enabled, health) = last_sys_status(&bench);
    assert_eq!(
        (present & GEOFENCE, enabled & GEOFENCE, health & GEOFENCE),
        (GEOFENCE, 0, GEOFENCE),
        "no zones: present, not enabled, healthy"
    );
    // A zone over where the drone predicts it lands.
    let landing = bench
        .drone
        .drone()
        .predicted_landing_ne_m()
        .expect("a prediction");
    let square = |c: [f64; 2], h: f64| {
        vec![
            [c[0] - h, c[1] - h],
            [c[0] + h, c[1] - h],
            [c[0] + h, c[1] + h],
            [c[0] - h, c[1] + h],
        ]
    };
    let zones = KeepOutZones {
        zones: vec![KeepOutZone {
            name: "pond".into(),
            rings_ne_m: vec![square(landing, 60.0)],
        }],
    };
    let site = bench.drone.drone().config().site;
    let fence = zones_to_fence(&zones, &site).unwrap();
    let now = bench.now();
    bench
        .ground
        .fence_upload(now, fence.clone())
        .expect("upload");
    assert!(bench.run_until(bench.time_s() + 10.0, |b| {
        b.ground_events
            .iter()
            .any(|(_, e)| matches!(e, GroundEvent::Fence(FenceEvent::UploadDone { items: 4 })))
    }));
    assert_eq!(bench.drone.counters().fences, 1);
    let onboard = bench.drone.drone().onboard().guidance().keep_out();
    assert_eq!(onboard.zones.len(), 1);
    for (a, b) in onboard.zones[0].rings_ne_m[0]
        .iter()
        .zip(&zones.zones[0].rings_ne_m[0])
    {
        assert!(
            (a[0] - b[0]).abs() < 0.05 && (a[1] - b[1]).abs() < 0.05,
            "{a:?} {b:?}"
        );
    }
    bench.run_for(3.0);
    let (_, enabled, health) = last_sys_status(&bench);
    assert_eq!(enabled & GEOFENCE, GEOFENCE, "zones loaded: enabled");
    let in_zone = bench
        .drone
        .drone()
        .predicted_landing_ne_m()
        .is_some_and(|p| onboard_zone_at(&bench, p));
    assert!(
        in_zone,
        "the zone is 120 m across the landing predicted 3 s before"
    );
    assert_eq!(
        health & GEOFENCE == 0,
        in_zone,
        "health clear exactly when the landing is in a zone"
    );
    // The download returns the fence held.
    let now = bench.now();
    bench.ground.fence_download(now).expect("download");
    assert!(bench.run_until(bench.time_s() + 10.0, |b| {
        b.ground_events.iter().any(
            |(_, e)| matches!(e, GroundEvent::Fence(FenceEvent::DownloadDone { items }) if items.len() == 4),
        )
    }));
}

fn onboard_zone_at(bench: &Bench, p: [f64; 2]) -> bool {
    bench
        .drone
        .drone()
        .onboard()
        .guidance()
        .keep_out()
        .zone_at(p)
        .is_some()
}

#[test]
fn the_automatic_cutdown_cuts_the_balloon_at_mis_cutdown_m_by_the_estimate() {
    let mut bench = Bench::new("mission-short", |c| {
        c.onboard.mission.cutdown_altitude_msl_m = 2000.0;
    });
    assert!(bench.run_until(1000.0, |b| b.stage() == FlightStage::RoundChute));
    let (end, _, altitude_msl_m) = bench
        .drone
        .drone()
        .summary()
        .balloon_end
        .expect("balloon gone");
    assert_eq!(end, BalloonEnd::Cutdown);
    // The estimate's altitude, a period's climb (≈1.3 m) and the GPS's error from the truth.
    assert!((altitude_msl_m - 2000.0).abs() < 15.0, "{altitude_msl_m}");
    bench.run_for(1.0);
    assert!(
        bench
            .texts()
            .iter()
            .any(|t| t.starts_with("automatic cutdown at")),
        "{:?}",
        bench.texts()
    );
}

#[test]
fn without_gps_under_the_round_chute_the_parafoil_still_deploys_by_barometric_height() {
    // mission-short releases the round chute at about 777 s; the GPS is silent from 650 s
    // until well after.
    let mut bench = Bench::new("mission-short", |c| {
        c.failures.gps_loss_s = vec![[650.0, 900.0]];
    });
    assert!(bench.run_until(1000.0, |b| b.stage() == FlightStage::ParafoilDeploy));
    let (at_s, height_m) = bench.drone.drone().summary().deployment.expect("deployed");
    assert!((650.0..900.0).contains(&at_s), "deployed at {at_s} s");
    assert!((height_m - 1200.0).abs() < 40.0, "deployed at {height_m} m");
    bench.run_for(1.0);
    let texts = bench.texts();
    assert!(
        texts
            .iter()
            .any(|t| t.contains("GPS lost") && t.contains("dead reckoning")),
        "{texts:?}"
    );
    bench.land();
}
