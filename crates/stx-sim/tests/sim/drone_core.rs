//! The simulated drone's pure core (`stx_sim::drone`), without a link or a clock: whole
//! missions with no operator, and each of the behaviours the operators rely on — cutdown,
//! manual control and its staleness, the GPS-loss policy, a stuck servo, a lost link, a
//! parameter change — each checked on the flight it produces.
//!
//! Everything is seeded: the same scenario and calls give the same flight, so the figures
//! printed here are the ones a rerun gives.

use std::time::Instant;

use stx_dynamics::rotation::wrap_pi;
use stx_dynamics::state::idx;
use stx_dynamics::vehicle::Vehicle;
use stx_gnc::mission::{FlightMode, FlightStage};
use stx_link::command::{Command, CommandResult};
use stx_link::manual::Sticks;
use stx_link::telemetry::{SystemState, Telemetry};
use stx_sim::drone::failures::{Servo, StuckServo};
use stx_sim::drone::{Drone, MissionConfig, Output};

fn mission(name: &str) -> MissionConfig {
    MissionConfig::builtin(name).expect("built-in mission")
}

fn drone(config: &MissionConfig) -> Drone {
    Drone::new(config, Vehicle::straplex()).expect("drone builds")
}

/// What a run said and sent, drained after every step.
#[derive(Default)]
struct Log {
    texts: Vec<(f64, String)>,
    telemetry: Vec<(f64, Telemetry)>,
}

impl Log {
    fn drain(&mut self, d: &mut Drone) {
        let t = d.time_s();
        while let Some(o) = d.poll_output() {
            match o {
                Output::Text { text, .. } => self.texts.push((t, text)),
                Output::Telemetry(m) => self.telemetry.push((t, m)),
                // The other bodies' IMUs: their own stream (body_imus.rs).
                Output::Body { .. } => {}
            }
        }
    }

    fn text_time(&self, needle: &str) -> Option<f64> {
        self.texts
            .iter()
            .find(|(_, text)| text.contains(needle))
            .map(|(t, _)| *t)
    }
}

/// Steps until `until` holds (or the mission lands), draining outputs.
fn fly(d: &mut Drone, log: &mut Log, mut until: impl FnMut(&Drone) -> bool) {
    while !until(d) && d.landing().is_none() {
        d.step().expect("the flight goes on");
        log.drain(d);
    }
}

fn heading_deg(d: &Drone) -> f64 {
    let (_, x) = d.physics().parafoil().expect("parafoil out");
    x[idx::CANOPY_EULER + 2].to_degrees()
}

