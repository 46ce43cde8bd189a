//! The ground endpoint as the station's link driver runs it: [`StationLink`] applies the
//! core's [`LinkAction`]s to the endpoint, synchronously, and reports each one's outcome as a
//! [`LinkReport`] through the same queue as the endpoint's own events, so an outcome can be
//! delayed by backpressure but never dropped. Sans-io like the endpoint it wraps: the tokio
//! driver (`stx_link_tokio::drive_paths`) moves its bytes, and tests drive it by hand.

use std::collections::VecDeque;
use std::time::Duration;

use stx_link::endpoint::{GroundEndpoint, GroundEvent, LinkStats};
use stx_link::param::ParamRequestError;
use stx_link::plan::PlanRequestError;
use stx_link::sansio::SansIo;

use crate::core::{ActionError, ActionId, LinkAction, LinkOp};

/// What the station link reports, in the order it happened.
#[derive(Debug, Clone, PartialEq)]
pub enum LinkReport {
    /// An event of the ground endpoint.
    Event(GroundEvent),
    /// What became of a link action (for [`crate::core::StationCore::on_action_outcome`]).
    Outcome {
        id: ActionId,
        result: Result<(), ActionError>,
    },
    /// The link statistics, sampled on request ([`StationLink::sample_stats`]).
    Stats(LinkStats),
}

/// Sees every byte the link carries, as it passes: the station's recording of the raw
/// link. Called on the driver's thread, so it must not block (the recorder queues).
pub trait FrameTap: Send {
    /// `bytes` were received on radio `path` (`sent` false: one datagram or one read of a
    /// stream) or sent on it (`sent` true: one frame).
    fn frame(&mut self, path: usize, sent: bool, bytes: &[u8]);
}

/// Takes each frame the link accepted, as received, for the read-only forwards
/// (`crate::forward`). Called on the driver's thread, so it must not block: a forward that
/// falls behind loses frames, the link never waits for it.
pub trait ForwardSink: Send {
    /// `frame` was accepted: checked, its signature verified when signing is on, not a copy.
    fn accepted(&mut self, frame: Vec<u8>);
}

/// The ground endpoint with the reports of what was done to it.
pub struct StationLink {
    endpoint: GroundEndpoint,
    reports: VecDeque<LinkReport>,
    tap: Option<Box<dyn FrameTap>>,
    forward: Option<Box<dyn ForwardSink>>,
}

impl std::fmt::Debug for StationLink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StationLink")
            .field("endpoint", &self.endpoint)
            .field("reports", &self.reports)
            .field("tap", &self.tap.is_some())
            .field("forward", &self.forward.is_some())
            .finish()
    }
}

impl StationLink {
    /// Wraps `endpoint`.
    pub fn new(endpoint: GroundEndpoint) -> Self {
        Self {
            endpoint,
            reports: VecDeque::new(),
            tap: None,
            forward: None,
        }
    }

    /// Hands every frame accepted from now on to `sink`.
    pub fn with_forward(mut self, sink: Box<dyn ForwardSink>) -> Self {
        self.endpoint.keep_accepted_frames(true);
        self.forward = Some(sink);
        self
    }

    /// Sends `frame` as it is: a watcher's frame its forward's filter let through.
    pub fn send_raw_frame(&mut self, frame: Vec<u8>) {
        self.endpoint.send_raw_frame(frame);
    }

    fn pass_accepted(&mut self) {
        if let Some(sink) = &mut self.forward {
            while let Some(frame) = self.endpoint.poll_accepted_frame() {
                sink.accepted(frame);
            }
        }
    }

    /// Shows every byte received and sent to `tap` from now on.
    pub fn with_tap(mut self, tap: Box<dyn FrameTap>) -> Self {
        self.tap = Some(tap);
        self
    }

    /// The endpoint.
    pub fn endpoint(&self) -> &GroundEndpoint {
        &self.endpoint
    }

    /// Applies `action` at link time `now`, unless the mission time `now_s` is past its
    /// deadline (the core has told the operator it was not sent); its outcome is queued.
    pub fn apply(&mut self, now: Duration, now_s: f64, action: LinkAction) {
        let LinkAction { id, op, deadline_s } = action;
        let result = if now_s > deadline_s {
            Err(ActionError::Expired)
        } else {
            self.run(now, op)
        };
        if let Err(e) = &result {
            tracing::debug!(?id, error = %e, "link action not applied");
        }
        self.reports.push_back(LinkReport::Outcome { id, result });
    }

