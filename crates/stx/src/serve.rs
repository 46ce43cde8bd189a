//! `stx serve`: the ground station daemon — the drone link, the station's estimator, guidance
//! replica and predictor, and the dashboard on localhost.
//!
//! With `--sim` the simulated drone of `stx drone` flies beside the station in the same process,
//! over a real UDP socket on loopback to the station's `udpin` link (the same bytes a radio
//! would carry), for rehearsals and demonstrations. One shutdown (Ctrl-C or SIGTERM) stops both.
//! When the station reads a ground anemometer on a UDP port (`[surface_wind] anemometer =
//! "udpin:…"`), the simulated world's anemometer sends its NMEA sentences there.

use std::future::Future;
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use stx_sim::drone::MissionOverrides;
use stx_sim::runner::{FlyOptions, ProgressLog, Signing, Speed};
use stx_station::config::{DEFAULT_STATION_TOML, StationConfig};
use stx_station::http::{RehearsalRequest, Rehearsals};

use crate::BadInput;
use crate::drone::{fly_error, load_vehicle_flag, mission};
use crate::inputs::load_gains;

#[derive(Args)]
pub struct ServeArgs {
    /// Station configuration (default: the shipped config/station.toml).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Listen on this address instead of the configuration's (e.g. 127.0.0.1:8080). Beyond
    /// loopback the shipped rehearsal tokens are refused, and plain HTTP needs --insecure-http.
    #[arg(long)]
    listen: Option<std::net::SocketAddr>,
    /// Serve plain HTTP beyond loopback without `[tls]`: tokens cross the network in clear.
    #[arg(long)]
    insecure_http: bool,
    /// The drone link instead of the configuration's (e.g. udpin:0.0.0.0:14550,
    /// serial:/dev/ttyUSB0:57600, tcpout:192.168.1.20:5760).
    #[arg(long)]
    link: Option<String>,
    /// Fly the simulated drone beside the station, over loopback UDP to its link (which must
    /// then be a `udpin:` link).
    #[arg(long)]
    sim: bool,
    /// The simulated drone's mission with --sim: `mission` (the whole 2 h 41 min flight),
    /// `mission-short`, `rehearsal` (under the parafoil from 900 m), or a mission TOML file.
    #[arg(long, default_value = "mission-short", requires = "sim")]
    sim_scenario: String,
    /// Mission time per real time for the simulated drone (a number or `max`).
    #[arg(long, default_value = "1", requires = "sim")]
    sim_speed: Speed,
    /// Seed of the simulated drone's randomness (default: the mission's).
    #[arg(long, requires = "sim")]
    sim_seed: Option<u64>,
    /// Control gains of the simulated drone's onboard guidance (a gains file as `stx tune`
    /// writes it).
    #[arg(long, value_name = "FILE", requires = "sim")]
    sim_gains: Option<PathBuf>,
    /// The vehicle file the simulated drone flies as the truth (default: the shipped STRAPLEX
    /// vehicle); its onboard guidance still starts from the mission's own polar.
    #[arg(long, value_name = "FILE", requires = "sim")]
    sim_vehicle: Option<PathBuf>,
    /// Record this run (MCAP) into this directory instead of the configuration's
    /// `recording.dir` (default: `recordings/` in the state directory).
    #[arg(long, value_name = "DIR", conflicts_with = "no_record")]
    record_dir: Option<PathBuf>,
    /// Do not record this run.
    #[arg(long)]
    no_record: bool,
    /// Where the Lab saves vehicle and gains files (default: `lab/` in the state directory,
    /// else `./lab`); never config/ unless named here.
    #[arg(long, value_name = "DIR")]
    lab_dir: Option<PathBuf>,
}

/// Reads and validates the station configuration.
pub fn load_config(path: Option<&std::path::Path>) -> anyhow::Result<StationConfig> {
    let text = match path {
        None => DEFAULT_STATION_TOML.to_string(),
        Some(p) => std::fs::read_to_string(p)
            .with_context(|| format!("cannot read station config {}", p.display()))
            .map_err(BadInput)?,
    };
    let name = || {
        format!(
            "station config {}",
            path.map_or("(shipped)".into(), |p| p.display().to_string())
        )
    };
    let mut config = StationConfig::from_toml_str_with_env(&text, |k| std::env::var_os(k))
        .with_context(name)
        .map_err(BadInput)?;
    // `[forecast_file]`: its rows become the forecast wind before anything starts.
    config
        .load_forecast_file()
        .and_then(|()| config.validate())
        .with_context(name)
        .map_err(BadInput)?;
    Ok(config)
}

