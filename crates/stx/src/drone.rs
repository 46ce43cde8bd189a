//! `stx drone`: the simulated drone on a real MAVLink link.
//!
//! A thin tokio adapter around the pure [`stx_sim::drone::Drone`]: it loads and validates the
//! mission (exit code 2 on a bad name, file or flag), opens the transport, and runs two tasks:
//!
//! - the **link** task is stx-link's [`drive`], running a [`VehicleEndpoint`] over the
//!   transport on the wall monotonic clock (heartbeats at 1 Hz, retries, stick staleness are
//!   all real time, whatever the simulation's speed). The endpoint is wrapped in
//!   [`GatedVehicle`], which applies the mission's link failures (link-drop windows, random
//!   packet loss) to every datagram in and out;
//! - the **simulation** task steps the drone one control period (0.25 s of mission time) at a
//!   time, paced at `--speed N` times real time or as fast as it goes (`--speed max`), feeds it
//!   what the endpoint reports (commands, parameter changes, plans, sticks, link state) and
//!   hands the endpoint what the drone sends, as actions run on the driven endpoint.
//!
//! Commands are answered as soon as they arrive (between two steps), not at the next step.
//! At `--speed max` the simulation yields to the runtime between steps and waits when the
//! link falls behind (the action channel is bounded), so telemetry is paced by what the socket
//! takes and nothing piles up.
//!
//! The process exits 0 once the drone has landed and its last telemetry has been handed to the
//! socket (after `--linger S` more seconds of answering on the ground, if asked), on Ctrl-C,
//! and 1 if the simulation fails. It prints one JSON summary line on stdout at the end: the
//! mission, whether and where it landed, mission and wall time, and the link's counters.

use std::fmt;
use std::str::FromStr;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use anyhow::{Context, anyhow};
use clap::Args;
use serde::Serialize;
use stx_dynamics::vehicle::Vehicle;
use stx_gnc::mission::FlightStage;
use stx_link::command::CommandResult;
use stx_link::endpoint::{LinkEvent, VehicleConfig, VehicleEndpoint, VehicleEvent};
use stx_link::manual::ManualEvent;
use stx_link::signing::{SigningConfig, SigningKey};
use stx_link::transport::{
    Action, DriveOptions, DriverEvent, IoEvent, IoStats, SansIo, Transport, drive,
};
use stx_sim::drone::failures::{LinkFaults, StuckServo, parse_window};
use stx_sim::drone::{Drone, MissionConfig, Output, stage_name};
use tokio::sync::mpsc;

use crate::BadInput;

/// How fast mission time runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Speed {
    /// This many times real time.
    Times(f64),
    /// As fast as the computer goes.
    Max,
}

impl FromStr for Speed {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        if s == "max" {
            return Ok(Self::Max);
        }
        match s.parse::<f64>() {
            Ok(v) if v > 0.0 && v.is_finite() => Ok(Self::Times(v)),
            _ => Err(format!(
                "{s:?} is not a speed: a number > 0 (times real time) or `max`"
            )),
        }
    }
}

impl fmt::Display for Speed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Times(v) => write!(f, "{v}x"),
            Self::Max => write!(f, "max"),
        }
    }
}

#[derive(Args, Debug)]
pub struct DroneArgs {
    /// Where the station is: udpout:HOST:PORT (the station's udpin), udpin:, tcp:, tcpin:,
    /// serial:PATH:BAUD.
    #[arg(long, default_value = "udpout:127.0.0.1:14550")]
    connect: String,
    /// A built-in mission (mission, mission-short) or a path to a mission TOML file.
    #[arg(long, default_value = "mission")]
    scenario: String,
    /// Mission time per real time: a number (1 = real time) or `max`.
    #[arg(long, default_value = "1")]
    speed: Speed,
    /// Seed of everything random (replaces the scenario's).
    #[arg(long)]
    seed: Option<u64>,
    /// MAVLink 2 signing key, 64 hex digits (32 bytes); unsigned traffic is then refused.
    #[arg(long, value_name = "HEX")]
    sign_key: Option<String>,
    /// Share of datagrams lost at random each way, % (replaces the scenario's).
    #[arg(long, value_name = "PCT")]
    packet_loss: Option<f64>,
    /// Link down both ways from FROM to TO seconds of mission time (repeatable).
    #[arg(long, value_name = "FROM:TO")]
    link_drop: Vec<String>,
    /// GPS silent from FROM to TO seconds of mission time (repeatable).
    #[arg(long, value_name = "FROM:TO")]
    gps_loss: Vec<String>,
    /// A servo (main, right, left) stuck from T seconds of mission time: e.g. `left@300`.
    #[arg(long, value_name = "SERVO@T")]
    stuck_servo: Option<String>,
    /// Seconds of real time to keep answering on the ground after landing.
    #[arg(long, default_value = "0", value_name = "S")]
    linger: f64,
    /// MAVLink system id of the drone.
    #[arg(long, default_value = "1")]
    system_id: u8,
}

