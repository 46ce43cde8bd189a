//! Ground and vehicle endpoints talking through a simulated lossy channel with a fake clock.

use crate::common;

use std::time::Duration;

use common::{Pair, msg_id};
use stx_link::command::{Command, CommandOutcome, CommandResult, RequestId};
use stx_link::endpoint::{
    GroundConfig, GroundEndpoint, GroundEvent, LinkConfig, LinkEvent, SenderStats, VehicleConfig,
    VehicleEvent,
};
use stx_link::frame::{FrameError, FrameIds, encode_frame_into};
use stx_link::manual::{ManualEvent, Sticks};
use stx_link::param::{ParamEvent, ParamSpec};
use stx_link::plan::{PlanEvent, PlanItem};
use stx_link::signing::{SigningConfig, SigningKey};
use stx_link::telemetry::{Attitude, Telemetry};
use stx_types::mission::FlightMode;

const COMMAND_LONG: u32 = 76;
const PARAM_VALUE: u32 = 22;
const HEARTBEAT: u32 = 0;

fn secs(s: f64) -> Duration {
    Duration::from_secs_f64(s)
}

fn command_outcome(pair: &Pair, id: RequestId) -> Option<(CommandOutcome, u8)> {
    pair.ground_events.iter().find_map(|(_, e)| match e {
        GroundEvent::Command(c)
            if c.request_id == id && !matches!(c.outcome, CommandOutcome::InProgress { .. }) =>
        {
            Some((c.outcome, c.attempts))
        }
        _ => None,
    })
}

fn delivered_commands(pair: &Pair) -> usize {
    pair.vehicle_events
        .iter()
        .filter(|(_, e)| matches!(e, VehicleEvent::Command(_)))
        .count()
}

#[test]
fn heartbeats_connect_both_ends() {
    let mut pair = Pair::default_pair(1);
    pair.run_for(secs(2.0));
    assert!(pair.ground.is_connected());
    assert!(pair.vehicle.is_connected());
    assert!(pair.ground_events.iter().any(|(_, e)| matches!(
        e,
        GroundEvent::Link(LinkEvent::Connected { system_id: 1, .. })
    )));
    let hb = pair
        .ground_events
        .iter()
        .filter(|(_, e)| {
            matches!(
                e,
                GroundEvent::Telemetry {
                    telemetry: Telemetry::Status(_),
                    ..
                }
            )
        })
        .count();
    assert!((2..=3).contains(&hb), "{hb} heartbeats in 2 s");
}

#[test]
fn command_retried_through_loss_then_acked() {
    let mut pair = Pair::default_pair(2);
    let mut dropped = 0;
    pair.to_vehicle.filter = Some(Box::new(move |f| {
        if msg_id(f) == Some(COMMAND_LONG) && dropped < 2 {
            dropped += 1;
            return true;
        }
        false
    }));
    pair.run_for(secs(1.5));
    pair.ground
        .send_command(
            pair.now,
            RequestId(42),
            Command::SetMode(FlightMode::SpiralLanding),
        )
        .expect("sent");
    pair.run_for(secs(5.0));
    assert_eq!(
        command_outcome(&pair, RequestId(42)),
        Some((CommandOutcome::Accepted, 3))
    );
    assert_eq!(delivered_commands(&pair), 1);
    // The retry carried confirmation 2 and arrived after two 1 s timeouts.
    let (t, _) = pair
        .ground_events
        .iter()
        .find(|(_, e)| matches!(e, GroundEvent::Command(_)))
        .expect("event");
    assert!(*t >= secs(101.5 + 2.0) && *t < secs(101.5 + 2.5), "{t:?}");
}

