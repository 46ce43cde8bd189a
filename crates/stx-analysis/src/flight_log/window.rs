//! A part of a flight log to compare or fit. A mission recording holds the ascent under the
//! balloon and the round-chute descent beside the parafoil's flight, and the model only
//! flies the parafoil: an engineer picks the part to use by its times on the log's own clock,
//! in seconds from the log's first sample (as the comparison's plots and `time_s` count
//! them), and the model starts from the recorded state at the window's first sample.

use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::{FlightLog, MIN_SAMPLES};

/// The part of a log from `from_s` to `to_s`, s from its first sample (either end open: the
/// log's own).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Window {
    /// Start, s from the log's first sample (≥ 0).
    pub from_s: Option<f64>,
    /// End, s from the log's first sample (> `from_s`).
    pub to_s: Option<f64>,
}

/// Which end of a window a refusal is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WindowEnd {
    /// The start.
    From,
    /// The end.
    To,
    /// The two together.
    Both,
}

/// Why a window was refused.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum WindowError {
    /// An end is not a finite, non-negative number of seconds.
    #[error("must be a finite number of seconds from the log's start, ≥ 0, not {value}")]
    NotATime { end: WindowEnd, value: f64 },
    /// The window ends where or before it starts.
    #[error("the window must end after it starts (from {from_s} s, to {to_s} s)")]
    Empty { from_s: f64, to_s: f64 },
    /// The window holds too few samples to fly.
    #[error(
        "the window from {from_s} s to {to_s} s holds {samples} samples of the flight's \
         {duration_s:.1} s; at least {MIN_SAMPLES} are needed"
    )]
    NoFlight {
        from_s: f64,
        to_s: f64,
        samples: usize,
        duration_s: f64,
    },
}

impl WindowError {
    /// The end the refusal is about, for a caller to name its field or flag.
    pub fn end(&self) -> WindowEnd {
        match self {
            WindowError::NotATime { end, .. } => *end,
            WindowError::Empty { .. } => WindowEnd::To,
            WindowError::NoFlight { .. } => WindowEnd::Both,
        }
    }
}

impl Window {
    /// The whole log.
    pub const WHOLE: Window = Window {
        from_s: None,
        to_s: None,
    };

    /// The window from `from_s` to `to_s` (not checked yet).
    pub fn new(from_s: Option<f64>, to_s: Option<f64>) -> Self {
        Self { from_s, to_s }
    }

    /// Refuses ends that are not times from the start, or that hold nothing between them
    /// (whether the log holds a flight there is [`FlightLog::cut`]'s question).
    pub fn check(&self) -> Result<(), WindowError> {
        for (end, value) in [(WindowEnd::From, self.from_s), (WindowEnd::To, self.to_s)] {
            if let Some(value) = value.filter(|v| !(v.is_finite() && *v >= 0.0)) {
                return Err(WindowError::NotATime { end, value });
            }
        }
        match (self.from_s, self.to_s) {
            (Some(from_s), Some(to_s)) if to_s <= from_s => {
                Err(WindowError::Empty { from_s, to_s })
            }
            _ => Ok(()),
        }
    }
}

impl FlightLog {
    /// The samples of `window`, times kept as they are (the replay counts from the first
    /// one kept, so the model starts from the recorded state there).
    pub fn cut(&self, window: &Window) -> Result<FlightLog, WindowError> {
        window.check()?;
        if *window == Window::WHOLE {
            return Ok(self.clone());
        }
        let t0 = self.samples()[0].time_s;
        let from_s = window.from_s.unwrap_or(0.0);
        let to_s = window.to_s.unwrap_or(f64::INFINITY);
        let kept: Vec<_> = self
            .samples()
            .iter()
            .filter(|s| (from_s..=to_s).contains(&(s.time_s - t0)))
            .copied()
            .collect();
        let samples = kept.len();
        // The samples of a valid log stay valid: only too few can be refused.
        let log = FlightLog::new(kept).map_err(|_| WindowError::NoFlight {
            from_s,
            to_s,
            samples,
            duration_s: self.duration_s(),
        })?;
        // A window of a recording's parafoil stage is still that stage, narrower.
        Ok(match self.part() {
            Some(part) => {
                let s = log.samples();
                let (first, last) = (s[0].time_s - t0, s[s.len() - 1].time_s - t0);
                log.taken_from(super::RecordedPart {
                    from_s: part.from_s + first,
                    to_s: part.from_s + last,
                    ..part
                })
            }
            None => log,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flight_log::tests::straight;

    #[test]
    fn a_window_counts_from_the_log_s_first_sample() {
        let mut samples = straight(10);
        for s in &mut samples {
            s.time_s += 100.0;
        }
        let log = FlightLog::new(samples).unwrap();
        let cut = log.cut(&Window::new(Some(2.0), Some(6.0))).unwrap();
        let times: Vec<f64> = cut.samples().iter().map(|s| s.time_s).collect();
        assert_eq!(times, vec![102.0, 103.0, 104.0, 105.0, 106.0]);
        assert_eq!(cut.duration_s(), 4.0);
        assert_eq!(
            log.cut(&Window::new(Some(7.0), None))
                .unwrap()
                .samples()
                .len(),
            3
        );
        assert_eq!(
            log.cut(&Window::new(None, Some(2.0)))
                .unwrap()
                .samples()
                .len(),
            3
        );
        assert_eq!(log.cut(&Window::WHOLE).unwrap(), log);
    }

    #[test]
    fn bad_windows_are_refused_naming_their_end() {
        let log = FlightLog::new(straight(10)).unwrap();
        let refused = |from_s, to_s| log.cut(&Window::new(from_s, to_s)).unwrap_err();
        let e = refused(Some(-1.0), None);
        assert_eq!(e.end(), WindowEnd::From);
        assert!(e.to_string().contains("≥ 0, not -1"), "{e}");
        assert_eq!(refused(None, Some(f64::NAN)).end(), WindowEnd::To);
        assert_eq!(refused(Some(f64::INFINITY), None).end(), WindowEnd::From);
        assert_eq!(
            refused(Some(5.0), Some(5.0)),
            WindowError::Empty {
                from_s: 5.0,
                to_s: 5.0
            }
        );
        let e = refused(Some(8.5), Some(20.0));
        assert_eq!(e.end(), WindowEnd::Both);
        assert!(
            e.to_string()
                .contains("holds 1 samples of the flight's 9.0 s"),
            "{e}"
        );
        assert!(
            refused(Some(20.0), Some(30.0))
                .to_string()
                .contains("holds 0")
        );
    }
}
