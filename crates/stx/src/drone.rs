//! `stx drone`: the simulated drone on a real MAVLink link.
//!
//! The flags become the runner's options ([`stx_sim::runner::FlyOptions`]): the mission
//! (`--scenario`, built-in or a file) with the command line's seed, failures and gains
//! ([`stx_sim::drone::MissionOverrides`]), the speed, the signing key and its timestamp file,
//! the system id and the linger. A bad name, file or flag is refused before anything opens
//! (exit code 2). The flight itself is `stx_sim::runner::fly`: see there for the pacing, the
//! link and the report. The process exits 0 once the drone has landed and lingered, or on
//! Ctrl-C, and 1 if the simulation fails. Progress (stage, altitude, mode, phase) is a
//! progress bar on a terminal and info-level log lines otherwise; `--summary-json` prints the
//! runner's report ([`stx_sim::runner::FlightReport`]) as one JSON line on stdout.
//!
//! Signing: the key comes from `--sign-key-file FILE` or the environment variable
//! `STX_SIGNING_KEY` (64 hexadecimal characters), never from the command line, where `ps` and
//! shell histories would show it. The timestamp's high-water mark lives in
//! `--signing-timestamp-file` (default `drone-sys<ID>.signing.timestamp` in the state
//! directory: `$STATE_DIRECTORY`, `$XDG_STATE_HOME/stx` or `~/.local/state/stx`).
//!
//! `--gains FILE` (a gains file as `stx tune` writes it) sets the onboard guidance's control
//! gains, which are also its parameters: the station reads and sets them over PARAM_*.
//!
//! `--anemometer-to HOST:PORT` puts the simulated world's ground anemometer (a 10-m mast by the
//! mission's target, in the drone's true wind) on the air: each of its reports, every 5 s of
//! mission time, goes to that UDP address as one NMEA 0183 MWV sentence.
//!
//! `--vehicle FILE` (a vehicle file, as `stx sim --vehicle` reads it) is the truth the drone
//! flies; the onboard guidance keeps the mission's polar, so an operator rehearses guidance
//! as it is against the stack they identified ([`stx_sim::drone::Drone::with_truth`]).
//!
//! A server address with port 0 (`udpin:…:0`, `tcpin:…:0`) is logged with the port actually
//! bound. Socket errors are counted in the report's `io` and logged by the transport at most
//! every few seconds with their count (a `tcpin:` link with no station yet fails every frame).

use std::ffi::OsString;
use std::io::IsTerminal;
use std::net::{SocketAddr, ToSocketAddrs};
use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::{Context, anyhow};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use stx_link::signing::persist::default_state_dir;
use stx_link::signing::{SIGNING_KEY_ENV, SigningKey};
use stx_sim::drone::failures::{StuckServo, parse_window};
use stx_sim::drone::{FailureFlags, MissionOverrides, stage_name};
use stx_sim::runner::{
    FlightObserver, FlightReport, FlyError, FlyOptions, ProgressLog, Signing, Speed, StepReport,
};

use crate::BadInput;
use crate::inputs::{load_gains, load_mission, load_vehicle};

#[derive(Args, Debug)]
pub struct DroneArgs {
    /// Where the station is: udpout:HOST:PORT (the station's udpin), udpin:, tcp:, tcpin:,
    /// serial:PATH:BAUD.
    #[arg(long, default_value = "udpout:127.0.0.1:14550")]
    connect: String,
    /// Fly a vehicle and sensors drawn (with the mission's seed) from a dispersion set:
    /// `nominal`, `realistic` (config/dispersions/) or a dispersion file, as
    /// `stx montecarlo --dispersions` does. Without it, the nominal vehicle.
    #[arg(long, value_name = "nominal|realistic|FILE")]
    dispersions: Option<String>,
    /// Fly this vehicle file as the truth (e.g. one `stx identify` or the Lab wrote) instead of
    /// the shipped STRAPLEX vehicle; with --dispersions, the draw is centred on it. The onboard
    /// guidance still starts from the mission's own polar and gains.
    #[arg(long, value_name = "FILE")]
    vehicle: Option<PathBuf>,
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
    /// Send the simulated ground anemometer's NMEA MWV sentences to this UDP address.
    #[arg(long, value_name = "HOST:PORT", value_parser = udp_address)]
    anemometer_to: Option<SocketAddr>,
}

/// A UDP destination: an IP address and port, or a host name resolved now (its first
/// address).
fn udp_address(text: &str) -> Result<SocketAddr, String> {
    if let Ok(address) = text.parse() {
        return Ok(address);
    }
    let expected = "expected HOST:PORT, e.g. 127.0.0.1:10110 or [::1]:10110";
    let addresses = text
        .to_socket_addrs()
        .map_err(|e| format!("{expected} ({e})"))?;
    addresses
        .into_iter()
        .next()
        .ok_or_else(|| format!("{expected} ({text:?} has no address)"))
}