pub fn run(args: ServeArgs) -> anyhow::Result<()> {
    let mut config = load_config(args.config.as_deref())?;
    if let Some(listen) = args.listen {
        config.listen = listen;
    }
    if let Some(link) = args.link.clone() {
        config.link.address = link;
        config.validate().context("--link").map_err(BadInput)?;
    }
    if let Some(dir) = args.record_dir.clone() {
        config.recording.enabled = true;
        config.recording.dir = Some(dir);
        config
            .validate()
            .context("--record-dir")
            .map_err(BadInput)?;
    }
    if args.no_record {
        config.recording.enabled = false;
    }
    check_exposure(&config, args.insecure_http)?;
    if !config.web_dir.join("index.html").exists() {
        tracing::warn!(
            dir = %config.web_dir.display(),
            "the dashboard is not built here: run `cd web && npm ci && npm run build` (the API works without it)"
        );
    }
    let lab_dir = args.lab_dir.clone().unwrap_or_else(|| {
        stx_link::signing::persist::default_state_dir(|k| std::env::var_os(k))
            .unwrap_or_default()
            .join("lab")
    });
    let lab = stx_lab::service(lab_dir);
    let sim = if args.sim {
        let options = sim_options(&config, &args)?;
        // The rehearsal's station knows the balloon it flies with: its burst, ascent rate and
        // round chute are the scenario's (the drone's parameters give the deploy height).
        // Its mass is the vehicle flown (--sim-vehicle), as an operator's configuration would say.
        config.flight_path = options.mission.stack_config(&options.vehicle);
        config.flight_path_unset.clear();
        Some(options)
    } else {
        None
    };
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .context("starting the async runtime")?;
    runtime.block_on(async move {
        let operator = config.operator_token().unwrap_or_default().to_owned();
        let (stop_tx, stop_rx) = tokio::sync::watch::channel(false);
        tokio::spawn(async move {
            shutdown_signal().await;
            let _ = stop_tx.send(true);
        });
        let mut drone_task = None;
        let station = stx_station::daemon::run(config, stopped(stop_rx.clone()), |running| {
            // Set once, on a station just started: it cannot have one already.
            let _ = running.shared.lab.set(lab);
            let mut banner = format!(
                "stx station: open {}://{}/?token={operator}\n",
                running.scheme, running.http
            );
            if let Some(link) = running.link_local {
                // For a drone started separately against a port the system chose.
                banner.push_str(&format!("stx station: drone link listening on {link}\n"));
            }
            announce(&banner);
            if let (Some(mut options), Some(link)) = (sim, running.link_local) {
                options.connect = format!("udpout:{}", loopback_if_unspecified(link));
                let (requests, incoming) = tokio::sync::mpsc::channel(1);
                // Set once, on a station just started: it cannot have one already.
                let _ = running.shared.rehearsal.set(Rehearsals {
                    requests,
                    last: std::sync::Mutex::new(None),
                });
                drone_task = Some(tokio::spawn(fly_rehearsals(options, incoming, stop_rx)));
            }
        })
        .await
        .context("station");
        if let Some(mut task) = drone_task {
            // After a shutdown the drone finishes its step and reports; if the station stopped
            // on its own (an error), nobody listens to the drone any more.
            if tokio::time::timeout(std::time::Duration::from_secs(3), &mut task)
                .await
                .is_err()
            {
                task.abort();
            }
        }
        station
    })
}

/// Refuses (exit code 2) to listen beyond loopback with a rehearsal token, or over plain HTTP
/// without `insecure_http` (`stx_station::exposure`); going on in clear is said in the log.
pub(crate) fn check_exposure(config: &StationConfig, insecure_http: bool) -> anyhow::Result<()> {
    stx_station::exposure::check_listen(config, insecure_http).map_err(|e| BadInput(e.into()))?;
    if config.tls.is_none() && !config.is_loopback(config.listen.ip()) {
        tracing::warn!(
            listen = %config.listen,
            "plain HTTP beyond loopback (--insecure-http): the tokens and all the dashboard shows cross the network in clear"
        );
    }
    Ok(())
}

