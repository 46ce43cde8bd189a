//! The simulated drone and the station's core on one link, sans-io, each on its own clock.
//!
//! The drone flies in mission time, one control period (0.25 s) per [`Pair::step`]; the station
//! lives in wall time, which runs `speed` times slower than mission time (`stx serve --sim
//! --sim-speed N` flies the same way). Between two steps the link's bytes go both ways until
//! neither side has anything to send, the link timers of both ends run, the station's core sees
//! every event, answers with its link actions, and publishes one `state` per telemetry burst
//! as the daemon's loop does (`stx_station::daemon`). Landing predictions run when the core says
//! one is due, at once (in the daemon they run on a blocking thread, off the telemetry path).

use std::time::Duration;

use stx_link::endpoint::{GroundConfig, GroundEndpoint, LinkConfig};
use stx_link::sansio::SansIo;
use stx_sim::dispersions::Dispersions;
use stx_sim::drone::link::LinkedDrone;
use stx_sim::drone::{DispersedDroneError, Drone, DroneError, MissionConfig};
use stx_station::config::StationConfig;
use stx_station::core::StationCore;
use stx_station::link::{LinkReport, StationLink};
use stx_station::messages::StateMsg;

/// Link statistics are sampled this often, s of the station's clock (the daemon's period).
const STATS_PERIOD_S: f64 = 0.5;

/// Why a pair cannot be built or go on.
#[derive(Debug, thiserror::Error)]
pub enum PairError {
    /// The drone of the mission (its file, its dispersed vehicle).
    #[error("the simulated drone: {0}")]
    Drone(#[from] DispersedDroneError),
    /// The drone failed in flight.
    #[error("the simulated drone in flight: {0}")]
    Flight(#[from] DroneError),
    /// The speed is not a positive number.
    #[error("speed {0} is not a positive factor of real time")]
    Speed(f64),
}

/// The drone and the station on one link.
pub struct Pair {
    drone: LinkedDrone,
    link: StationLink,
    core: StationCore,
    /// Mission seconds per station second.
    speed: f64,
    state: Option<StateMsg>,
    next_stats_s: f64,
    predictions: u64,
}

impl std::fmt::Debug for Pair {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Pair")
            .field("mission_s", &self.drone.drone().time_s())
            .field("speed", &self.speed)
            .finish_non_exhaustive()
    }
}

impl Pair {
    /// `mission` (dispersed by `dispersions` with its seed) beside a station configured by
    /// `station`, whose keep-out zones are `keep_out` (file name and text) if any, flown at
    /// `speed` times real time.
    pub fn new(
        mission: &MissionConfig,
        dispersions: Option<&Dispersions>,
        station: StationConfig,
        keep_out: Option<(&str, String)>,
        speed: f64,
    ) -> Result<Self, PairError> {
        if !(speed.is_finite() && speed > 0.0) {
            return Err(PairError::Speed(speed));
        }
        let drone = Drone::dispersed(mission, dispersions)?;
        let drone = LinkedDrone::new(drone, LinkConfig::vehicle(), Duration::ZERO)
            .map_err(DispersedDroneError::from)?;
        let link = StationLink::new(GroundEndpoint::new(GroundConfig::default(), Duration::ZERO));
        let mut core = StationCore::new(station, 0);
        if let Some((file, text)) = keep_out {
            core.load_keep_out(0.0, file, Ok(text));
        }
        let mut pair = Self {
            drone,
            link,
            core,
            speed,
            state: None,
            next_stats_s: 0.0,
            predictions: 0,
        };
        pair.exchange();
        Ok(pair)
    }

    /// The drone (its truth, its onboard software).
    pub fn drone(&self) -> &Drone {
        self.drone.drone()
    }

    /// The station's core.
    pub fn core(&self) -> &StationCore {
        &self.core
    }

    /// The station's newest `state`, as its pages have it.
    pub fn state(&self) -> Option<&StateMsg> {
        self.state.as_ref()
    }

    /// Landing predictions the station has made.
    pub fn predictions(&self) -> u64 {
        self.predictions
    }

    /// Mission time, s.
    pub fn mission_s(&self) -> f64 {
        self.drone.drone().time_s()
    }

    /// Whether the drone is on the ground.
    pub fn landed(&self) -> bool {
        self.drone.landed()
    }

    /// The station's clock now, s: mission time over the speed.
    fn station_s(&self) -> f64 {
        self.mission_s() / self.speed
    }

    fn link_now(&self) -> Duration {
        Duration::from_secs_f64(self.station_s())
    }

    /// Flies one control period the station does not hear yet: its telemetry waits on the
    /// link until the next [`Pair::step`], as it waits in a loaded station's socket.
    pub fn step_unheard(&mut self) -> Result<(), PairError> {
        let now = self.link_now();
        self.drone.step(now)?;
        Ok(())
    }

    /// Flies one control period and lets the station hear and answer it.
    pub fn step(&mut self) -> Result<(), PairError> {
        let now = self.link_now();
        self.drone.step(now)?;
        self.exchange();
        Ok(())
    }

    /// Moves bytes both ways until both ends are quiet, with their timers run, then publishes
    /// the station's state and runs a prediction if one is due.
    fn exchange(&mut self) {
        let now = self.link_now();
        let now_s = self.station_s();
        if now_s >= self.next_stats_s {
            self.next_stats_s = now_s + STATS_PERIOD_S;
            self.link.sample_stats(now);
        }
        loop {
            if self.drone.poll_timeout().is_some_and(|t| t <= now) {
                self.drone.handle_timeout(now);
            }
            if self.link.poll_timeout().is_some_and(|t| t <= now) {
                self.link.handle_timeout(now);
            }
            let mut moved = false;
            while let Some(frame) = self.drone.poll_transmit(now) {
                self.link.handle_datagram_on(0, now, &frame);
                moved = true;
            }
            while let Some(report) = self.link.poll_event() {
                self.report(now_s, report);
            }
            for action in self.core.take_link_actions(now_s) {
                self.link.apply(now, now_s, action);
                moved = true;
            }
            while let Some(report) = self.link.poll_event() {
                self.report(now_s, report);
            }
            while let Some(frame) = self.link.poll_transmit(now) {
                self.drone.handle_datagram_on(0, now, &frame);
                moved = true;
            }
            while self.drone.poll_event().is_some() {}
            if !moved {
                break;
            }
        }
        let state = self.core.tick(now_s);
        self.core.drain_outbound();
        if let Some(job) = self.core.prediction_job() {
            self.core.set_prediction(job.run());
            self.predictions += 1;
        }
        self.state = Some(state);
    }

    fn report(&mut self, now_s: f64, report: LinkReport) {
        match report {
            LinkReport::Event(e) => self.core.on_link_event(now_s, e),
            LinkReport::Outcome { id, result } => self.core.on_action_outcome(now_s, id, result),
            LinkReport::Stats(stats) => self.core.set_link_stats(now_s, stats),
        }
    }
}
