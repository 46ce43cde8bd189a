//! Flight versus model (issue 16 item 1; the seed's Estimation panel, Fig. 4.12): fly the
//! model through a recorded flight ([`replay`]) and set the two side by side, channel by
//! channel — position north, east and height, roll, pitch and yaw, airspeed, sink rate and
//! turn rate — with the error figures of each (RMS, largest, bias).
//!
//! Pure: takes a [`FlightLog`] and a [`Vehicle`], returns a [`CompareReport`] (serde, JSON
//! Schema) that `stx compare` prints and the dashboard's Lab page draws.

pub mod replay;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use stx_dynamics::vehicle::Vehicle;

use crate::flight_log::{FlightLog, LogSample};
pub use replay::{Flown, Nuisance, ReplayError, fly, fly_corrected, fly_watched, initial_state};

/// Default integration step of a replay, s: RK4 at 20 ms follows the stack's fastest modes
/// (the servo and pendulum poles, a few rad/s) to well under a centimetre over minutes.
pub const DEFAULT_STEP_S: f64 = 0.02;

/// Error figures of one channel, simulated minus recorded, over the samples where both exist.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ErrorFigures {
    /// Root-mean-square error, in the channel's unit.
    pub rms: f64,
    /// Largest absolute error, in the channel's unit.
    pub max_abs: f64,
    /// Mean error (simulated − recorded), in the channel's unit.
    pub bias: f64,
    /// Samples compared.
    pub count: usize,
}

impl ErrorFigures {
    /// The figures of `errors` (NaN entries skipped; zeros when there are none).
    pub fn of(errors: impl IntoIterator<Item = f64>) -> Self {
        let (mut n, mut sum, mut sq, mut max) = (0usize, 0.0, 0.0, 0.0_f64);
        for e in errors.into_iter().filter(|e| e.is_finite()) {
            n += 1;
            sum += e;
            sq += e * e;
            max = max.max(e.abs());
        }
        let d = n.max(1) as f64;
        Self {
            rms: (sq / d).sqrt(),
            max_abs: max,
            bias: sum / d,
            count: n,
        }
    }
}

/// One channel, recorded and simulated, at the log's instants.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ChannelComparison {
    /// Name (`north_m`, `east_m`, `height_m`, `roll_deg`, `pitch_deg`, `yaw_deg`,
    /// `airspeed_mps`, `sink_mps`, `turn_rate_deg_s`).
    pub name: String,
    /// Unit (`m`, `deg`, `m/s`, `deg/s`).
    pub unit: String,
    /// What the drone recorded (`null` where it measured nothing).
    pub recorded: Vec<Option<f64>>,
    /// What the model flew.
    pub simulated: Vec<f64>,
    /// Simulated minus recorded (yaw wrapped to ±180°).
    pub error: ErrorFigures,
}

/// A flight compared with the model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct CompareReport {
    /// The instants, s from the log's first.
    pub time_s: Vec<f64>,
    /// Flight duration, s.
    pub duration_s: f64,
    /// The part of a longer recording compared (a mission's parafoil stage; `None`: all of it).
    #[serde(default)]
    pub part: Option<crate::flight_log::RecordedPart>,
    /// Each channel.
    pub channels: Vec<ChannelComparison>,
}

impl CompareReport {
    /// The channel called `name`.
    pub fn channel(&self, name: &str) -> Option<&ChannelComparison> {
        self.channels.iter().find(|c| c.name == name)
    }
}

/// How a comparison flies.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct CompareOptions {
    /// Largest integration step, s.
    pub step_s: f64,
}

impl Default for CompareOptions {
    fn default() -> Self {
        Self {
            step_s: DEFAULT_STEP_S,
        }
    }
}

/// Flies `vehicle` through `log` and compares the two.
pub fn compare(
    log: &FlightLog,
    vehicle: &Vehicle,
    options: &CompareOptions,
) -> Result<CompareReport, ReplayError> {
    let flown = fly(log, vehicle, options.step_s)?;
    Ok(report(log, &flown))
}

