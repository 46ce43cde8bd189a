//! What the pages get, from the station loop and a replay's feeder alike: the newest
//! `state` (latest wins), and on the reliable channel the core's events, command results,
//! parameter tables and the like (recorded as they go out).

use std::sync::atomic::Ordering;

use crate::core::Outbound;
use crate::http::Shared;

/// Sends the `state` message `text` to the pages.
pub(super) fn show_state(shared: &Shared, text: String) {
    // Latest wins: a page that is behind gets the newest state, never a queue of old ones.
    shared.states.send_modify(|frame| {
        frame.seq += 1;
        frame.text = text.into();
    });
}

/// Puts the message `text` on every page's reliable channel.
pub(super) fn broadcast(shared: &Shared, text: String) {
    shared.broadcast_total.fetch_add(1, Ordering::Relaxed);
    // No page connected is not an error.
    let _ = shared.broadcast.send(text.into());
}

/// Sends what the core queued for the pages (and records it).
pub(super) fn send_outbound(shared: &Shared, outbound: Vec<Outbound>) {
    shared.recording.outbound(&outbound);
    for o in outbound {
        let text = match o {
            Outbound::Event(e) => serde_json::to_string(&e),
            Outbound::CommandResult(r) => serde_json::to_string(&r),
            Outbound::Params(p) => serde_json::to_string(&p),
            Outbound::AscentWind(a) => serde_json::to_string(&a),
            Outbound::KeepOut(k) => serde_json::to_string(&k),
            // Recorded only: pages see the request's event.
            Outbound::Command(_) => continue,
        };
        if let Ok(text) = text {
            broadcast(shared, text);
        }
    }
}
