//! The replay's feeder: reads the recording from the replay's position (through the file's
//! chunk index, so a seek anywhere costs one index lookup, not a scan) and hands each message
//! to the sink when the clock says it is due. Runs on its own thread: reading a file blocks.

use std::io::{Read, Seek};
use std::time::Duration;

use stx_record::{Direction, MavlinkFrame, ReadError, Recording};

use super::{ReplayControl, ReplayMode};
use crate::recording::{EVENTS, FRAMES, STATE};

/// Where a replay's messages go.
pub trait ReplaySink {
    /// Bytes the station received on radio `radio` (re-run).
    fn link_bytes(&mut self, radio: u16, bytes: &[u8]);
    /// A recorded `state` message, JSON (as recorded).
    fn state(&mut self, json: &[u8]);
    /// A recorded event, JSON (as recorded).
    fn event(&mut self, json: &[u8]);
    /// The replay jumped: what was shown before no longer holds.
    fn reset(&mut self);
    /// The replay is over (the station stopped).
    fn stopped(&self) -> bool;
}

/// The longest the feeder sleeps before looking at the clock again.
const MAX_WAIT: Duration = Duration::from_millis(200);

/// Plays `recording` into `sink` as `control`'s clock says, until the sink stops.
pub fn feed<R: Read + Seek>(
    recording: &mut Recording<R>,
    control: &ReplayControl,
    sink: &mut dyn ReplaySink,
) -> Result<(), ReadError> {
    let mode = control.mode();
    let mut epoch = control.clock().epoch();
    'replay: while !sink.stopped() {
        let from = control.clock().anchor_position();
        let mut messages = recording.messages_from(from)?;
        for message in messages.by_ref() {
            let message = message?;
            let wanted = match mode {
                ReplayMode::Rerun => &*message.topic == FRAMES,
                ReplayMode::Recorded => &*message.topic == STATE || &*message.topic == EVENTS,
            };
            if !wanted {
                continue;
            }
            // Wait until it is due; a seek starts the reading again from the new place.
            loop {
                if sink.stopped() {
                    return Ok(());
                }
                let (due, seeked) = {
                    let c = control.clock();
                    (c.due_at(message.log_time), c.epoch() != epoch)
                };
                if seeked {
                    epoch = control.clock().epoch();
                    sink.reset();
                    continue 'replay;
                }
                let now = control.now();
                match due {
                    Some(t) if t <= now => break,
                    Some(t) => control.wait((t - now).min(MAX_WAIT)),
                    None => control.wait(MAX_WAIT),
                }
            }
            deliver(&message.topic, &message.data, sink);
        }
        // At the end: wait for a seek back (or the stop).
        drop(messages);
        loop {
            if sink.stopped() {
                return Ok(());
            }
            if control.clock().epoch() != epoch {
                epoch = control.clock().epoch();
                sink.reset();
                continue 'replay;
            }
            control.wait(MAX_WAIT);
        }
    }
    Ok(())
}

fn deliver(topic: &str, data: &[u8], sink: &mut dyn ReplaySink) {
    if topic == FRAMES {
        // A frame entry we cannot read is skipped: the replay goes on with the rest.
        if let Ok(frame) = serde_json::from_slice::<MavlinkFrame>(data)
            && frame.direction == Direction::Rx
        {
            sink.link_bytes(frame.radio, &frame.data);
        }
    } else if topic == STATE {
        sink.state(data);
    } else if topic == EVENTS {
        sink.event(data);
    }
}

#[cfg(test)]
mod tests;