#[test]
fn a_whole_mission_flies_from_the_pad_to_the_target_with_no_operator() {
    let config = mission("mission");
    let mut d = drone(&config);
    let mut log = Log::default();
    let started = Instant::now();
    let mut peak_descent_mps: f64 = 0.0;
    let mut peak_altitude_msl_m: f64 = 0.0;
    let mut deployed_at_ne_m = None;
    fly(&mut d, &mut log, |d| {
        let truth = d.physics().truth();
        peak_altitude_msl_m = peak_altitude_msl_m.max(d.physics().altitude_msl_m());
        if d.stage() == FlightStage::RoundChute {
            peak_descent_mps = peak_descent_mps.max(truth.velocity_ned_mps.z);
        }
        if d.stage() == FlightStage::ParafoilDeploy && deployed_at_ne_m.is_none() {
            deployed_at_ne_m = Some([truth.position_ned_m.x, truth.position_ned_m.y]);
        }
        false
    });
    let target = config.target_ned_m().expect("a target");
    let deployed = deployed_at_ne_m.expect("deployed");
    println!(
        "deployed at {:.0} m N {:.0} m E, {:.0} m from the target",
        deployed[0],
        deployed[1],
        (deployed[0] - target.x).hypot(deployed[1] - target.y)
    );
    let wall_s = started.elapsed().as_secs_f64();
    let landing = d.landing().expect("landed");
    let stages: Vec<FlightStage> = d.stage_log().iter().map(|(s, _)| *s).collect();
    assert_eq!(
        stages,
        [
            FlightStage::PreLaunch,
            FlightStage::Ascent,
            FlightStage::RoundChute,
            FlightStage::ParafoilDeploy,
            FlightStage::Parafoil,
            FlightStage::Landed
        ],
        "every stage, in order"
    );
    let at = |stage| {
        d.stage_log()
            .iter()
            .find(|(s, _)| *s == stage)
            .map(|(_, t)| *t)
            .unwrap_or(f64::NAN)
    };
    let miss = landing.miss_m.expect("a target");
    println!(
        "whole mission: launch {:.0} s, burst {:.0} s at {:.0} m MSL, deploy {:.0} s, landing {:.0} s; \
         peak round-chute descent {:.0} m/s; miss {:.1} m at {:.1} m/s; wall {:.1} s ({:.0}x real time)",
        at(FlightStage::Ascent),
        at(FlightStage::RoundChute),
        peak_altitude_msl_m,
        at(FlightStage::ParafoilDeploy),
        landing.time_s,
        peak_descent_mps,
        miss,
        landing.vertical_speed_mps,
        wall_s,
        landing.time_s / wall_s
    );
    // The balloon took it to its burst altitude at 5 m/s on average (the "≈5 m/s"):
    // 34 755 m of climb in 6951 s.
    assert!((34_900.0..35_200.0).contains(&peak_altitude_msl_m));
    let ascent_s = at(FlightStage::RoundChute) - at(FlightStage::Ascent);
    let climb_m = config.balloon.burst_altitude_msl_m - config.site.alt_msl_m;
    let mean_ascent_mps = climb_m / ascent_s;
    println!(
        "timeline: pad 0–{:.0} s, ascent {ascent_s:.0} s at {mean_ascent_mps:.3} m/s on average, \
         round chute {:.0} s, parafoil {:.0} s (deployment to landing)",
        at(FlightStage::Ascent),
        at(FlightStage::ParafoilDeploy) - at(FlightStage::RoundChute),
        landing.time_s - at(FlightStage::ParafoilDeploy),
    );
    assert!(
        (mean_ascent_mps - config.balloon.mean_ascent_rate_mps).abs() < 0.01,
        "mean ascent {mean_ascent_mps} m/s"
    );
    // Very fast in thin air under the round chute (the spec's "up to ≈300 km/h").
    assert!(
        (50.0..110.0).contains(&peak_descent_mps),
        "{peak_descent_mps}"
    );
    // Deployed at the configured height, flown by the onboard plan onto the target.
    assert!(landing.under_parafoil);
    assert!(miss < 30.0, "missed by {miss:.1} m");
    assert!(landing.vertical_speed_mps < 4.0);
    for needle in [
        "launched",
        "burst",
        "round chute released",
        "parafoil flying",
        "landed",
    ] {
        assert!(log.text_time(needle).is_some(), "no {needle:?} text");
    }
    // The landing prediction sent before deployment (the round chute's, in the forecast
    // wind) and after (guidance's plan) both pointed the recovery team somewhere sensible.
    let predictions: Vec<(f64, f64, f64)> = log
        .telemetry
        .iter()
        .filter_map(|(t, m)| match m {
            Telemetry::PredictedLanding(p) => Some((*t, p.lat_deg, p.lon_deg)),
            _ => None,
        })
        .collect();
    assert!(
        predictions
            .iter()
            .any(|p| p.0 < at(FlightStage::RoundChute))
    );
    let (_, lat, lon) = *predictions.last().expect("predictions");
    let last = config.site.to_ned(lat, lon, config.site.alt_msl_m);
    assert!(
        (last.x - landing.position_ne_m[0]).hypot(last.y - landing.position_ne_m[1]) < 60.0,
        "last prediction {last:?}, landing {:?}",
        landing.position_ne_m
    );
}

