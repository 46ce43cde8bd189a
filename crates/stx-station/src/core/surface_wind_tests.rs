//! The surface wind in the core: the anemometer's mean, the operator's value, the uplink and
//! the replica's copy, on the fake clock.

use stx_link::command::{Command, CommandEvent, CommandOutcome, CommandResult};
use stx_link::endpoint::{GroundEvent, LinkEvent};
use stx_types::mwv::{MwvReference, format_mwv};

use super::actions::LinkOp;
use super::tests::{core, level_attitude, sent_ops};
use super::{Outbound, StationCore};
use crate::messages::Level;
use crate::surface_wind::{DroneCopy, SurfaceWindSource};

fn connect(core: &mut StationCore, now_s: f64) {
    core.on_link_event(
        now_s,
        GroundEvent::Link(LinkEvent::Connected {
            system_id: 1,
            component_id: 1,
        }),
    );
}

/// The drone's clock heard at `now_s` reading `drone_s`.
fn hear_clock(core: &mut StationCore, now_s: f64, drone_s: f64) {
    core.on_link_event(
        now_s,
        GroundEvent::Telemetry {
            from: (1, 1),
            telemetry: level_attitude((drone_s * 1000.0) as u32),
        },
    );
}

/// The surface-wind uplinks among the link actions due at `now_s`, reported applied.
fn uplinks(core: &mut StationCore, now_s: f64) -> Vec<(u64, f64, f64, f64)> {
    sent_ops(core, now_s)
        .into_iter()
        .filter_map(|op| match op {
            LinkOp::Command {
                request_id,
                command:
                    Command::SetSurfaceWind {
                        speed_mps,
                        from_deg,
                        age_s,
                    },
            } => Some((request_id.0, speed_mps, from_deg, age_s)),
            _ => None,
        })
        .collect()
}

fn answer(core: &mut StationCore, now_s: f64, id: u64, outcome: CommandOutcome) {
    core.on_link_event(
        now_s,
        GroundEvent::Command(CommandEvent {
            request_id: stx_link::command::RequestId(id),
            command: Command::Cutdown,
            outcome,
            attempts: 1,
        }),
    );
}

/// The log since the last call, from the surface wind's sources.
fn said(core: &mut StationCore) -> Vec<(Level, String)> {
    core.drain_outbound()
        .into_iter()
        .filter_map(|o| match o {
            Outbound::Event(e) if e.source == "anemometer" || e.source == "command" => {
                Some((e.level, e.text))
            }
            _ => None,
        })
        .collect()
}