#[test]
fn lost_ack_is_recovered_by_retry_without_executing_twice() {
    let mut pair = Pair::default_pair(3);
    let mut dropped = false;
    pair.to_ground.filter = Some(Box::new(move |f| {
        if msg_id(f) == Some(77) && !dropped {
            dropped = true;
            return true;
        }
        false
    }));
    pair.run_for(secs(1.5));
    pair.ground
        .send_command(pair.now, RequestId(1), Command::Cutdown)
        .expect("sent");
    pair.run_for(secs(5.0));
    assert_eq!(
        command_outcome(&pair, RequestId(1)),
        Some((CommandOutcome::Accepted, 2))
    );
    assert_eq!(
        delivered_commands(&pair),
        1,
        "a retried cutdown must not be executed twice"
    );
}

#[test]
fn command_times_out_after_all_attempts_lost() {
    let mut pair = Pair::default_pair(4);
    pair.to_vehicle.filter = Some(Box::new(|f| msg_id(f) == Some(COMMAND_LONG)));
    pair.run_for(secs(1.5));
    let t0 = pair.now;
    pair.ground
        .send_command(t0, RequestId(9), Command::HoldHeading { heading_deg: 90.0 })
        .expect("sent");
    pair.run_for(secs(10.0));
    assert_eq!(
        command_outcome(&pair, RequestId(9)),
        Some((CommandOutcome::TimedOut { attempts: 4 }, 4))
    );
    let (t, _) = pair
        .ground_events
        .iter()
        .find(|(_, e)| matches!(e, GroundEvent::Command(_)))
        .expect("event");
    assert_eq!(*t - t0, secs(4.0));
    assert_eq!(delivered_commands(&pair), 0);
}

#[test]
fn rejected_command_reports_the_mav_result() {
    let mut pair = Pair::default_pair(5);
    pair.auto_ack = Some(CommandResult::Denied);
    pair.run_for(secs(1.5));
    pair.ground
        .send_command(pair.now, RequestId(5), Command::Cutdown)
        .expect("sent");
    pair.run_for(secs(2.0));
    assert_eq!(
        command_outcome(&pair, RequestId(5)),
        Some((
            CommandOutcome::Rejected {
                result: CommandResult::Denied
            },
            1
        ))
    );
}

fn many_params() -> Vec<ParamSpec> {
    (0..20)
        .map(|i| ParamSpec::new(&format!("P{i:02}"), i as f32, 0.0, 100.0, "test"))
        .collect()
}

#[test]
fn param_list_completes_despite_lost_values() {
    let mut pair = Pair::new(
        GroundConfig::default(),
        VehicleConfig {
            params: many_params(),
            ..Default::default()
        },
        6,
    );
    let mut count = 0;
    // Drop PARAM_VALUEs number 3, 4, 10 and 19 of the first answer.
    pair.to_ground.filter = Some(Box::new(move |f| {
        if msg_id(f) == Some(PARAM_VALUE) {
            count += 1;
            return [3, 4, 10, 19].contains(&count);
        }
        false
    }));
    pair.run_for(secs(1.0));
    pair.ground.param_list(pair.now).expect("started");
    let done = pair.run_until_ground(secs(10.0), |e| {
        matches!(
            e,
            GroundEvent::Param(ParamEvent::ListComplete { .. } | ParamEvent::ListFailed { .. })
        )
    });
    let Some(GroundEvent::Param(ParamEvent::ListComplete { params })) = done else {
        panic!("{done:?}")
    };
    assert_eq!(params.len(), 20);
    for (i, p) in params.iter().enumerate() {
        assert_eq!(p.name, format!("P{i:02}"));
        assert_eq!(p.value, i as f32);
    }
}

#[test]
fn param_list_fails_when_vehicle_is_silent() {
    let mut pair = Pair::new(
        GroundConfig::default(),
        VehicleConfig {
            params: many_params(),
            ..Default::default()
        },
        7,
    );
    pair.to_ground.filter = Some(Box::new(|f| msg_id(f) == Some(PARAM_VALUE)));
    pair.ground.param_list(pair.now).expect("started");
    let done = pair.run_until_ground(secs(10.0), |e| matches!(e, GroundEvent::Param(_)));
    assert!(
        matches!(
            done,
            Some(GroundEvent::Param(ParamEvent::ListFailed {
                expected_count: None,
                ..
            }))
        ),
        "{done:?}"
    );
}

