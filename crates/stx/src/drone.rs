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
//! or on Ctrl-C, and 1 if the simulation fails. Progress (stage, altitude, mode, phase) is a
//! progress bar on a terminal and info-level log lines otherwise; the drone's texts are logged
//! at info level; `--summary-json` prints the mission's figures
//! ([`stx_sim::drone::MissionSummary`]) with the run's wall time and link counters as one JSON
//! line on stdout.
//!
//! Signing: the key comes from `--sign-key-file FILE` or the environment variable
//! `STX_SIGNING_KEY` (64 hexadecimal characters), never from the command line, where `ps` and
//! shell histories would show it. The timestamp's high-water mark lives in
//! `--signing-timestamp-file` (default `drone-sys<ID>.signing.timestamp` in the state
//! directory: `$STATE_DIRECTORY`, `$XDG_STATE_HOME/stx` or `~/.local/state/stx`); it is written
//! before the first signed frame and ahead of every later one, so a restart with the clock set
//! back still signs above every timestamp already used.
//!
//! `--gains FILE` (a gains file as `stx tune` writes it) sets the onboard guidance's control
//! gains, which are also its parameters: the station reads and sets them over PARAM_*.
//!
//! A server address with port 0 (`udpin:…:0`, `tcpin:…:0`) is logged with the port actually
//! bound. Socket errors are counted in the report's `io` and logged by the transport at most
//! every few seconds with their count (a `tcpin:` link with no station yet fails every frame).
//!
//! The same flight is a library call for the station's `stx serve --sim`: [`fly`] with
//! [`DroneOptions`] and a shutdown future, returning a [`DroneReport`].

use std::ffi::OsString;
use std::fmt;
use std::future::Future;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use anyhow::{Context, anyhow};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use stx_dynamics::vehicle::Vehicle;
use stx_gnc::control::ControlGains;
use stx_gnc::mission::{FlightMode, FlightStage, GuidancePhase};
use stx_link::endpoint::LinkConfig;
use stx_link::sansio::{IoEvent, IoStats};
use stx_link::signing::persist::{default_state_dir, persist_signing_mark};
use stx_link::signing::{SIGNING_KEY_ENV, SigningKey};
use stx_link_tokio::{Action, DriveOptions, DriverEvent, Transport, drive};
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
    /// File holding the MAVLink 2 signing key, 64 hex digits (32 bytes); unsigned traffic is
    /// then refused. Or the key in the environment variable STX_SIGNING_KEY.
    #[arg(long, value_name = "FILE")]
    sign_key_file: Option<PathBuf>,
    /// Where the signing timestamp's high-water mark is kept across restarts (default:
    /// drone-sys<ID>.signing.timestamp in $STATE_DIRECTORY, $XDG_STATE_HOME/stx or
    /// ~/.local/state/stx).
    #[arg(long, value_name = "FILE")]
    signing_timestamp_file: Option<PathBuf>,
    /// Control gains of the onboard guidance (a gains file as `stx tune` writes it); they are
    /// its parameters' starting values.
    #[arg(long, value_name = "FILE")]
    gains: Option<PathBuf>,
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

/// Failures to inject on top of the scenario's own (`[failures]`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FailureFlags {
    /// Random loss of datagrams each way, % (replaces the scenario's).
    pub packet_loss_pct: Option<f64>,
    /// Link-drop windows, s of mission time (added to the scenario's).
    pub link_drop_s: Vec<[f64; 2]>,
    /// GPS-loss windows, s of mission time (added to the scenario's).
    pub gps_loss_s: Vec<[f64; 2]>,
    /// A stuck servo (replaces the scenario's).
    pub stuck_servo: Option<StuckServo>,
}