#[test]
fn the_anemometers_mean_goes_to_the_drone_and_the_replica_takes_what_the_drone_took() {
    let mut c = core();
    c.config.surface_wind.anemometer = Some("udpin:127.0.0.1:10110".into());
    connect(&mut c, 0.0);
    hear_clock(&mut c, 0.0, 1000.0);
    // No wind yet: nothing is sent.
    assert!(uplinks(&mut c, 0.5).is_empty());
    // From the west at 3 m/s, then from the south-west at 3 m/s (a relative angle, the vane's
    // zero mark on true north by default): the mean blows from about 247.5°.
    c.on_anemometer_line(1.0, &format_mwv(270.0, MwvReference::True, 3.0));
    c.on_anemometer_line(
        2.0,
        format_mwv(225.0, MwvReference::Relative, 3.0).trim_end(),
    );
    c.on_anemometer_line(2.5, "$WIXDR,C,12.3,C,TEMP");
    c.on_anemometer_line(2.6, "$WIMWV,270.0,T,3.0,M,A*00");
    let sent = uplinks(&mut c, 3.0);
    assert_eq!(sent.len(), 1, "{sent:?}");
    let (id, speed, from, age) = sent[0];
    assert!((from - 247.5).abs() < 0.01, "{from}");
    assert!(
        (speed - 3.0 * 22.5_f64.to_radians().cos()).abs() < 1e-6,
        "{speed}"
    );
    // Measured at 2.0 s, sent at 3.0 s, the drone's clock at 1:1.
    assert!((age - 1.0).abs() < 1e-6, "{age}");
    let v = c.state_msg_now(3.0).surface_wind;
    assert_eq!(v.drone, DroneCopy::Sending);
    let a = v.anemometer.expect("configured");
    assert_eq!((a.sentences, a.rejected, a.in_mean), (2, 1, 2));
    assert!(a.last_error.expect("the bad checksum").contains("checksum"));
    // The replica holds nothing until the drone accepts.
    assert!(c.guidance.surface_wind().is_none());
    answer(&mut c, 3.2, id, CommandOutcome::Accepted);
    let held = c.guidance.surface_wind().expect("the replica's copy");
    assert!((held.time_s - 1002.0).abs() < 1e-6, "{}", held.time_s);
    let (n, e) = (held.ne_mps[0], held.ne_mps[1]);
    assert!(
        n > 0.0 && e > 0.0,
        "from the south-west the air goes north-east: {n} {e}"
    );
    let v = c.state_msg_now(3.5).surface_wind;
    assert_eq!(v.drone, DroneCopy::Held);
    let held = v.held.expect("what the drone took");
    assert!((held.from_deg - 247.5).abs() < 0.01 && (held.age_s - 1.5).abs() < 1e-9);
    let wind = v.wind.expect("in force");
    assert_eq!(wind.source, SurfaceWindSource::Anemometer);
    assert!((wind.age_s - 1.5).abs() < 1e-9);
    let log = said(&mut c);
    assert!(
        log.iter()
            .any(|(_, t)| t.contains("ground anemometer heard")),
        "{log:?}"
    );
    assert!(
        log.iter()
            .any(|(_, t)| t.contains("the drone holds the surface wind")),
        "{log:?}"
    );
    // The next mean goes after the period (5 s), not before.
    c.on_anemometer_line(4.0, &format_mwv(250.0, MwvReference::True, 3.0));
    assert!(uplinks(&mut c, 7.9).is_empty());
    assert_eq!(uplinks(&mut c, 8.0).len(), 1);
}

#[test]
fn in_a_rehearsal_the_age_runs_on_the_drones_clock() {
    let mut c = core();
    connect(&mut c, 0.0);
    // The drone's clock runs 20× the station's.
    hear_clock(&mut c, 0.0, 100.0);
    hear_clock(&mut c, 2.0, 140.0);
    c.on_anemometer_line(2.0, &format_mwv(90.0, MwvReference::True, 2.0));
    let sent = uplinks(&mut c, 2.5);
    let (id, _, _, age) = sent[0];
    assert!(
        (age - 10.0).abs() < 1e-6,
        "half a station second is 10 drone seconds: {age}"
    );
    answer(&mut c, 2.6, id, CommandOutcome::Accepted);
    let held = c.guidance.surface_wind().expect("held");
    assert!((held.time_s - 140.0).abs() < 1e-6, "{}", held.time_s);
}

