//! A recorded flight as model comparison ([`crate::compare`]) and identification
//! ([`crate::identify`]) need it: one time series of what the drone measured (GPS position and
//! velocity, attitude, airspeed), what its servos were told, and the wind it estimated.
//!
//! Kept apart from where it came from so that both analyses stay pure: [`csv`] reads and
//! writes the documented one-file CSV form, [`recording`] builds a log from the decoded
//! telemetry of a station recording (the caller reads the MCAP file), and tests build logs
//! from simulated flights. [`window`] cuts the part of a log to use.

pub mod csv;
pub mod recording;
pub mod synthetic;
mod telemetry;
pub mod window;

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Fewest samples a log must have to be compared or fitted.
pub const MIN_SAMPLES: usize = 3;

/// Why a flight log was refused.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum FlightLogError {
    /// Too few samples to fly anything.
    #[error("flight log has {samples} samples; at least {MIN_SAMPLES} are needed")]
    TooShort { samples: usize },
    /// Times do not increase.
    #[error("flight log sample {index}: time {time_s} s does not follow the previous one")]
    NotIncreasing { index: usize, time_s: f64 },
    /// A value is NaN or infinite.
    #[error("flight log sample {index}: `{field}` is not a finite number")]
    NonFinite { index: usize, field: &'static str },
    /// A CSV line could not be read.
    #[error("flight log CSV line {line}: {message}")]
    Csv { line: usize, message: String },
    /// A CSV column the format requires is missing from the header.
    #[error(
        "flight log CSV has no column `{0}` (see the column list in stx_analysis::flight_log::csv)"
    )]
    MissingColumn(&'static str),
    /// A recording lacks the telemetry a log is made of.
    #[error("the recording has no `{0}` telemetry: cannot make a flight log of it")]
    MissingTelemetry(&'static str),
    /// A recorded message could not be decoded.
    #[error("recorded `{topic}` message at {time_s} s is not valid: {message}")]
    BadMessage {
        topic: String,
        time_s: f64,
        message: String,
    },
}

/// One instant of a flight, in the local frame: north and east of an origin, down from mean
/// sea level (so `−position_ned_m[2]` is the altitude MSL).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct LogSample {
    /// Time, s (any origin; only differences matter).
    pub time_s: f64,
    /// Drone position (its GPS), NED, m; down is from mean sea level.
    pub position_ned_m: [f64; 3],
    /// Drone velocity over the ground, NED, m/s.
    pub velocity_ned_mps: [f64; 3],
    /// Drone roll, pitch, yaw relative to NED (3-2-1), rad.
    pub euler_rad: [f64; 3],
    /// True airspeed, m/s, when measured.
    pub airspeed_mps: Option<f64>,
    /// Main-line command, −1 (full left) … +1 (full right) of the vehicle's travel.
    pub main_line: f64,
    /// Right brake command, 0 … 1.
    pub brake_right: f64,
    /// Left brake command, 0 … 1.
    pub brake_left: f64,
    /// The drone's wind estimate (the air's velocity), NED, m/s.
    pub wind_ned_mps: [f64; 3],
}

/// A validated flight: at least [`MIN_SAMPLES`] samples, times increasing, values finite.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FlightLog {
    samples: Vec<LogSample>,
    /// Where in a longer recording the log was taken from (`None`: the whole of it).
    #[serde(default)]
    part: Option<RecordedPart>,
}

/// The part of a recording a log holds, when it is not the whole: a mission recording's
/// parafoil flight (the model is a parafoil's; the balloon's ascent, the round chute, the
/// canopy's inflation and the ground are not its to fly).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct RecordedPart {
    /// The flight stage the log holds (`parafoil`).
    #[schemars(with = "String")]
    pub stage: stx_gnc::mission::FlightStage,
    /// Its start and end, s of the recording's drone clock from the recording's first position.
    pub from_s: f64,
    /// End, s.
    pub to_s: f64,
    /// How long the recording's positions last, s.
    pub recorded_s: f64,
}