/// Reads a mission by built-in name or path, with the command line's overrides applied.
fn load_mission(args: &DroneArgs) -> anyhow::Result<MissionConfig> {
    let path = std::path::Path::new(&args.scenario);
    let mut config = if args.scenario.ends_with(".toml") || path.exists() {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read mission file {}", path.display()))
            .map_err(BadInput)?;
        MissionConfig::from_toml_str(&args.scenario, &text).map_err(|e| BadInput(e.into()))?
    } else {
        MissionConfig::builtin(&args.scenario).map_err(|e| BadInput(e.into()))?
    };
    let bad = |e: anyhow::Error| anyhow::Error::from(BadInput(e));
    if let Some(seed) = args.seed {
        config.seed = seed;
    }
    if let Some(pct) = args.packet_loss {
        config.failures.packet_loss_pct = pct;
    }
    for w in &args.link_drop {
        let window = parse_window(w).map_err(|e| bad(anyhow!("--link-drop: {e}")))?;
        config.failures.link_drop_s.push(window);
    }
    for w in &args.gps_loss {
        let window = parse_window(w).map_err(|e| bad(anyhow!("--gps-loss: {e}")))?;
        config.failures.gps_loss_s.push(window);
    }
    if let Some(s) = &args.stuck_servo {
        let stuck: StuckServo = s.parse().map_err(|e| bad(anyhow!("--stuck-servo: {e}")))?;
        config.failures.stuck_servo = Some(stuck);
    }
    config
        .validate()
        .map_err(|e| bad(anyhow::Error::from(e).context("with the command line's failures")))?;
    if !(args.linger >= 0.0 && args.linger.is_finite()) {
        return Err(bad(anyhow!(
            "--linger {}: must be ≥ 0 seconds",
            args.linger
        )));
    }
    Ok(config)
}

fn parse_key(hex: &str) -> anyhow::Result<SigningKey> {
    let hex = hex.trim();
    let bad = || {
        // The text is a secret: never echo it.
        anyhow::Error::from(BadInput(anyhow!(
            "--sign-key: expected 64 hexadecimal digits (32 bytes)"
        )))
    };
    if hex.len() != 64 || !hex.is_ascii() {
        return Err(bad());
    }
    let mut bytes = [0_u8; 32];
    for (i, b) in bytes.iter_mut().enumerate() {
        *b = u8::from_str_radix(hex.get(2 * i..2 * i + 2).ok_or_else(bad)?, 16)
            .map_err(|_| bad())?;
    }
    Ok(SigningKey::from_bytes(bytes))
}

/// The vehicle endpoint with the mission's link failures applied to every datagram.
pub struct GatedVehicle {
    endpoint: VehicleEndpoint,
    faults: LinkFaults,
    /// Mission time of the simulation's last step, s: where the failure windows are read.
    mission_time_s: f64,
}

impl SansIo for GatedVehicle {
    type Event = VehicleEvent;

    fn handle_bytes(&mut self, now: Duration, bytes: &[u8]) {
        if !self.faults.drops_datagram(self.mission_time_s) {
            self.endpoint.handle_bytes(now, bytes);
        }
    }

    fn handle_timeout(&mut self, now: Duration) {
        self.endpoint.handle_timeout(now);
    }

    fn poll_timeout(&self) -> Option<Duration> {
        self.endpoint.poll_timeout()
    }

    fn poll_transmit(&mut self, now: Duration) -> Option<Vec<u8>> {
        // Every frame is one datagram on UDP: a lost one is simply not sent.
        loop {
            let frame = self.endpoint.poll_transmit(now)?;
            if !self.faults.drops_datagram(self.mission_time_s) {
                return Some(frame);
            }
        }
    }

    fn poll_event(&mut self) -> Option<VehicleEvent> {
        self.endpoint.poll_event()
    }

