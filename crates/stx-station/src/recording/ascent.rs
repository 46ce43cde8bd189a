//! The wind an earlier flight measured on its ascent, read back from its recording, as a
//! forecast to plan the next flight with: the recording's decoded GPS_RAW_INT fixes through
//! the ascent wind estimator, merged into a forecast over the span it measured
//! (`merge_measured`; refused bands are listed, not merged). `stx plan --from-recording` and
//! the station's `POST /api/plan` both call [`measured_forecast`], so a recording gives both
//! the same winds.
//!
//! **Clock.** The fixes are timed on the drone's clock, as the live station times them
//! (`core/ascent.rs`): each GPS_RAW_INT takes the `time_boot_ms` of the latest message that
//! carries one (GLOBAL_POSITION_INT, ATTITUDE, SCALED_PRESSURE, POSITION_TARGET_GLOBAL_INT),
//! since GPS_RAW_INT's own time may be the receiver's. A recording's log times are the
//! station's clock: in a rehearsal at 20× the drone flies 20 s for each of them, and a drift
//! divided by them reads 20 times the wind. A clock that steps back (the drone restarted) is
//! continued from the last fix by the log time since it, as the live station does. A
//! recording without the decoded telemetry (only `/vehicle/gps`) has no drone clock and
//! measures nothing: [`MeasuredAscentError::NoDroneClock`].

use std::io::{Read, Seek};

use nalgebra::Vector3;
use serde::Deserialize;
use stx_gnc::ascent_wind::{AscentFix, AscentWindConfig, AscentWindEstimator, WindBand};
use stx_gnc::flight_path::{Forecast, ForecastError, ForecastRow, merge_measured};
use stx_gnc::geo::LocalFrame;
use stx_link::telemetry::{GlobalPosition, GpsRaw};
use stx_record::{ReadError, Recording};

use super::telemetry_topic;

/// Most a GLOBAL_POSITION_INT's vertical speed may lag a GPS fix on the drone's clock to give
/// the fix its vertical velocity, s (GPS_RAW_INT carries none).
const VERTICAL_SPEED_MAX_AGE_S: f64 = 1.0;

/// A clock stepping back by more than this is a restarted drone, s (as the live station).
const RESTART_STEP_BACK_S: f64 = 5.0;

/// Messages whose `time_boot_ms` is the drone's clock.
const CLOCKED: [&str; 4] = [
    "GLOBAL_POSITION_INT",
    "ATTITUDE",
    "SCALED_PRESSURE",
    "POSITION_TARGET_GLOBAL_INT",
];

/// A forecast with a recording's measured ascent wind in it.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasuredForecast {
    /// The merged forecast.
    pub forecast: Forecast,
    /// Every band the recording measured, lowest first, refused ones included
    /// ([`WindBand::refused`]); altitudes above `origin_msl_m`.
    pub bands: Vec<WindBand>,
    /// The bands' origin (the recording's first 3-D fix), m above mean sea level.
    pub origin_msl_m: f64,
}

impl MeasuredForecast {
    /// The bands merged into the forecast.
    pub fn believed(&self) -> impl Iterator<Item = &WindBand> {
        self.bands.iter().filter(|b| b.is_believed())
    }
}

/// Why a recording gave no measured wind.
#[derive(Debug, thiserror::Error)]
pub enum MeasuredAscentError {
    /// The recording could not be read.
    #[error("{0}")]
    Read(#[from] ReadError),
    /// It holds no decoded GPS fixes with the drone's clock.
    #[error(
        "it holds no decoded GPS_RAW_INT with the drone's clock (a message with time_boot_ms): its log times are the station's, which misstate the wind of a rehearsal run faster than real time"
    )]
    NoDroneClock,
    /// The track has too few fixes while rising for any band.
    #[error("no ascent wind could be measured (too few GPS fixes while rising)")]
    NoAscent,
    /// Every band was refused, and there is no forecast to plan in instead.
    #[error("every measured wind band was refused, and no forecast was given: {0}")]
    AllRefused(String),
    /// The measured bands and the forecast make no forecast together.
    #[error("the wind it measured: {0}")]
    Merge(#[from] ForecastError),
}

/// The fix of a GPS_RAW_INT with a 3-D fix, timed `time_s`: its velocity when the receiver
/// gives speed and course and a vertical speed `down_mps` is known, else its position alone.
/// The live station builds its fixes with it too.
pub(crate) fn fix_from_gps(
    frame: &LocalFrame,
    time_s: f64,
    g: &GpsRaw,
    down_mps: Option<f64>,
) -> Option<AscentFix> {
    if !g.has_3d_fix() {
        return None;
    }
    let velocity = match (g.ground_speed_mps, g.course_deg, down_mps) {
        (Some(speed), Some(course), Some(down)) => {
            let c = course.to_radians();
            Some(Vector3::new(speed * c.cos(), speed * c.sin(), down))
        }
        _ => None,
    };
    Some(AscentFix::from_geodetic(
        frame,
        time_s,
        g.lat_deg,
        g.lon_deg,
        g.alt_msl_m,
        velocity,
    ))
}