/// The comparison of `log` with what the model `flown` through it.
pub fn report(log: &FlightLog, flown: &[Flown]) -> CompareReport {
    let rec = log.samples();
    let t0 = rec[0].time_s;
    let deg = f64::to_degrees;
    type Pick<T> = fn(&T) -> f64;
    let both: [(&str, &str, Pick<LogSample>, Pick<Flown>); 5] = [
        (
            "north_m",
            "m",
            |s| s.position_ned_m[0],
            |f| f.position_ned_m[0],
        ),
        (
            "east_m",
            "m",
            |s| s.position_ned_m[1],
            |f| f.position_ned_m[1],
        ),
        (
            "height_m",
            "m",
            |s| -s.position_ned_m[2],
            |f| -f.position_ned_m[2],
        ),
        (
            "roll_deg",
            "deg",
            |s| s.euler_rad[0].to_degrees(),
            |f| f.euler_rad[0].to_degrees(),
        ),
        (
            "pitch_deg",
            "deg",
            |s| s.euler_rad[1].to_degrees(),
            |f| f.euler_rad[1].to_degrees(),
        ),
    ];
    let mut channels: Vec<ChannelComparison> = both
        .iter()
        .map(|(name, unit, r, s)| {
            channel(
                name,
                unit,
                rec.iter().map(|x| Some(r(x))).collect(),
                flown.iter().map(s).collect(),
                false,
            )
        })
        .collect();
    channels.push(channel(
        "yaw_deg",
        "deg",
        rec.iter().map(|s| Some(deg(s.euler_rad[2]))).collect(),
        flown.iter().map(|f| deg(f.euler_rad[2])).collect(),
        true,
    ));
    channels.push(channel(
        "airspeed_mps",
        "m/s",
        rec.iter().map(|s| s.airspeed_mps).collect(),
        flown.iter().map(|f| f.airspeed_mps).collect(),
        false,
    ));
    channels.push(channel(
        "sink_mps",
        "m/s",
        rec.iter().map(|s| Some(s.velocity_ned_mps[2])).collect(),
        flown.iter().map(|f| f.velocity_ned_mps[2]).collect(),
        false,
    ));
    let times: Vec<f64> = rec.iter().map(|s| s.time_s).collect();
    let rec_yaw: Vec<f64> = rec.iter().map(|s| s.euler_rad[2]).collect();
    let sim_yaw: Vec<f64> = flown.iter().map(|f| f.euler_rad[2]).collect();
    channels.push(channel(
        "turn_rate_deg_s",
        "deg/s",
        turn_rate_deg_s(&times, &rec_yaw)
            .into_iter()
            .map(Some)
            .collect(),
        turn_rate_deg_s(&times, &sim_yaw),
        false,
    ));
    CompareReport {
        time_s: times.iter().map(|t| t - t0).collect(),
        duration_s: log.duration_s(),
        part: log.part(),
        channels,
    }
}

fn channel(
    name: &str,
    unit: &str,
    recorded: Vec<Option<f64>>,
    simulated: Vec<f64>,
    wrap_degrees: bool,
) -> ChannelComparison {
    let error = ErrorFigures::of(recorded.iter().zip(&simulated).map(|(r, s)| match r {
        Some(r) if wrap_degrees => wrap_deg(s - r),
        Some(r) => s - r,
        None => f64::NAN,
    }));
    ChannelComparison {
        name: name.into(),
        unit: unit.into(),
        recorded,
        simulated,
        error,
    }
}

/// An angle difference in degrees wrapped into (−180, 180].
pub fn wrap_deg(d: f64) -> f64 {
    let w = (d + 180.0).rem_euclid(360.0) - 180.0;
    if w == -180.0 { 180.0 } else { w }
}

/// Half-width of the window over which the turn rate is differenced, s: a second each side
/// smooths the AHRS noise and the drone's own quick yaw swings under the canopy, so that the
/// channel shows the stack's turn.
pub const TURN_RATE_HALF_WINDOW_S: f64 = 1.0;

/// Heading rate, deg/s: the yaw change (wrapped, summed sample to sample) across a window of
/// [`TURN_RATE_HALF_WINDOW_S`] each side, shrunk at the ends of the flight.
fn turn_rate_deg_s(times: &[f64], yaw_rad: &[f64]) -> Vec<f64> {
    let n = times.len();
    let mut unwrapped = vec![yaw_rad[0].to_degrees(); n];
    for k in 1..n {
        unwrapped[k] = unwrapped[k - 1] + wrap_deg((yaw_rad[k] - yaw_rad[k - 1]).to_degrees());
    }
    (0..n)
        .map(|k| {
            let a = times.partition_point(|t| *t < times[k] - TURN_RATE_HALF_WINDOW_S);
            let b = times.partition_point(|t| *t <= times[k] + TURN_RATE_HALF_WINDOW_S) - 1;
            let (a, b) = if a == b {
                (a.saturating_sub(1), (b + 1).min(n - 1))
            } else {
                (a, b)
            };
            (unwrapped[b] - unwrapped[a]) / (times[b] - times[a])
        })
        .collect()
}

#[cfg(test)]
mod tests;