    fn persist_request(event: &VehicleEvent) -> Option<u64> {
        match event {
            VehicleEvent::Link(LinkEvent::PersistSigningTimestamp(v)) => Some(*v),
            _ => None,
        }
    }
}

/// The summary printed at the end (one JSON line on stdout).
#[derive(Debug, Serialize)]
struct RunSummary {
    mission: String,
    speed: String,
    landed: bool,
    landing: Option<stx_sim::drone::Landing>,
    mission_time_s: f64,
    wall_time_s: f64,
    stages: Vec<(String, f64)>,
    interrupted: bool,
    io: Option<IoStats>,
    datagrams_dropped_link_down: u64,
    datagrams_dropped_random: u64,
}

pub fn run(args: DroneArgs) -> anyhow::Result<()> {
    let config = load_mission(&args)?;
    let signing = args.sign_key.as_deref().map(parse_key).transpose()?;
    let drone = Drone::new(&config, Vehicle::straplex())
        .with_context(|| format!("building the drone of mission {}", config.name))
        .map_err(BadInput)?;
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .context("starting the tokio runtime")?;
    let summary = runtime.block_on(fly(args, drone, signing))?;
    println!("{}", serde_json::to_string(&summary)?);
    Ok(())
}

/// Steps at most this far behind the link before waiting for it (the action channel's size).
const ACTIONS_IN_FLIGHT: usize = 64;

async fn fly(
    args: DroneArgs,
    drone: Drone,
    signing: Option<SigningKey>,
) -> anyhow::Result<RunSummary> {
    let transport = Transport::open_str(&args.connect)
        .await
        .with_context(|| format!("opening {}", args.connect))
        .map_err(BadInput)?;
    let mut vehicle_config = VehicleConfig::default();
    vehicle_config.link.system_id = args.system_id;
    vehicle_config.params = drone.param_specs();
    vehicle_config.manual_timeout = Duration::from_secs_f64(drone.manual_timeout_s());
    vehicle_config.initial_status = drone.status();
    if let Some(key) = signing {
        let unix = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .context("the system clock is before 1970")?;
        vehicle_config.link.signing = Some(SigningConfig::new(key, 0, unix));
    }
    let mut endpoint = VehicleEndpoint::new(vehicle_config, Duration::ZERO)
        .context("building the drone's parameter table")?;
    endpoint.set_plan(drone.plan_items());
    let gated = GatedVehicle {
        endpoint,
        faults: drone.link_faults(),
        mission_time_s: drone.time_s(),
    };
    tracing::info!(
        mission = %drone.config().name,
        connect = %args.connect,
        speed = %args.speed,
        stage = %stage_name(drone.stage()),
        "drone starting"
    );

    let (action_tx, action_rx) = mpsc::channel::<Action<GatedVehicle>>(ACTIONS_IN_FLIGHT);
    let (event_tx, mut event_rx) = mpsc::channel(1024);
    let link = tokio::spawn(drive(
        transport,
        gated,
        action_rx,
        event_tx,
        DriveOptions::default(),
    ));

    let started = Instant::now();
    let mut sim = Simulation {
        drone,
        actions: action_tx,
        responses: Vec::new(),
        pending: Vec::new(),
        last_progress: Instant::now(),
        last_stage: None,
    };
    let period_s = stx_sim::guided::CONTROL_PERIOD_S;
    let mission_t0 = sim.drone.time_s();
    let mut pace_from = (tokio::time::Instant::now(), mission_t0);
    let mut landed_at: Option<Instant> = None;
    let mut interrupted = false;
    let mut steps: u64 = 0;
    let ctrl_c = tokio::signal::ctrl_c();
    tokio::pin!(ctrl_c);
    loop {
        if let Some(at) = landed_at
            && at.elapsed().as_secs_f64() >= args.linger
        {
            break;
        }
        // On the ground after landing the drone answers in real time; in flight at the
        // requested speed.
        let speed = match (args.speed, landed_at) {
            (_, Some(_)) => Speed::Times(1.0),
            (s, None) => s,
        };
        match speed {
            Speed::Max => {
                while let Ok(event) = event_rx.try_recv() {
                    sim.handle(event);
                }
                sim.flush().await?;
                tokio::select! {
                    biased;
                    _ = &mut ctrl_c => { interrupted = true; break; }
                    _ = tokio::task::yield_now() => {}
                }
                sim.step().await?;
            }
            Speed::Times(times) => {
                let due = pace_from.0
                    + Duration::from_secs_f64(
                        ((sim.drone.time_s() + period_s - pace_from.1) / times).max(0.0),
                    );
                tokio::select! {
                    biased;
                    _ = &mut ctrl_c => { interrupted = true; break; }
                    event = event_rx.recv() => match event {
                        Some(e) => { sim.handle(e); sim.flush().await?; continue; }
                        None => return Err(anyhow!("the link task stopped")),
                    },
                    _ = tokio::time::sleep_until(due) => {}
                }
                sim.step().await?;
                // A slow step (a prediction, a slow machine) is not made up for by running
                // fast afterwards: pacing restarts from now when it falls a second behind.
                if tokio::time::Instant::now() > due + Duration::from_secs(1) {
                    pace_from = (tokio::time::Instant::now(), sim.drone.time_s());
                }
            }
        }
        steps += 1;
        if landed_at.is_none() && sim.drone.landing().is_some() {
            landed_at = Some(Instant::now());
            pace_from = (tokio::time::Instant::now(), sim.drone.time_s());
            let l = sim.drone.landing();
            tracing::info!(
                mission_time_s = sim.drone.time_s(),
                wall_time_s = started.elapsed().as_secs_f64(),
                miss_m = ?l.and_then(|l| l.miss_m),
                steps,
                "landed"
            );
        }
    }
    sim.flush().await?;
    let Simulation { drone, actions, .. } = sim;
    // Closing the channel ends the link task once it has sent what it was handed.
    drop(actions);
    drop(event_rx);
    let (gated, io) = match link.await {
        Ok((gated, io)) => (Some(gated), Some(io)),
        Err(e) => {
            tracing::error!(error = %e, "link task failed");
            (None, None)
        }
    };
    if interrupted {
        tracing::info!("interrupted: stopping");
    }
    Ok(RunSummary {
        mission: drone.config().name.clone(),
        speed: args.speed.to_string(),
        landed: drone.landing().is_some(),
        landing: drone.landing(),
        mission_time_s: drone.time_s(),
        wall_time_s: started.elapsed().as_secs_f64(),
        stages: drone
            .stage_log()
            .iter()
            .map(|(s, t)| (stage_name(*s), *t))
            .collect(),
        interrupted,
        io,
        datagrams_dropped_link_down: gated.as_ref().map_or(0, |g| g.faults.dropped_down),
        datagrams_dropped_random: gated.as_ref().map_or(0, |g| g.faults.dropped_random),
    })
}

