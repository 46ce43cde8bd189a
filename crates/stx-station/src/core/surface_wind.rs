//! The surface wind on its way to the drone (see [`crate::surface_wind`] for where it comes
//! from): the anemometer's sentences averaged, the operator's value held, the one in force
//! uplinked as `SetSurfaceWind` every `uplink_every_s` while the drone is heard, and the
//! replica given what the drone accepted, so both plan the final with the same wind.
//!
//! **Which wind.** The vector mean of the anemometer's sentences of the last `average_s`
//! (before its newest), while it was heard within `stale_after_s`; else the operator's value
//! within `operator_valid_s` of being typed, sent as the wind now (the operator vouches for
//! it until it lapses). An anemometer that falls silent hands over to the operator's value,
//! and says so in the log.
//!
//! **Its age.** The command carries how long ago the wind was measured on the drone's clock
//! (the mission clock's run between then and now), so in a rehearsal at 20× an anemometer
//! mean 5 s old is 100 s old to the drone, as it truly is in its world.
//!
//! **Withdrawn.** The operator's value is sent as the wind now, again every period, so once it
//! is withdrawn or lapses the drone would fly on with it for guidance's two minutes: it is
//! sent once more as [`SURFACE_WIND_MAX_AGE_S`] old, which guidance ignores, and the station
//! and the replica hold no surface wind from then. An anemometer's mean carries its true time
//! of measurement, so when the anemometer falls silent the drone's copy lapses by itself.
//!
//! **Its own request ids.** The uplinks are the station's own initiative, not operators'
//! requests: they go out under ids from [`FIRST_ID`] upwards (operators' requests count from
//! 1), so their answers are told apart, and they make no `command_result` (one every few
//! seconds would bury the operators' own). A refusal or silence is logged when it starts, a
//! recovery when it ends.

use std::collections::VecDeque;

use stx_gnc::guidance::SurfaceWind;
use stx_link::command::{
    Command, CommandEvent, CommandOutcome, RequestId, SURFACE_WIND_MAX_AGE_S, SURFACE_WIND_MAX_MPS,
};
use stx_types::mwv::{MwvError, MwvReference, parse_mwv};

use super::StationCore;
use super::actions::{APPLY_WITHIN_S, ActionError, LinkOp, Purpose};
use super::requests::ApiError;
use crate::messages::Level;
use crate::surface_wind::{
    AnemometerView, DroneCopy, SurfaceWindReadingView, SurfaceWindSource, SurfaceWindView,
};

/// The first request id of the station's own surface-wind uplinks.
pub const FIRST_ID: u64 = 1 << 48;

/// Most sentences kept for the mean: ten a second over the longest averaging time.
const MAX_SAMPLES: usize = 6000;

/// One uplink, from its sending to the drone's answer.
#[derive(Debug, Clone, Copy)]
struct Sent {
    id: u64,
    /// When it was measured, station time, s.
    measured_s: f64,
    /// The air's velocity (north, east), m/s.
    ne_mps: [f64; 2],
    source: SurfaceWindSource,
    /// When it was measured, on the drone's clock, s; `None` before the drone's clock is known.
    measured_drone_s: Option<f64>,
    /// It withdraws the operator's value from the drone.
    withdraw: bool,
}

/// The surface wind's sources and the drone's copy.
#[derive(Debug, Default)]
pub(crate) struct SurfaceWindState {
    /// Anemometer sentences: (station time, air velocity north and east, m/s).
    samples: VecDeque<(f64, [f64; 2])>,
    sentences: u64,
    rejected: u64,
    last_error: Option<String>,
    /// The operator's value (air velocity north and east, m/s) and when it was typed.
    operator: Option<([f64; 2], f64)>,
    /// The source of the wind last in force, to say when it changes.
    source: Option<SurfaceWindSource>,
    sending: Option<Sent>,
    next_id: u64,
    next_send_s: f64,
    accepted_s: Option<f64>,
    /// What the drone accepted last: air velocity, source, when measured (station time).
    held: Option<([f64; 2], SurfaceWindSource, f64)>,
    failed: bool,
    send_error: Option<String>,
    connected: bool,
}

impl SurfaceWindState {
    /// Whether the answer under `id` is one of these uplinks'.
    pub fn owns(id: RequestId) -> bool {
        id.0 >= FIRST_ID
    }
}

/// The air's velocity (north, east) of a wind of `speed_mps` blowing from `from_deg`.
fn velocity(speed_mps: f64, from_deg: f64) -> [f64; 2] {
    let (north, east) = stx_types::wind::blowing_north_east_mps(speed_mps, from_deg);
    [north, east]
}

