//! The keep-out zones on the drone: the station sends the zones in force as MAVLink's fence
//! (mission type FENCE, one exclusion polygon per zone) so that the onboard guidance keeps
//! out of them when the link is lost, and MAVProxy or QGroundControl see them too.
//!
//! **When.** Whenever the zones change (read at start, an operator's edit) and whenever the
//! drone is heard again (it may have restarted and lost them), as soon as the link takes the
//! transfer. A station that was never given zones (no `keep_out` file, no edit) sends
//! nothing: it leaves alone a fence someone else gave the drone.
//!
//! **Until acknowledged.** A transfer the link is busy with, or that the drone refused or
//! stopped answering, is tried again after [`FENCE_RETRY_S`], at most [`FENCE_TRIES`] times
//! for one set of zones; then it waits for the next change or reconnection, with an error in
//! the log. The replica flies the zones the drone acknowledged (what the drone flies), not
//! those merely sent.
//!
//! A zone's holes do not travel: the fence has exclusion polygons only, so the drone keeps
//! out of a clearing in a wood too (the safe side).

use stx_gnc::keep_out::KeepOutZones;
use stx_link::plan::{FenceEvent, zones_to_fence};

use super::StationCore;
use super::actions::{APPLY_WITHIN_S, ActionError, LinkOp, Purpose};
use crate::keep_out::{FenceState, FenceView};
use crate::messages::Level;

/// Seconds before a fence transfer that failed is tried again, s.
pub const FENCE_RETRY_S: f64 = 3.0;
/// Most transfers of one set of zones before the station gives up until the next change.
pub const FENCE_TRIES: u32 = 5;

/// Where the drone's copy of the zones stands.
#[derive(Debug, Clone, Default)]
pub(crate) struct FenceSync {
    /// Counts the sets of zones put in force; 0: none ever (nothing to send).
    revision: u64,
    /// The revision the drone acknowledged.
    held: Option<u64>,
    /// The revision being transferred, and its zones (the replica takes them on the ack).
    sending: Option<(u64, KeepOutZones)>,
    /// Transfers of this revision so far.
    tries: u32,
    /// Not before this mission time, s.
    next_try_s: f64,
    /// The drone is heard.
    connected: bool,
    /// Why the last transfer failed.
    last_error: Option<String>,
}

impl FenceSync {
    fn state(&self) -> FenceState {
        if self.revision == 0 {
            FenceState::None
        } else if self.held == Some(self.revision) {
            FenceState::Held
        } else if self.sending.is_some() {
            FenceState::Sending
        } else if self.tries >= FENCE_TRIES {
            FenceState::Failed
        } else {
            FenceState::Waiting
        }
    }

    /// The `fence` part of the `keep_out` message.
    pub fn view(&self) -> FenceView {
        FenceView {
            state: self.state(),
            last_error: self.last_error.clone(),
        }
    }
}

impl StationCore {
    /// The zones in force changed: the drone is to have them.
    pub(crate) fn fence_changed(&mut self, now_s: f64) {
        let f = &mut self.fence;
        f.revision += 1;
        f.tries = 0;
        f.next_try_s = now_s;
        f.last_error = None;
    }

    /// The drone was heard again (`true`) or lost: after a reconnection it gets the zones
    /// again, as it may have restarted without them.
    pub(crate) fn fence_link(&mut self, now_s: f64, connected: bool) {
        let f = &mut self.fence;
        f.connected = connected;
        if connected {
            f.held = None;
            f.tries = 0;
            f.next_try_s = now_s;
        }
    }

    /// Offers the fence transfer to the link when one is due.
    pub(crate) fn fence_timeout(&mut self, now_s: f64) {
        let f = &self.fence;
        let due = f.revision > 0
            && f.connected
            && f.held != Some(f.revision)
            && f.sending.is_none()
            && f.tries < FENCE_TRIES
            && now_s >= f.next_try_s;
        if !due {
            return;
        }
        let zones = self.keep_out.zones.clone();
        let items = match zones_to_fence(&zones, &self.frame) {
            Ok(items) => items,
            Err(e) => {
                // Only a new set of zones can mend this: do not try again.
                self.fence.tries = FENCE_TRIES;
                self.fence_failed(now_s, format!("the zones cannot be sent as a fence: {e}"));
                return;
            }
        };
        let f = &mut self.fence;
        f.tries += 1;
        f.sending = Some((f.revision, zones));
        self.outbox.issue(
            now_s,
            LinkOp::FenceUpload(items),
            Purpose::FenceUpload,
            APPLY_WITHIN_S,
        );
    }

    /// What the link did with the transfer: taken, or not (busy with another, refused).
    pub(crate) fn fence_applied(&mut self, now_s: f64, result: Result<(), ActionError>) {
        if let Err(e) = result {
            self.fence.sending = None;
            self.fence.next_try_s = now_s + FENCE_RETRY_S;
            if !matches!(e, ActionError::Busy(_)) {
                self.fence_failed(now_s, format!("keep-out fence not sent: {e}"));
            }
        }
    }

