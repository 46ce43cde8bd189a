//! A flight log from a station recording's decoded telemetry (`/telemetry/<MAVLINK_NAME>`
//! topics, stx-link's typed values as JSON, of which `telemetry.rs` reads the fields used; see
//! stx-station's `recording` module): GPS position and velocity from GLOBAL_POSITION_INT (the
//! time base: one sample per message), attitude from ATTITUDE, airspeed from VFR_HUD, servo
//! commands from SERVO_OUTPUT_RAW and the wind estimate from WIND_COV, each the latest at or
//! before the position's time.
//!
//! The log's time is the drone's (GLOBAL_POSITION_INT's `time_boot_ms`), not the station's
//! receive time (the recording's log time): a simulated drone flying faster than real time
//! (`stx serve --sim --sim-speed 10`) packs ten seconds of flight into one second of the
//! station's clock, and a model flown on the receive times was hundreds of metres off the
//! recorded track. ATTITUDE and SERVO_OUTPUT_RAW are placed on that clock by their own stamps
//! too: at 10× a burst (and the backlog at the start) arrives within one millisecond, so the
//! receive times no longer tell which attitude goes with which position, and the model
//! started 45° off the recorded heading and kept it. VFR_HUD and WIND_COV (no stamp, or one
//! that may be the Unix epoch's) go by their receive time after the last position received.
//! The receive times stand in for the drone's clock where it has none (every `time_boot_ms`
//! the same, as some autopilots send) or where it restarts. `stx compare` on 20 s of the
//! rehearsal at 10×: north and east RMS 349 m and 391 m before, 32.5 m and 16.4 m after;
//! its first 73 s compare as the same flight recorded in real time (11.6/12.1 m against
//! 12.1/12.1 m; with only the positions on the drone's clock the real-time one gave
//! 17.9/31.7 m, its positions taking the previous period's attitude).
//!
//! A mission recording holds the whole flight: the balloon's ascent, the round chute, the
//! canopy's inflation, the parafoil flight and the ground after it. The model flies only the
//! parafoil, so when the drone's HEARTBEAT says it reached the parafoil stage the log is that
//! stage alone (from the first position received in it to the last before the next stage),
//! its times and frame starting there, and it says which part it is ([`RecordedPart`]).
//! Compared whole, a 20-minute `mission-short` recording came out 1.6 km north and 3.2 km
//! east RMS off (the model dropped from the launch pad); a recording that never shows the
//! parafoil stage (one begun under the canopy's inflation, or a drone that sends no stage) is
//! taken whole.
//!
//! Pure: the caller reads the MCAP file (stx-record's `Recording`) and hands over the
//! messages. The local frame's origin is the first position, horizontally, and mean sea level.

use serde::de::DeserializeOwned;
use stx_gnc::geo::LocalFrame;
use stx_gnc::mission::FlightStage;

use super::telemetry::{Actuators, Attitude, GlobalPosition, Hud, VehicleStatus, Wind};
use super::{FlightLog, FlightLogError, LogSample, RecordedPart};

/// The topics read (the station's recording layout).
pub const POSITION: &str = "/telemetry/GLOBAL_POSITION_INT";
/// Attitude.
pub const ATTITUDE: &str = "/telemetry/ATTITUDE";
/// Airspeed.
pub const HUD: &str = "/telemetry/VFR_HUD";
/// Servo commands.
pub const ACTUATORS: &str = "/telemetry/SERVO_OUTPUT_RAW";
/// Wind estimate.
pub const WIND: &str = "/telemetry/WIND_COV";
/// The drone's mode and flight stage.
pub const HEARTBEAT: &str = "/telemetry/HEARTBEAT";

/// Collects the telemetry a log is made of, message by message.
#[derive(Default)]
pub struct LogBuilder {
    positions: Vec<(f64, GlobalPosition)>,
    attitudes: Vec<(f64, Attitude)>,
    airspeeds: Vec<(f64, f64)>,
    commands: Vec<(f64, Actuators)>,
    winds: Vec<(f64, [f64; 3])>,
    stages: Vec<(f64, FlightStage)>,
}

