//! The tokio adapter (see the module documentation): [`Flight::start`] puts the drone on the
//! air, [`Flight::run`] paces it to the end and reports.

use std::future::Future;
use std::io;
use std::net::SocketAddr;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use serde::Serialize;

use stx_link::sansio::IoStats;
use stx_link::signing::persist::{persist_signing_mark, start_signing};
use stx_link_tokio::{Action, DriveOptions, DriverEvent, Transport, TransportError, drive};
use tokio::sync::mpsc;
use tokio::task::{JoinError, JoinHandle};

use super::anemometer::{AnemometerCounters, AnemometerLink};
use super::observe::{FlightObserver, StepReport, log_event};
use super::options::{FlyOptions, Speed};
use super::pacing::Pacer;
use crate::drone::link::{DroneEvent, LinkCounters, LinkedDrone};
use crate::drone::{DispersedDroneError, Drone, DroneError, MissionSummary, stage_name};
use crate::guided::CONTROL_PERIOD_S;

/// Steps handed to the driver ahead of its progress at maximum speed.
pub const STEPS_IN_FLIGHT: usize = 16;

/// Events of the driver waiting for the flight's task.
const EVENTS_QUEUED: usize = 4096;

/// Why a flight did not start or did not finish.
#[derive(Debug, thiserror::Error)]
pub enum FlyError {
    /// The mission's drone cannot be built (its configuration).
    #[error("building the drone of mission {mission}")]
    Drone {
        mission: String,
        #[source]
        source: DroneError,
    },
    /// The vehicle drawn from the dispersion set is one the model refuses.
    #[error("the dispersed vehicle of mission {mission} is refused")]
    Dispersed {
        mission: String,
        #[source]
        source: stx_dynamics::vehicle::VehicleError,
    },
    /// The link's address is bad or cannot be opened.
    #[error("opening {address}")]
    Open {
        address: String,
        #[source]
        source: TransportError,
    },
    /// No socket to send the ground anemometer's sentences to `to` from.
    #[error("opening a UDP socket for the ground anemometer's sentences to {to}")]
    Anemometer {
        to: SocketAddr,
        #[source]
        source: io::Error,
    },
    /// The system clock reads before 1970: no signing timestamp can be made.
    #[error("the system clock is before 1970")]
    Clock,
    /// Signing cannot start (its timestamp file cannot be read).
    #[error("{0}")]
    Signing(io::Error),
    /// The signing timestamp's high-water mark cannot be written.
    #[error("{0}")]
    PersistMark(io::Error),
    /// The drone cannot go on its link.
    #[error("putting the drone on the link")]
    Link(#[source] DroneError),
    /// The simulation failed in flight.
    #[error("simulation failed: {0}")]
    Simulation(DroneError),
    /// The link's task stopped taking steps.
    #[error("the link task stopped")]
    LinkStopped,
    /// The link's task panicked or was cancelled.
    #[error("the link task failed")]
    LinkTask(#[source] JoinError),
}

impl FlyError {
    /// Whether the caller's input was refused (the mission, the address, the signing files):
    /// nothing flew.
    pub fn is_input(&self) -> bool {
        matches!(
            self,
            Self::Drone { .. }
                | Self::Dispersed { .. }
                | Self::Open { .. }
                | Self::Anemometer { .. }
                | Self::Signing(_)
                | Self::PersistMark(_)
        )
    }
}

/// How a flight went: the mission's figures and the run's (what `stx drone --summary-json`
/// prints).
#[derive(Debug, Clone, Serialize)]
pub struct FlightReport {
    /// The mission in figures.
    #[serde(flatten)]
    pub mission: MissionSummary,
    /// Whether the drone landed.
    pub landed: bool,
    /// The speed flown.
    pub speed: String,
    /// Real time of the run, s.
    pub wall_time_s: f64,
    /// Stopped by the shutdown future before the end.
    pub interrupted: bool,
    /// The drone's side of the link.
    pub link: LinkCounters,
    /// The socket's counters.
    pub io: IoStats,
    /// What the ground anemometer sent, if it was on ([`FlyOptions::anemometer_to`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub anemometer: Option<AnemometerCounters>,
}

/// A drone on the air, not yet paced: its link is up (heartbeats, answers), no step flown.
pub struct Flight {
    speed: Speed,
    linger: Option<Duration>,
    actions: mpsc::Sender<Action<LinkedDrone>>,
    events: mpsc::Receiver<DriverEvent<DroneEvent>>,
    driver: JoinHandle<(LinkedDrone, IoStats)>,
    anemometer: Option<AnemometerLink>,
}

/// Reads the drone of a [`Flight`] between two of its steps.
#[derive(Debug, Clone)]
pub struct FlightHandle {
    actions: mpsc::WeakSender<Action<LinkedDrone>>,
}

impl FlightHandle {
    /// `f` of the drone as it is between two steps; `None` once the flight has ended.
    pub async fn query<T: Send + 'static>(
        &self,
        f: impl FnOnce(&LinkedDrone) -> T + Send + 'static,
    ) -> Option<T> {
        let (tx, rx) = tokio::sync::oneshot::channel();
        let ask: Action<LinkedDrone> = Box::new(move |d, _| {
            let _ = tx.send(f(d));
        });
        // A strong sender only for this request: the flight's end still closes the channel.
        self.actions.upgrade()?.send(ask).await.ok()?;
        rx.await.ok()
    }
}

impl Flight {
    /// Builds the drone of `options.mission`, opens the ground anemometer's socket (if
    /// asked) and the link, starts signing and the driver.
    /// A refused input is an error for which [`FlyError::is_input`] holds; nothing is opened
    /// for a drone that cannot be built.
    pub async fn start(options: FlyOptions) -> Result<Self, FlyError> {
        let mission = options.mission.name.clone();
        // The drone's truth is the options' vehicle, or a draw around it (vehicle and sensors,
        // from the mission's seed); its onboard software keeps the mission's own polar, as on a
        // real flight.
        let drone = Drone::with_truth(
            &options.mission,
            &options.vehicle,
            options.dispersions.as_ref(),
        )
        .map_err(|e| match e {
            DispersedDroneError::Vehicle(source) => FlyError::Dispersed {
                mission: mission.clone(),
                source,
            },
            DispersedDroneError::Drone(source) => FlyError::Drone {
                mission: mission.clone(),
                source,
            },
        })?;
        let anemometer = match options.anemometer_to {
            Some(to) => Some(
                AnemometerLink::open(to, &drone)
                    .await
                    .map_err(|source| FlyError::Anemometer { to, source })?,
            ),
            None => None,
        };
        let transport = Transport::open_str(&options.connect)
            .await
            .map_err(|source| FlyError::Open {
                address: options.connect.clone(),
                source,
            })?;
        if let Some(address) = transport.listening_address() {
            tracing::info!(%address, "drone link listening");
        }
        let mut link = options.link.clone();
        link.signing = None;
        if let Some(signing) = &options.signing {
            let unix = match signing.clock_unix {
                Some(t) => t,
                None => SystemTime::now()
                    .duration_since(UNIX_EPOCH)
                    .map_err(|_| FlyError::Clock)?,
            };
            link.signing = Some(
                start_signing(signing.key.clone(), unix, Some(&signing.timestamp_file))
                    .map_err(FlyError::Signing)?,
            );
        }
        tracing::info!(
            %mission,
            connect = %options.connect,
            speed = %options.speed,
            stage = %stage_name(drone.stage()),
            "drone starting"
        );
        let linked = LinkedDrone::new(drone, link, Duration::ZERO).map_err(FlyError::Link)?;
        let timestamp_file = options.signing.map(|s| s.timestamp_file);
        persist_signing_mark(&linked, timestamp_file.as_deref()).map_err(FlyError::PersistMark)?;

        let (actions, action_rx) = mpsc::channel(STEPS_IN_FLIGHT);
        let (event_tx, events) = mpsc::channel(EVENTS_QUEUED);
        let driver = tokio::spawn(drive(
            transport,
            linked,
            action_rx,
            event_tx,
            DriveOptions {
                signing_timestamp_file: timestamp_file,
            },
        ));
        Ok(Self {
            speed: options.speed,
            linger: options.linger,
            actions,
            events,
            driver,
            anemometer,
        })
    }

