//! The replay's feeder thread on a running station: re-run frames go to the station's own
//! link socket over loopback (the bytes a radio would carry, so the whole station pipeline
//! runs), recorded states and events go straight to the pages, and a seek starts the core
//! afresh.

use std::net::{SocketAddr, UdpSocket};
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;

use stx_record::Recording;

use crate::http::Shared;
use crate::replay::feeder::{ReplaySink, feed};
use crate::replay::{ReplayControl, ReplayMode};

struct StationSink {
    socket: UdpSocket,
    shared: Arc<Shared>,
    control: Arc<ReplayControl>,
    stop: Arc<AtomicBool>,
}

impl ReplaySink for StationSink {
    fn link_bytes(&mut self, _radio: u16, bytes: &[u8]) {
        // Loopback UDP to our own link: a lost datagram is what a radio does too.
        let _ = self.socket.send(bytes);
    }

    fn state(&mut self, json: &[u8]) {
        let Ok(mut state) = serde_json::from_slice::<serde_json::Value>(json) else {
            return;
        };
        if let Some(map) = state.as_object_mut() {
            map.insert("recording".into(), serde_json::Value::Null);
            map.insert(
                "replay".into(),
                serde_json::to_value(self.control.view()).unwrap_or_default(),
            );
        }
        let text = state.to_string();
        self.shared.states.send_modify(|frame| {
            frame.seq += 1;
            frame.text = text.into();
        });
    }

    fn event(&mut self, json: &[u8]) {
        if let Ok(text) = std::str::from_utf8(json) {
            self.shared.broadcast_total.fetch_add(1, Ordering::Relaxed);
            let _ = self.shared.broadcast.send(text.to_owned().into());
        }
    }

    fn reset(&mut self) {
        if self.control.mode() == ReplayMode::Rerun {
            self.shared.reset_core();
        }
    }

    fn stopped(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

/// Starts feeding `recording` into the station of `shared` (its link at `link`) as
/// `control` says, until `stop` is set.
pub fn spawn_replay_feeder(
    recording: Recording<std::fs::File>,
    file: PathBuf,
    control: Arc<ReplayControl>,
    shared: Arc<Shared>,
    link: SocketAddr,
    stop: Arc<AtomicBool>,
) -> std::io::Result<JoinHandle<()>> {
    let socket = UdpSocket::bind(SocketAddr::from(([127, 0, 0, 1], 0)))?;
    socket.connect(link)?;
    let mut sink = StationSink {
        socket,
        shared,
        control: control.clone(),
        stop,
    };
    std::thread::Builder::new()
        .name("stx-replay".into())
        .spawn(move || {
            let mut recording = recording;
            if let Err(e) = feed(&mut recording, &control, &mut sink) {
                tracing::error!(file = %file.display(), error = %e, "the replay stopped: the recording could not be read further");
            }
        })
}
