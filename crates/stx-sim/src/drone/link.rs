//! The simulated drone on the link: a [`Drone`] behind a [`VehicleEndpoint`], with the
//! rehearsal's link failures, still sans-io — bytes and a link clock in, bytes and events out.
//!
//! Two clocks meet here. Mission time (the drone's, [`Drone::time_s`]) advances one control
//! period per [`LinkedDrone::step`] and stamps all telemetry, so the station sees sensors at
//! 4 Hz of mission time whatever the speed. The link clock (`link_now`, any monotonic
//! [`Duration`]) runs the endpoint's own timers — heartbeats (1 Hz), the station's liveness,
//! stick staleness, retries — because those face a person and a station living in wall time:
//! at ten times real speed the station still sends its joystick at 10 Hz of wall time, and a
//! stick timeout in mission time would declare every stick stale. Tests that want one clock
//! pass mission time as `link_now`; `stx drone` passes wall time.
//!
//! Every frame out and every `handle_bytes` call in (one datagram) passes through
//! [`LinkFaults`]: the link-drop windows (mission time) and the random packet loss. What the
//! endpoint reports is applied to the drone at once: commands are executed and acknowledged,
//! parameter sets checked by the drone's own rules inside the link's table before they are
//! taken or echoed ([`Drone::check_param`] as the table's validator: a refused set is answered
//! only with the value in force), uploaded plans flown, link loss and return noted (the drone
//! keeps flying its plan either way).

use std::collections::VecDeque;
use std::time::Duration;

use stx_gnc::mission::FlightStage;
use stx_link::command::{Command, CommandResult};
use stx_link::endpoint::{
    LinkConfig, LinkEvent, LinkStats, VehicleConfig, VehicleEndpoint, VehicleEvent,
};
use stx_link::sansio::SansIo;
use stx_link::telemetry::{Severity, Telemetry, VehicleStatus};

use crate::drone::failures::LinkFaults;
use crate::drone::{Drone, DroneError, Output};

/// Most events kept for a caller that does not drain them (older ones are dropped and
/// counted in [`LinkCounters::events_dropped`]).
pub const MAX_QUEUED_EVENTS: usize = 10_000;

/// What happened on the drone's side of the link, for the adapter's log and for tests.
#[derive(Debug, Clone, PartialEq)]
pub enum DroneEvent {
    /// A text the drone sent the operator (STATUSTEXT).
    Text {
        /// Mission time, s.
        time_s: f64,
        /// Its severity.
        severity: Severity,
        /// The text.
        text: String,
    },
    /// The station's heartbeats started (`true`) or stopped (`false`).
    Link {
        /// Mission time, s.
        time_s: f64,
        /// Whether the station is heard.
        connected: bool,
    },
    /// A command was executed and answered.
    Command {
        /// Mission time, s.
        time_s: f64,
        /// The command.
        command: Command,
        /// The answer sent in COMMAND_ACK.
        result: CommandResult,
    },
    /// A parameter set from the station, applied or refused.
    Param {
        /// Mission time, s.
        time_s: f64,
        /// Its name.
        name: String,
        /// The value asked for.
        value: f32,
        /// Whether the drone took it.
        accepted: bool,
    },
    /// A plan was uploaded and taken.
    Plan {
        /// Mission time, s.
        time_s: f64,
        /// Number of items.
        items: usize,
    },
    /// Signing's timestamp high-water mark moved (stx-link-tokio's `drive` persists the
    /// mark itself, before the frames signed under it leave).
    PersistSigningTimestamp(u64),
}

/// Counters of the drone's side of the link.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct LinkCounters {
    /// Commands executed (each answered).
    pub commands: u64,
    /// Parameter sets taken.
    pub params_set: u64,
    /// Parameter sets refused (range or the onboard rules); the value in force was kept.
    pub params_refused: u64,
    /// Plans uploaded.
    pub plans: u64,
    /// Keep-out fences uploaded.
    pub fences: u64,
    /// Datagrams in and frames out dropped because the link was down (injected).
    pub dropped_link_down: u64,
    /// Datagrams in and frames out dropped at random (injected packet loss).
    pub dropped_random: u64,
    /// Frames from the station of a kind the drone does not use.
    pub ignored_frames: u64,
    /// Events dropped because nobody drained them.
    pub events_dropped: u64,
}

