//! The dashboard's Plan page over the API (`API.md`): `POST /api/plan` asks for a pre-flight
//! plan ([`PreflightBody`]: the request of `stx plan`, and optionally one of the station's
//! recordings whose measured ascent wind replaces the forecast where it measured, as
//! `stx plan --from-recording`), answered with the plan ([`PreflightReport`]: the
//! `stx_gnc::flight_path::PlanReport` and the recording's measured bands, each merged or
//! refused with its reason; what `stx plan --json` prints); `GET /api/plan/defaults` gives the page the station's own
//! launch site, forecast and target to start from ([`PreflightDefaults`]).
//!
//! Pure: the HTTP adapter finds the recording's file, runs [`preflight_plan`] off the async
//! workers, one at a time.

use std::path::Path;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use stx_gnc::flight_path::plan::MAX_RUNS;
use stx_gnc::flight_path::{ForecastRow, PlanError, PlanReport, PlanRequest, plan};

use crate::config::StationConfig;
use crate::messages::AscentBandView;
use crate::recording::ascent::{MeasuredAscentError, measured_forecast};

/// `POST /api/plan`.
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PreflightBody {
    /// What to plan (as `stx plan` takes it; fields left out take its defaults).
    pub request: PlanRequest,
    /// A recording of the station (a name `GET /api/recordings` lists) whose measured ascent
    /// wind replaces `request.forecast` over the altitudes it measured; `null`: the forecast
    /// alone.
    #[serde(default)]
    pub from_recording: Option<String>,
}

/// The answer of `POST /api/plan` (and `stx plan --json`): the plan, and what the recording's
/// ascent measured.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct PreflightReport {
    /// The plan (its `request.forecast` is the forecast it flew: the measured bands merged).
    #[serde(flatten)]
    pub plan: PlanReport,
    /// The wind measured on the recording's ascent; `null` without `from_recording`.
    pub measured_ascent: Option<MeasuredAscentView>,
}

/// The wind bands a recording's ascent measured.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct MeasuredAscentView {
    /// The recording (its name, or the file `stx plan` was given).
    pub recording: String,
    /// Every band, lowest first: those with `refused` null are merged into the forecast the
    /// plan flew, the others are not (the forecast, or the neighbouring bands, stand in).
    pub bands: Vec<AscentBandView>,
}

/// `GET /api/plan/defaults`: the station's own settings, to start a plan from.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct PreflightDefaults {
    /// A request from the station's launch site (the mission frame's origin) over its
    /// configured forecast (`forecast_wind`, empty if it has none), to the drone's target
    /// when the station knows it, with `stx plan`'s defaults for the rest.
    pub request: PlanRequest,
    /// Most Monte Carlo samples a plan may fly.
    pub max_runs: u32,
    /// Where the target comes from (as the state's `guidance.target_source`); `null`: the
    /// station knows no target.
    pub target_source: Option<String>,
}

/// The defaults from the station's `config` and the drone's `target` (`[lat, lon]` degrees,
/// with its source), if known.
pub fn defaults(config: &StationConfig, target: Option<([f64; 2], &str)>) -> PreflightDefaults {
    // The configuration's rows may come in any order (the live station sorts them too); a
    // forecast's go up.
    let mut forecast: Vec<ForecastRow> = config.forecast_wind.clone();
    forecast.sort_by(|a, b| a.alt_msl_m.total_cmp(&b.alt_msl_m));
    forecast.dedup_by(|a, b| a.alt_msl_m == b.alt_msl_m);
    let mut request = PlanRequest::new(config.origin, forecast);
    request.target_lat_lon_deg = target.map(|(t, _)| t);
    PreflightDefaults {
        request,
        max_runs: MAX_RUNS,
        target_source: target.map(|(_, source)| source.to_string()),
    }
}

/// Why a plan was refused: every one is the request's fault (a 400), and says which field.
#[derive(Debug, thiserror::Error)]
pub enum PreflightError {
    /// The recording could not be read.
    #[error("from_recording: {name:?} cannot be read: {reason}")]
    Unreadable {
        /// Its name.
        name: String,
        /// Why.
        reason: String,
    },
    /// The recording measured no wind, or none that merges with the forecast.
    #[error("from_recording: {name:?}: {source}")]
    Measured {
        /// Its name.
        name: String,
        /// Why.
        #[source]
        source: MeasuredAscentError,
    },
    /// The plan refused the request.
    #[error("request: {0}")]
    Plan(#[from] PlanError),
}

/// The plan of `request`, with the ascent wind measured in the recording `(name, file)` in
/// its forecast if one is given. Costs up to about a second of one core (at [`MAX_RUNS`]).
pub fn preflight_plan(
    mut request: PlanRequest,
    recording: Option<(&str, &Path)>,
) -> Result<PreflightReport, PreflightError> {
    let mut measured_ascent = None;
    if let Some((name, file)) = recording {
        let mut reader =
            stx_record::Recording::open(file).map_err(|e| PreflightError::Unreadable {
                name: name.to_string(),
                reason: e.to_string(),
            })?;
        let measured = measured_forecast(&mut reader, &request.forecast).map_err(|source| {
            PreflightError::Measured {
                name: name.to_string(),
                source,
            }
        })?;
        request.forecast = measured.forecast.rows().to_vec();
        measured_ascent = Some(MeasuredAscentView {
            recording: name.to_string(),
            bands: measured
                .bands
                .iter()
                .map(|b| AscentBandView::of(b, measured.origin_msl_m))
                .collect(),
        });
    }
    Ok(PreflightReport {
        plan: plan(&request)?,
        measured_ascent,
    })
}