#[test]
fn param_set_through_loss_reports_value_and_vehicle_change() {
    let mut pair = Pair::new(
        GroundConfig::default(),
        VehicleConfig {
            params: many_params(),
            ..Default::default()
        },
        8,
    );
    pair.to_vehicle.loss = 0.3;
    pair.to_ground.loss = 0.3;
    pair.ground
        .param_set(pair.now, "P05", 55.5)
        .expect("started");
    let done = pair.run_until_ground(secs(10.0), |e| {
        matches!(
            e,
            GroundEvent::Param(ParamEvent::SetDone { .. } | ParamEvent::SetFailed { .. })
        )
    });
    assert_eq!(
        done,
        Some(GroundEvent::Param(ParamEvent::SetDone {
            name: "P05".into(),
            requested: 55.5,
            actual: 55.5,
            accepted: true
        }))
    );
    assert_eq!(pair.vehicle.params().get("P05"), Some(55.5));
    assert!(pair.vehicle_events.iter().any(
        |(_, e)| matches!(e, VehicleEvent::ParamChanged(c) if c.name == "P05" && c.new == 55.5)
    ));
}

fn test_plan() -> Vec<PlanItem> {
    let mut plan: Vec<PlanItem> = (0..8)
        .map(|i| PlanItem::Waypoint {
            lat_deg: 41.0 + f64::from(i) * 0.01,
            lon_deg: -8.6,
            alt_msl_m: 1000.0 - f64::from(i) * 100.0,
        })
        .collect();
    plan.push(PlanItem::Land {
        lat_deg: 41.1,
        lon_deg: -8.61,
        alt_msl_m: 95.0,
        approach_heading_deg: None,
    });
    plan
}

#[test]
fn plan_upload_and_download_with_losses() {
    // 25 % loss each way: an exchange fails 44 % of the time, so allow more retries than the
    // default for the 20 exchanges of an upload and a download.
    let plan = stx_link::plan::PlanConfig {
        retries: 10,
        ..Default::default()
    };
    let mut pair = Pair::new(
        GroundConfig {
            plan,
            ..Default::default()
        },
        VehicleConfig {
            plan,
            ..Default::default()
        },
        9,
    );
    pair.to_vehicle.loss = 0.25;
    pair.to_ground.loss = 0.25;
    pair.ground
        .plan_upload(pair.now, test_plan())
        .expect("started");
    let done = pair.run_until_ground(secs(60.0), |e| matches!(e, GroundEvent::Plan(_)));
    assert_eq!(
        done,
        Some(GroundEvent::Plan(PlanEvent::UploadDone { items: 9 }))
    );
    assert_eq!(pair.vehicle.plan().len(), 9);
    assert!(
        pair.vehicle_events
            .iter()
            .any(|(_, e)| matches!(e, VehicleEvent::PlanReceived(p) if p.len() == 9))
    );
    pair.ground_events.clear();
    pair.ground.plan_download(pair.now).expect("started");
    let done = pair.run_until_ground(secs(60.0), |e| matches!(e, GroundEvent::Plan(_)));
    let Some(GroundEvent::Plan(PlanEvent::DownloadDone { items })) = done else {
        panic!("{done:?}")
    };
    assert_eq!(items, pair.vehicle.plan());
    assert!(
        pair.to_vehicle.dropped > 0 && pair.to_ground.dropped > 0,
        "the channel lost nothing: test is void"
    );
}

#[test]
fn plan_upload_fails_when_vehicle_never_answers() {
    let mut pair = Pair::default_pair(10);
    pair.to_vehicle.loss = 1.0;
    pair.ground
        .plan_upload(pair.now, test_plan())
        .expect("started");
    let done = pair.run_until_ground(secs(60.0), |e| matches!(e, GroundEvent::Plan(_)));
    assert!(
        matches!(
            done,
            Some(GroundEvent::Plan(PlanEvent::UploadFailed {
                result: None,
                ..
            }))
        ),
        "{done:?}"
    );
}