/// What [`fly`] flies, and how.
#[derive(Debug, Clone)]
pub struct DroneOptions {
    /// Where the station is, as an stx-link address: `udpout:127.0.0.1:14550` (the station's
    /// `udpin`), `udpin:…`, `tcp:…`, `tcpin:…`, `serial:PATH:BAUD`.
    pub connect: String,
    /// A built-in mission (`mission`, `mission-short`, `rehearsal`) or a mission TOML file.
    pub scenario: String,
    /// Mission time per real time.
    pub speed: Speed,
    /// Seed of everything random; `None` keeps the scenario's.
    pub seed: Option<u64>,
    /// Failures to inject.
    pub failures: FailureFlags,
    /// MAVLink 2 signing key; with one, unsigned traffic is refused.
    pub signing_key: Option<SigningKey>,
    /// File keeping the signing timestamp's high-water mark; required with a key.
    pub signing_timestamp_file: Option<PathBuf>,
    /// The wall-clock reading the signing clock starts from (time since the Unix epoch);
    /// `None` reads the system clock. Tests set it to rehearse a clock set back.
    pub signing_clock_unix: Option<Duration>,
    /// Control gains replacing the mission's (the onboard guidance's parameters).
    pub gains: Option<ControlGains>,
    /// The drone's MAVLink system id.
    pub system_id: u8,
    /// How long to keep answering on the ground after landing, real time; `None`: until the
    /// shutdown future resolves (what a station running the drone beside it wants).
    pub linger: Option<Duration>,
    /// Draw a progress bar on stderr when it is a terminal.
    pub progress: bool,
}

impl DroneOptions {
    /// Mission `scenario` towards `connect` in real time, the scenario's seed and failures,
    /// system id 1, no signing, stopping as soon as it has landed, no progress bar.
    pub fn new(connect: &str, scenario: &str) -> Self {
        Self {
            connect: connect.to_string(),
            scenario: scenario.to_string(),
            speed: Speed::Times(1.0),
            seed: None,
            failures: FailureFlags::default(),
            signing_key: None,
            signing_timestamp_file: None,
            signing_clock_unix: None,
            gains: None,
            system_id: 1,
            linger: Some(Duration::ZERO),
            progress: false,
        }
    }
}

/// Whether `options` name a mission that loads and validates, without flying it.
pub fn check_mission(options: &DroneOptions) -> anyhow::Result<()> {
    load_mission(options).map(drop)
}

/// Reads a mission by built-in name or path, with the options' overrides applied and
/// validated. Every error is the user's input ([`BadInput`], exit code 2).
fn load_mission(options: &DroneOptions) -> anyhow::Result<MissionConfig> {
    let path = std::path::Path::new(&options.scenario);
    let mut config = if options.scenario.ends_with(".toml") || path.exists() {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read mission file {}", path.display()))
            .map_err(BadInput)?;
        MissionConfig::from_toml_str(&options.scenario, &text).map_err(|e| BadInput(e.into()))?
    } else {
        MissionConfig::builtin(&options.scenario).map_err(|e| BadInput(e.into()))?
    };
    if let Some(seed) = options.seed {
        config.seed = seed;
    }
    let f = &options.failures;
    if let Some(pct) = f.packet_loss_pct {
        config.failures.packet_loss_pct = pct;
    }
    config.failures.link_drop_s.extend(&f.link_drop_s);
    config.failures.gps_loss_s.extend(&f.gps_loss_s);
    if let Some(stuck) = f.stuck_servo {
        config.failures.stuck_servo = Some(stuck);
    }
    if let Some(gains) = options.gains {
        config.onboard.guidance.gains = gains;
    }
    config.validate().map_err(|e| {
        BadInput(anyhow::Error::from(e).context("with the command line's failures"))
    })?;
    Ok(config)
}

impl DroneArgs {
    /// The options these flags (and the environment `env`, e.g. `|k| std::env::var_os(k)`)
    /// ask for; a malformed flag is [`BadInput`].
    fn options(&self, env: impl Fn(&str) -> Option<OsString>) -> anyhow::Result<DroneOptions> {
        let bad = |e: anyhow::Error| anyhow::Error::from(BadInput(e));
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
        let stuck_servo = self
            .stuck_servo
            .as_deref()
            .map(|s| {
                s.parse::<StuckServo>()
                    .map_err(|e| bad(anyhow!("--stuck-servo: {e}")))
            })
            .transpose()?;
        if !(self.linger >= 0.0 && self.linger.is_finite()) {
            return Err(bad(anyhow!(
                "--linger {}: must be ≥ 0 seconds",
                self.linger
            )));
        }
        let mut options = DroneOptions::new(&self.connect, &self.scenario);
        options.speed = self.speed;
        options.seed = self.seed;
        options.failures = FailureFlags {
            packet_loss_pct: self.packet_loss,
            link_drop_s: self
                .link_drop
                .iter()
                .map(|w| window("--link-drop", w))
                .collect::<anyhow::Result<_>>()?,
            gps_loss_s: self
                .gps_loss
                .iter()
                .map(|w| window("--gps-loss", w))
                .collect::<anyhow::Result<_>>()?,
            stuck_servo,
        };
        options.signing_key = signing_key(self.sign_key_file.as_deref(), &env)?;
        options.system_id = self.system_id;
        if options.signing_key.is_some() {
            let file = self.signing_timestamp_file.clone().or_else(|| {
                default_state_dir(&env)
                    .map(|d| d.join(format!("drone-sys{}.signing.timestamp", self.system_id)))
            });
            options.signing_timestamp_file = Some(file.ok_or_else(|| {
                bad(anyhow!(
                    "--signing-timestamp-file: needed with signing (no $STATE_DIRECTORY, \
                     $XDG_STATE_HOME or $HOME to put it in)"
                ))
            })?);
        }
        options.gains = self
            .gains
            .as_deref()
            .map(crate::tune::load_gains)
            .transpose()?;
        options.linger = Some(Duration::from_secs_f64(self.linger));
        options.progress = true;
        Ok(options)
    }
}