    fn run(&mut self, now: Duration, op: LinkOp) -> Result<(), ActionError> {
        let ep = &mut self.endpoint;
        match op {
            LinkOp::Command {
                request_id,
                command,
            } => ep
                .send_command(now, request_id, command)
                // Busy: the same command is still waiting for its acknowledgement.
                .map_err(|e| ActionError::Busy(e.to_string())),
            LinkOp::ParamSet { name, value } => {
                ep.param_set(now, &name, value).map_err(param_error)
            }
            LinkOp::PlanUpload(items) => ep.plan_upload(now, items).map_err(plan_error),
            LinkOp::PlanDownload => ep.plan_download(now).map_err(plan_error),
            LinkOp::FenceUpload(items) => ep.fence_upload(now, items).map_err(plan_error),
            LinkOp::ParamList => ep.param_list(now).map_err(param_error),
            LinkOp::ManualHold(sticks) => {
                ep.manual_hold(now, sticks);
                Ok(())
            }
            LinkOp::ManualRelease => {
                ep.manual_release();
                Ok(())
            }
        }
    }

    /// Queues the link statistics at `now` as a report.
    pub fn sample_stats(&mut self, now: Duration) {
        let stats = self.endpoint.link_stats(now);
        self.reports.push_back(LinkReport::Stats(stats));
    }
}

fn param_error(e: ParamRequestError) -> ActionError {
    match e {
        ParamRequestError::Busy { .. } | ParamRequestError::ListInProgress => {
            ActionError::Busy(e.to_string())
        }
        ParamRequestError::BadName { .. } => ActionError::Refused(e.to_string()),
    }
}

fn plan_error(e: PlanRequestError) -> ActionError {
    match e {
        PlanRequestError::Busy => ActionError::Busy(e.to_string()),
        PlanRequestError::TooLong { .. } => ActionError::Refused(e.to_string()),
    }
}

impl SansIo for StationLink {
    type Event = LinkReport;

    fn handle_bytes_on(&mut self, path: usize, now: Duration, bytes: &[u8]) {
        if let Some(tap) = &mut self.tap {
            tap.frame(path, false, bytes);
        }
        self.endpoint.handle_bytes_on(path, now, bytes);
        self.pass_accepted();
    }

    fn handle_datagram_on(&mut self, path: usize, now: Duration, datagram: &[u8]) -> bool {
        if let Some(tap) = &mut self.tap {
            tap.frame(path, false, datagram);
        }
        let from_peer = self.endpoint.handle_datagram_on(path, now, datagram);
        self.pass_accepted();
        from_peer
    }

    fn handle_timeout(&mut self, now: Duration) {
        self.endpoint.handle_timeout(now);
    }

    fn poll_timeout(&self) -> Option<Duration> {
        self.endpoint.poll_timeout()
    }

    fn poll_transmit(&mut self, now: Duration) -> Option<Vec<u8>> {
        let frame = self.endpoint.poll_transmit(now)?;
        if let Some(tap) = &mut self.tap {
            tap.frame(self.endpoint.transmit_path(now), true, &frame);
        }
        Some(frame)
    }

    /// Reports of actions first: the endpoint's events queued before an action were polled
    /// before it was applied, so this keeps the order things happened in.
    fn poll_event(&mut self) -> Option<LinkReport> {
        self.reports
            .pop_front()
            .or_else(|| self.endpoint.poll_event().map(LinkReport::Event))
    }

    fn handle_stream_end_on(&mut self, path: usize, now: Duration) {
        self.endpoint.handle_stream_end_on(path, now);
        self.pass_accepted();
    }

    fn transmit_path(&self, now: Duration) -> usize {
        self.endpoint.transmit_path(now)
    }