#[test]
fn manual_control_streams_then_goes_stale_after_release() {
    let mut pair = Pair::default_pair(11);
    pair.run_for(secs(1.0));
    let t0 = pair.now;
    pair.ground.manual_hold(
        t0,
        Sticks {
            y: 0.5,
            ..Default::default()
        },
    );
    pair.run_for(secs(1.0));
    pair.ground.manual_release();
    let released = pair.now;
    pair.run_for(secs(2.0));
    let sticks: Vec<Duration> = pair
        .vehicle_events
        .iter()
        .filter(|(_, e)| matches!(e, VehicleEvent::Manual(ManualEvent::Sticks(s)) if s.y == 0.5))
        .map(|(t, _)| *t)
        .collect();
    assert!(
        (10..=11).contains(&sticks.len()),
        "{} stick messages in 1 s at 10 Hz",
        sticks.len()
    );
    let stale: Vec<Duration> = pair
        .vehicle_events
        .iter()
        .filter(|(_, e)| matches!(e, VehicleEvent::Manual(ManualEvent::Stale { .. })))
        .map(|(t, _)| *t)
        .collect();
    assert_eq!(stale.len(), 1);
    let last = *sticks.last().expect("sticks");
    assert_eq!(stale[0] - last, secs(0.5));
    assert!(stale[0] <= released + secs(0.6));
    assert_eq!(pair.vehicle.sticks(pair.now), None);
}

#[test]
fn link_lost_and_regained() {
    let mut pair = Pair::default_pair(12);
    pair.run_for(secs(3.0));
    assert!(pair.ground.is_connected());
    pair.to_ground.loss = 1.0;
    pair.to_vehicle.loss = 1.0;
    let cut = pair.now;
    pair.run_for(secs(6.0));
    assert!(!pair.ground.is_connected() && !pair.vehicle.is_connected());
    let lost_at = pair
        .ground_events
        .iter()
        .find(|(_, e)| matches!(e, GroundEvent::Link(LinkEvent::Lost { .. })))
        .map(|(t, _)| *t)
        .expect("lost");
    // Heartbeats already in flight (50 ms) still arrive after the cut.
    assert!(
        lost_at > cut && lost_at <= cut + secs(3.55),
        "{:?}",
        lost_at - cut
    );
    assert!(
        pair.ground
            .link_stats(pair.now)
            .last_heartbeat_age_s
            .is_some_and(|a| a > 5.0)
    );
    pair.to_ground.loss = 0.0;
    pair.to_vehicle.loss = 0.0;
    pair.run_for(secs(2.0));
    assert!(pair.ground.is_connected() && pair.vehicle.is_connected());
    let connected = pair
        .ground_events
        .iter()
        .filter(|(_, e)| matches!(e, GroundEvent::Link(LinkEvent::Connected { .. })))
        .count();
    assert_eq!(connected, 2);
    assert!(
        pair.vehicle_events
            .iter()
            .any(|(_, e)| matches!(e, VehicleEvent::Link(LinkEvent::Lost { .. })))
    );
}

#[test]
fn packet_loss_is_computed_from_sequence_gaps() {
    let mut pair = Pair::default_pair(13);
    pair.to_ground.loss = 0.10;
    let att = attitude();
    for i in 0..2000 {
        let t = secs(100.0 + f64::from(i) * 0.02);
        pair.run_until(t);
        pair.vehicle.send_telemetry(pair.now, &att);
    }
    pair.run_for(secs(0.1));
    let stats = pair.ground.link_stats(pair.now);
    let sent = pair.to_ground.sent as f64;
    let truth = 100.0 * pair.to_ground.dropped as f64 / sent;
    let v = stats
        .senders
        .iter()
        .find(|s| s.system_id == 1)
        .expect("vehicle sender");
    // Frames lost after the last received one cannot be seen as a gap: allow one.
    assert!(
        (v.loss_pct - truth).abs() < 0.1,
        "estimated {} vs true {truth}",
        v.loss_pct
    );
    assert!(
        (stats.packet_loss_pct - 10.0).abs() < 2.0,
        "{}",
        stats.packet_loss_pct
    );
    assert!(
        (stats.messages_per_s - 45.0).abs() < 5.0,
        "{}",
        stats.messages_per_s
    );
    assert!(
        stats
            .last_message_age_s
            .get("ATTITUDE")
            .is_some_and(|&a| a < 1.5)
    );
    // Serialisable for the station.
    let json = serde_json::to_string(&stats).expect("serialises");
    assert!(json.contains("packet_loss_pct"));
}