/// The simulation side: the drone, and what it owes the link.
struct Simulation {
    drone: Drone,
    actions: mpsc::Sender<Action<GatedVehicle>>,
    /// Command results not yet handed to the endpoint.
    responses: Vec<(stx_link::command::IncomingId, CommandResult)>,
    /// Other actions not yet handed to the endpoint, in order.
    pending: Vec<Action<GatedVehicle>>,
    last_progress: Instant,
    last_stage: Option<FlightStage>,
}

impl Simulation {
    /// Takes one event from the link.
    fn handle(&mut self, event: DriverEvent<VehicleEvent>) {
        match event {
            DriverEvent::Endpoint(e) => self.endpoint_event(e),
            DriverEvent::Io(e) => match e {
                IoEvent::RecvError { .. } | IoEvent::SendError { .. } => {
                    tracing::warn!(event = ?e, "link I/O error");
                }
                IoEvent::QueuedWithoutPeer { .. } => {}
                other => tracing::info!(event = ?other, "link"),
            },
        }
    }

    fn endpoint_event(&mut self, event: VehicleEvent) {
        match event {
            VehicleEvent::Command(c) => {
                let result = self.drone.handle_command(&c.command);
                tracing::info!(command = ?c.command, ?result, from = ?c.from, "command");
                self.responses.push((c.id, result));
            }
            VehicleEvent::ParamChanged(change) => {
                match self.drone.set_param(&change.name, change.new) {
                    Ok(()) => {
                        tracing::info!(name = %change.name, value = change.new, "parameter set");
                        if change.name == "MAN_TIMEOUT_S" {
                            let timeout = Duration::from_secs_f64(self.drone.manual_timeout_s());
                            self.act(move |ep, _| ep.endpoint.set_manual_timeout(timeout));
                        }
                    }
                    Err(e) => {
                        // The link's table took a value the drone refuses (a rule between
                        // parameters): put the old one back, which announces it.
                        tracing::warn!(name = %change.name, error = %e, "parameter refused");
                        let text = format!("PARAM {}: {e}", change.name);
                        self.act(move |ep, now| {
                            let _ = ep.endpoint.params_mut().set(&change.name, change.old);
                            ep.endpoint.send_status_text(
                                now,
                                stx_link::telemetry::Severity::Warning,
                                &text,
                            );
                        });
                    }
                }
            }
            VehicleEvent::PlanReceived(items) => {
                tracing::info!(items = items.len(), "plan received");
                self.drone.handle_plan(&items);
            }
            VehicleEvent::Manual(ManualEvent::Sticks(s)) => self.drone.set_sticks(Some(s)),
            VehicleEvent::Manual(ManualEvent::Stale { since_last }) => {
                tracing::info!(?since_last, "sticks stale");
                self.drone.set_sticks(None);
            }
            VehicleEvent::Link(LinkEvent::Connected {
                system_id,
                component_id,
            }) => {
                tracing::info!(system_id, component_id, "station connected");
                self.drone.link_changed(true);
            }
            VehicleEvent::Link(LinkEvent::Lost {
                system_id,
                since_last,
            }) => {
                tracing::warn!(system_id, ?since_last, "station lost: flying the plan");
                self.drone.link_changed(false);
            }
            VehicleEvent::Link(LinkEvent::FrameError(e)) => {
                tracing::debug!(error = ?e, "frame dropped");
            }
            VehicleEvent::Link(LinkEvent::PersistSigningTimestamp(_)) => {}
            VehicleEvent::Other(frame) => {
                tracing::debug!(message = ?frame.message, "message not handled");
            }
        }
    }