/// The signing key from `file`, or from `STX_SIGNING_KEY` in `env`; both is ambiguous.
/// Errors never repeat the key.
fn signing_key(
    file: Option<&Path>,
    env: impl Fn(&str) -> Option<OsString>,
) -> anyhow::Result<Option<SigningKey>> {
    let bad = |e: anyhow::Error| anyhow::Error::from(BadInput(e));
    match (file, env(SIGNING_KEY_ENV)) {
        (Some(_), Some(_)) => Err(bad(anyhow!(
            "--sign-key-file and {SIGNING_KEY_ENV} both give a signing key: use one"
        ))),
        (Some(path), None) => SigningKey::from_file(path)
            .map(Some)
            .map_err(|e| bad(anyhow!("--sign-key-file: {e}"))),
        (None, Some(text)) => text
            .to_str()
            .ok_or(stx_link::signing::KeyError::NotHex)
            .and_then(SigningKey::from_hex)
            .map(Some)
            .map_err(|e| bad(anyhow!("{SIGNING_KEY_ENV}: {e}"))),
        (None, None) => Ok(None),
    }
}

/// How a flight went: the mission's figures and the run's; what `--summary-json` prints.
#[derive(Debug, Clone, Serialize)]
pub struct DroneReport {
    /// The mission in figures.
    #[serde(flatten)]
    pub mission: MissionSummary,
    /// Whether the drone landed.
    pub landed: bool,
    /// The speed flown.
    pub speed: String,
    /// Real time of the run, s.
    pub wall_time_s: f64,
    /// Stopped by the shutdown future (Ctrl-C for `stx drone`) before the end.
    pub interrupted: bool,
    /// The drone's side of the link.
    pub link: Option<LinkCounters>,
    /// The socket's counters.
    pub io: Option<IoStats>,
}

