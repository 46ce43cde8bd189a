//! The replay's feeder: reads the recording and hands each message to the sink when the
//! clock says it is due. Runs on its own thread: reading a file blocks.
//!
//! At the start and after every seek it reads from the recording's beginning: everything up
//! to the position goes to the sink at once, unpaced ([`ReplaySink::restart`] …
//! [`ReplaySink::caught_up`]), so the sink rebuilds what the station showed at that moment
//! — the track and plots up to it, the state of it — instead of starting empty there; then
//! the clock, released, paces the rest. Besides the messages, the sink may ask to act at
//! times of its own ([`ReplaySink::deadline`]: a telemetry burst to answer, its timers),
//! which are taken in log-time order with the messages.

use std::io::{Read, Seek};
use std::time::Duration;

use stx_record::{Direction, MavlinkFrame, ReadError, RecordedMessage, Recording};

use super::{ReplayControl, ReplayMode};
use crate::recording::{EVENTS, FRAMES, STATE};

/// Where a replay's messages go; times are the recording's log times, ns.
pub trait ReplaySink {
    /// The replay starts again to show `target_ns` (the recording's start, or where a seek
    /// put it): what the sink held no longer holds. What comes until
    /// [`ReplaySink::caught_up`] comes unpaced and builds the state at `target_ns`.
    fn restart(&mut self, epoch: u64, target_ns: u64);
    /// Everything up to `target_ns` has come: what was built replaces what was shown. The
    /// sink calls `release` once the new state is in place (the clock then moves on from the
    /// target unless paused, and says the pages are shown this epoch).
    fn caught_up(&mut self, target_ns: u64, release: &mut dyn FnMut());
    /// Bytes the station received on radio `radio` (re-run).
    fn link_bytes(&mut self, t_ns: u64, radio: u16, bytes: &[u8]);
    /// A recorded `state` message, JSON (as recorded).
    fn state(&mut self, t_ns: u64, json: &[u8]);
    /// A recorded event, JSON (as recorded).
    fn event(&mut self, t_ns: u64, json: &[u8]);
    /// The next time the sink has something to do without a message, if any.
    fn deadline(&self) -> Option<u64>;
    /// That time has come.
    fn at(&mut self, t_ns: u64);
    /// The replay is over (the station stopped).
    fn stopped(&self) -> bool;
}

/// The longest the feeder sleeps before looking at the clock again.
const MAX_WAIT: Duration = Duration::from_millis(200);

/// What happened while waiting for something to be due.
enum Wait {
    Due,
    Seeked,
    Stopped,
}

/// One pass over the recording, for one seek: its epoch and target, and whether the sink
/// has caught up with the target.
struct Pass {
    epoch: u64,
    target_ns: u64,
    caught_up: bool,
}

impl Pass {
    /// Waits until `t_ns` is due: at once up to the target (unpaced), then as the clock says.
    fn wait_for(&mut self, control: &ReplayControl, sink: &mut dyn ReplaySink, t_ns: u64) -> Wait {
        loop {
            if sink.stopped() {
                return Wait::Stopped;
            }
            let (due, epoch) = {
                let c = control.clock();
                (c.due_at(t_ns), c.epoch())
            };
            if epoch != self.epoch {
                return Wait::Seeked;
            }
            if !self.caught_up {
                if t_ns <= self.target_ns {
                    return Wait::Due;
                }
                self.catch_up(control, sink);
                continue;
            }
            let now = control.now();
            match due {
                Some(t) if t <= now => return Wait::Due,
                Some(t) => control.wait((t - now).min(MAX_WAIT)),
                None => control.wait(MAX_WAIT),
            }
        }
    }

    fn catch_up(&mut self, control: &ReplayControl, sink: &mut dyn ReplaySink) {
        let epoch = self.epoch;
        sink.caught_up(self.target_ns, &mut || {
            control.release(epoch);
        });
        // A sink that did not release does not hold the replay up.
        control.release(epoch);
        self.caught_up = true;
    }
}

/// Plays `recording` into `sink` as `control`'s clock says, until the sink stops.
pub fn feed<R: Read + Seek>(
    recording: &mut Recording<R>,
    control: &ReplayControl,
    sink: &mut dyn ReplaySink,
) -> Result<(), ReadError> {
    let mode = control.mode();
    let (start_ns, end_ns) = control.clock().range();
    'replay: while !sink.stopped() {
        let mut pass = {
            let c = control.clock();
            Pass {
                epoch: c.epoch(),
                target_ns: c.position(control.now()),
                caught_up: false,
            }
        };
        sink.restart(pass.epoch, pass.target_ns);
        let mut messages = recording.messages_from(start_ns)?;
        let mut next: Option<RecordedMessage> = None;
        loop {
            if next.is_none() {
                next = messages
                    .by_ref()
                    .find(|m| match m {
                        Ok(m) => wanted(mode, m),
                        Err(_) => true,
                    })
                    .transpose()?;
            }
            let at = next.as_ref().map(|m| m.log_time);
            // The sink's own time first when it comes before the message (or, at the end,
            // within the recording).
            let deadline = sink
                .deadline()
                .filter(|&d| at.map_or(d <= end_ns, |m| d < m));
            let Some(t_ns) = deadline.or(at) else { break };
            match pass.wait_for(control, sink, t_ns) {
                Wait::Due => {}
                Wait::Seeked => continue 'replay,
                Wait::Stopped => return Ok(()),
            }
            match deadline {
                Some(d) => sink.at(d),
                None => {
                    if let Some(message) = next.take() {
                        deliver(&message, sink);
                    }
                }
            }
        }
        drop(messages);
        if !pass.caught_up {
            pass.catch_up(control, sink);
        }
        // At the end: wait for a seek back (or the stop).
        loop {
            if sink.stopped() {
                return Ok(());
            }
            if control.clock().epoch() != pass.epoch {
                continue 'replay;
            }
            control.wait(MAX_WAIT);
        }
    }
    Ok(())
}

/// The topics a replay in `mode` plays.
fn wanted(mode: ReplayMode, message: &RecordedMessage) -> bool {
    match mode {
        ReplayMode::Rerun => &*message.topic == FRAMES,
        ReplayMode::Recorded => &*message.topic == STATE || &*message.topic == EVENTS,
    }
}

fn deliver(message: &RecordedMessage, sink: &mut dyn ReplaySink) {
    let (t, data) = (message.log_time, &message.data);
    match &*message.topic {
        FRAMES => {
            // A frame entry we cannot read is skipped: the replay goes on with the rest.
            if let Ok(frame) = serde_json::from_slice::<MavlinkFrame>(data)
                && frame.direction == Direction::Rx
            {
                sink.link_bytes(t, frame.radio, &frame.data);
            }
        }
        STATE => sink.state(t, data),
        EVENTS => sink.event(t, data),
        _ => {}
    }
}

#[cfg(test)]
mod tests;