#[test]
fn the_drone_sends_its_telemetry_at_the_documented_rates() {
    let mut d = drone(&mission("rehearsal"));
    let mut log = Log::default();
    fly(&mut d, &mut log, |d| d.time_s() >= 70.0);
    // 60 s of parafoil flight, from 10 s on.
    let count = |name: &str| {
        log.telemetry
            .iter()
            .filter(|(t, m)| *t > 10.0 && *t <= 70.0 && m.message_name() == name)
            .count()
    };
    for (name, per_s) in [
        ("GPS_RAW_INT", 4),
        ("ATTITUDE", 4),
        ("SCALED_PRESSURE", 4),
        ("GLOBAL_POSITION_INT", 4),
        ("VFR_HUD", 4),
        ("SERVO_OUTPUT_RAW", 4),
        ("WIND_COV", 1),
        ("NAV_CONTROLLER_OUTPUT", 1),
        ("SYS_STATUS", 1),
        ("BATTERY_STATUS", 1),
    ] {
        let n = count(name);
        assert!(
            n.abs_diff(60 * per_s) <= 1,
            "{name}: {n} in 60 s, expected {}",
            60 * per_s
        );
    }
    assert_eq!(count("POSITION_TARGET_GLOBAL_INT"), 30, "every 2 s");
    // Rates can be changed and messages requested.
    assert_eq!(
        d.handle_command(&Command::SetMessageInterval {
            message_id: 231,
            interval_us: -1
        }),
        CommandResult::Accepted
    );
    assert_eq!(
        d.handle_command(&Command::RequestMessage { message_id: 147 }),
        CommandResult::Accepted
    );
    assert_eq!(
        d.handle_command(&Command::RequestMessage { message_id: 12345 }),
        CommandResult::Unsupported
    );
    let before = log.telemetry.len();
    fly(&mut d, &mut log, |d| d.time_s() >= 80.0);
    let after = &log.telemetry[before..];
    assert!(!after.iter().any(|(_, m)| m.message_name() == "WIND_COV"));
    assert!(
        after
            .iter()
            .any(|(_, m)| m.message_name() == "BATTERY_STATUS")
    );
}

#[test]
fn cutdown_ends_the_ascent_and_is_refused_when_there_is_no_balloon() {
    let config = mission("mission");
    let mut d = drone(&config);
    let mut log = Log::default();
    assert_eq!(d.handle_command(&Command::Cutdown), CommandResult::Denied);
    assert!(log.text_time("cutdown refused").is_none());
    log.drain(&mut d);
    assert!(
        log.text_time("cutdown refused").is_some(),
        "the reason is told"
    );
    fly(&mut d, &mut log, |d| d.physics().altitude_msl_m() > 4000.0);
    assert_eq!(d.stage(), FlightStage::Ascent);
    assert_eq!(d.handle_command(&Command::Cutdown), CommandResult::Accepted);
    assert_eq!(
        d.stage(),
        FlightStage::RoundChute,
        "the balloon is gone at once"
    );
    let cut_at = d.time_s();
    assert_eq!(d.handle_command(&Command::Cutdown), CommandResult::Denied);
    // From then on it only comes down: the round chute, then the parafoil at its height.
    let mut highest = d.physics().altitude_msl_m();
    fly(&mut d, &mut log, |d| {
        highest = highest.max(d.physics().altitude_msl_m());
        d.stage() == FlightStage::Parafoil
    });
    assert!(
        highest < 4000.0 + 30.0,
        "rose to {highest} m after the cutdown"
    );
    let deployed = d
        .stage_log()
        .iter()
        .find(|(s, _)| *s == FlightStage::ParafoilDeploy)
        .expect("deployed")
        .1;
    println!(
        "cutdown at {cut_at:.0} s, 4000 m MSL; parafoil out {:.0} s later",
        deployed - cut_at
    );
    assert!(log.text_time("cutdown at").is_some());
}