/// The mission `scenario` (built-in name or file) with `overrides`, validated; every error is
/// the user's input.
pub fn mission(
    scenario: &str,
    overrides: &MissionOverrides,
) -> anyhow::Result<stx_sim::drone::MissionConfig> {
    overrides.apply(load_mission(scenario)?).map_err(|e| {
        BadInput(anyhow::Error::from(e).context("with the command line's failures")).into()
    })
}

/// The vehicle file given with `flag`; unreadable, not TOML or a field out of range is
/// [`BadInput`] naming the flag, the file and the field.
pub fn load_vehicle_flag(
    flag: &str,
    path: &Path,
) -> anyhow::Result<stx_dynamics::vehicle::Vehicle> {
    load_vehicle(Some(path)).map_err(|e| match e.downcast::<BadInput>() {
        Ok(BadInput(e)) => BadInput(e.context(flag.to_string())).into(),
        Err(e) => e.context(flag.to_string()),
    })
}

/// A flight's error for the exit code: refused input is [`BadInput`].
pub fn fly_error(e: FlyError) -> anyhow::Error {
    match e {
        FlyError::PersistMark(_) => {
            BadInput(anyhow::Error::from(e).context("--signing-timestamp-file")).into()
        }
        e if e.is_input() => BadInput(e.into()).into(),
        e => e.into(),
    }
}

impl DroneArgs {
    /// The options these flags (and the environment `env`, e.g. `|k| std::env::var_os(k)`)
    /// ask for, the mission loaded; a malformed flag or a bad file is [`BadInput`].
    fn options(&self, env: impl Fn(&str) -> Option<OsString>) -> anyhow::Result<FlyOptions> {
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
        let overrides = MissionOverrides {
            seed: self.seed,
            failures: FailureFlags {
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
            },
            gains: self.gains.as_deref().map(load_gains).transpose()?,
        };
        let signing = match signing_key(self.sign_key_file.as_deref(), &env)? {
            None => None,
            Some(key) => {
                let file = self.signing_timestamp_file.clone().or_else(|| {
                    default_state_dir(&env)
                        .map(|d| d.join(format!("drone-sys{}.signing.timestamp", self.system_id)))
                });
                Some(Signing {
                    key,
                    timestamp_file: file.ok_or_else(|| {
                        bad(anyhow!(
                            "--signing-timestamp-file: needed with signing (no \
                             $STATE_DIRECTORY, $XDG_STATE_HOME or $HOME to put it in)"
                        ))
                    })?,
                    clock_unix: None,
                })
            }
        };
        let mut options = FlyOptions::new(&self.connect, mission(&self.scenario, &overrides)?);
        options.speed = self.speed;
        options.link.system_id = self.system_id;
        options.signing = signing;
        options.linger = Some(Duration::from_secs_f64(self.linger));
        options.anemometer_to = self.anemometer_to;
        if let Some(path) = &self.vehicle {
            options.vehicle = load_vehicle_flag("--vehicle", path)?;
        }
        options.dispersions = self
            .dispersions
            .as_deref()
            .map(stx_sim::dispersions::Dispersions::load)
            .transpose()
            .map_err(|e| bad(anyhow::Error::new(e).context("--dispersions")))?;
        Ok(options)
    }
}

