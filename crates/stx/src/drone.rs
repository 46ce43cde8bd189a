//! `stx drone`: the simulated drone on a real MAVLink link.
//!
//! A thin tokio adapter around the pure [`LinkedDrone`] (the drone of `stx_sim::drone` behind
//! its stx-link `VehicleEndpoint`, with the rehearsal's link failures): it loads and validates
//! the mission (exit code 2 on a bad name, file or flag), opens the transport and hands the
//! linked drone to stx-link's [`drive`], which feeds it the datagrams and timers on the wall
//! monotonic clock — heartbeats at 1 Hz, the station's liveness, stick staleness and retries
//! all run in real time whatever the simulation's speed. The simulation's steps go in as the
//! driver's actions, one control period (0.25 s of mission time) each:
//!
//! - at `--speed N` the pacing task sends a step every `0.25/N` s of real time and waits for
//!   its report;
//! - at `--speed max` it sends steps as fast as the driver takes them (the action channel is
//!   bounded, so steps queue behind the socket's traffic, never ahead of it), and the driver
//!   still serves incoming datagrams between two steps, so commands are answered within a step.
//!
//! The process exits 0 once the drone has landed and its last telemetry has been handed to the
//! socket (after `--linger S` more seconds of answering on the ground, at real time, if asked)
//! or on Ctrl-C, and 1 if the simulation fails. Progress (stage, altitude, mode, phase) and the
//! drone's texts are logged at info level; `--summary-json` prints the mission's figures
//! ([`stx_sim::drone::MissionSummary`]) with the run's wall time and link counters as one JSON
//! line on stdout.