fn attitude() -> Telemetry {
    Telemetry::Attitude(Attitude {
        time_boot_ms: 0,
        roll_rad: 0.1,
        pitch_rad: 0.0,
        yaw_rad: 1.0,
        roll_rate_radps: 0.0,
        pitch_rate_radps: 0.0,
        yaw_rate_radps: 0.0,
    })
}

/// Frames from system 1 with the given sequence numbers, each its own datagram.
fn frames_with_sequences(sequences: &[u8]) -> Vec<Vec<u8>> {
    let msg = attitude().to_mavlink();
    sequences
        .iter()
        .map(|&sequence| {
            let mut out = Vec::new();
            encode_frame_into(
                Duration::ZERO,
                &msg,
                FrameIds {
                    system_id: 1,
                    component_id: 1,
                    sequence,
                },
                None,
                &mut out,
            );
            out
        })
        .collect()
}

fn sender_after(sequences: &[u8]) -> SenderStats {
    let mut ground = GroundEndpoint::new(GroundConfig::default(), Duration::ZERO);
    for f in frames_with_sequences(sequences) {
        ground.handle_bytes(Duration::ZERO, &f);
    }
    let stats = ground.link_stats(Duration::ZERO);
    assert_eq!(stats.frames_in, sequences.len() as u64);
    stats.senders[0]
}

/// Regression: a reordered frame or a sender restarting its sequence counted as ~255 lost
/// packets (the modulo-256 gap).
#[test]
fn reordered_frames_and_restarts_are_counted_apart_from_loss() {
    // A real loss of three frames, across the wrap.
    let s = sender_after(&[253, 254, 255, 3, 4]);
    assert_eq!((s.lost, s.reordered, s.restarts), (3, 0, 0));
    // Two frames swapped: nothing lost.
    let s = sender_after(&[10, 11, 13, 12, 14, 15]);
    assert_eq!((s.lost, s.reordered, s.restarts), (0, 1, 0), "{s:?}");
    assert_eq!(s.loss_pct, 0.0);
    // A late frame across the wrap, and one of two lost frames arriving late.
    let s = sender_after(&[254, 0, 255, 1, 4, 2, 5]);
    assert_eq!((s.lost, s.reordered, s.restarts), (1, 2, 0), "{s:?}");
    // The sender restarts at 0 after 100: one restart, no loss.
    let s = sender_after(&[98, 99, 100, 0, 1, 2]);
    assert_eq!((s.lost, s.reordered, s.restarts), (0, 0, 1), "{s:?}");
    // A duplicate is neither.
    let s = sender_after(&[7, 7, 8]);
    assert_eq!((s.lost, s.duplicates, s.reordered), (0, 1, 0));
}