/// The signing key from `file`, or from `STX_SIGNING_KEY` in `env`; both is ambiguous.
/// Errors never repeat the key.
pub fn signing_key(
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

pub fn run(args: DroneArgs) -> anyhow::Result<()> {
    // Bad missions and flags are refused before anything starts.
    let options = args.options(|k| std::env::var_os(k))?;
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
    let report: FlightReport = if std::io::stderr().is_terminal() {
        let bar = Bar::new();
        let report = runtime.block_on(stx_sim::runner::fly(options, shutdown, bar.clone()));
        bar.0.finish_and_clear();
        report
    } else {
        runtime.block_on(stx_sim::runner::fly(
            options,
            shutdown,
            ProgressLog::default(),
        ))
    }
    .map_err(fly_error)?;
    if args.summary_json {
        println!("{}", serde_json::to_string(&report)?);
    }
    Ok(())
}

/// A spinner with the flight's state, for a terminal.
#[derive(Clone)]
struct Bar(ProgressBar);

impl Bar {
    fn new() -> Self {
        let bar = ProgressBar::new_spinner();
        bar.set_style(
            ProgressStyle::with_template("{spinner} {elapsed} {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        );
        bar.enable_steady_tick(Duration::from_millis(200));
        Self(bar)
    }
}

impl FlightObserver for Bar {
    fn step(&mut self, r: &StepReport) {
        self.0.set_message(format!(
            "t {:.0} s, {}, {:.0} m MSL, {:?}, {:?}",
            r.time_s,
            stage_name(r.stage),
            r.altitude_msl_m,
            r.mode,
            r.phase
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        drone: DroneArgs,
    }

    fn options(flags: &[&str]) -> anyhow::Result<FlyOptions> {
        options_env(flags, &[("HOME", "/home/op")])
    }

    fn options_env(flags: &[&str], vars: &[(&str, &str)]) -> anyhow::Result<FlyOptions> {
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

    fn key_and_file(o: &FlyOptions) -> Option<(&SigningKey, &Path)> {
        o.signing
            .as_ref()
            .map(|s| (&s.key, s.timestamp_file.as_path()))
    }

    #[test]
    fn the_key_comes_from_a_file_or_the_environment_never_the_command_line() {
        let dir = temp_dir("key");
        let key_file = dir.join("key");
        std::fs::write(&key_file, format!("{KEY}\n")).expect("write");
        let file_flag = key_file.to_str().expect("utf-8");
        let key = SigningKey::from_hex(KEY).expect("hex");
        let o = options(&["--sign-key-file", file_flag]).expect("valid");
        // The default timestamp file: the state directory, per system id.
        assert!(
            key_and_file(&o)
                == Some((
                    &key,
                    Path::new("/home/op/.local/state/stx/drone-sys1.signing.timestamp")
                ))
        );
        let o = options_env(
            &["--system-id", "7"],
            &[(SIGNING_KEY_ENV, KEY), ("STATE_DIRECTORY", "/var/lib/stx")],
        )
        .expect("valid");
        assert!(
            key_and_file(&o)
                == Some((&key, Path::new("/var/lib/stx/drone-sys7.signing.timestamp")))
        );
        assert_eq!(o.link.system_id, 7);
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
            "--linger",
            "2.5",
        ])
        .expect("valid flags");
        assert_eq!(o.speed, Speed::Max);
        assert_eq!(o.mission.name, "rehearsal");
        assert_eq!(o.mission.seed, 9);
        assert_eq!(o.mission.failures.link_drop_s, vec![[100.0, 160.0]]);
        assert_eq!(o.mission.failures.gps_loss_s, vec![[300.0, 330.0]]);
        assert_eq!(o.mission.failures.packet_loss_pct, 20.0);
        assert!(o.mission.failures.stuck_servo.is_some());
        assert_eq!(o.linger, Some(Duration::from_millis(2500)));
        assert!(o.signing.is_none());
        for flags in [
            &["--link-drop", "160:100"][..],
            &["--stuck-servo", "up@3"],
            &["--linger=-1"],
            &["--gains", "/nonexistent/gains.toml"],
            &["--scenario", "rehearsal", "--packet-loss", "120"],
        ] {
            let err = options(flags).expect_err("refused");
            assert!(err.downcast_ref::<BadInput>().is_some(), "{flags:?}: {err}");
        }
        let err = options(&["--scenario", "rehearsal", "--packet-loss", "120"]).expect_err("120 %");
        assert!(format!("{err:#}").contains("packet_loss_pct"), "{err:#}");
    }

    #[test]
    fn the_anemometer_address_is_an_ip_and_port_or_a_host_and_port() {
        assert_eq!(options(&[]).expect("valid").anemometer_to, None);
        let to = |flag: &str| options(&["--anemometer-to", flag]).map(|o| o.anemometer_to);
        assert_eq!(
            to("127.0.0.1:10110").expect("valid"),
            Some("127.0.0.1:10110".parse().expect("address"))
        );
        assert_eq!(
            to("[::1]:10110").expect("valid"),
            Some("[::1]:10110".parse().expect("address"))
        );
        let local = to("localhost:10110").expect("resolved").expect("given");
        assert!(local.ip().is_loopback() && local.port() == 10110, "{local}");
        for bad in ["10110", "127.0.0.1", "127.0.0.1:99999", "[::1]"] {
            let err = to(bad).expect_err(bad).to_string();
            assert!(
                err.contains("--anemometer-to") && err.contains("HOST:PORT"),
                "{bad}: {err}"
            );
        }
    }

    #[test]
    fn an_unknown_mission_is_bad_input_and_names_the_built_in_ones() {
        let err = options(&["--scenario", "no-such-mission"]).expect_err("refused");
        assert!(err.downcast_ref::<BadInput>().is_some());
        assert!(format!("{err:#}").contains("mission-short"), "{err:#}");
    }

    #[test]
    fn a_refused_flight_is_bad_input_and_a_failed_one_is_not() {
        let bad = fly_error(FlyError::PersistMark(std::io::Error::other("read-only")));
        assert!(bad.downcast_ref::<BadInput>().is_some());
        assert!(
            format!("{bad:#}").contains("--signing-timestamp-file"),
            "{bad:#}"
        );
        let failed = fly_error(FlyError::LinkStopped);
        assert!(failed.downcast_ref::<BadInput>().is_none());
    }
}