#[test]
fn the_operators_value_stands_in_for_a_silent_anemometer_and_lapses() {
    let mut c = core();
    c.config.surface_wind.anemometer = Some("udpin:127.0.0.1:10110".into());
    connect(&mut c, 0.0);
    assert!(c.set_operator_surface_wind(0.0, "ana", -1.0, 90.0).is_err());
    assert!(
        c.set_operator_surface_wind(0.0, "ana", 2.0, f64::NAN)
            .is_err()
    );
    assert!(c.set_operator_surface_wind(0.0, "ana", 99.0, 90.0).is_err());
    c.set_operator_surface_wind(0.0, "ana", 4.0, -90.0)
        .expect("a good value");
    let sent = uplinks(&mut c, 0.0);
    assert_eq!(sent.len(), 1);
    let (id, speed, from, age) = sent[0];
    assert!((speed - 4.0).abs() < 1e-9 && (from - 270.0).abs() < 1e-9 && age == 0.0);
    answer(&mut c, 0.1, id, CommandOutcome::Accepted);
    let log = said(&mut c);
    assert!(
        log.iter()
            .any(|(_, t)| t.contains("ana set the surface wind")),
        "{log:?}"
    );
    // The anemometer speaks: it wins while it is fresh; the operator's value is still shown.
    c.on_anemometer_line(10.0, &format_mwv(180.0, MwvReference::True, 1.0));
    let (id, _, from, _) = uplinks(&mut c, 10.0)[0];
    assert!((from - 180.0).abs() < 1e-9);
    answer(&mut c, 10.1, id, CommandOutcome::Accepted);
    let v = c.state_msg_now(10.0).surface_wind;
    assert_eq!(
        v.wind.expect("in force").source,
        SurfaceWindSource::Anemometer
    );
    assert!(v.operator.is_some());
    // Silent for longer than `stale_after_s` (30 s): the operator's value again.
    let v = c.state_msg_now(41.0).surface_wind;
    assert_eq!(
        v.wind.expect("in force").source,
        SurfaceWindSource::Operator
    );
    let (id, _, from, _) = uplinks(&mut c, 41.0)[0];
    assert!((from - 270.0).abs() < 1e-9);
    answer(&mut c, 41.1, id, CommandOutcome::Accepted);
    let log = said(&mut c);
    assert!(
        log.iter().any(|(_, t)| t.contains("anemometer silent")),
        "{log:?}"
    );
    // The operator's value lapses after `operator_valid_s` (900 s), said once, and is
    // withdrawn from the drone: sent once more as too old for guidance.
    hear_clock(&mut c, 900.0, 2000.0);
    let sent = uplinks(&mut c, 901.0);
    assert_eq!(sent.len(), 1, "{sent:?}");
    let (id, _, _, age) = sent[0];
    assert_eq!(age, stx_link::command::SURFACE_WIND_MAX_AGE_S);
    answer(&mut c, 901.1, id, CommandOutcome::Accepted);
    let v = c.state_msg_now(901.2).surface_wind;
    assert!(v.wind.is_none() && v.held.is_none(), "{v:?}");
    assert_eq!(v.drone, DroneCopy::None);
    let replica = c
        .guidance
        .surface_wind()
        .expect("the drone's stale copy, mirrored");
    assert!(replica.time_s < 2000.0 - 3000.0, "{}", replica.time_s);
    let log = said(&mut c);
    assert!(
        log.iter().any(|(_, t)| t.contains("withdrawn or lapsed")),
        "{log:?}"
    );
    assert!(
        log.iter().any(|(_, t)| t.contains("no longer uses")),
        "{log:?}"
    );
    // Nothing more to send.
    assert!(uplinks(&mut c, 910.0).is_empty());
}

#[test]
fn a_refusal_is_said_once_shown_and_retried_until_it_is_taken() {
    let mut c = core();
    connect(&mut c, 0.0);
    hear_clock(&mut c, 0.0, 50.0);
    c.set_operator_surface_wind(0.0, "ana", 3.0, 10.0)
        .expect("ok");
    said(&mut c);
    let (id, ..) = uplinks(&mut c, 0.0)[0];
    answer(
        &mut c,
        0.1,
        id,
        CommandOutcome::Rejected {
            result: CommandResult::Unsupported,
        },
    );
    let v = c.state_msg_now(0.2).surface_wind;
    assert_eq!(v.drone, DroneCopy::Failed);
    assert!(v.last_error.expect("why").contains("Unsupported"));
    assert!(c.guidance.surface_wind().is_none());
    let (id, ..) = uplinks(&mut c, 5.0)[0];
    answer(&mut c, 5.1, id, CommandOutcome::TimedOut { attempts: 4 });
    let warnings: Vec<_> = said(&mut c)
        .into_iter()
        .filter(|(l, _)| *l == Level::Warning)
        .collect();
    assert_eq!(
        warnings.len(),
        1,
        "said once while it goes on: {warnings:?}"
    );
    let (id, ..) = uplinks(&mut c, 10.0)[0];
    answer(&mut c, 10.1, id, CommandOutcome::Accepted);
    assert_eq!(c.state_msg_now(10.2).surface_wind.drone, DroneCopy::Held);
    assert!(c.guidance.surface_wind().is_some());
    // Lost and heard again: sent at once, not at the next period.
    c.on_link_event(
        11.0,
        GroundEvent::Link(LinkEvent::Lost {
            system_id: 1,
            since_last: std::time::Duration::from_secs(5),
        }),
    );
    assert!(
        uplinks(&mut c, 12.0).is_empty(),
        "nothing goes to a drone not heard"
    );
    connect(&mut c, 12.5);
    assert_eq!(uplinks(&mut c, 12.5).len(), 1);
}