/// Any telemetry message's drone clock.
#[derive(Deserialize)]
struct Stamped {
    time_boot_ms: u32,
}

/// The drone's clock as the recording shows it, continued across restarts.
#[derive(Default)]
struct DroneClock {
    /// Latest `time_boot_ms`, s, as the drone sent it.
    raw_s: Option<f64>,
    /// Added to it, s (grows at each restart).
    offset_s: f64,
    /// The continued clock and the log time of the latest reading, s.
    last: Option<(f64, f64)>,
}

impl DroneClock {
    fn observe(&mut self, log_s: f64, time_boot_ms: u32) {
        let t = f64::from(time_boot_ms) / 1000.0;
        let raw = match (self.raw_s, self.last) {
            (Some(raw), Some((last_t, last_log))) if raw - t > RESTART_STEP_BACK_S => {
                self.offset_s = last_t + (log_s - last_log).max(1e-3) - t;
                t
            }
            (Some(raw), _) => raw.max(t),
            (None, _) => t,
        };
        self.raw_s = Some(raw);
        self.last = Some((raw + self.offset_s, log_s));
    }

    fn now_s(&self) -> Option<f64> {
        self.last.map(|(t, _)| t)
    }
}

/// `forecast` (possibly empty) with the ascent wind `recording` measured in place of its rows
/// where it measured (see the module doc).
pub fn measured_forecast<R: Read + Seek>(
    recording: &mut Recording<R>,
    forecast: &[ForecastRow],
) -> Result<MeasuredForecast, MeasuredAscentError> {
    let gps_topic = telemetry_topic("GPS_RAW_INT");
    let position_topic = telemetry_topic("GLOBAL_POSITION_INT");
    let clocked: Vec<String> = CLOCKED.iter().map(|n| telemetry_topic(n)).collect();
    let mut estimator = AscentWindEstimator::new(AscentWindConfig::default())
        .map_err(|_| MeasuredAscentError::NoAscent)?;
    let mut clock = DroneClock::default();
    let mut frame: Option<LocalFrame> = None;
    // The latest vertical speed (down, m/s) and its drone time, s.
    let mut down: Option<(f64, f64)> = None;
    let mut clocked_fixes = 0u64;
    for message in recording.messages()? {
        let message = message?;
        let log_s = message.log_time as f64 * 1e-9;
        let topic = &*message.topic;
        if topic == gps_topic {
            let (Some(t), Ok(g)) = (
                clock.now_s(),
                serde_json::from_slice::<GpsRaw>(&message.data),
            ) else {
                continue;
            };
            let origin = *frame.get_or_insert(LocalFrame {
                lat_deg: g.lat_deg,
                lon_deg: g.lon_deg,
                alt_msl_m: g.alt_msl_m,
            });
            let fresh = down
                .filter(|(_, at)| (t - at).abs() <= VERTICAL_SPEED_MAX_AGE_S)
                .map(|(d, _)| d);
            if let Some(fix) = fix_from_gps(&origin, t, &g, fresh) {
                clocked_fixes += 1;
                // A refused fix (out of order, non-finite) is one the estimator cannot use.
                let _ = estimator.push_fix(&fix);
            }
        } else if clocked.iter().any(|c| c == topic)
            && let Ok(s) = serde_json::from_slice::<Stamped>(&message.data)
        {
            clock.observe(log_s, s.time_boot_ms);
            if topic == position_topic
                && let (Ok(p), Some(t)) = (
                    serde_json::from_slice::<GlobalPosition>(&message.data),
                    clock.now_s(),
                )
            {
                down = Some((p.v_down_mps, t));
            }
        }
    }
    if clocked_fixes == 0 {
        return Err(MeasuredAscentError::NoDroneClock);
    }
    let bands = estimator.profile();
    let origin_msl_m = frame.map_or(0.0, |f| f.alt_msl_m);
    if bands.is_empty() {
        return Err(MeasuredAscentError::NoAscent);
    }
    if forecast.is_empty() && !bands.iter().any(WindBand::is_believed) {
        let reasons: Vec<String> = bands
            .iter()
            .filter_map(|b| {
                let r = b.refused?;
                Some(format!(
                    "{:.0}–{:.0} m MSL: {r}",
                    b.altitude_min_m + origin_msl_m,
                    b.altitude_max_m + origin_msl_m
                ))
            })
            .collect();
        return Err(MeasuredAscentError::AllRefused(reasons.join("; ")));
    }
    Ok(MeasuredForecast {
        forecast: merge_measured(forecast, &bands, origin_msl_m)?,
        bands,
        origin_msl_m,
    })
}