/// Speed, m/s, and where it blows from, degrees 0…360, of the air's velocity (north, east).
fn speed_from(ne: [f64; 2]) -> (f64, f64) {
    let (from_deg, speed_mps) = stx_types::wind::from_deg_and_speed(ne[0], ne[1]);
    (speed_mps, from_deg)
}

impl StationCore {
    /// One line from the ground anemometer, as the daemon's reader got it at `now_s`.
    pub fn on_anemometer_line(&mut self, now_s: f64, line: &str) {
        let reading = match parse_mwv(line) {
            Ok(r) => r,
            // Other sentences of the instrument (temperature, pressure) are not its wind.
            Err(MwvError::NotMwv) => return,
            Err(e) => {
                self.surface_wind.rejected += 1;
                let text = format!("anemometer line refused: {e}");
                if self.surface_wind.last_error.as_deref() != Some(text.as_str()) {
                    self.log(now_s, Level::Warning, "anemometer", text.clone());
                }
                self.surface_wind.last_error = Some(text);
                return;
            }
        };
        let from_deg = match reading.reference {
            MwvReference::True => reading.from_deg,
            MwvReference::Relative => reading.from_deg + self.config.surface_wind.zero_mark_deg,
        };
        let w = &mut self.surface_wind;
        w.sentences += 1;
        if w.sentences == 1 {
            let text = format!(
                "ground anemometer heard: {:.1} m/s from {:.0}°",
                reading.speed_mps,
                from_deg.rem_euclid(360.0)
            );
            self.log(now_s, Level::Info, "anemometer", text);
        }
        let w = &mut self.surface_wind;
        w.samples
            .push_back((now_s, velocity(reading.speed_mps, from_deg)));
        let keep_from = now_s - self.config.surface_wind.average_s;
        while w
            .samples
            .front()
            .is_some_and(|(t, _)| *t < keep_from || w.samples.len() > MAX_SAMPLES)
        {
            w.samples.pop_front();
        }
    }

    /// The anemometer's reader failed (a serial port unplugged, a socket refused): said in
    /// the log and shown; the reader tries again.
    pub fn on_anemometer_error(&mut self, now_s: f64, error: String) {
        if self.surface_wind.last_error.as_deref() != Some(error.as_str()) {
            self.log(now_s, Level::Warning, "anemometer", error.clone());
        }
        self.surface_wind.last_error = Some(error);
    }

    /// The operator's surface wind: `speed_mps` from `from_deg` (degrees true), sent at once.
    pub fn set_operator_surface_wind(
        &mut self,
        now_s: f64,
        who: &str,
        speed_mps: f64,
        from_deg: f64,
    ) -> Result<(), ApiError> {
        if !(speed_mps.is_finite() && (0.0..=SURFACE_WIND_MAX_MPS).contains(&speed_mps)) {
            return Err(ApiError::bad_request(format!(
                "speed_mps must be within 0…{SURFACE_WIND_MAX_MPS} m/s"
            )));
        }
        if !(from_deg.is_finite() && (-360.0..=360.0).contains(&from_deg)) {
            return Err(ApiError::bad_request("from_deg must be within ±360°"));
        }
        let from_deg = from_deg.rem_euclid(360.0);
        self.surface_wind.operator = Some((velocity(speed_mps, from_deg), now_s));
        self.surface_wind.next_send_s = now_s;
        self.log(
            now_s,
            Level::Info,
            "command",
            format!("{who} set the surface wind: {speed_mps:.1} m/s from {from_deg:.0}°"),
        );
        Ok(())
    }

    /// Withdraws the operator's surface wind.
    pub fn clear_operator_surface_wind(&mut self, now_s: f64, who: &str) {
        if self.surface_wind.operator.take().is_some() {
            self.surface_wind.next_send_s = now_s;
            self.log(
                now_s,
                Level::Info,
                "command",
                format!("{who} withdrew the surface wind they had set"),
            );
        }
    }