impl FlightLog {
    /// Checks `samples` and makes a log of them.
    pub fn new(samples: Vec<LogSample>) -> Result<Self, FlightLogError> {
        if samples.len() < MIN_SAMPLES {
            return Err(FlightLogError::TooShort {
                samples: samples.len(),
            });
        }
        for (index, s) in samples.iter().enumerate() {
            let fields: [(&'static str, &[f64]); 6] = [
                ("time_s", &[s.time_s]),
                ("position_ned_m", &s.position_ned_m),
                ("velocity_ned_mps", &s.velocity_ned_mps),
                ("euler_rad", &s.euler_rad),
                ("commands", &[s.main_line, s.brake_right, s.brake_left]),
                ("wind_ned_mps", &s.wind_ned_mps),
            ];
            for (field, values) in fields {
                if values.iter().any(|v| !v.is_finite()) {
                    return Err(FlightLogError::NonFinite { index, field });
                }
            }
            if s.airspeed_mps.is_some_and(|a| !a.is_finite()) {
                return Err(FlightLogError::NonFinite {
                    index,
                    field: "airspeed_mps",
                });
            }
            if index > 0 && s.time_s <= samples[index - 1].time_s {
                return Err(FlightLogError::NotIncreasing {
                    index,
                    time_s: s.time_s,
                });
            }
        }
        Ok(Self {
            samples,
            part: None,
        })
    }

    /// The same log, marked as `part` of a longer recording.
    pub fn taken_from(mut self, part: RecordedPart) -> Self {
        self.part = Some(part);
        self
    }

    /// Where in a longer recording the log was taken from (`None`: the whole of it).
    pub fn part(&self) -> Option<RecordedPart> {
        self.part
    }

    /// The samples, in time order.
    pub fn samples(&self) -> &[LogSample] {
        &self.samples
    }

    /// Duration, s.
    pub fn duration_s(&self) -> f64 {
        self.samples[self.samples.len() - 1].time_s - self.samples[0].time_s
    }

    /// The commands in force at `time_s`: main line (−1 … 1), right and left brake, each
    /// held from its sample until the next (the first before the log). A recorded command is
    /// what the servos were told from then on, so holding it, not interpolating between
    /// samples, is what they did: a step interpolated over a sample interval is a step moved
    /// by half an interval, and that bias showed in identification.
    pub fn commands_at(&self, time_s: f64) -> [f64; 3] {
        let s = &self.samples;
        let i = s.partition_point(|x| x.time_s <= time_s).saturating_sub(1);
        [s[i].main_line, s[i].brake_right, s[i].brake_left]
    }

    /// The wind estimate at `time_s`, NED, m/s, interpolated linearly between samples (held
    /// beyond them).
    pub fn wind_at(&self, time_s: f64) -> [f64; 3] {
        self.interpolate(time_s, |s| s.wind_ned_mps)
    }

    fn interpolate(&self, time_s: f64, f: impl Fn(&LogSample) -> [f64; 3]) -> [f64; 3] {
        let s = &self.samples;
        let i = s.partition_point(|x| x.time_s <= time_s);
        if i == 0 {
            return f(&s[0]);
        }
        if i == s.len() {
            return f(&s[i - 1]);
        }
        let (a, b) = (&s[i - 1], &s[i]);
        let w = (time_s - a.time_s) / (b.time_s - a.time_s);
        let (fa, fb) = (f(a), f(b));
        std::array::from_fn(|k| fa[k] + w * (fb[k] - fa[k]))
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A straight, steady flight north at 5 m/s, sinking 2.5 m/s from 1000 m, sampled at 1 Hz.
    pub fn straight(n: usize) -> Vec<LogSample> {
        (0..n)
            .map(|i| {
                let t = i as f64;
                LogSample {
                    time_s: t,
                    position_ned_m: [5.0 * t, 0.0, -1000.0 + 2.5 * t],
                    velocity_ned_mps: [5.0, 0.0, 2.5],
                    euler_rad: [0.0, 0.1, 0.0],
                    airspeed_mps: Some(5.6),
                    main_line: 0.0,
                    brake_right: 0.1 * t,
                    brake_left: 0.0,
                    wind_ned_mps: [0.0, 1.0, 0.0],
                }
            })
            .collect()
    }

    #[test]
    fn commands_are_held_and_winds_interpolated() {
        let log = FlightLog::new(straight(5)).unwrap();
        assert!((log.commands_at(1.5)[1] - 0.1).abs() < 1e-12);
        assert!((log.commands_at(2.0)[1] - 0.2).abs() < 1e-12);
        assert_eq!(log.commands_at(-3.0)[1], 0.0);
        assert!((log.commands_at(10.0)[1] - 0.4).abs() < 1e-12);
        assert_eq!(log.wind_at(2.2), [0.0, 1.0, 0.0]);
    }

    #[test]
    fn bad_logs_are_refused_with_the_reason() {
        assert_eq!(
            FlightLog::new(straight(2)),
            Err(FlightLogError::TooShort { samples: 2 })
        );
        let mut s = straight(4);
        s[2].time_s = 1.0;
        assert_eq!(
            FlightLog::new(s),
            Err(FlightLogError::NotIncreasing {
                index: 2,
                time_s: 1.0
            })
        );
        let mut s = straight(4);
        s[3].euler_rad[1] = f64::NAN;
        assert_eq!(
            FlightLog::new(s),
            Err(FlightLogError::NonFinite {
                index: 3,
                field: "euler_rad"
            })
        );
    }
}