use std::fmt;
use std::str::FromStr;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use anyhow::{Context, anyhow};
use clap::Args;
use serde::Serialize;
use stx_dynamics::vehicle::Vehicle;
use stx_gnc::mission::{FlightMode, FlightStage, GuidancePhase};
use stx_link::endpoint::LinkConfig;
use stx_link::signing::{SigningConfig, SigningKey};
use stx_link::transport::{Action, DriveOptions, DriverEvent, IoEvent, IoStats, Transport, drive};
use stx_sim::drone::failures::{StuckServo, parse_window};
use stx_sim::drone::link::{DroneEvent, LinkCounters, LinkedDrone};
use stx_sim::drone::{Drone, MissionConfig, MissionSummary, stage_name};
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
    /// Print the mission's figures as one JSON line on stdout at the end.
    #[arg(long)]
    summary_json: bool,
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
    // Windows are FROM:TO on the command line (FROM..TO, the scenario file's form, too).
    let window = |flag: &str, w: &str| {
        let text = if w.contains("..") {
            w.to_string()
        } else {
            w.replacen(':', "..", 1)
        };
        parse_window(&text).map_err(|_| {
            bad(anyhow!(
                "{flag} {w:?}: expected FROM:TO, seconds of mission time with 0 ≤ FROM < TO"
            ))
        })
    };
    for w in &args.link_drop {
        config.failures.link_drop_s.push(window("--link-drop", w)?);
    }
    for w in &args.gps_loss {
        config.failures.gps_loss_s.push(window("--gps-loss", w)?);
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

/// What `--summary-json` prints: the mission's figures and how the run went.
#[derive(Debug, Serialize)]
struct RunSummary {
    #[serde(flatten)]
    mission: MissionSummary,
    /// Whether the drone landed.
    landed: bool,
    /// `--speed`.
    speed: String,
    /// Real time of the run, s.
    wall_time_s: f64,
    /// Stopped by Ctrl-C.
    interrupted: bool,
    /// The drone's side of the link.
    link: Option<LinkCounters>,
    /// The socket.
    io: Option<IoStats>,
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
    let summary_json = args.summary_json;
    let summary = runtime.block_on(fly(args, drone, signing))?;
    if summary_json {
        println!("{}", serde_json::to_string(&summary)?);
    }
    Ok(())
}

/// Steps handed to the driver ahead of its progress at `--speed max`.
const STEPS_IN_FLIGHT: usize = 16;

/// What one step reports back to the pacing task.
#[derive(Debug, Clone, Copy)]
struct StepReport {
    time_s: f64,
    stage: FlightStage,
    mode: FlightMode,
    phase: GuidancePhase,
    altitude_msl_m: f64,
    landed: bool,
}

/// A step of the linked drone, run by the driver; its report (or the simulation's failure)
/// goes back on `reports`.
fn step_action(reports: mpsc::UnboundedSender<Result<StepReport, String>>) -> Action<LinkedDrone> {
    Box::new(move |linked, now| {
        let result = linked.step(now).map_err(|e| e.to_string()).map(|()| {
            let d = linked.drone();
            let status = d.status();
            StepReport {
                time_s: d.time_s(),
                stage: status.stage,
                mode: status.mode,
                phase: status.phase,
                altitude_msl_m: d.physics().altitude_msl_m(),
                landed: linked.landed(),
            }
        });
        let _ = reports.send(result);
    })
}

async fn fly(
    args: DroneArgs,
    drone: Drone,
    signing: Option<SigningKey>,
) -> anyhow::Result<RunSummary> {
    let transport = Transport::open_str(&args.connect)
        .await
        .with_context(|| format!("opening {}", args.connect))
        .map_err(BadInput)?;
    let mut link = LinkConfig::vehicle();
    link.system_id = args.system_id;
    if let Some(key) = signing {
        let unix = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .context("the system clock is before 1970")?;
        link.signing = Some(SigningConfig::new(key, 0, unix));
    }
    tracing::info!(
        mission = %drone.config().name,
        connect = %args.connect,
        speed = %args.speed,
        stage = %stage_name(drone.stage()),
        "drone starting"
    );
    let linked =
        LinkedDrone::new(drone, link, Duration::ZERO).context("putting the drone on the link")?;

    let (action_tx, action_rx) = mpsc::channel::<Action<LinkedDrone>>(STEPS_IN_FLIGHT);
    let (event_tx, mut event_rx) = mpsc::channel(4096);
    let driver = tokio::spawn(drive(
        transport,
        linked,
        action_rx,
        event_tx,
        DriveOptions::default(),
    ));
    // The driver's events are the drone's log: texts, commands, parameters, link state.
    let logger = tokio::spawn(async move {
        while let Some(event) = event_rx.recv().await {
            log_event(event);
        }
    });

    let started = Instant::now();
    let (report_tx, mut report_rx) = mpsc::unbounded_channel();
    let period_s = stx_sim::guided::CONTROL_PERIOD_S;
    let mut pace_from = (tokio::time::Instant::now(), 0_u64);
    let mut sent: u64 = 0;
    let mut landed_at: Option<Instant> = None;
    let mut interrupted = false;
    let mut last_progress = Instant::now();
    let mut last_stage = None;
    let ctrl_c = tokio::signal::ctrl_c();
    tokio::pin!(ctrl_c);
    let send_step = |tx: &mpsc::Sender<Action<LinkedDrone>>| {
        let action = step_action(report_tx.clone());
        let tx = tx.clone();
        async move {
            tx.send(action)
                .await
                .map_err(|_| anyhow!("the link task stopped"))
        }
    };
    'flight: loop {
        if let Some(at) = landed_at
            && at.elapsed().as_secs_f64() >= args.linger
        {
            break;
        }
        // After landing the drone answers on the ground in real time.
        let speed = if landed_at.is_some() {
            Speed::Times(1.0)
        } else {
            args.speed
        };
        match speed {
            Speed::Max => {
                tokio::select! {
                    biased;
                    _ = &mut ctrl_c => { interrupted = true; break 'flight; }
                    sent_ok = send_step(&action_tx) => { sent_ok?; sent += 1; }
                }
            }
            Speed::Times(times) => {
                let due = pace_from.0
                    + Duration::from_secs_f64((sent - pace_from.1 + 1) as f64 * period_s / times);
                tokio::select! {
                    biased;
                    _ = &mut ctrl_c => { interrupted = true; break 'flight; }
                    _ = tokio::time::sleep_until(due) => {}
                }
                send_step(&action_tx).await?;
                sent += 1;
                // A slow step is not made up for by running fast afterwards.
                if tokio::time::Instant::now() > due + Duration::from_secs(1) {
                    pace_from = (tokio::time::Instant::now(), sent);
                }
            }
        }
        // Reports of the steps done so far (at max speed the driver may be a few behind).
        while let Ok(report) = report_rx.try_recv() {
            let r = report.map_err(|e| anyhow!("simulation failed: {e}"))?;
            if last_stage != Some(r.stage) || last_progress.elapsed() >= Duration::from_secs(5) {
                last_stage = Some(r.stage);
                last_progress = Instant::now();
                tracing::info!(
                    t = format!("{:.0}", r.time_s),
                    stage = %stage_name(r.stage),
                    alt_msl_m = format!("{:.0}", r.altitude_msl_m),
                    mode = ?r.mode,
                    phase = ?r.phase,
                    "progress"
                );
            }
            if r.landed && landed_at.is_none() {
                landed_at = Some(Instant::now());
                pace_from = (tokio::time::Instant::now(), sent);
                tracing::info!(
                    mission_time_s = format!("{:.1}", r.time_s),
                    wall_time_s = format!("{:.2}", started.elapsed().as_secs_f64()),
                    "landed"
                );
            }
        }
    }
    // Closing the channel ends the driver once it has run the steps queued and sent what they
    // produced.
    drop(action_tx);
    let (linked, io) = driver.await.context("the link task failed")?;
    let _ = logger.await;
    while let Ok(report) = report_rx.try_recv() {
        report.map_err(|e| anyhow!("simulation failed: {e}"))?;
    }
    if interrupted {
        tracing::info!("interrupted: stopping");
    }
    let mission = linked.drone().summary();
    Ok(RunSummary {
        landed: mission.landing.is_some(),
        mission,
        speed: args.speed.to_string(),
        wall_time_s: started.elapsed().as_secs_f64(),
        interrupted,
        link: Some(linked.counters()),
        io: Some(io),
    })
}

fn log_event(event: DriverEvent<DroneEvent>) {
    match event {
        DriverEvent::Endpoint(DroneEvent::Text {
            time_s,
            severity,
            text,
        }) => tracing::info!(t = format!("{time_s:.1}"), ?severity, "{text}"),
        DriverEvent::Endpoint(DroneEvent::Command {
            time_s,
            command,
            result,
        }) => tracing::info!(t = format!("{time_s:.1}"), ?command, ?result, "command"),
        DriverEvent::Endpoint(DroneEvent::Param {
            time_s,
            name,
            value,
            accepted,
        }) => tracing::info!(t = format!("{time_s:.1}"), %name, value, accepted, "parameter"),
        DriverEvent::Endpoint(DroneEvent::Plan { time_s, items }) => {
            tracing::info!(t = format!("{time_s:.1}"), items, "plan received");
        }
        DriverEvent::Endpoint(DroneEvent::Link { time_s, connected }) => {
            tracing::info!(t = format!("{time_s:.1}"), connected, "station link");
        }
        DriverEvent::Endpoint(DroneEvent::PersistSigningTimestamp(_)) => {}
        DriverEvent::Io(e @ (IoEvent::RecvError { .. } | IoEvent::SendError { .. })) => {
            tracing::warn!(event = ?e, "link I/O error");
        }
        DriverEvent::Io(IoEvent::QueuedWithoutPeer { .. }) => {}
        DriverEvent::Io(e) => tracing::info!(event = ?e, "link"),
    }
}