impl LogBuilder {
    /// Takes one recorded message (`log_time_ns`: ns since the Unix epoch; `data`: JSON).
    /// Topics it does not use are ignored.
    pub fn add(
        &mut self,
        topic: &str,
        log_time_ns: u64,
        data: &[u8],
    ) -> Result<(), FlightLogError> {
        let t = log_time_ns as f64 * 1e-9;
        fn parse<T: DeserializeOwned>(
            topic: &str,
            t: f64,
            data: &[u8],
        ) -> Result<T, FlightLogError> {
            serde_json::from_slice(data).map_err(|e| FlightLogError::BadMessage {
                topic: topic.to_owned(),
                time_s: t,
                message: e.to_string(),
            })
        }
        match topic {
            POSITION => {
                // An autopilot sends 0°, 0° before its estimator has an origin: no position,
                // and as the log's first it would put the frame's origin in the Gulf of Guinea.
                let p: GlobalPosition = parse(topic, t, data)?;
                if p.has_position() {
                    self.positions.push((t, p));
                }
            }
            ATTITUDE => self.attitudes.push((t, parse(topic, t, data)?)),
            HUD => self
                .airspeeds
                .push((t, parse::<Hud>(topic, t, data)?.airspeed_mps)),
            ACTUATORS => self.commands.push((t, parse(topic, t, data)?)),
            HEARTBEAT => self
                .stages
                .push((t, parse::<VehicleStatus>(topic, t, data)?.stage)),
            WIND => {
                let w: Wind = parse(topic, t, data)?;
                if let (Some(n), Some(e)) = (w.wind_north_mps, w.wind_east_mps) {
                    self.winds.push((t, [n, e, w.wind_down_mps.unwrap_or(0.0)]));
                }
            }
            _ => {}
        }
        Ok(())
    }

    /// The log: one sample per position message. Times start at the first position.
    pub fn finish(mut self) -> Result<FlightLog, FlightLogError> {
        for (name, empty) in [
            ("GLOBAL_POSITION_INT", self.positions.is_empty()),
            ("ATTITUDE", self.attitudes.is_empty()),
            ("SERVO_OUTPUT_RAW", self.commands.is_empty()),
        ] {
            if empty {
                return Err(FlightLogError::MissingTelemetry(name));
            }
        }
        let by_time = |a: &f64, b: &f64| a.total_cmp(b);
        // Stable: messages received in the same millisecond (a burst, or a backlog at 10×)
        // keep the order they arrived in.
        self.positions.sort_by(|a, b| by_time(&a.0, &b.0));
        let (times, clock) = drone_times(&self.positions);
        let anchors: Vec<Anchor> = self
            .positions
            .iter()
            .zip(times)
            .filter_map(|((received_s, p), mission_s)| {
                Some(Anchor {
                    received_s: *received_s,
                    boot_ms: f64::from(p.time_boot_ms),
                    mission_s: mission_s?,
                    position: *p,
                })
            })
            .collect();
        let on_mission_time =
            |r: f64, stamp_ms: Option<f64>| mission_time(&anchors, r, stamp_ms.filter(|_| clock));
        let mut attitudes: Vec<(f64, Attitude)> = self
            .attitudes
            .iter()
            .map(|(r, a)| (on_mission_time(*r, Some(f64::from(a.time_boot_ms))), *a))
            .collect();
        let mut commands: Vec<(f64, Actuators)> = self
            .commands
            .iter()
            .map(|(r, c)| (on_mission_time(*r, Some(f64::from(c.time_usec) * 1e-3)), *c))
            .collect();
        // VFR_HUD has no time; WIND_COV's may be the Unix epoch's.
        let mut airspeeds: Vec<(f64, f64)> = self
            .airspeeds
            .iter()
            .map(|(r, v)| (on_mission_time(*r, None), *v))
            .collect();
        let mut winds: Vec<(f64, [f64; 3])> = self
            .winds
            .iter()
            .map(|(r, v)| (on_mission_time(*r, None), *v))
            .collect();
        attitudes.sort_by(|a, b| by_time(&a.0, &b.0));
        commands.sort_by(|a, b| by_time(&a.0, &b.0));
        airspeeds.sort_by(|a, b| by_time(&a.0, &b.0));
        winds.sort_by(|a, b| by_time(&a.0, &b.0));
        self.stages.sort_by(|a, b| by_time(&a.0, &b.0));
        let (kept, part) = parafoil_stage(&anchors, &self.stages);
        let start_s = kept[0].mission_s;
        let first = &kept[0].position;
        let frame = LocalFrame {
            lat_deg: first.lat_deg,
            lon_deg: first.lon_deg,
            alt_msl_m: 0.0,
        };
        let samples = kept
            .iter()
            .map(|anchor| {
                let (t, p) = (anchor.mission_s, &anchor.position);
                let t_log = t - start_s;
                let a = latest(&attitudes, t).copied().unwrap_or(attitudes[0].1);
                let c = latest(&commands, t).copied().unwrap_or(commands[0].1);
                let ned = frame.to_ned(p.lat_deg, p.lon_deg, p.alt_msl_m);
                LogSample {
                    time_s: t_log,
                    position_ned_m: [ned.x, ned.y, ned.z],
                    velocity_ned_mps: [p.v_north_mps, p.v_east_mps, p.v_down_mps],
                    euler_rad: [a.roll_rad, a.pitch_rad, a.yaw_rad],
                    airspeed_mps: latest(&airspeeds, t).copied(),
                    main_line: c.main_line,
                    brake_right: c.brake_right,
                    brake_left: c.brake_left,
                    wind_ned_mps: latest(&winds, t).copied().unwrap_or([0.0; 3]),
                }
            })
            .collect();
        let log = FlightLog::new(samples)?;
        Ok(match part {
            Some(part) => log.taken_from(part),
            None => log,
        })
    }
}