    /// Queues an action on the endpoint, handed over by the next [`flush`](Self::flush).
    fn act(&mut self, f: impl FnOnce(&mut GatedVehicle, Duration) + Send + 'static) {
        self.pending.push(Box::new(f));
    }

    /// Hands the endpoint what the drone has to send: command results first (every command
    /// is answered at once), then telemetry and texts, and the heartbeat's status.
    async fn flush(&mut self) -> anyhow::Result<()> {
        let mut outputs = Vec::new();
        while let Some(o) = self.drone.poll_output() {
            if let Output::Text { severity, text } = &o {
                tracing::info!(
                    t = format!("{:.1}", self.drone.time_s()),
                    severity = ?severity,
                    "{text}"
                );
            }
            outputs.push(o);
        }
        for action in std::mem::take(&mut self.pending) {
            self.actions
                .send(action)
                .await
                .map_err(|_| anyhow!("the link task stopped"))?;
        }
        let responses = std::mem::take(&mut self.responses);
        let status = self.drone.status();
        let mission_time_s = self.drone.time_s();
        let action: Action<GatedVehicle> = Box::new(move |ep, now| {
            ep.mission_time_s = mission_time_s;
            for (id, result) in responses {
                ep.endpoint.respond_command(id, result);
            }
            ep.endpoint.set_status(status);
            for o in outputs {
                match o {
                    Output::Telemetry(t) => ep.endpoint.send_telemetry(now, &t),
                    Output::Text { severity, text } => {
                        ep.endpoint.send_status_text(now, severity, &text);
                    }
                }
            }
        });
        self.actions
            .send(action)
            .await
            .map_err(|_| anyhow!("the link task stopped"))
    }

    /// One control period, then what it produced goes to the link.
    async fn step(&mut self) -> anyhow::Result<()> {
        self.drone
            .step()
            .with_context(|| format!("simulation failed at t = {:.2} s", self.drone.time_s()))?;
        self.flush().await?;
        let stage = self.drone.stage();
        if self.last_stage != Some(stage) || self.last_progress.elapsed() >= Duration::from_secs(5)
        {
            self.last_stage = Some(stage);
            self.last_progress = Instant::now();
            let truth = self.drone.physics().truth();
            tracing::info!(
                t = format!("{:.0}", self.drone.time_s()),
                stage = %stage_name(stage),
                mode = ?self.drone.mode(),
                phase = ?self.drone.status().phase,
                alt_msl_m = format!("{:.0}", self.drone.config().site.alt_msl_m - truth.position_ned_m.z),
                "progress"
            );
        }
        Ok(())
    }
}