/// Regression: when a TCP or serial connection dropped mid-frame, the partial frame was never
/// counted (the decoder waited for bytes that could not come).
#[test]
fn a_frame_cut_off_by_the_end_of_the_stream_is_counted_as_truncated() {
    let frames = frames_with_sequences(&[0, 1]);
    let mut ground = GroundEndpoint::new(GroundConfig::default(), Duration::ZERO);
    ground.handle_bytes(Duration::ZERO, &frames[0]);
    ground.handle_bytes(Duration::ZERO, &frames[1][..frames[1].len() / 2]);
    assert_eq!(ground.link_stats(Duration::ZERO).decoder.truncated, 0);
    ground.handle_stream_end(Duration::ZERO);
    let stats = ground.link_stats(Duration::ZERO);
    assert_eq!(stats.frames_in, 1);
    assert_eq!(stats.decoder.truncated, 1);
    assert_eq!(
        stats.decoder.bytes_discarded as usize,
        frames[1].len() / 2,
        "every byte of the cut-off frame is accounted for"
    );
    let mut events = Vec::new();
    while let Some(e) = ground.poll_event() {
        events.push(e);
    }
    assert!(
        events.iter().any(|e| matches!(
            e,
            GroundEvent::Link(LinkEvent::FrameError(FrameError::Truncated { .. }))
        )),
        "{events:?}"
    );
    // A new connection starts clean.
    ground.handle_bytes(Duration::ZERO, &frames[1]);
    assert_eq!(ground.link_stats(Duration::ZERO).frames_in, 2);
}

fn signing(key: u8, link_id: u8, unix_s: u64) -> SigningConfig {
    SigningConfig::new(
        SigningKey::from_bytes([key; 32]),
        link_id,
        Duration::from_secs(unix_s),
    )
}

const JAN_2026: u64 = 1_767_225_600;

fn signed_pair(ground: Option<SigningConfig>, vehicle: Option<SigningConfig>, seed: u64) -> Pair {
    let g = GroundConfig {
        link: LinkConfig::ground().with_signing(ground),
        ..Default::default()
    };
    let v = VehicleConfig {
        link: LinkConfig::vehicle().with_signing(vehicle),
        ..Default::default()
    };
    Pair::new(g, v, seed)
}

#[test]
fn signed_link_works_end_to_end() {
    let mut pair = signed_pair(
        Some(signing(7, 1, JAN_2026)),
        Some(signing(7, 2, JAN_2026)),
        14,
    );
    pair.run_for(secs(1.5));
    pair.ground
        .send_command(pair.now, RequestId(3), Command::Cutdown)
        .expect("sent");
    pair.run_for(secs(2.0));
    assert_eq!(
        command_outcome(&pair, RequestId(3)),
        Some((CommandOutcome::Accepted, 1))
    );
    let s = pair.vehicle.link_stats(pair.now);
    assert!(s.decoder.signed_frames > 0);
    assert_eq!(s.signature_failures, 0);
    assert!(
        pair.ground_events
            .iter()
            .any(|(_, e)| matches!(e, GroundEvent::Link(LinkEvent::PersistSigningTimestamp(_))))
    );
}

#[test]
fn signing_on_refuses_and_counts_unsigned_frames() {
    let mut pair = signed_pair(None, Some(signing(7, 2, JAN_2026)), 15);
    pair.run_for(secs(3.0));
    pair.ground
        .send_command(pair.now, RequestId(4), Command::Cutdown)
        .expect("sent");
    pair.run_for(secs(6.0));
    assert_eq!(delivered_commands(&pair), 0);
    assert!(
        !pair.vehicle.is_connected(),
        "unsigned heartbeats must not count"
    );
    let s = pair.vehicle.link_stats(pair.now);
    assert!(s.decoder.unsigned_refused >= 8, "{:?}", s.decoder);
    assert_eq!(s.signature_failures, s.decoder.unsigned_refused);
    assert_eq!(
        command_outcome(&pair, RequestId(4)),
        Some((CommandOutcome::TimedOut { attempts: 4 }, 4))
    );
    // A wrong key is refused as well.
    let mut pair = signed_pair(
        Some(signing(8, 1, JAN_2026)),
        Some(signing(7, 2, JAN_2026)),
        16,
    );
    pair.run_for(secs(3.0));
    assert!(pair.vehicle.link_stats(pair.now).decoder.bad_signatures >= 3);
}