#[test]
fn sticks_drive_the_servos_and_stale_sticks_return_the_drone_to_its_plan() {
    let mut d = drone(&mission("rehearsal"));
    let mut log = Log::default();
    fly(&mut d, &mut log, |d| d.time_s() >= 20.0);
    assert_eq!(d.mode(), FlightMode::SpiralLanding);
    // Manual needs a live stick.
    assert_eq!(
        d.handle_command(&Command::SetMode(FlightMode::Manual)),
        CommandResult::TemporarilyRejected
    );
    let sticks = Sticks {
        y: 0.3,
        z: 0.8,
        ..Default::default()
    };
    d.set_sticks(Some(sticks));
    assert_eq!(
        d.handle_command(&Command::SetMode(FlightMode::Manual)),
        CommandResult::Accepted
    );
    let travel = Vehicle::straplex().main_line_travel_m;
    for _ in 0..20 {
        d.set_sticks(Some(sticks));
        d.step().expect("flies");
        let c = d.commanded_controls();
        assert!((c.main_line_m - 0.3 * travel).abs() < 1e-12, "{c:?}");
        assert!((c.brake_right - 0.8).abs() < 1e-12 && (c.brake_left - 0.8).abs() < 1e-12);
    }
    // Five seconds with the main line at 30 % of its travel: a right turn, brakes pulled in.
    let servos = d.physics().servo_positions();
    assert!(
        (servos.main_line_m - 0.3 * travel).abs() < 1e-3,
        "{servos:?}"
    );
    assert!(servos.brake_left > 0.7);
    log.drain(&mut d);
    // The operator lets go: the link's receiver reports the sticks stale.
    d.set_sticks(None);
    assert_eq!(
        d.mode(),
        FlightMode::SpiralLanding,
        "back to the plan at once"
    );
    log.drain(&mut d);
    assert!(log.text_time("sticks stale").is_some());
    d.step().expect("flies");
    let c = d.commanded_controls();
    assert!(
        c.brake_left != 0.8 && c.main_line_m != 0.3 * travel,
        "never the last stick values: {c:?}"
    );
    fly(&mut d, &mut log, |_| false);
    let miss = d.landing().and_then(|l| l.miss_m).expect("landed");
    assert!(miss < 40.0, "the plan still lands it: {miss} m");
}

#[test]
fn a_gps_loss_turns_the_drone_into_the_wind_and_it_resumes_when_fixes_return() {
    let mut config = mission("rehearsal");
    config.failures.gps_loss_s = vec![[40.0, 100.0]];
    let mut d = drone(&config);
    let mut log = Log::default();
    let mut critical = false;
    let mut headings = Vec::new();
    fly(&mut d, &mut log, |d| {
        if d.time_s() > 41.0 && d.time_s() < 100.0 {
            critical |= d.status().state == SystemState::Critical;
        }
        if (85.0..100.0).contains(&d.time_s()) {
            headings.push(heading_deg(d));
        }
        d.time_s() >= 120.0
    });
    let lost = log
        .text_time("GPS lost: navigating")
        .expect("loss announced");
    let acted = log.text_time("into the wind").expect("action announced");
    let back = log.text_time("resuming").expect("recovery announced");
    println!("GPS out 40–100 s: lost told at {lost} s, acted at {acted} s, back at {back} s");
    assert!((40.0..42.0).contains(&lost));
    assert!((43.0..46.0).contains(&acted), "after GPS_LOSS_S = 3 s");
    assert!((100.0..102.0).contains(&back));
    assert!(critical, "the heartbeat says it is in a failsafe");
    // Into the wind: the rehearsal's wind comes from about 293° at 500–700 m.
    let mean_error = headings
        .iter()
        .map(|h| wrap_pi((h - 293.0).to_radians()).to_degrees().abs())
        .sum::<f64>()
        / headings.len() as f64;
    assert!(mean_error < 25.0, "mean heading error {mean_error:.0}°");
    // Meanwhile GPS_RAW_INT said there was no fix.
    assert!(log.telemetry.iter().any(|(t, m)| *t > 45.0
        && *t < 100.0
        && matches!(m, Telemetry::GpsRaw(g) if g.fix == stx_link::telemetry::GpsFix::NoFix)));
    // Back on GPS the spiral steers it back toward the target.
    assert_eq!(d.mode(), FlightMode::SpiralLanding);
    let p = d.physics().truth().position_ned_m;
    let away_m = p.x.hypot(p.y);
    let height_m = -p.z;
    fly(&mut d, &mut log, |_| false);
    let miss = d.landing().and_then(|l| l.miss_m).expect("landed");
    println!(
        "GPS back at 100 s {away_m:.0} m from the target, {height_m:.0} m up; landed {miss:.0} m from it"
    );
    assert!(miss < 0.6 * away_m, "missed by {miss} m");
}