pub fn run(args: DroneArgs) -> anyhow::Result<()> {
    let options = args.options(|k| std::env::var_os(k))?;
    // Bad missions and flags are refused before anything starts.
    load_mission(&options)?;
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .context("starting the tokio runtime")?;
    let shutdown = async {
        if let Err(e) = tokio::signal::ctrl_c().await {
            tracing::error!(error = %e, "cannot listen for Ctrl-C: stop the drone another way");
            std::future::pending::<()>().await;
        }
    };
    let report = runtime.block_on(fly(options, shutdown))?;
    if args.summary_json {
        println!("{}", serde_json::to_string(&report)?);
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

/// Flies `options`' mission over its link until the drone has landed (and lingered), or until
/// `shutdown` resolves: then the steps already handed to the link are flown, their telemetry
/// is sent, and the report says `interrupted`. A bad mission, flag or address is a
/// [`BadInput`] error; a failing simulation or link task is any other error.
pub async fn fly(
    options: DroneOptions,
    shutdown: impl Future<Output = ()> + Send,
) -> anyhow::Result<DroneReport> {
    let config = load_mission(&options)?;
    let drone = Drone::new(&config, Vehicle::straplex())
        .with_context(|| format!("building the drone of mission {}", config.name))
        .map_err(BadInput)?;
    let transport = Transport::open_str(&options.connect)
        .await
        .with_context(|| format!("opening {}", options.connect))
        .map_err(BadInput)?;
    if let Some(address) = transport.listening_address() {
        tracing::info!(%address, "drone link listening");
    }
    let mut link = LinkConfig::vehicle();
    link.system_id = options.system_id;
    if let Some(key) = options.signing_key.clone() {
        let path = options.signing_timestamp_file.as_deref().ok_or_else(|| {
            BadInput(anyhow!(
                "signing needs a timestamp file, so the timestamps stay monotonic across restarts"
            ))
        })?;
        let unix = match options.signing_clock_unix {
            Some(t) => t,
            None => SystemTime::now()
                .duration_since(UNIX_EPOCH)
                .context("the system clock is before 1970")?,
        };
        link.signing = Some(
            stx_link::signing::persist::start_signing(key, unix, Some(path))
                .map_err(|e| BadInput(e.into()))?,
        );
    }
    tracing::info!(
        mission = %drone.config().name,
        connect = %options.connect,
        speed = %options.speed,
        stage = %stage_name(drone.stage()),
        "drone starting"
    );
    let linked =
        LinkedDrone::new(drone, link, Duration::ZERO).context("putting the drone on the link")?;
    let timestamp_file = options
        .signing_timestamp_file
        .clone()
        .filter(|_| options.signing_key.is_some());
    persist_signing_mark(&linked, timestamp_file.as_deref())
        .context("--signing-timestamp-file")
        .map_err(BadInput)?;

    let (action_tx, action_rx) = mpsc::channel::<Action<LinkedDrone>>(STEPS_IN_FLIGHT);
    let (event_tx, mut event_rx) = mpsc::channel(4096);
    let driver = tokio::spawn(drive(
        transport,
        linked,
        action_rx,
        event_tx,
        DriveOptions {
            signing_timestamp_file: timestamp_file,
        },
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
    tokio::pin!(shutdown);
    let bar = (options.progress && std::io::stderr().is_terminal()).then(progress_bar);
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
        if let (Some(at), Some(linger)) = (landed_at, options.linger)
            && at.elapsed() >= linger
        {
            break;
        }
        // After landing the drone answers on the ground in real time.
        let speed = if landed_at.is_some() {
            Speed::Times(1.0)
        } else {
            options.speed
        };
        match speed {
            Speed::Max => {
                tokio::select! {
                    biased;
                    () = &mut shutdown => { interrupted = true; break 'flight; }
                    sent_ok = send_step(&action_tx) => { sent_ok?; sent += 1; }
                }
            }
            Speed::Times(times) => {
                let due = pace_from.0
                    + Duration::from_secs_f64((sent - pace_from.1 + 1) as f64 * period_s / times);
                tokio::select! {
                    biased;
                    () = &mut shutdown => { interrupted = true; break 'flight; }
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
            if let Some(bar) = &bar {
                bar.set_message(format!(
                    "t {:.0} s, {}, {:.0} m MSL, {:?}, {:?}",
                    r.time_s,
                    stage_name(r.stage),
                    r.altitude_msl_m,
                    r.mode,
                    r.phase
                ));
            } else if last_stage != Some(r.stage)
                || last_progress.elapsed() >= Duration::from_secs(5)
            {
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
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    if interrupted {
        tracing::info!("interrupted: stopping");
    }
    let mission = linked.drone().summary();
    Ok(DroneReport {
        landed: mission.landing.is_some(),
        mission,
        speed: options.speed.to_string(),
        wall_time_s: started.elapsed().as_secs_f64(),
        interrupted,
        link: Some(linked.counters()),
        io: Some(io),
    })
}

/// A spinner with the flight's state, for a terminal.
fn progress_bar() -> ProgressBar {
    let bar = ProgressBar::new_spinner();
    bar.set_style(
        ProgressStyle::with_template("{spinner} {elapsed} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    bar.enable_steady_tick(Duration::from_millis(200));
    bar
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
        // The transport logs these itself, rate-limited, and counts every one (the report's
        // `io`): logging each again flooded stderr while no station listened.
        DriverEvent::Io {
            event:
                IoEvent::RecvError { .. }
                | IoEvent::SendError { .. }
                | IoEvent::QueuedWithoutPeer { .. },
            ..
        } => {}
        DriverEvent::Io { event, .. } => tracing::info!(?event, "link"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;
    use tokio::time::timeout;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        drone: DroneArgs,
    }

    fn options(flags: &[&str]) -> anyhow::Result<DroneOptions> {
        options_env(flags, &[("HOME", "/home/op")])
    }

    fn options_env(flags: &[&str], vars: &[(&str, &str)]) -> anyhow::Result<DroneOptions> {
        let cli = Cli::try_parse_from(std::iter::once("stx-drone").chain(flags.iter().copied()))
            .map_err(|e| anyhow!("{e}"))?;
        cli.drone.options(|k| {
            vars.iter()
                .find(|(name, _)| *name == k)
                .map(|(_, v)| OsString::from(v))
        })
    }

    const KEY: &str = "c0ffee00c0ffee00c0ffee00c0ffee00c0ffee00c0ffee00c0ffee00c0ffee00";

    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("stx-drone-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        dir
    }

    #[test]
    fn the_key_comes_from_a_file_or_the_environment_never_the_command_line() {
        let dir = temp_dir("key");
        let key_file = dir.join("key");
        std::fs::write(&key_file, format!("{KEY}\n")).expect("write");
        let file_flag = key_file.to_str().expect("utf-8");
        let o = options(&["--sign-key-file", file_flag]).expect("valid");
        assert!(o.signing_key == Some(SigningKey::from_hex(KEY).expect("hex")));
        // The default timestamp file: the state directory, per system id.
        assert_eq!(
            o.signing_timestamp_file,
            Some(PathBuf::from(
                "/home/op/.local/state/stx/drone-sys1.signing.timestamp"
            ))
        );
        let o = options_env(
            &["--system-id", "7"],
            &[(SIGNING_KEY_ENV, KEY), ("STATE_DIRECTORY", "/var/lib/stx")],
        )
        .expect("valid");
        assert!(o.signing_key == Some(SigningKey::from_hex(KEY).expect("hex")));
        assert_eq!(
            o.signing_timestamp_file,
            Some(PathBuf::from("/var/lib/stx/drone-sys7.signing.timestamp"))
        );
        // Nothing printable holds the key.
        assert!(!format!("{o:?}").contains("c0ffee"));
        // No key on the command line at all.
        assert!(options(&["--sign-key", KEY]).is_err());
        for (flags, vars) in [
            (
                vec!["--sign-key-file", file_flag],
                vec![(SIGNING_KEY_ENV, KEY)],
            ),
            (vec![], vec![(SIGNING_KEY_ENV, "c0ffee")]),
            (vec!["--sign-key-file", "/nonexistent/key"], vec![]),
            // Signing without anywhere to keep the timestamp.
            (vec!["--sign-key-file", file_flag], vec![("UNRELATED", "x")]),
        ] {
            let err = options_env(&flags, &vars).expect_err("refused");
            assert!(err.downcast_ref::<BadInput>().is_some(), "{flags:?}: {err}");
            assert!(!format!("{err:#}").contains("c0ffee"), "{err:#}");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn flags_become_options_and_bad_ones_are_bad_input() {
        let o = options(&[
            "--scenario",
            "rehearsal",
            "--speed",
            "max",
            "--seed",
            "9",
            "--link-drop",
            "100:160",
            "--gps-loss",
            "300..330",
            "--stuck-servo",
            "left@400",
            "--packet-loss",
            "20",
        ])
        .expect("valid flags");
        assert_eq!(o.speed, Speed::Max);
        assert_eq!(o.seed, Some(9));
        assert_eq!(o.failures.link_drop_s, vec![[100.0, 160.0]]);
        assert_eq!(o.failures.gps_loss_s, vec![[300.0, 330.0]]);
        assert_eq!(o.failures.packet_loss_pct, Some(20.0));
        assert!(o.failures.stuck_servo.is_some());
        load_mission(&o).expect("the mission with these failures is valid");
        for flags in [
            &["--link-drop", "160:100"][..],
            &["--stuck-servo", "up@3"],
            &["--linger=-1"],
            &["--gains", "/nonexistent/gains.toml"],
        ] {
            let err = options(flags).expect_err("refused");
            assert!(err.downcast_ref::<BadInput>().is_some(), "{flags:?}: {err}");
        }
        let mut o = DroneOptions::new("udpout:127.0.0.1:9", "rehearsal");
        o.failures.packet_loss_pct = Some(120.0);
        let err = load_mission(&o).expect_err("120 % refused");
        assert!(err.downcast_ref::<BadInput>().is_some());
        assert!(format!("{err:#}").contains("packet_loss_pct"), "{err:#}");
    }

    #[tokio::test]
    async fn an_unknown_mission_is_bad_input_and_nothing_is_opened() {
        let err = fly(
            DroneOptions::new("udpout:127.0.0.1:9", "no-such-mission"),
            std::future::pending(),
        )
        .await
        .expect_err("refused");
        assert!(err.downcast_ref::<BadInput>().is_some());
        assert!(format!("{err:#}").contains("mission-short"), "{err:#}");
    }

    /// Every signing timestamp `stx drone` sends until it has sent `frames`, then all it sends
    /// while stopping (the flight of `options`, pointed at a fresh socket).
    async fn signed_timestamps(mut options: DroneOptions, frames: usize) -> Vec<u64> {
        let station = tokio::net::UdpSocket::bind("127.0.0.1:0")
            .await
            .expect("station socket");
        let port = station.local_addr().expect("bound").port();
        options.connect = format!("udpout:127.0.0.1:{port}");
        let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
        let flight = tokio::spawn(fly(options, async {
            let _ = stopped.await;
        }));
        let mut stamps = Vec::new();
        let mut buf = [0_u8; 512];
        let decode = |bytes: &[u8], stamps: &mut Vec<u64>| {
            let mut dec = stx_link::frame::FrameDecoder::default();
            dec.push(bytes);
            while let Some(Ok(f)) = dec.poll(Duration::ZERO) {
                stamps.push(f.header.signature.expect("signed").timestamp_10us);
            }
        };
        while stamps.len() < frames {
            let n = timeout(Duration::from_secs(20), station.recv(&mut buf))
                .await
                .expect("the drone sends")
                .expect("recv");
            decode(&buf[..n], &mut stamps);
        }
        stop.send(()).expect("flight running");
        timeout(Duration::from_secs(20), flight)
            .await
            .expect("fly returns after the shutdown")
            .expect("task")
            .expect("flight");
        while let Ok(n) = station.try_recv(&mut buf) {
            decode(&buf[..n], &mut stamps);
        }
        stamps
    }

    /// Regression: `stx drone` signed with `SigningConfig::new(key, 0, now)` and no timestamp
    /// file, so a restart with the clock set back signed below its last run (replays to the
    /// station). Now the high-water mark is kept in a file, written before the first frame.
    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn a_restarted_drone_signs_above_its_last_run_with_the_clock_set_back() {
        let dir = temp_dir("restart");
        let file = dir.join("drone.signing.timestamp");
        let options = |unix: Duration| {
            let mut o = DroneOptions::new("udpout:127.0.0.1:9", "rehearsal");
            o.speed = Speed::Times(10.0);
            o.linger = None;
            o.signing_key = Some(SigningKey::from_hex(KEY).expect("hex"));
            o.signing_timestamp_file = Some(file.clone());
            o.signing_clock_unix = Some(unix);
            o
        };
        let jan_2026 = Duration::from_secs(1_767_225_600);
        let first = signed_timestamps(options(jan_2026), 20).await;
        let mark = stx_link::signing::persist::load_signing_timestamp(&file)
            .expect("readable")
            .expect("written");
        let last = *first.iter().max().expect("frames");
        assert!(
            mark > last,
            "mark {mark} on disk above every timestamp sent ({last})"
        );
        let second = signed_timestamps(options(jan_2026 - Duration::from_secs(3600)), 5).await;
        assert!(
            second[0] > last,
            "after the restart {} <= before {last}",
            second[0]
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn fly_stops_when_shutdown_resolves_and_reports_the_flight_so_far() {
        let station = tokio::net::UdpSocket::bind("127.0.0.1:0")
            .await
            .expect("station socket");
        let port = station.local_addr().expect("bound").port();
        let mut options = DroneOptions::new(&format!("udpout:127.0.0.1:{port}"), "rehearsal");
        options.speed = Speed::Times(10.0);
        // Stay on the ground after landing: only the shutdown ends this flight.
        options.linger = None;
        let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
        let flight = tokio::spawn(fly(options, async {
            let _ = stopped.await;
        }));
        // The drone is on the air once its first frame arrives.
        let mut buf = [0_u8; 512];
        let n = timeout(Duration::from_secs(20), station.recv(&mut buf))
            .await
            .expect("the drone sends")
            .expect("recv");
        assert!(n > 0 && buf[0] == 0xFD, "a MAVLink 2 frame");
        stop.send(()).expect("flight running");
        let report = timeout(Duration::from_secs(20), flight)
            .await
            .expect("fly returns after the shutdown")
            .expect("task")
            .expect("flight");
        assert!(report.interrupted);
        assert!(!report.landed, "stopped long before the landing");
        assert!(report.mission.mission_time_s < 100.0);
        assert!(report.io.is_some_and(|io| io.tx_bytes > 0));
    }
}