/// The drone with its end of the link.
#[derive(Debug)]
pub struct LinkedDrone {
    drone: Drone,
    endpoint: VehicleEndpoint,
    faults: LinkFaults,
    status: VehicleStatus,
    events: VecDeque<DroneEvent>,
    counters: LinkCounters,
    /// `time_boot_ms` of the latest ATTITUDE handed to the endpoint.
    last_attitude_ms: Option<u32>,
}

impl LinkedDrone {
    /// Puts `drone` on a link with `link` settings (ids, heartbeat, signing), starting the
    /// link clock at `link_now`.
    pub fn new(drone: Drone, link: LinkConfig, link_now: Duration) -> Result<Self, DroneError> {
        let status = drone.status();
        let mut endpoint = VehicleEndpoint::new(
            VehicleConfig {
                link,
                params: drone.param_specs(),
                manual_timeout: Duration::from_secs_f64(drone.manual_timeout_s()),
                initial_status: status,
                ..VehicleConfig::default()
            },
            link_now,
        )?;
        endpoint.set_plan(drone.plan_items());
        let faults = drone.link_faults();
        let mut linked = Self {
            drone,
            endpoint,
            faults,
            status,
            events: VecDeque::new(),
            counters: LinkCounters::default(),
            last_attitude_ms: None,
        };
        linked.forward_outputs(link_now);
        Ok(linked)
    }

    /// The drone.
    pub fn drone(&self) -> &Drone {
        &self.drone
    }

    /// The endpoint (its parameter table, plan and statistics).
    pub fn endpoint(&self) -> &VehicleEndpoint {
        &self.endpoint
    }

    /// Counters.
    pub fn counters(&self) -> LinkCounters {
        let mut c = self.counters;
        c.dropped_link_down = self.faults.dropped_down;
        c.dropped_random = self.faults.dropped_random;
        c
    }

    /// Link quality as the drone sees the station.
    pub fn link_stats(&mut self, link_now: Duration) -> LinkStats {
        self.endpoint.link_stats(link_now)
    }

    /// Flies one control period of mission time at link time `link_now`: the sticks as the
    /// endpoint has them now (stale ones are `None`), the drone's step, its telemetry and
    /// texts onto the link, and a heartbeat at once when mode, stage, phase or state changed.
    pub fn step(&mut self, link_now: Duration) -> Result<(), DroneError> {
        self.drone.set_sticks(self.endpoint.sticks(link_now));
        let result = self.drone.step();
        self.forward_outputs(link_now);
        result
    }

    /// `time_boot_ms` of the latest ATTITUDE sent: the stamp a station shows the frame by.
    pub fn last_attitude_time_boot_ms(&self) -> Option<u32> {
        self.last_attitude_ms
    }

    /// Whether the drone has landed.
    pub fn landed(&self) -> bool {
        self.drone.stage() == FlightStage::Landed
    }

    /// Feeds one datagram (or stream chunk) received at `link_now`.
    pub fn handle_bytes(&mut self, link_now: Duration, bytes: &[u8]) {
        self.handle_bytes_on(0, link_now, bytes);
    }

    /// Bytes received on radio `path` of the drone's link.
    pub fn handle_bytes_on(&mut self, path: usize, link_now: Duration, bytes: &[u8]) {
        if self.faults.drops_datagram(self.drone.time_s()) {
            return;
        }
        let drone = &self.drone;
        self.endpoint
            .handle_bytes_on_with(path, link_now, bytes, &mut |name: &str, value: f32| {
                drone.check_param(name, value).map_err(|e| e.to_string())
            });
        self.process(link_now);
    }