/// Regression: a GPS lost in heading mode was flown through and marked as acted on, so a
/// spiral landing selected afterwards steered on the lost position with no failsafe.
#[test]
fn a_gps_loss_flown_through_in_heading_mode_engages_when_a_position_mode_is_selected() {
    let mut config = mission("rehearsal");
    config.failures.gps_loss_s = vec![[40.0, 200.0]];
    let mut d = drone(&config);
    let mut log = Log::default();
    fly(&mut d, &mut log, |d| d.time_s() >= 30.0);
    assert_eq!(d.stage(), FlightStage::Parafoil);
    assert_eq!(
        d.handle_command(&Command::HoldHeading { heading_deg: 90.0 }),
        CommandResult::Accepted
    );
    fly(&mut d, &mut log, |d| d.time_s() >= 60.0);
    assert!(
        log.text_time("continuing heading").is_some(),
        "{:?}",
        log.texts
    );
    assert!(log.text_time("into the wind").is_none());
    assert!(!d.onboard().gps_failsafe_active());
    for mode in [FlightMode::SpiralLanding, FlightMode::Course] {
        assert_eq!(
            d.handle_command(&Command::SetMode(mode)),
            CommandResult::Accepted
        );
        let selected_s = d.time_s();
        fly(&mut d, &mut log, |d| d.time_s() >= selected_s + 1.0);
        assert!(
            d.onboard().gps_failsafe_active(),
            "{mode:?} selected without GPS: {:?}",
            d.onboard().gps_state()
        );
        assert_eq!(d.status().state, SystemState::Critical);
        // Back to heading mode: the failsafe steps aside (heading needs no GPS).
        d.handle_command(&Command::HoldHeading { heading_deg: 90.0 });
        fly(&mut d, &mut log, |d| d.time_s() >= selected_s + 2.0);
        assert!(!d.onboard().gps_failsafe_active());
    }
    let acted = log.text_time("into the wind").expect("the action, once");
    assert!((60.0..61.0).contains(&acted), "acted at {acted} s");
}

#[test]
fn with_the_continue_policy_a_gps_loss_keeps_the_plan_on_dead_reckoning() {
    let mut config = mission("rehearsal");
    config.failures.gps_loss_s = vec![[40.0, 70.0]];
    let mut d = drone(&config);
    let name = d
        .param_specs()
        .into_iter()
        .map(|s| s.name)
        .find(|n| n.starts_with("GPS_LOSS_A") || n.ends_with("GPS_ACTION"))
        .expect("the GPS-loss action is a parameter");
    d.set_param(&name, 0.0).expect("continue");
    let mut log = Log::default();
    fly(&mut d, &mut log, |d| d.time_s() >= 75.0);
    assert!(log.text_time("continuing spiral_landing").is_some());
    assert!(log.text_time("into the wind").is_none());
}

#[test]
fn a_stuck_servo_stays_where_it_stuck_whatever_it_is_commanded() {
    let mut config = mission("rehearsal");
    config.failures.stuck_servo = Some(StuckServo {
        servo: Servo::Left,
        at_s: 30.0,
    });
    let mut d = drone(&config);
    let mut log = Log::default();
    fly(&mut d, &mut log, |d| d.time_s() >= 31.0);
    let held = d.physics().servo_positions().brake_left;
    let mut commanded_left = Vec::new();
    fly(&mut d, &mut log, |d| {
        let s = d.physics().servo_positions();
        assert!(
            (s.brake_left - held).abs() < 1e-6,
            "left brake moved from {held} to {} at {} s",
            s.brake_left,
            d.time_s()
        );
        commanded_left.push(d.commanded_controls().brake_left);
        false
    });
    assert!(log.text_time("left brake servo stuck").is_some());
    // Guidance did ask for it to move (the flare pulls both brakes fully).
    assert!(
        commanded_left.iter().any(|b| (b - held).abs() > 0.3),
        "{commanded_left:?}"
    );
    // The right brake still answered.
    assert!(d.physics().servo_positions().brake_right > 0.5);
}

