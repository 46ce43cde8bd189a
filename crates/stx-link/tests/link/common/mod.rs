//! Test harness in the style of quinn-proto's `Pair`: a ground and a vehicle endpoint joined by
//! a simulated channel with latency and loss, driven by a fake clock. Deterministic: loss is
//! drawn from a seeded RNG or decided by a filter.
#![allow(dead_code)]

use std::collections::VecDeque;
use std::time::Duration;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use stx_link::command::CommandResult;
use stx_link::endpoint::{
    GroundConfig, GroundEndpoint, GroundEvent, VehicleConfig, VehicleEndpoint, VehicleEvent,
};

/// Message id of a MAVLink 2 frame.
pub fn msg_id(frame: &[u8]) -> Option<u32> {
    let b = frame.get(7..10)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], 0]))
}

/// Decides whether a frame is dropped.
pub type Filter = Box<dyn FnMut(&[u8]) -> bool>;

/// One direction of the channel.
pub struct Channel {
    /// One-way delay.
    pub latency: Duration,
    /// Probability of losing a frame.
    pub loss: f64,
    /// Extra deterministic drop rule.
    pub filter: Option<Filter>,
    queue: VecDeque<(Duration, Vec<u8>)>,
    /// Frames sent into the channel.
    pub sent: u64,
    /// Frames dropped.
    pub dropped: u64,
    /// Every frame that entered the channel (kept for replay tests).
    pub log: Vec<Vec<u8>>,
}

impl Channel {
    fn new(latency: Duration) -> Self {
        Self {
            latency,
            loss: 0.0,
            filter: None,
            queue: VecDeque::new(),
            sent: 0,
            dropped: 0,
            log: Vec::new(),
        }
    }

    fn push(&mut self, now: Duration, frame: Vec<u8>, rng: &mut ChaCha8Rng) {
        self.sent += 1;
        self.log.push(frame.clone());
        let filtered = self.filter.as_mut().is_some_and(|f| f(&frame));
        let lost = self.loss > 0.0 && rng.random::<f64>() < self.loss;
        if filtered || lost {
            self.dropped += 1;
            return;
        }
        self.queue.push_back((now + self.latency, frame));
    }

    fn next_delivery(&self) -> Option<Duration> {
        self.queue.front().map(|(t, _)| *t)
    }

    fn pop_due(&mut self, now: Duration) -> Option<Vec<u8>> {
        if self.queue.front().is_some_and(|(t, _)| *t <= now) {
            self.queue.pop_front().map(|(_, f)| f)
        } else {
            None
        }
    }
}

pub struct Pair {
    pub now: Duration,
    pub ground: GroundEndpoint,
    pub vehicle: VehicleEndpoint,
    pub to_vehicle: Channel,
    pub to_ground: Channel,
    pub ground_events: Vec<(Duration, GroundEvent)>,
    pub vehicle_events: Vec<(Duration, VehicleEvent)>,
    /// When set, the vehicle answers every command with this result.
    pub auto_ack: Option<CommandResult>,
    rng: ChaCha8Rng,
}

impl Pair {
    pub fn new(ground: GroundConfig, vehicle: VehicleConfig, seed: u64) -> Self {
        let now = Duration::from_secs(100);
        Self {
            now,
            ground: GroundEndpoint::new(ground, now),
            vehicle: VehicleEndpoint::new(vehicle, now).expect("valid vehicle config"),
            to_vehicle: Channel::new(Duration::from_millis(50)),
            to_ground: Channel::new(Duration::from_millis(50)),
            ground_events: Vec::new(),
            vehicle_events: Vec::new(),
            auto_ack: Some(CommandResult::Accepted),
            rng: ChaCha8Rng::seed_from_u64(seed),
        }
    }

    pub fn default_pair(seed: u64) -> Self {
        Self::new(GroundConfig::default(), VehicleConfig::default(), seed)
    }

    /// Moves everything that can move at `now`, without advancing the clock.
    pub fn drive_now(&mut self) {
        loop {
            let mut moved = false;
            while let Some(f) = self.ground.poll_transmit(self.now) {
                self.to_vehicle.push(self.now, f, &mut self.rng);
                moved = true;
            }
            while let Some(f) = self.vehicle.poll_transmit(self.now) {
                self.to_ground.push(self.now, f, &mut self.rng);
                moved = true;
            }
            while let Some(f) = self.to_vehicle.pop_due(self.now) {
                self.vehicle.handle_bytes(self.now, &f);
                moved = true;
            }
            while let Some(f) = self.to_ground.pop_due(self.now) {
                self.ground.handle_bytes(self.now, &f);
                moved = true;
            }
            while let Some(e) = self.ground.poll_event() {
                self.ground_events.push((self.now, e));
                moved = true;
            }
            while let Some(e) = self.vehicle.poll_event() {
                if let (VehicleEvent::Command(c), Some(r)) = (&e, self.auto_ack) {
                    self.vehicle.respond_command(c.id, r);
                }
                self.vehicle_events.push((self.now, e));
                moved = true;
            }
            if !moved {
                break;
            }
        }
    }

    /// Advances the clock to the next timer or delivery (at most `limit`) and runs it.
    pub fn step(&mut self, limit: Duration) {
        self.drive_now();
        let next = [
            self.ground.poll_timeout(),
            self.vehicle.poll_timeout(),
            self.to_vehicle.next_delivery(),
            self.to_ground.next_delivery(),
        ]
        .into_iter()
        .flatten()
        .min()
        .unwrap_or(limit)
        .min(limit)
        .max(self.now);
        self.now = next;
        self.ground.handle_timeout(self.now);
        self.vehicle.handle_timeout(self.now);
        self.drive_now();
    }

    /// Runs until the clock reaches `until`.
    pub fn run_until(&mut self, until: Duration) {
        while self.now < until {
            self.step(until);
        }
    }

    /// Runs for `d` more.
    pub fn run_for(&mut self, d: Duration) {
        let until = self.now + d;
        self.run_until(until);
    }

    /// Runs until `pred` holds for some ground event, or `timeout` passes.
    pub fn run_until_ground<F: Fn(&GroundEvent) -> bool>(
        &mut self,
        timeout: Duration,
        pred: F,
    ) -> Option<GroundEvent> {
        let until = self.now + timeout;
        let mut seen = 0;
        loop {
            if let Some((_, e)) = self.ground_events.iter().skip(seen).find(|(_, e)| pred(e)) {
                return Some(e.clone());
            }
            seen = self.ground_events.len();
            if self.now >= until {
                return None;
            }
            self.step(until);
        }
    }
}