    /// One whole datagram received on radio `path` (UDP); returns whether it carried a frame
    /// accepted from the ground station (see `VehicleEndpoint::handle_datagram_on_with`). A
    /// datagram the fault model drops carried nothing.
    pub fn handle_datagram_on(&mut self, path: usize, link_now: Duration, datagram: &[u8]) -> bool {
        if self.faults.drops_datagram(self.drone.time_s()) {
            return false;
        }
        let drone = &self.drone;
        let from_station = self.endpoint.handle_datagram_on_with(
            path,
            link_now,
            datagram,
            &mut |name: &str, value: f32| drone.check_param(name, value).map_err(|e| e.to_string()),
        );
        self.process(link_now);
        from_station
    }

    /// The stream connection carrying the link ended (TCP, serial).
    pub fn handle_stream_end(&mut self, link_now: Duration) {
        self.handle_stream_end_on(0, link_now);
    }

    /// The stream connection of radio `path` ended.
    pub fn handle_stream_end_on(&mut self, path: usize, link_now: Duration) {
        let drone = &self.drone;
        self.endpoint
            .handle_stream_end_on_with(path, link_now, &mut |name: &str, value: f32| {
                drone.check_param(name, value).map_err(|e| e.to_string())
            });
        self.process(link_now);
    }

    /// Runs the endpoint's timers (heartbeats, liveness, stick staleness).
    pub fn handle_timeout(&mut self, link_now: Duration) {
        self.endpoint.handle_timeout(link_now);
        self.process(link_now);
    }

    /// When [`handle_timeout`](Self::handle_timeout) must run next (link clock).
    pub fn poll_timeout(&self) -> Option<Duration> {
        self.endpoint.poll_timeout()
    }

    /// The next frame to send, past the injected link failures.
    pub fn poll_transmit(&mut self, link_now: Duration) -> Option<Vec<u8>> {
        loop {
            let frame = self.endpoint.poll_transmit(link_now)?;
            if !self.faults.drops_datagram(self.drone.time_s()) {
                return Some(frame);
            }
        }
    }

    /// The next event.
    pub fn poll_event(&mut self) -> Option<DroneEvent> {
        self.events.pop_front()
    }

    fn event(&mut self, event: DroneEvent) {
        if self.events.len() >= MAX_QUEUED_EVENTS {
            self.events.pop_front();
            self.counters.events_dropped += 1;
        }
        self.events.push_back(event);
    }

    /// Moves the drone's telemetry and texts onto the link, and its status into the
    /// heartbeat.
    fn forward_outputs(&mut self, link_now: Duration) {
        let time_s = self.drone.time_s();
        while let Some(output) = self.drone.poll_output() {
            match output {
                Output::Telemetry(t) => {
                    if let Telemetry::Attitude(a) = &t {
                        self.last_attitude_ms = Some(a.time_boot_ms);
                    }
                    self.endpoint.send_telemetry(link_now, &t);
                }
                Output::Body { body, telemetry } => {
                    self.endpoint
                        .send_telemetry_from(link_now, body.component_id(), &telemetry);
                }
                Output::Text { severity, text } => {
                    self.endpoint.send_status_text(link_now, severity, &text);
                    self.event(DroneEvent::Text {
                        time_s,
                        severity,
                        text,
                    });
                }
            }
        }
        let status = self.drone.status();
        if status != self.status {
            self.status = status;
            self.endpoint.set_status(status);
            // The operator sees a mode or stage change now, not at the next 1 Hz heartbeat.
            self.endpoint
                .send_telemetry(link_now, &Telemetry::Status(status));
        }
    }