/// The positions of the parafoil stage (each in the stage the last HEARTBEAT received at or
/// before it announced) and which part of the recording they are; all of them, and no part,
/// when no position falls in that stage.
fn parafoil_stage<'a>(
    anchors: &'a [Anchor],
    stages: &[(f64, FlightStage)],
) -> (&'a [Anchor], Option<RecordedPart>) {
    let in_parafoil = |a: &Anchor| {
        let i = stages.partition_point(|(t, _)| *t <= a.received_s);
        i > 0 && stages[i - 1].1 == FlightStage::Parafoil
    };
    let Some(first) = anchors.iter().position(in_parafoil) else {
        return (anchors, None);
    };
    let end = first
        + anchors[first..]
            .iter()
            .take_while(|a| in_parafoil(a))
            .count();
    // Fewer than a log needs is no parafoil flight to compare: the whole, which says why.
    if end - first < super::MIN_SAMPLES {
        return (anchors, None);
    }
    let kept = &anchors[first..end];
    let part = RecordedPart {
        stage: FlightStage::Parafoil,
        from_s: kept[0].mission_s,
        to_s: kept[kept.len() - 1].mission_s,
        recorded_s: anchors[anchors.len() - 1].mission_s,
    };
    (kept, Some(part))
}

/// A position taken into the log: when it was received, its drone time, its log time.
struct Anchor {
    received_s: f64,
    boot_ms: f64,
    mission_s: f64,
    position: GlobalPosition,
}

/// A drone clock going back by more than this restarted (a reboot), ms; less is a message
/// received late, out of order.
const CLOCK_RESTART_MS: u32 = 1000;

/// A message's own drone time further than this from the last position received before it
/// is not on the same clock (a wrapped or Unix-epoch stamp), ms.
const STAMP_REACH_MS: f64 = 5000.0;

/// Each position's time (in receive order) on the drone's clock, s from the first; `None`
/// for one not to be used: received twice (the same `time_boot_ms`, over two radios) or
/// late, behind one already taken. Where the drone's clock restarts, or when it never moves,
/// the receive times carry the log across. Also whether the drone's clock is used at all.
fn drone_times(positions: &[(f64, GlobalPosition)]) -> (Vec<Option<f64>>, bool) {
    let clock = positions
        .windows(2)
        .any(|w| w[0].1.time_boot_ms != w[1].1.time_boot_ms);
    let Some((first_received, first)) = positions.first() else {
        return (Vec::new(), clock);
    };
    let (mut mission_s, mut last_received, mut last_boot_ms) =
        (0.0, *first_received, first.time_boot_ms);
    let mut times = vec![Some(0.0)];
    for (received, p) in &positions[1..] {
        let boot_ms = p.time_boot_ms;
        let restarted = clock && last_boot_ms.saturating_sub(boot_ms) > CLOCK_RESTART_MS;
        let step_s = if (!clock || restarted) && *received > last_received {
            received - last_received
        } else if clock && !restarted && boot_ms > last_boot_ms {
            f64::from(boot_ms - last_boot_ms) * 1e-3
        } else {
            times.push(None);
            continue;
        };
        mission_s += step_s;
        (last_received, last_boot_ms) = (*received, boot_ms);
        times.push(Some(mission_s));
    }
    (times, clock)
}