/// The simulated drone's options from the command line, checked before anything starts.
fn sim_options(config: &StationConfig, args: &ServeArgs) -> anyhow::Result<FlyOptions> {
    if !config.link.address.starts_with("udpin:") {
        return Err(BadInput(anyhow::anyhow!(
            "--sim flies the drone over loopback UDP: the station's link must be `udpin:…`, not `{}`",
            config.link.address
        ))
        .into());
    }
    let overrides = MissionOverrides {
        seed: args.sim_seed,
        gains: args.sim_gains.as_deref().map(load_gains).transpose()?,
        ..MissionOverrides::default()
    };
    // Fail on an unknown mission now, with exit code 2, not after the dashboard is up.
    let mut options = FlyOptions::new(
        "udpout:127.0.0.1:0",
        mission(&args.sim_scenario, &overrides)?,
    );
    options.speed = args.sim_speed;
    if let Ok(Some(stx_link::address::Address::UdpIn(at))) =
        config.surface_wind.anemometer_address()
    {
        // A port bound on every address is reached on loopback.
        let ip = if at.ip().is_unspecified() {
            std::net::Ipv4Addr::LOCALHOST.into()
        } else {
            at.ip()
        };
        options.anemometer_to = Some(std::net::SocketAddr::new(ip, at.port()));
    }
    if let Some(path) = &args.sim_vehicle {
        options.vehicle = load_vehicle_flag("--sim-vehicle", path)?;
    }
    // On the ground it keeps answering (parameters, replay of the landing) until the station stops.
    options.linger = None;
    if let Some(key) = config.link.signing_key().map_err(|e| BadInput(e.into()))? {
        // The drone's own high-water mark, beside the station's.
        let timestamp_file = config
            .link
            .signing_timestamp_file
            .as_ref()
            .map(|p| p.with_file_name("sim-drone.signing.timestamp"))
            .ok_or_else(|| {
                BadInput(anyhow::anyhow!(
                    "--sim with signing needs link.signing_timestamp_file, so the simulated \
                     drone's timestamps stay monotonic across restarts"
                ))
            })?;
        options.signing = Some(Signing {
            key,
            timestamp_file,
            clock_unix: None,
        });
    }
    Ok(options)
}

/// The simulated drone beside the station, flown again from its mission's start with another
/// vehicle as its truth whenever the Lab asks (`POST /api/lab/rehearse`), until the shutdown.
async fn fly_rehearsals(
    mut options: FlyOptions,
    mut requests: tokio::sync::mpsc::Receiver<RehearsalRequest>,
    stop: tokio::sync::watch::Receiver<bool>,
) {
    loop {
        let (halt, halted) = tokio::sync::watch::channel(false);
        let either = {
            let stop = stop.clone();
            async move {
                tokio::select! {
                    () = stopped(stop) => {}
                    () = stopped(halted) => {}
                }
            }
        };
        let mut flight = tokio::spawn(fly_beside(options.clone(), either));
        let request = tokio::select! {
            () = stopped(stop.clone()) => None,
            request = requests.recv() => request,
        };
        let _ = halt.send(true);
        // The drone finishes its step and saves its signing timestamp before the next one
        // starts from the same file.
        if tokio::time::timeout(std::time::Duration::from_secs(2), &mut flight)
            .await
            .is_err()
        {
            flight.abort();
        }
        let Some(request) = request else {
            return;
        };
        options.vehicle = request.vehicle;
        let _ = request.answer.send(Ok(options.mission.name.clone()));
    }
}

/// The drone's flight, its outcome logged: a simulated drone that fails does not stop the
/// station (the operator sees the link go quiet, as with a real one).
async fn fly_beside(options: FlyOptions, shutdown: impl Future<Output = ()> + Send) {
    tracing::info!(
        mission = %options.mission.name,
        speed = %options.speed,
        to = %options.connect,
        "simulated drone taking off"
    );
    match stx_sim::runner::fly(options, shutdown, ProgressLog::default()).await {
        Ok(report) => tracing::info!(
            landed = report.landed,
            miss_m = ?report.mission.landing.as_ref().and_then(|l| l.miss_m),
            wall_time_s = report.wall_time_s,
            "simulated drone finished"
        ),
        Err(e) => tracing::error!(
            error = format!("{:#}", fly_error(e)),
            "simulated drone failed"
        ),
    }
}

/// Resolves once the shutdown has been asked for.
async fn stopped(mut stop: tokio::sync::watch::Receiver<bool>) {
    let _ = stop.wait_for(|stop| *stop).await;
}