    /// Applies what the endpoint reports.
    fn process(&mut self, link_now: Duration) {
        while let Some(event) = self.endpoint.poll_event() {
            let time_s = self.drone.time_s();
            match event {
                VehicleEvent::Link(LinkEvent::Connected { .. }) => {
                    self.drone.link_changed(true);
                    self.event(DroneEvent::Link {
                        time_s,
                        connected: true,
                    });
                }
                VehicleEvent::Link(LinkEvent::Lost { .. }) => {
                    tracing::warn!(time_s, "station lost: flying the plan");
                    self.drone.link_changed(false);
                    self.event(DroneEvent::Link {
                        time_s,
                        connected: false,
                    });
                }
                VehicleEvent::Link(LinkEvent::PersistSigningTimestamp(v)) => {
                    self.event(DroneEvent::PersistSigningTimestamp(v));
                }
                VehicleEvent::Link(LinkEvent::FrameError(e)) => {
                    tracing::debug!(error = %e, "frame dropped");
                }
                VehicleEvent::Command(incoming) => {
                    let result = self.drone.handle_command(&incoming.command);
                    self.endpoint.respond_command(incoming.id, result);
                    self.endpoint.set_plan(self.drone.plan_items());
                    self.counters.commands += 1;
                    self.event(DroneEvent::Command {
                        time_s,
                        command: incoming.command,
                        result,
                    });
                }
                VehicleEvent::ParamChanged(change) => {
                    // The table asked the drone before taking the value, so this holds; were
                    // the two ever to disagree, the table is brought back to what the drone
                    // flies (that echo's own change is the value in force: skipped).
                    if self.drone.param(&change.name) == Some(change.new) {
                        continue;
                    }
                    let accepted = self.drone.set_param(&change.name, change.new).is_ok();
                    if accepted {
                        self.counters.params_set += 1;
                        self.endpoint.set_manual_timeout(Duration::from_secs_f64(
                            self.drone.manual_timeout_s(),
                        ));
                    } else {
                        self.counters.params_refused += 1;
                        tracing::error!(name = %change.name, "parameter passed the table's check but not the drone's");
                        if let Some(v) = self.drone.param(&change.name)
                            && let Err(e) = self.endpoint.params_mut().set(&change.name, v)
                        {
                            tracing::error!(error = %e, "cannot restore parameter");
                        }
                    }
                    self.event(DroneEvent::Param {
                        time_s,
                        name: change.name,
                        value: change.new,
                        accepted,
                    });
                }
                VehicleEvent::ParamRefused(refusal) => {
                    self.counters.params_refused += 1;
                    self.event(DroneEvent::Param {
                        time_s,
                        name: refusal.name,
                        value: refusal.value,
                        accepted: false,
                    });
                }
                VehicleEvent::PlanReceived(items) => {
                    self.drone.handle_plan(&items);
                    self.endpoint.set_plan(self.drone.plan_items());
                    self.counters.plans += 1;
                    self.event(DroneEvent::Plan {
                        time_s,
                        items: items.len(),
                    });
                }
                VehicleEvent::FenceReceived(items) => {
                    self.drone.handle_fence(&items);
                    self.counters.fences += 1;
                }
                VehicleEvent::Manual(_) => {}
                VehicleEvent::Other(_) => self.counters.ignored_frames += 1,
            }
        }
        self.forward_outputs(link_now);
    }
}

/// So that stx-link-tokio's `drive` runs the linked drone over a socket like any
/// endpoint; the simulation's steps go in as its actions (`|d, now| d.step(now)`).
impl SansIo for LinkedDrone {
    type Event = DroneEvent;

    fn handle_bytes_on(&mut self, path: usize, now: Duration, bytes: &[u8]) {
        LinkedDrone::handle_bytes_on(self, path, now, bytes);
    }

    fn handle_datagram_on(&mut self, path: usize, now: Duration, datagram: &[u8]) -> bool {
        LinkedDrone::handle_datagram_on(self, path, now, datagram)
    }

    fn handle_timeout(&mut self, now: Duration) {
        LinkedDrone::handle_timeout(self, now);
    }

    fn poll_timeout(&self) -> Option<Duration> {
        LinkedDrone::poll_timeout(self)
    }

    fn poll_transmit(&mut self, now: Duration) -> Option<Vec<u8>> {
        LinkedDrone::poll_transmit(self, now)
    }

    fn poll_event(&mut self) -> Option<DroneEvent> {
        LinkedDrone::poll_event(self)
    }

    fn handle_stream_end_on(&mut self, path: usize, now: Duration) {
        LinkedDrone::handle_stream_end_on(self, path, now);
    }

    fn transmit_path(&self, now: Duration) -> usize {
        self.endpoint.transmit_path(now)
    }

    fn signing_timestamp_mark(&self) -> Option<u64> {
        self.endpoint.signing_timestamp_mark()
    }
}