#[test]
fn losing_the_link_changes_nothing_in_flight() {
    let config = mission("rehearsal");
    let mut quiet = drone(&config);
    let mut cut = drone(&config);
    let (mut log_quiet, mut log_cut) = (Log::default(), Log::default());
    while quiet.landing().is_none() {
        if cut.time_s() == 30.0 {
            cut.link_changed(false);
        }
        if cut.time_s() == 90.0 {
            cut.link_changed(true);
        }
        quiet.step().expect("flies");
        cut.step().expect("flies");
        log_quiet.drain(&mut quiet);
        log_cut.drain(&mut cut);
        assert_eq!(
            quiet.physics().truth().position_ned_m,
            cut.physics().truth().position_ned_m,
            "same flight at {} s",
            quiet.time_s()
        );
    }
    assert_eq!(quiet.landing(), cut.landing());
    let told = log_cut
        .texts
        .iter()
        .find(|(_, t)| t.starts_with("link back"))
        .expect("the return is told");
    assert!(told.1.contains("60 s"), "{told:?}");
    assert!(log_quiet.text_time("link back").is_none());
    // The adapter's view of the same failure: nothing in or out during the window.
    let mut with_window = config.clone();
    with_window.failures.link_drop_s = vec![[30.0, 90.0]];
    let mut faults = drone(&with_window).link_faults();
    assert!(faults.drops_datagram(45.0) && !faults.drops_datagram(95.0));
}

#[test]
fn a_parameter_set_changes_the_guidance_gain_at_once() {
    let config = mission("rehearsal");
    let mut soft = drone(&config);
    let mut firm = drone(&config);
    let mut log = Log::default();
    for d in [&mut soft, &mut firm] {
        fly(d, &mut log, |d| d.time_s() >= 20.0);
        assert_eq!(
            d.handle_command(&Command::HoldHeading { heading_deg: 60.0 }),
            CommandResult::Accepted
        );
    }
    let hk1 = soft
        .param_specs()
        .into_iter()
        .map(|s| s.name)
        .find(|n| n.ends_with("HK1"))
        .expect("HK1 is a parameter");
    let before = soft.param(&hk1).expect("value");
    assert!(firm.set_param(&hk1, 1e3).is_err(), "out of range");
    assert!(firm.set_param(&hk1, f32::NAN).is_err());
    assert_eq!(firm.param(&hk1), Some(before));
    firm.set_param(&hk1, before * 3.0).expect("in range");
    assert_eq!(firm.param(&hk1), Some(before * 3.0));
    assert_eq!(
        firm.onboard().guidance().config().gains.hk1_m_per_rad,
        f64::from(before * 3.0)
    );
    soft.step().expect("flies");
    firm.step().expect("flies");
    let (a, b) = (
        soft.commanded_controls().main_line_m,
        firm.commanded_controls().main_line_m,
    );
    println!("main line for the same heading error: HK1 {before}: {a:.5} m, x3: {b:.5} m");
    assert!(
        (a - b).abs() > 1e-4,
        "the new gain is flown at the next period"
    );
}

/// What one flight identified serves the next: a vehicle's polar sent as the `PL_*`
/// parameters (`stx polar`) is the polar the drone's guidance plans with from the next period.
#[test]
fn a_polar_sent_as_parameters_is_what_the_drones_guidance_plans_with() {
    let config = mission("rehearsal");
    let mut d = drone(&config);
    let mut slow = stx_gnc::performance::GlidePerformance::default();
    for k in 0..slow.brake_points.len() {
        slow.airspeed_mps[k] *= 0.9;
        slow.sink_rate_mps[k] *= 1.12;
    }
    for (name, value) in stx_gnc::params::polar_params(&slow) {
        d.set_param(name, value as f32).expect(name);
        assert_eq!(d.param(name), Some(value as f32), "{name} reads back");
    }
    let held = d.onboard().guidance().config().performance;
    for k in 0..slow.brake_points.len() {
        assert!((held.airspeed_mps[k] - slow.airspeed_mps[k]).abs() < 1e-5);
        assert!((held.sink_rate_mps[k] - slow.sink_rate_mps[k]).abs() < 1e-5);
    }
    // Not a glide (sink above airspeed): refused, the polar in force kept.
    assert!(d.set_param("PL_SINK_0", 9.0).is_err());
    assert_eq!(d.onboard().guidance().config().performance, held);
}