    /// The wind in force at `now_s`: air velocity (north, east), its source and when it was
    /// measured (station time).
    fn surface_wind_now(&self, now_s: f64) -> Option<([f64; 2], SurfaceWindSource, f64)> {
        let c = &self.config.surface_wind;
        let w = &self.surface_wind;
        if let Some(&(newest, _)) = w.samples.back()
            && now_s - newest <= c.stale_after_s
        {
            let used = w.samples.iter().filter(|(t, _)| newest - t <= c.average_s);
            let (mut sum, mut n) = ([0.0, 0.0], 0.0);
            for (_, v) in used {
                sum[0] += v[0];
                sum[1] += v[1];
                n += 1.0;
            }
            return Some((
                [sum[0] / n, sum[1] / n],
                SurfaceWindSource::Anemometer,
                newest,
            ));
        }
        let (ne, typed_s) = w.operator?;
        (now_s - typed_s <= c.operator_valid_s).then_some((ne, SurfaceWindSource::Operator, now_s))
    }

    /// The drone was heard again (`true`) or lost: after a reconnection it gets the wind at
    /// once, as it may have restarted without it.
    pub(crate) fn surface_wind_link(&mut self, now_s: f64, connected: bool) {
        let w = &mut self.surface_wind;
        w.connected = connected;
        if connected {
            w.next_send_s = now_s;
        }
    }

    /// Sends the wind in force when an uplink is due; says when the source changes or lapses.
    pub(crate) fn surface_wind_timeout(&mut self, now_s: f64) {
        let now = self.surface_wind_now(now_s);
        let source = now.map(|(_, s, _)| s);
        if source != self.surface_wind.source {
            let was = self.surface_wind.source;
            self.surface_wind.source = source;
            let text = match (was, source) {
                (_, Some(SurfaceWindSource::Anemometer)) => {
                    "surface wind from the ground anemometer"
                }
                (Some(SurfaceWindSource::Anemometer), Some(SurfaceWindSource::Operator)) => {
                    "ground anemometer silent: the operator's surface wind is used"
                }
                (_, Some(SurfaceWindSource::Operator)) => "surface wind from the operator",
                (Some(SurfaceWindSource::Anemometer), None) => {
                    "ground anemometer silent: no surface wind (the drone's lapses in 2 min)"
                }
                (_, None) => "no surface wind: the operator's is withdrawn or lapsed",
            };
            self.log(now_s, Level::Info, "anemometer", text.into());
        }
        let w = &self.surface_wind;
        if !w.connected || w.sending.is_some() || now_s < w.next_send_s {
            return;
        }
        let (ne, source, measured_s, withdraw) = match (now, w.held) {
            (Some((ne, source, measured_s)), _) => (ne, source, measured_s, false),
            (None, Some((ne, SurfaceWindSource::Operator, _))) => {
                (ne, SurfaceWindSource::Operator, now_s, true)
            }
            (None, _) => return,
        };
        // The age on the drone's clock, which runs at the mission clock's rate.
        let age_s = if withdraw {
            SURFACE_WIND_MAX_AGE_S
        } else {
            ((now_s - measured_s) * self.mission_clock.rate()).clamp(0.0, SURFACE_WIND_MAX_AGE_S)
        };
        let (speed_mps, from_deg) = speed_from(ne);
        let w = &mut self.surface_wind;
        w.next_id += 1;
        let id = FIRST_ID + w.next_id;
        w.next_send_s = now_s + self.config.surface_wind.uplink_every_s;
        w.sending = Some(Sent {
            id,
            measured_s,
            ne_mps: ne,
            source,
            measured_drone_s: self.mission_clock.at(now_s).map(|t| t - age_s),
            withdraw,
        });
        self.outbox.issue(
            now_s,
            LinkOp::Command {
                request_id: RequestId(id),
                command: Command::SetSurfaceWind {
                    speed_mps: speed_mps.min(SURFACE_WIND_MAX_MPS),
                    from_deg,
                    age_s,
                },
            },
            Purpose::SurfaceWind,
            APPLY_WITHIN_S,
        );
    }

    /// What the link did with an uplink: taken (its answer comes as a command event), or not.
    pub(crate) fn surface_wind_applied(&mut self, now_s: f64, result: Result<(), ActionError>) {
        if let Err(e) = result {
            self.surface_wind.sending = None;
            // Busy: the previous one is still being retried; the next period tries again.
            if !matches!(e, ActionError::Busy(_)) {
                self.surface_wind_failed(now_s, format!("surface wind not sent: {e}"));
            }
        }
    }