    /// The drone's answer to a fence transfer.
    pub(crate) fn on_fence_event(&mut self, now_s: f64, event: FenceEvent) {
        match event {
            FenceEvent::UploadDone { items } => {
                let Some((revision, zones)) = self.fence.sending.take() else {
                    // Someone else's transfer (a tool through the station's link).
                    self.log(
                        now_s,
                        Level::Info,
                        "link",
                        format!("keep-out fence acknowledged ({items} vertices)"),
                    );
                    return;
                };
                let current = revision == self.fence.revision;
                self.fence.held = Some(revision);
                self.fence.last_error = None;
                let n = zones.zones.len();
                self.guidance.set_keep_out(zones);
                if current {
                    self.log(
                        now_s,
                        Level::Info,
                        "keep_out",
                        format!("the drone holds the keep-out zones ({n} areas, {items} vertices)"),
                    );
                    self.push_keep_out_msg(now_s);
                }
            }
            FenceEvent::UploadFailed { reason, .. } => {
                let reason = format!("keep-out fence upload failed: {reason}");
                if self.fence.sending.take().is_some() {
                    self.fence.next_try_s = now_s + FENCE_RETRY_S;
                    self.fence_failed(now_s, reason);
                } else {
                    self.log(now_s, Level::Warning, "link", reason);
                }
            }
            FenceEvent::DownloadDone { items } => self.log(
                now_s,
                Level::Info,
                "link",
                format!("keep-out fence held by the drone: {} vertices", items.len()),
            ),
            FenceEvent::DownloadFailed { reason } => self.log(
                now_s,
                Level::Warning,
                "link",
                format!("keep-out fence download failed: {reason}"),
            ),
        }
    }

    fn fence_failed(&mut self, now_s: f64, reason: String) {
        let given_up = self.fence.tries >= FENCE_TRIES;
        let (level, text) = if given_up {
            (
                Level::Error,
                format!(
                    "{reason}; the drone does NOT have the keep-out zones (given up until they change or the drone reconnects)"
                ),
            )
        } else {
            (Level::Warning, format!("{reason}; trying again"))
        };
        self.fence.last_error = Some(reason);
        self.log(now_s, level, "keep_out", text);
        if given_up {
            self.push_keep_out_msg(now_s);
        }
    }

    fn push_keep_out_msg(&mut self, now_s: f64) {
        let msg = self.keep_out_msg(now_s);
        self.outbound.push(super::Outbound::KeepOut(msg));
    }
}

#[cfg(test)]
mod tests {
    use serde_json::json;
    use stx_link::endpoint::{GroundEvent, LinkEvent};

    use super::super::keep_out::tests::events;
    use super::super::tests::core;
    use super::super::{ActionId, LinkAction};
    use super::*;

    /// A square zone `name` of 100 m side centred 300 m north of the origin, shifted `east_m`.
    fn pond(core: &StationCore, name: &str, east_m: f64) -> serde_json::Value {
        let corner = |dn: f64, de: f64| {
            let (lat, lon, _) =
                core.frame
                    .to_geodetic(&nalgebra::Vector3::new(300.0 + dn, east_m + de, 0.0));
            json!([lon, lat])
        };
        json!({"type": "FeatureCollection", "features": [{
            "type": "Feature", "properties": {"name": name},
            "geometry": {"type": "Polygon", "coordinates": [[
                corner(-50.0, -50.0), corner(-50.0, 50.0), corner(50.0, 50.0),
                corner(50.0, -50.0), corner(-50.0, -50.0)
            ]]}
        }]})
    }

    fn set_zones(core: &mut StationCore, now_s: f64, name: &str, east_m: f64) {
        let checked = core
            .check_keep_out(pond(core, name, east_m))
            .expect("zones");
        core.set_keep_out(now_s, "operator", checked, None);
    }

    fn link(core: &mut StationCore, now_s: f64, connected: bool) {
        let event = if connected {
            LinkEvent::Connected {
                system_id: 1,
                component_id: 1,
            }
        } else {
            LinkEvent::Lost {
                system_id: 1,
                since_last: std::time::Duration::from_secs(5),
            }
        };
        core.on_link_event(now_s, GroundEvent::Link(event));
    }

    /// The fence transfers due at `now_s` (other actions are reported applied).
    fn fences(core: &mut StationCore, now_s: f64) -> Vec<(ActionId, usize)> {
        let mut out = Vec::new();
        for LinkAction { id, op, .. } in core.take_link_actions(now_s) {
            match op {
                LinkOp::FenceUpload(items) => out.push((id, items.len())),
                _ => core.on_action_outcome(now_s, id, Ok(())),
            }
        }
        out
    }

    fn ack(core: &mut StationCore, now_s: f64, id: ActionId, items: usize) {
        core.on_action_outcome(now_s, id, Ok(()));
        core.on_link_event(now_s, GroundEvent::Fence(FenceEvent::UploadDone { items }));
    }