/// The log time of a message received at `received_s` with its own drone time `stamp_ms`:
/// on the clock of the last position received before it (the first, if none was) — the
/// difference of the drone times, which a burst or a backlog received within one millisecond
/// keeps apart; without a usable stamp, the difference of the receive times.
fn mission_time(anchors: &[Anchor], received_s: f64, stamp_ms: Option<f64>) -> f64 {
    let i = anchors.partition_point(|a| a.received_s <= received_s);
    let a = &anchors[i.saturating_sub(1)];
    match stamp_ms {
        Some(b) if (b - a.boot_ms).abs() <= STAMP_REACH_MS => a.mission_s + (b - a.boot_ms) * 1e-3,
        _ => a.mission_s + (received_s - a.received_s),
    }
}

/// The value of the last entry at or before `t` (or the first, if all are later).
fn latest<T>(series: &[(f64, T)], t: f64) -> Option<&T> {
    let i = series.partition_point(|(ts, _)| *ts <= t);
    series.get(i.saturating_sub(1)).map(|(_, v)| v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn telemetry_becomes_a_log_held_at_the_positions_times() {
        let mut b = LogBuilder::default();
        let ns = |s: f64| (s * 1e9) as u64;
        for i in 0..4 {
            let t = 100.0 + f64::from(i);
            let pos = format!(
                r#"{{"time_boot_ms":0,"lat_deg":41.0,"lon_deg":-8.0,"alt_msl_m":{},"alt_rel_m":0,"v_north_mps":5,"v_east_mps":0,"v_down_mps":2.5,"heading_deg":null}}"#,
                1000.0 - 2.5 * f64::from(i)
            );
            b.add(POSITION, ns(t), pos.as_bytes()).unwrap();
            let att = r#"{"time_boot_ms":0,"roll_rad":0.1,"pitch_rad":0.0,"yaw_rad":1.0,"roll_rate_radps":0,"pitch_rate_radps":0,"yaw_rate_radps":0}"#;
            b.add(ATTITUDE, ns(t - 0.1), att.as_bytes()).unwrap();
            let act = format!(
                r#"{{"time_usec":0,"main_line":0.5,"brake_right":{},"brake_left":0}}"#,
                0.1 * f64::from(i)
            );
            b.add(ACTUATORS, ns(t - 0.05), act.as_bytes()).unwrap();
        }
        b.add("/station/state", 0, b"not json").unwrap();
        let log = b.finish().unwrap();
        let s = log.samples();
        assert_eq!(s.len(), 4);
        assert_eq!(s[0].time_s, 0.0);
        assert!((s[3].position_ned_m[2] + 992.5).abs() < 1e-9);
        assert!((s[2].brake_right - 0.2).abs() < 1e-12);
        assert_eq!(s[1].euler_rad, [0.1, 0.0, 1.0]);

        // No drone clock (every time_boot_ms 0): the receive times.
        assert_eq!(
            s.iter().map(|x| x.time_s).collect::<Vec<_>>(),
            [0.0, 1.0, 2.0, 3.0]
        );

        let mut bad = LogBuilder::default();
        assert!(matches!(
            bad.add(POSITION, 0, b"{}"),
            Err(FlightLogError::BadMessage { .. })
        ));
        assert_eq!(
            LogBuilder::default().finish(),
            Err(FlightLogError::MissingTelemetry("GLOBAL_POSITION_INT"))
        );
    }

    /// Regression: GLOBAL_POSITION_INT at 0°, 0° (an autopilot's before its estimator has an
    /// origin) was the log's first position, its frame's origin, 4,000 km from the flight.
    #[test]
    fn positions_at_zero_zero_are_left_out() {
        let mut b = LogBuilder::default();
        with_attitude_and_commands(&mut b);
        let nowhere = r#"{"time_boot_ms":1000,"lat_deg":0,"lon_deg":0,"alt_msl_m":0,"alt_rel_m":0,"v_north_mps":0,"v_east_mps":0,"v_down_mps":0,"heading_deg":null}"#;
        b.add(POSITION, 1_000_000_000, nowhere.as_bytes()).unwrap();
        for i in 0..3u32 {
            let msg = position(2000 + 250 * i, 2.5 * f64::from(i));
            b.add(
                POSITION,
                2_000_000_000 + u64::from(i) * 250_000_000,
                msg.as_bytes(),
            )
            .unwrap();
        }
        let log = b.finish().unwrap();
        let s = log.samples();
        assert_eq!(s.len(), 3);
        assert!(
            s[0].position_ned_m[0].abs() < 1e-6,
            "{:?}",
            s[0].position_ned_m
        );
        assert!(
            (s[2].position_ned_m[0] - 5.0).abs() < 0.1,
            "{:?}",
            s[2].position_ned_m
        );
    }

    /// A position (at `north_m` north of the first) stamped `boot_ms` by the drone.
    fn position(boot_ms: u32, north_m: f64) -> String {
        let lat = 41.0 + north_m / 111_000.0;
        format!(
            r#"{{"time_boot_ms":{boot_ms},"lat_deg":{lat},"lon_deg":-8.0,"alt_msl_m":900,"alt_rel_m":0,"v_north_mps":10,"v_east_mps":0,"v_down_mps":2.5,"heading_deg":null}}"#
        )
    }

    fn with_attitude_and_commands(b: &mut LogBuilder) {
        let att = r#"{"time_boot_ms":0,"roll_rad":0,"pitch_rad":0,"yaw_rad":0,"roll_rate_radps":0,"pitch_rate_radps":0,"yaw_rate_radps":0}"#;
        let act = r#"{"time_usec":0,"main_line":0,"brake_right":0,"brake_left":0}"#;
        b.add(ATTITUDE, 0, att.as_bytes()).unwrap();
        b.add(ACTUATORS, 0, act.as_bytes()).unwrap();
    }

    /// Regression: a recording of the simulated drone at 10× (`stx serve --sim --sim-speed
    /// 10`) was timed by the station's receive clock, a tenth of the drone's, and `stx
    /// compare` found the model hundreds of metres off the track; and with a burst received
    /// within one millisecond, a position took another period's attitude (45° off at the
    /// start, which the model then kept).
    #[test]
    fn an_accelerated_drone_s_log_runs_on_the_drone_s_clock() {
        let mut b = LogBuilder::default();
        let act = r#"{"time_usec":0,"main_line":0,"brake_right":0,"brake_left":0}"#;
        b.add(ACTUATORS, 0, act.as_bytes()).unwrap();
        // 10 m/s for 4 s of the drone's time, received within 0.4 s, four periods at a time
        // in the same millisecond, each attitude (its yaw in rad its stamp in s) after its
        // position.
        for i in 0..=16u32 {
            let received_ns = 1_000_000_000 + u64::from(i / 4) * 100_000_000;
            let boot_ms = 5_000 + 250 * i;
            let msg = position(boot_ms, 2.5 * f64::from(i));
            b.add(POSITION, received_ns, msg.as_bytes()).unwrap();
            let att = format!(
                r#"{{"time_boot_ms":{boot_ms},"roll_rad":0,"pitch_rad":0,"yaw_rad":{},"roll_rate_radps":0,"pitch_rate_radps":0,"yaw_rate_radps":0}}"#,
                f64::from(boot_ms) * 1e-3
            );
            b.add(ATTITUDE, received_ns, att.as_bytes()).unwrap();
        }
        let log = b.finish().unwrap();
        let s = log.samples();
        assert_eq!(s.len(), 17);
        assert!((s[16].time_s - 4.0).abs() < 1e-9, "{}", s[16].time_s);
        // The track's speed matches the drone's velocity, as a model flown on it will.
        let speed = s[16].position_ned_m[0] / s[16].time_s;
        assert!((speed - 10.0).abs() < 0.05, "{speed} m/s");
        for x in s {
            assert!(
                (x.euler_rad[2] - (5.0 + x.time_s)).abs() < 1e-9,
                "at {} s the attitude of {} s",
                x.time_s,
                x.euler_rad[2] - 5.0
            );
        }
    }

    #[test]
    fn duplicates_and_late_positions_are_dropped_and_a_restart_carries_on() {
        let mut b = LogBuilder::default();
        with_attitude_and_commands(&mut b);
        let s_ns = |s: f64| (s * 1e9) as u64;
        for (received_s, boot_ms) in [
            (0.0, 10_000),
            (0.1, 11_000),
            (0.11, 11_000), // the same message over a second radio
            (0.2, 12_000),
            (0.21, 11_500), // late
            (0.3, 13_000),
            (5.3, 200), // the drone rebooted: 5 s of the station's clock between
            (5.4, 1_200),
        ] {
            let msg = position(boot_ms, 0.0);
            b.add(POSITION, s_ns(received_s), msg.as_bytes()).unwrap();
        }
        let log = b.finish().unwrap();
        let times: Vec<f64> = log.samples().iter().map(|x| x.time_s).collect();
        let want = [0.0, 1.0, 2.0, 3.0, 8.0, 9.0];
        assert_eq!(times.len(), want.len(), "{times:?}");
        for (t, w) in times.iter().zip(want) {
            assert!((t - w).abs() < 1e-6, "{times:?}");
        }
    }

    /// A mission recording is compared over its parafoil stage: the positions received
    /// while the last HEARTBEAT said `parafoil`, timed and placed from the first of them.
    #[test]
    fn a_mission_recording_gives_its_parafoil_stage() {
        let mut b = LogBuilder::default();
        with_attitude_and_commands(&mut b);
        let ns = |s: f64| (s * 1e9) as u64;
        let heartbeat = |stage: &str| {
            format!(
                r#"{{"mode":"spiral_landing","phase":"idle","stage":"{stage}","state":"active"}}"#
            )
        };
        // One position a second, 10 m north each: ascent to 4 s, deployment from 4 s,
        // parafoil from 6 s, landed from 10 s.
        for (at_s, stage) in [
            (0.0, "ascent"),
            (3.9, "parafoil_deploy"),
            (5.9, "parafoil"),
            (9.9, "landed"),
        ] {
            b.add(HEARTBEAT, ns(at_s), heartbeat(stage).as_bytes())
                .unwrap();
        }
        for i in 0..13u32 {
            let msg = position(1_000 * i, 10.0 * f64::from(i));
            b.add(POSITION, ns(f64::from(i)), msg.as_bytes()).unwrap();
        }
        let log = b.finish().unwrap();
        let times: Vec<f64> = log.samples().iter().map(|x| x.time_s).collect();
        assert_eq!(times, [0.0, 1.0, 2.0, 3.0], "the positions of 6…9 s");
        assert!(
            log.samples()[0].position_ned_m[0].abs() < 1e-6,
            "the frame starts there"
        );
        assert!(
            (log.samples()[3].position_ned_m[0] - 30.0).abs() < 0.2,
            "111 km a degree in the helper"
        );
        assert_eq!(
            log.part(),
            Some(RecordedPart {
                stage: FlightStage::Parafoil,
                from_s: 6.0,
                to_s: 9.0,
                recorded_s: 12.0
            })
        );

        // Without the parafoil stage (begun under the inflating canopy): the whole.
        let mut b = LogBuilder::default();
        with_attitude_and_commands(&mut b);
        b.add(HEARTBEAT, 0, heartbeat("parafoil_deploy").as_bytes())
            .unwrap();
        for i in 0..5u32 {
            let msg = position(1_000 * i, 0.0);
            b.add(POSITION, ns(f64::from(i)), msg.as_bytes()).unwrap();
        }
        let log = b.finish().unwrap();
        assert_eq!((log.samples().len(), log.part()), (5, None));
        let mut bad = LogBuilder::default();
        assert!(matches!(
            bad.add(HEARTBEAT, 0, b"{\"stage\":\"orbit\"}"),
            Err(FlightLogError::BadMessage { .. })
        ));
    }
}