    /// The drone's answer to an uplink.
    pub(crate) fn on_surface_wind_answer(&mut self, now_s: f64, e: &CommandEvent) {
        let Some(sent) = self.surface_wind.sending.filter(|s| s.id == e.request_id.0) else {
            return;
        };
        match e.outcome {
            CommandOutcome::InProgress { .. } => return,
            CommandOutcome::Accepted => {
                let first = self.surface_wind.held.is_none();
                let recovered = std::mem::take(&mut self.surface_wind.failed);
                self.surface_wind.accepted_s = Some(now_s);
                self.surface_wind.held =
                    (!sent.withdraw).then_some((sent.ne_mps, sent.source, sent.measured_s));
                self.surface_wind.send_error = None;
                // The replica takes what the drone took, with the same time of measurement.
                if let Some(measured) = sent.measured_drone_s {
                    self.guidance.set_surface_wind(Some(SurfaceWind {
                        ne_mps: sent.ne_mps,
                        time_s: measured,
                    }));
                }
                if sent.withdraw {
                    let text = "the drone no longer uses the operator's surface wind";
                    self.log(now_s, Level::Info, "anemometer", text.into());
                } else if first || recovered {
                    let (speed, from) = speed_from(sent.ne_mps);
                    let source = match sent.source {
                        SurfaceWindSource::Anemometer => "anemometer",
                        SurfaceWindSource::Operator => "operator",
                    };
                    let text = format!(
                        "the drone holds the surface wind: {speed:.1} m/s from {from:.0}° ({source})"
                    );
                    self.log(now_s, Level::Info, "anemometer", text);
                }
            }
            CommandOutcome::Rejected { result } => {
                self.surface_wind_failed(
                    now_s,
                    format!("the drone refused the surface wind: {result:?}"),
                );
            }
            CommandOutcome::TimedOut { attempts } => self.surface_wind_failed(
                now_s,
                format!("surface wind not acknowledged after {attempts} attempts"),
            ),
        }
        self.surface_wind.sending = None;
    }

    fn surface_wind_failed(&mut self, now_s: f64, reason: String) {
        let w = &mut self.surface_wind;
        let first = !w.failed;
        w.failed = true;
        w.send_error = Some(reason.clone());
        if first {
            self.log(
                now_s,
                Level::Warning,
                "anemometer",
                format!("{reason} (tried again every period)"),
            );
        }
    }

    /// The `surface_wind` part of the `state` message.
    pub(crate) fn surface_wind_view(&self, now_s: f64) -> SurfaceWindView {
        let c = &self.config.surface_wind;
        let w = &self.surface_wind;
        let reading = |ne: [f64; 2], source, measured_s: f64| {
            let (speed_mps, from_deg) = speed_from(ne);
            SurfaceWindReadingView {
                speed_mps,
                from_deg,
                source,
                age_s: (now_s - measured_s).max(0.0),
            }
        };
        let wind = self
            .surface_wind_now(now_s)
            .map(|(ne, source, measured_s)| reading(ne, source, measured_s));
        let operator = w
            .operator
            .filter(|(_, typed_s)| now_s - typed_s <= c.operator_valid_s)
            .map(|(ne, typed_s)| reading(ne, SurfaceWindSource::Operator, typed_s));
        let drone = if w.sending.is_some() {
            DroneCopy::Sending
        } else if w.failed {
            DroneCopy::Failed
        } else if w.held.is_some() {
            DroneCopy::Held
        } else {
            DroneCopy::None
        };
        let anemometer = c.anemometer.as_ref().map(|address| {
            let newest = w.samples.back().map(|(t, _)| *t);
            AnemometerView {
                address: address.clone(),
                sentences: w.sentences,
                rejected: w.rejected,
                last_error: w.last_error.clone(),
                heard_age_s: newest.map(|t| (now_s - t).max(0.0)),
                in_mean: newest.map_or(0, |n| {
                    w.samples
                        .iter()
                        .filter(|(t, _)| n - t <= c.average_s)
                        .count()
                }),
            }
        });
        SurfaceWindView {
            wind,
            operator,
            drone,
            held: w
                .held
                .map(|(ne, source, measured_s)| reading(ne, source, measured_s)),
            drone_accepted_age_s: w.accepted_s.map(|t| (now_s - t).max(0.0)),
            last_error: w.send_error.clone(),
            anemometer,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn velocity_and_direction_are_each_others_inverse() {
        for from in [0.0, 45.0, 90.0, 200.0, 359.0] {
            let (s, f) = speed_from(velocity(3.0, from));
            assert!((s - 3.0).abs() < 1e-9);
            assert!((f - from).abs() < 1e-9, "{from} → {f}");
        }
        // A wind from the west blows the air east.
        let v = velocity(2.0, 270.0);
        assert!(v[0].abs() < 1e-9 && (v[1] - 2.0).abs() < 1e-9);
    }
}
