//! What a flight tells whoever watches it: a [`StepReport`] after each step, the driver's
//! events, and the log every flight writes of them ([`log_event`]); [`ProgressLog`] is the
//! progress as log lines, for a process without a terminal.

use std::time::{Duration, Instant};

use stx_gnc::mission::{FlightMode, FlightStage, GuidancePhase};
use stx_link::sansio::IoEvent;
use stx_link_tokio::DriverEvent;

use crate::drone::link::{DroneEvent, LinkedDrone};
use crate::drone::stage_name;

/// What one step did.
#[derive(Debug, Clone, Copy)]
pub struct StepReport {
    /// Mission time after the step, s.
    pub time_s: f64,
    /// The stage.
    pub stage: FlightStage,
    /// The mode.
    pub mode: FlightMode,
    /// The guidance phase.
    pub phase: GuidancePhase,
    /// True altitude, m MSL.
    pub altitude_msl_m: f64,
    /// Whether the drone has landed.
    pub landed: bool,
    /// `time_boot_ms` of the ATTITUDE this step handed to the link, if it sent one: how a
    /// benchmark finds the frame again in what the station publishes.
    pub attitude_time_boot_ms: Option<u32>,
    /// When the step finished, its frames queued for the socket (the driver sends them before
    /// it does anything else).
    pub finished_at: Instant,
}

impl StepReport {
    /// The report of the step `linked` just flew; `attitude_before` is its latest ATTITUDE
    /// stamp before the step.
    pub(super) fn of(linked: &LinkedDrone, attitude_before: Option<u32>) -> Self {
        let d = linked.drone();
        let status = d.status();
        let attitude = linked.last_attitude_time_boot_ms();
        StepReport {
            time_s: d.time_s(),
            stage: status.stage,
            mode: status.mode,
            phase: status.phase,
            altitude_msl_m: d.physics().altitude_msl_m(),
            landed: linked.landed(),
            attitude_time_boot_ms: attitude.filter(|_| attitude != attitude_before),
            finished_at: Instant::now(),
        }
    }
}

/// Watches a flight. Both methods are called from the task running the flight, between
/// steps: keep them quick.
pub trait FlightObserver: Send {
    /// After each step (reports can come a few steps late at maximum speed).
    fn step(&mut self, _report: &StepReport) {}

    /// Each event of the link's driver, after it has been logged.
    fn event(&mut self, _event: &DriverEvent<DroneEvent>) {}
}

/// Watches nothing.
impl FlightObserver for () {}

/// The flight's progress (stage, altitude, mode, phase) as info-level log lines: at every
/// stage change and at least every [`ProgressLog::INTERVAL`].
#[derive(Debug, Default)]
pub struct ProgressLog {
    last_stage: Option<FlightStage>,
    last_line: Option<Instant>,
}

impl ProgressLog {
    /// Longest time between two lines.
    pub const INTERVAL: Duration = Duration::from_secs(5);
}

impl FlightObserver for ProgressLog {
    fn step(&mut self, r: &StepReport) {
        if self.last_stage != Some(r.stage)
            || self
                .last_line
                .is_none_or(|at| at.elapsed() >= Self::INTERVAL)
        {
            self.last_stage = Some(r.stage);
            self.last_line = Some(Instant::now());
            tracing::info!(
                t = format!("{:.0}", r.time_s),
                stage = %stage_name(r.stage),
                alt_msl_m = format!("{:.0}", r.altitude_msl_m),
                mode = ?r.mode,
                phase = ?r.phase,
                "progress"
            );
        }
    }
}

/// The drone's log: its texts, commands, parameters and link state at info level.
pub(super) fn log_event(event: &DriverEvent<DroneEvent>) {
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