    fn fence_state(core: &mut StationCore) -> FenceState {
        core.keep_out_msg(0.0).fence.state
    }

    #[test]
    fn a_station_given_no_zones_leaves_the_drones_fence_alone() {
        let mut core = core();
        link(&mut core, 0.0, true);
        assert!(fences(&mut core, 0.0).is_empty());
        assert!(fences(&mut core, 60.0).is_empty());
        assert_eq!(fence_state(&mut core), FenceState::None);
    }

    #[test]
    fn zones_go_to_the_drone_when_it_is_heard_and_the_replica_flies_them_once_acknowledged() {
        let mut core = core();
        set_zones(&mut core, 0.0, "Pond", 0.0);
        assert!(fences(&mut core, 0.5).is_empty(), "nobody to send them to");
        assert_eq!(fence_state(&mut core), FenceState::Waiting);
        link(&mut core, 1.0, true);
        let sent = fences(&mut core, 1.0);
        assert_eq!(sent.len(), 1);
        // One closed square: its four corners (the fence repeats no vertex).
        assert_eq!(sent[0].1, 4);
        assert_eq!(fence_state(&mut core), FenceState::Sending);
        assert!(
            core.guidance.keep_out().zones.is_empty(),
            "not before the ack"
        );
        core.drain_outbound();
        ack(&mut core, 1.5, sent[0].0, 4);
        assert_eq!(fence_state(&mut core), FenceState::Held);
        assert_eq!(core.guidance.keep_out().zones.len(), 1);
        let texts = events(&mut core);
        assert!(
            texts.iter().any(|(_, t)| t.contains("drone holds")),
            "{texts:?}"
        );
        assert!(
            fences(&mut core, 30.0).is_empty(),
            "held: nothing more to send"
        );
        // The drone heard again (perhaps restarted): it gets them again.
        link(&mut core, 40.0, false);
        link(&mut core, 45.0, true);
        assert_eq!(fences(&mut core, 45.0).len(), 1);
    }

    #[test]
    fn zones_changed_during_a_transfer_are_sent_after_it() {
        let mut core = core();
        link(&mut core, 0.0, true);
        set_zones(&mut core, 0.0, "Pond", 0.0);
        let first = fences(&mut core, 0.0);
        assert_eq!(first.len(), 1);
        set_zones(&mut core, 0.2, "Moved pond", 500.0);
        assert!(fences(&mut core, 0.3).is_empty(), "one transfer at a time");
        ack(&mut core, 0.5, first[0].0, 4);
        assert_ne!(
            fence_state(&mut core),
            FenceState::Held,
            "the drone has the old ones"
        );
        let second = fences(&mut core, 0.6);
        assert_eq!(second.len(), 1);
        ack(&mut core, 0.8, second[0].0, 4);
        assert_eq!(fence_state(&mut core), FenceState::Held);
        let replica = &core.guidance.keep_out().zones;
        assert!(
            replica[0].rings_ne_m[0].iter().all(|p| p[1] > 400.0),
            "the new pond"
        );
    }

    #[test]
    fn failed_transfers_are_tried_again_then_given_up_with_an_error_until_the_zones_change() {
        let mut core = core();
        link(&mut core, 0.0, true);
        set_zones(&mut core, 0.0, "Pond", 0.0);
        let mut t = 0.0;
        // Busy once (the link's own transfer of another fence): not counted as a failure.
        let busy = fences(&mut core, t);
        core.on_action_outcome(t, busy[0].0, Err(ActionError::Busy("busy".into())));
        assert!(
            fences(&mut core, t + 0.1).is_empty(),
            "waits before trying again"
        );
        t += FENCE_RETRY_S;
        for k in 1..FENCE_TRIES {
            let sent = fences(&mut core, t);
            assert_eq!(sent.len(), 1, "try {k}");
            core.on_action_outcome(t, sent[0].0, Ok(()));
            core.on_link_event(
                t + 1.0,
                GroundEvent::Fence(FenceEvent::UploadFailed {
                    result: None,
                    reason: "no answer".into(),
                }),
            );
            t += 1.0 + FENCE_RETRY_S;
        }
        // Busy counted as a try: FENCE_TRIES transfers in all, the busy one included.
        assert_eq!(fence_state(&mut core), FenceState::Failed);
        let texts = events(&mut core);
        let errors: Vec<_> = texts.iter().filter(|(l, _)| *l == Level::Error).collect();
        assert_eq!(errors.len(), 1, "{texts:?}");
        assert!(errors[0].1.contains("does NOT have"), "{errors:?}");
        assert!(fences(&mut core, t + 100.0).is_empty(), "given up");
        set_zones(&mut core, t + 200.0, "Pond", 10.0);
        assert_eq!(
            fences(&mut core, t + 200.0).len(),
            1,
            "new zones, new tries"
        );
    }
}
