//! MAVLink telemetry logs (`.tlog`, as QGroundControl and MAVProxy write them) as stx
//! recordings: each frame on [`super::FRAMES`] as received (radio 0, at its logged time), and
//! what the station decodes of it on the telemetry channels ([`super::telemetry`]), so an
//! imported flight replays and exports as a recorded one does.
//!
//! A tlog is a sequence of records: the time (µs since the Unix epoch, 8 bytes big-endian)
//! and one whole MAVLink frame (v1 or v2, signed or not), whose length its header gives.

use std::time::Duration;

use stx_link::frame::{DecoderPolicy, FrameDecoder};
use stx_link::telemetry::Telemetry;
use stx_record::frame::mavlink_frame_channel;
use stx_record::{
    CoreOptions, Direction, MavlinkFrame, Output, RecorderCore, RecordingInfo, WriteError,
};
use thiserror::Error;

use super::FRAMES;
use super::telemetry::TelemetryChannels;

/// Why a tlog could not be imported.
#[derive(Debug, Error)]
pub enum TlogError {
    /// Not one whole record at the start: not a tlog.
    #[error("not a MAVLink telemetry log: {0}")]
    NotATlog(String),
    /// The recording could not be written.
    #[error("writing the recording: {0}")]
    Write(#[from] WriteError),
}

/// What an import found.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TlogReport {
    /// Frames recorded.
    pub frames: u64,
    /// Of those, decoded into telemetry the station knows.
    pub decoded: u64,
    /// Frames the decoder refused (bad CRC, unknown message).
    pub undecodable: u64,
    /// Where the log stopped making sense (a record cut short or not a frame), if before its
    /// end: the byte offset.
    pub stopped_at: Option<usize>,
}

/// The length of the MAVLink frame at the start of `bytes`, from its header.
fn frame_len(bytes: &[u8]) -> Option<usize> {
    match *bytes.first()? {
        0xFD => {
            let len = usize::from(*bytes.get(1)?);
            let signed = bytes.get(2)? & 0x01 != 0;
            Some(10 + len + 2 + if signed { 13 } else { 0 })
        }
        0xFE => Some(6 + usize::from(*bytes.get(1)?) + 2),
        _ => None,
    }
}

/// The recording (MCAP bytes) of the tlog `bytes`, described by `info`.
pub fn import_tlog(bytes: &[u8], info: RecordingInfo) -> Result<(Vec<u8>, TlogReport), TlogError> {
    let options = CoreOptions {
        max_file_bytes: None,
        max_file_duration: None,
        ..CoreOptions::default()
    };
    let mut core = RecorderCore::new(options, info, Duration::ZERO)?;
    let spec = mavlink_frame_channel(FRAMES).map_err(WriteError::from)?;
    let frames = core.add_channel(Duration::ZERO, spec)?;
    let telemetry = TelemetryChannels::register(&mut core, Duration::ZERO)?;
    let mut decoder = FrameDecoder::new(DecoderPolicy { accept_v1: true });
    let mut report = TlogReport::default();
    let mut out = Vec::new();
    let drain = |core: &mut RecorderCore, out: &mut Vec<u8>| {
        while let Some(o) = core.poll_output() {
            if let Output::Bytes { data, .. } = o {
                out.extend(data);
            }
        }
    };
    let mut at = 0;
    let mut first_ns = None;
    while at < bytes.len() {
        let record = bytes
            .get(at + 8..)
            .and_then(|rest| Some((rest, frame_len(rest)?)));
        let Some((rest, len)) = record.filter(|(rest, len)| rest.len() >= *len) else {
            if report.frames == 0 {
                return Err(TlogError::NotATlog(format!(
                    "no whole record (time + MAVLink frame) at byte {at}"
                )));
            }
            report.stopped_at = Some(at);
            break;
        };
        let mut time = [0u8; 8];
        time.copy_from_slice(&bytes[at..at + 8]);
        let log_ns = u64::from_be_bytes(time).saturating_mul(1000);
        let frame = &rest[..len];
        // The core's clock: time since the log's first record (chunks close by it).
        let now = Duration::from_nanos(log_ns.saturating_sub(*first_ns.get_or_insert(log_ns)));
        core.write(
            now,
            frames,
            log_ns,
            log_ns,
            &MavlinkFrame::encode(Direction::Rx, 0, log_ns, frame),
        )?;
        report.frames += 1;
        decoder.push(frame);
        while let Some(decoded) = decoder.poll(now) {
            match decoded {
                Ok(f) => {
                    if let Some(t) = Telemetry::from_mavlink(&f.message) {
                        report.decoded += 1;
                        for (ch, payload) in telemetry.records(log_ns, &t) {
                            core.write(now, ch, log_ns, log_ns, &payload)?;
                        }
                    }
                }
                Err(_) => report.undecodable += 1,
            }
        }
        drain(&mut core, &mut out);
        at += 8 + len;
    }
    core.finish()?;
    drain(&mut core, &mut out);
    Ok((out, report))
}

#[cfg(test)]
mod tests;