#[test]
fn the_same_seed_flies_the_same_mission() {
    let config = mission("rehearsal");
    let (mut a, mut b) = (drone(&config), drone(&config));
    let mut log = Log::default();
    fly(&mut a, &mut log, |_| false);
    fly(&mut b, &mut log, |_| false);
    assert_eq!(a.landing(), b.landing());
    let mut other = config.clone();
    other.seed = 2;
    let mut c = drone(&other);
    fly(&mut c, &mut log, |_| false);
    assert_ne!(a.landing(), c.landing(), "another seed, other sensor noise");
}

/// Regression (issue 17 item 2): MAVProxy announced "fence breach" on connecting, because
/// SYS_STATUS left the health bit of the geofence (which the drone then did not have) clear. A
/// subsystem not present is reported healthy; a present one is unhealthy only when it fails.
/// The geofence (keep-out zones, issue 15) is present, and without zones not enabled and
/// healthy.
#[test]
fn sys_status_reports_absent_subsystems_healthy_and_present_ones_as_they_are() {
    const GEOFENCE: u32 = 0x10_0000; // MAV_SYS_STATUS_GEOFENCE
    const GPS: u32 = 0x20; // MAV_SYS_STATUS_SENSOR_GPS
    let config = mission("rehearsal");
    let mut d = drone(&config);
    let mut log = Log::default();
    fly(&mut d, &mut log, |d| d.time_s() > 10.0);
    let statuses: Vec<_> = log
        .telemetry
        .iter()
        .filter_map(|(_, m)| match m {
            Telemetry::System(s) => Some(*s),
            _ => None,
        })
        .collect();
    assert!(!statuses.is_empty(), "SYS_STATUS is sent");
    for s in &statuses {
        assert_eq!(
            s.sensors_present & GEOFENCE,
            GEOFENCE,
            "a geofence on board"
        );
        assert_eq!(s.sensors_enabled & GEOFENCE, 0, "no zones: not enabled");
        assert_eq!(s.sensors_health & GEOFENCE, GEOFENCE, "no zones: healthy");
        assert_eq!(
            s.sensors_health | s.sensors_present,
            u32::MAX,
            "every absent bit healthy"
        );
        assert_eq!(
            s.sensors_enabled & !s.sensors_present,
            0,
            "nothing absent is enabled"
        );
    }
    let last = statuses.last().expect("one");
    assert_eq!(last.sensors_present & GPS, GPS);
    assert_eq!(last.sensors_health & GPS, GPS, "GPS fixes arrive: healthy");
}

#[test]
fn a_surface_wind_from_the_station_becomes_guidances_measured_when_it_says_and_is_told_once() {
    let config = mission("rehearsal");
    let mut d = drone(&config);
    let mut log = Log::default();
    fly(&mut d, &mut log, |d| d.time_s() >= 10.0);
    assert!(d.onboard().guidance().surface_wind().is_none());
    let wind = Command::SetSurfaceWind {
        speed_mps: 3.0,
        from_deg: 270.0,
        age_s: 4.0,
    };
    assert_eq!(d.handle_command(&wind), CommandResult::Accepted);
    let held = d.onboard().guidance().surface_wind().expect("held");
    // From the west: the air goes east.
    assert!(held.ne_mps[0].abs() < 1e-9 && (held.ne_mps[1] - 3.0).abs() < 1e-9);
    assert!(
        (held.time_s - (d.time_s() - 4.0)).abs() < 1e-9,
        "{}",
        held.time_s
    );
    fly(&mut d, &mut log, |d| d.time_s() >= 15.0);
    assert_eq!(d.handle_command(&wind), CommandResult::Accepted);
    log.drain(&mut d);
    let told = log
        .texts
        .iter()
        .filter(|(_, t)| t.contains("surface wind"))
        .count();
    assert_eq!(told, 1, "{:?}", log.texts);
}