#[test]
fn signing_switched_on_at_run_time_refuses_the_unsigned_peer() {
    let mut pair = Pair::default_pair(20);
    pair.run_for(secs(2.0));
    assert!(pair.vehicle.is_connected());
    pair.vehicle
        .set_signing(pair.now, Some(signing(7, 2, JAN_2026)));
    pair.run_for(secs(5.0));
    assert!(
        !pair.vehicle.is_connected(),
        "unsigned ground heartbeats still accepted"
    );
    assert!(pair.vehicle.link_stats(pair.now).decoder.unsigned_refused >= 4);
    pair.ground
        .set_signing(pair.now, Some(signing(7, 1, JAN_2026)));
    pair.run_for(secs(2.0));
    assert!(pair.vehicle.is_connected() && pair.ground.is_connected());
}

#[test]
fn replayed_signed_frame_is_refused() {
    let mut pair = signed_pair(
        Some(signing(7, 1, JAN_2026)),
        Some(signing(7, 2, JAN_2026)),
        17,
    );
    pair.run_for(secs(1.5));
    pair.ground
        .send_command(pair.now, RequestId(1), Command::Cutdown)
        .expect("sent");
    pair.run_for(secs(1.0));
    assert_eq!(delivered_commands(&pair), 1);
    let recorded = pair
        .to_vehicle
        .log
        .iter()
        .find(|f| msg_id(f) == Some(COMMAND_LONG))
        .expect("recorded")
        .clone();
    pair.run_for(secs(10.0));
    pair.vehicle.handle_bytes(pair.now, &recorded);
    pair.drive_now();
    assert_eq!(
        delivered_commands(&pair),
        1,
        "a replayed cutdown must not execute"
    );
    assert_eq!(pair.vehicle.link_stats(pair.now).decoder.replays_refused, 1);
    assert!(pair.vehicle_events.iter().any(|(_, e)| matches!(
        e,
        VehicleEvent::Link(LinkEvent::FrameError(
            stx_link::frame::FrameError::Signature { .. }
        ))
    )));
}

/// The vehicle restarts with its wall clock an hour behind. With the persisted high-water
/// mark its timestamps continue after the old ones and the ground keeps accepting them;
/// without it they go backwards and the ground refuses them as replays.
#[test]
fn signing_timestamp_is_monotonic_across_restart() {
    for use_persisted in [true, false] {
        let mut pair = signed_pair(
            Some(signing(7, 1, JAN_2026)),
            Some(signing(7, 2, JAN_2026)),
            18,
        );
        pair.ground.link_stats(pair.now);
        pair.run_for(secs(5.0));
        let persisted = pair
            .vehicle_events
            .iter()
            .filter_map(|(_, e)| match e {
                VehicleEvent::Link(LinkEvent::PersistSigningTimestamp(v)) => Some(*v),
                _ => None,
            })
            .max();
        assert!(persisted.is_some());
        // Restart: new endpoint, clock one hour behind.
        let behind = signing(7, 2, JAN_2026 - 3600).with_persisted_timestamp(if use_persisted {
            persisted
        } else {
            None
        });
        let cfg = VehicleConfig {
            link: LinkConfig::vehicle().with_signing(Some(behind)),
            ..Default::default()
        };
        pair.vehicle = stx_link::endpoint::VehicleEndpoint::new(cfg, pair.now).expect("vehicle");
        let before = pair.ground.link_stats(pair.now).decoder;
        pair.run_for(secs(3.0));
        let after = pair.ground.link_stats(pair.now).decoder;
        if use_persisted {
            assert_eq!(after.replays_refused, before.replays_refused);
            assert!(after.signed_frames > before.signed_frames + 2);
            assert!(pair.ground.is_connected());
        } else {
            assert!(
                after.replays_refused > before.replays_refused,
                "control case: without the mark frames are replays"
            );
        }
    }
}

#[test]
fn long_status_text_arrives_whole() {
    let mut pair = Pair::default_pair(19);
    let text = "Parafoil deployed; round chute released at 3124 m; guidance entering approximation phase towards branch 2";
    pair.vehicle
        .send_status_text(pair.now, stx_link::telemetry::Severity::Notice, text);
    let got = pair.run_until_ground(secs(1.0), |e| matches!(e, GroundEvent::StatusText { .. }));
    assert_eq!(
        got,
        Some(GroundEvent::StatusText {
            from: (1, 1),
            severity: stx_link::telemetry::Severity::Notice,
            text: text.to_string()
        })
    );
    let _ = HEARTBEAT;
}