    /// A handle to read the drone while it flies.
    pub fn handle(&self) -> FlightHandle {
        FlightHandle {
            actions: self.actions.downgrade(),
        }
    }

    /// Flies until the drone has landed and lingered, or until `shutdown` resolves (then the
    /// report says `interrupted`); the steps already handed to the link are flown and their
    /// telemetry sent before it returns. `observer` sees every step and event.
    pub async fn run(
        self,
        shutdown: impl Future<Output = ()> + Send,
        mut observer: impl FlightObserver,
    ) -> Result<FlightReport, FlyError> {
        let Flight {
            speed,
            linger,
            actions,
            mut events,
            mut driver,
            mut anemometer,
        } = self;
        let started = Instant::now();
        let clock = tokio::time::Instant::now();
        let mut pacer = Pacer::new(speed, CONTROL_PERIOD_S, Duration::ZERO);
        let (report_tx, mut reports) = mpsc::unbounded_channel::<Result<StepReport, DroneError>>();
        let mut landed_at: Option<Instant> = None;
        let mut interrupted = false;
        tokio::pin!(shutdown);
        loop {
            if let (Some(at), Some(linger)) = (landed_at, linger)
                && at.elapsed() >= linger
            {
                break;
            }
            let due = pacer.due().map(|d| clock + d);
            tokio::select! {
                biased;
                () = &mut shutdown => {
                    interrupted = true;
                    break;
                }
                Some(report) = reports.recv() => {
                    let r = report.map_err(FlyError::Simulation)?;
                    observer.step(&r);
                    if let Some(a) = &mut anemometer {
                        a.step(r.time_s).await;
                    }
                    if r.landed && landed_at.is_none() {
                        landed_at = Some(Instant::now());
                        pacer.landed(clock.elapsed());
                        tracing::info!(
                            mission_time_s = format!("{:.1}", r.time_s),
                            wall_time_s = format!("{:.2}", started.elapsed().as_secs_f64()),
                            "landed"
                        );
                    }
                }
                Some(event) = events.recv() => {
                    log_event(&event);
                    observer.event(&event);
                }
                permit = slot_after(&actions, due) => {
                    let permit = permit.map_err(|_| FlyError::LinkStopped)?;
                    permit.send(step_action(report_tx.clone()));
                    pacer.stepped(clock.elapsed());
                }
            }
        }
        // Closing the channel ends the driver once it has run the steps queued and sent what
        // they produced; its events are read meanwhile, so it never waits on a full queue.
        drop(actions);
        let joined = loop {
            tokio::select! {
                joined = &mut driver => break joined,
                Some(event) = events.recv() => {
                    log_event(&event);
                    observer.event(&event);
                }
            }
        };
        let (linked, io) = joined.map_err(FlyError::LinkTask)?;
        while let Ok(event) = events.try_recv() {
            log_event(&event);
            observer.event(&event);
        }
        while let Ok(report) = reports.try_recv() {
            report.map_err(FlyError::Simulation)?;
        }
        if interrupted {
            tracing::info!("interrupted: stopping");
        }
        let mission = linked.drone().summary();
        Ok(FlightReport {
            landed: mission.landing.is_some(),
            mission,
            speed: speed.to_string(),
            wall_time_s: started.elapsed().as_secs_f64(),
            interrupted,
            link: linked.counters(),
            io,
            anemometer: anemometer.as_ref().map(AnemometerLink::counters),
        })
    }
}

/// Flies `options` from start to end: [`Flight::start`] then [`Flight::run`].
pub async fn fly(
    options: FlyOptions,
    shutdown: impl Future<Output = ()> + Send,
    observer: impl FlightObserver,
) -> Result<FlightReport, FlyError> {
    Flight::start(options).await?.run(shutdown, observer).await
}

/// A place in the action channel, once `due` (if any) has come.
async fn slot_after(
    actions: &mpsc::Sender<Action<LinkedDrone>>,
    due: Option<tokio::time::Instant>,
) -> Result<mpsc::Permit<'_, Action<LinkedDrone>>, mpsc::error::SendError<()>> {
    if let Some(due) = due {
        tokio::time::sleep_until(due).await;
    }
    actions.reserve().await
}

/// A step of the linked drone, run by the driver; its report (or the simulation's failure)
/// goes back on `reports`.
fn step_action(
    reports: mpsc::UnboundedSender<Result<StepReport, DroneError>>,
) -> Action<LinkedDrone> {
    Box::new(move |linked, now| {
        let attitude_before = linked.last_attitude_time_boot_ms();
        let result = linked
            .step(now)
            .map(|()| StepReport::of(linked, attitude_before));
        let _ = reports.send(result);
    })
}