/// A UDP server bound to every interface is reached on loopback.
fn loopback_if_unspecified(address: std::net::SocketAddr) -> std::net::SocketAddr {
    if address.ip().is_unspecified() {
        let loopback: std::net::IpAddr = match address {
            std::net::SocketAddr::V4(_) => std::net::Ipv4Addr::LOCALHOST.into(),
            std::net::SocketAddr::V6(_) => std::net::Ipv6Addr::LOCALHOST.into(),
        };
        std::net::SocketAddr::new(loopback, address.port())
    } else {
        address
    }
}

/// Ctrl-C, or SIGTERM from systemd or a container runtime.
pub(crate) async fn shutdown_signal() {
    let interrupt = tokio::signal::ctrl_c();
    #[cfg(unix)]
    {
        let mut term =
            match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
                Ok(term) => term,
                Err(e) => {
                    tracing::warn!(error = %e, "SIGTERM will not stop the station gracefully");
                    let _ = interrupt.await;
                    return;
                }
            };
        tokio::select! {
            _ = interrupt => {}
            _ = term.recv() => {}
        }
    }
    #[cfg(not(unix))]
    let _ = interrupt.await;
    tracing::info!("shutting down");
}

/// Writes the start banner to stdout. A station must not stop because nobody reads its
/// stdout any more (a closed pipe, a supervisor that went away): `println!` would panic on
/// the broken pipe, so a failed write is only logged.
pub(crate) fn announce(banner: &str) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_all(banner.as_bytes()).and_then(|()| out.flush()) {
        tracing::warn!(error = %e, "could not print the start banner on stdout");
    }
}

#[cfg(test)]
mod sim_gains_tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        serve: ServeArgs,
    }

    #[test]
    fn sim_gains_reach_the_simulated_drone_and_a_bad_file_is_bad_input() {
        let gains = stx_gnc::control::ControlGains {
            hk1_m_per_rad: 0.0123,
            ..Default::default()
        };
        let path = std::env::temp_dir().join(format!("stx-sim-gains-{}.toml", std::process::id()));
        std::fs::write(&path, gains.to_toml_string()).expect("write");
        let config = load_config(None).expect("shipped config");
        let args = |file: &str| {
            Cli::try_parse_from(["stx-serve", "--sim", "--sim-gains", file])
                .expect("flags parse")
                .serve
        };
        let options = sim_options(&config, &args(path.to_str().expect("utf-8"))).expect("valid");
        assert_eq!(options.mission.onboard.guidance.gains, gains);
        let err = sim_options(&config, &args("/nonexistent/gains.toml")).expect_err("refused");
        assert!(err.downcast_ref::<BadInput>().is_some(), "{err}");
        let _ = std::fs::remove_file(&path);
    }
}

#[cfg(test)]
mod sim_vehicle_tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        serve: ServeArgs,
    }

    #[test]
    fn sim_vehicle_is_the_simulated_drones_truth_and_a_bad_file_is_bad_input() {
        let config = load_config(None).expect("shipped config");
        let options = |flags: &[&str]| {
            let cli = Cli::try_parse_from(["stx-serve", "--sim"].iter().chain(flags))
                .expect("flags parse");
            sim_options(&config, &cli.serve)
        };
        let shipped = stx_dynamics::vehicle::Vehicle::straplex();
        assert_eq!(options(&[]).expect("valid").vehicle, shipped);
        let dir = std::env::temp_dir().join(format!("stx-sim-vehicle-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let text = include_str!("../../../config/vehicle/straplex.toml");
        let (good, bad) = (dir.join("good.toml"), dir.join("bad.toml"));
        std::fs::write(
            &good,
            text.replacen("cl_alpha = 2.300", "cl_alpha = 1.840", 1),
        )
        .expect("write");
        std::fs::write(&bad, text.replacen("cl_alpha = 2.300", "cl_alpha = nan", 1))
            .expect("write");
        let flown = options(&["--sim-vehicle", good.to_str().expect("utf-8")])
            .expect("valid")
            .vehicle;
        assert_eq!(flown.config.canopy.aero.cl_alpha, 1.84);
        let err = options(&["--sim-vehicle", bad.to_str().expect("utf-8")]).expect_err("refused");
        assert!(err.downcast_ref::<BadInput>().is_some(), "{err}");
        let said = format!("{err:#}");
        assert!(
            said.contains("--sim-vehicle") && said.contains("canopy.aero.cl_alpha"),
            "{said}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