#[test]
fn two_radios_deliver_each_signed_frame_once_and_refuse_a_replay_on_either() {
    use stx_link::endpoint::VehicleEndpoint;
    let mut vehicle = VehicleEndpoint::new(
        VehicleConfig {
            link: LinkConfig::vehicle().with_signing(Some(signing(7, 2, JAN_2026))),
            ..Default::default()
        },
        Duration::ZERO,
    )
    .expect("vehicle");
    let mut ground = GroundEndpoint::new(
        GroundConfig {
            link: LinkConfig::ground()
                .with_signing(Some(signing(7, 1, JAN_2026)))
                .with_paths(2),
            ..Default::default()
        },
        Duration::ZERO,
    );
    let mut frames = Vec::new();
    for i in 0..10_u32 {
        let now = secs(0.1 * f64::from(i));
        vehicle.send_telemetry(
            now,
            &Telemetry::Attitude(Attitude {
                time_boot_ms: i * 100,
                roll_rad: 0.0,
                pitch_rad: 0.0,
                yaw_rad: 0.0,
                roll_rate_radps: 0.0,
                pitch_rate_radps: 0.0,
                yaw_rate_radps: 0.0,
            }),
        );
        while let Some(f) = vehicle.poll_transmit(now) {
            frames.push((now, f));
        }
    }
    // Radio 2 delivers each frame 50 ms after radio 1; radio 1 misses the fourth frame.
    for (i, (t, f)) in frames.iter().enumerate() {
        if i != 3 {
            ground.handle_bytes_on(0, *t, f);
        }
        ground.handle_bytes_on(1, *t + secs(0.05), f);
    }
    let attitudes = std::iter::from_fn(|| ground.poll_event())
        .filter(|e| {
            matches!(
                e,
                GroundEvent::Telemetry {
                    telemetry: Telemetry::Attitude(_),
                    ..
                }
            )
        })
        .count();
    assert_eq!(
        attitudes, 10,
        "each attitude once, the one radio 1 missed from radio 2"
    );
    let now = secs(1.5);
    let s = ground.link_stats(now);
    assert_eq!(s.signature_failures, 0, "a copy is not a replay: {s:?}");
    assert_eq!(s.duplicates_dropped, frames.len() as u64 - 1, "{s:?}");
    assert_eq!(s.packet_loss_pct, 0.0, "nothing lost on the merged link");
    assert!(
        s.paths[0].packet_loss_pct > 0.0,
        "radio 1 lost a frame: {s:?}"
    );
    assert_eq!(s.paths[1].packet_loss_pct, 0.0);
    // A captured frame played again later is refused on either radio.
    let (_, old) = &frames[5];
    ground.handle_bytes_on(0, secs(4.0), old);
    ground.handle_bytes_on(1, secs(4.0), old);
    let s = ground.link_stats(secs(4.0));
    assert_eq!(s.decoder.replays_refused, 2, "{s:?}");
    assert!(
        std::iter::from_fn(|| ground.poll_event())
            .all(|e| !matches!(e, GroundEvent::Telemetry { .. }))
    );
}

#[test]
fn bytes_for_a_radio_that_does_not_exist_are_dropped_without_harm() {
    let mut ground = GroundEndpoint::new(GroundConfig::default(), Duration::ZERO);
    ground.handle_bytes_on(3, Duration::ZERO, &[0xFD, 9, 0, 0, 0, 1, 1, 0, 0, 0]);
    ground.handle_stream_end_on(3, Duration::ZERO);
    let s = ground.link_stats(Duration::ZERO);
    assert_eq!((s.frames_in, s.decoder.bytes_in), (0, 0));
    assert_eq!(ground.transmit_path(Duration::ZERO), 0);
}