    fn signing_timestamp_mark(&self) -> Option<u64> {
        self.endpoint.signing_timestamp_mark()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use stx_link::command::{Command, RequestId};
    use stx_link::endpoint::GroundConfig;
    use stx_link::plan::PlanItem;

    fn link() -> StationLink {
        StationLink::new(GroundEndpoint::new(GroundConfig::default(), Duration::ZERO))
    }

    fn action(id: u64, op: LinkOp, deadline_s: f64) -> LinkAction {
        LinkAction {
            id: ActionId(id),
            op,
            deadline_s,
        }
    }

    fn outcomes(link: &mut StationLink) -> Vec<(ActionId, Result<(), ActionError>)> {
        std::iter::from_fn(|| link.poll_event())
            .filter_map(|r| match r {
                LinkReport::Outcome { id, result } => Some((id, result)),
                _ => None,
            })
            .collect()
    }

    fn land() -> Vec<PlanItem> {
        vec![PlanItem::Land {
            lat_deg: 38.5,
            lon_deg: -7.9,
            alt_msl_m: 245.0,
            approach_heading_deg: None,
        }]
    }

    #[test]
    fn every_action_reports_its_outcome_in_order() {
        let mut link = link();
        let now = Duration::from_secs(1);
        link.apply(now, 1.0, action(1, LinkOp::PlanDownload, 6.0));
        link.apply(now, 1.0, action(2, LinkOp::PlanUpload(land()), 6.0));
        let mode = LinkOp::Command {
            request_id: RequestId(7),
            command: Command::SetMode(stx_gnc::mission::FlightMode::Heading),
        };
        link.apply(now, 1.0, action(3, mode.clone(), 6.0));
        link.apply(now, 1.0, action(4, mode, 6.0));
        link.apply(now, 1.0, action(5, LinkOp::ManualRelease, 6.0));
        let got = outcomes(&mut link);
        let ids: Vec<u64> = got.iter().map(|(id, _)| id.0).collect();
        assert_eq!(ids, [1, 2, 3, 4, 5]);
        assert_eq!(got[0].1, Ok(()));
        assert!(
            matches!(&got[1].1, Err(ActionError::Busy(r)) if r.contains("plan transfer")),
            "an upload during the download is busy: {:?}",
            got[1].1
        );
        assert_eq!(got[2].1, Ok(()));
        assert!(
            matches!(&got[3].1, Err(ActionError::Busy(r)) if r.contains("in flight")),
            "the same command twice: {:?}",
            got[3].1
        );
        assert_eq!(got[4].1, Ok(()));
    }

    #[test]
    fn an_action_past_its_deadline_is_not_applied() {
        let mut link = link();
        link.apply(
            Duration::from_secs(9),
            9.0,
            action(1, LinkOp::PlanDownload, 6.0),
        );
        assert!(matches!(
            outcomes(&mut link)[..],
            [(ActionId(1), Err(ActionError::Expired))]
        ));
        // Not started: a download is possible now.
        link.apply(
            Duration::from_secs(9),
            9.0,
            action(2, LinkOp::PlanDownload, 14.0),
        );
        assert_eq!(outcomes(&mut link), [(ActionId(2), Ok(()))]);
    }

    /// Radio, sent, bytes.
    type Tapped = (usize, bool, Vec<u8>);

    #[derive(Clone, Default)]
    struct Seen(std::sync::Arc<std::sync::Mutex<Vec<Tapped>>>);

    impl FrameTap for Seen {
        fn frame(&mut self, path: usize, sent: bool, bytes: &[u8]) {
            self.0.lock().unwrap().push((path, sent, bytes.to_vec()));
        }
    }

    #[test]
    fn the_tap_sees_every_byte_received_and_every_frame_sent() {
        let seen = Seen::default();
        let mut link = link().with_tap(Box::new(seen.clone()));
        link.handle_datagram_on(0, Duration::ZERO, b"garbage");
        link.handle_bytes_on(0, Duration::ZERO, &[0xfd, 1]);
        // The station's heartbeat is due at once.
        link.handle_timeout(Duration::from_secs(1));
        let mut sent = Vec::new();
        while let Some(f) = link.poll_transmit(Duration::from_secs(1)) {
            sent.push(f);
        }
        assert!(!sent.is_empty(), "a heartbeat goes out");
        let seen = seen.0.lock().unwrap();
        assert_eq!(seen[0], (0, false, b"garbage".to_vec()));
        assert_eq!(seen[1], (0, false, vec![0xfd, 1]));
        let tapped: Vec<Vec<u8>> = seen[2..].iter().map(|(_, _, b)| b.clone()).collect();
        assert_eq!(tapped, sent);
        assert!(seen[2..].iter().all(|(p, s, _)| *p == 0 && *s));
    }

    #[derive(Clone, Default)]
    struct Forwarded(std::sync::Arc<std::sync::Mutex<Vec<Vec<u8>>>>);

    impl ForwardSink for Forwarded {
        fn accepted(&mut self, frame: Vec<u8>) {
            self.0.lock().unwrap().push(frame);
        }
    }

    #[test]
    fn the_forward_gets_each_accepted_frame_unchanged_and_sends_a_watchers_frame_as_is() {
        use stx_link::MavMessage;
        use stx_link::frame::FrameEncoder;
        let got = Forwarded::default();
        let mut link = link().with_forward(Box::new(got.clone()));
        let mut drone = FrameEncoder::new(1, 1);
        let hb = MavMessage::HEARTBEAT(Default::default());
        let first = drone.encode(Duration::ZERO, &hb);
        let second = drone.encode(Duration::ZERO, &hb);
        let mut datagram = b"noise".to_vec();
        datagram.extend_from_slice(&first);
        datagram.extend_from_slice(&second[..4]);
        link.handle_datagram_on(0, Duration::ZERO, &datagram);
        // A stream may cut a frame anywhere: it is passed on once whole.
        link.handle_bytes_on(0, Duration::ZERO, &second[..7]);
        assert_eq!(got.0.lock().unwrap().len(), 1);
        link.handle_bytes_on(0, Duration::ZERO, &second[7..]);
        assert_eq!(*got.0.lock().unwrap(), vec![first, second]);

        let watcher = FrameEncoder::new(255, 190).encode(Duration::ZERO, &hb);
        link.send_raw_frame(watcher.clone());
        let sent: Vec<Vec<u8>> =
            std::iter::from_fn(|| link.poll_transmit(Duration::ZERO)).collect();
        assert!(sent.contains(&watcher), "{sent:?}");
    }

    #[test]
    fn stats_are_reported_on_request() {
        let mut link = link();
        link.sample_stats(Duration::from_secs(1));
        assert!(matches!(link.poll_event(), Some(LinkReport::Stats(_))));
        assert!(link.poll_event().is_none());
    }
}
