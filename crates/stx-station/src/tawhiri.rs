//! Tawhiri's prediction API (CUSF's `tawhiri/api.py`, version 1) answered by the station, so
//! that balloon tools written against Tawhiri (`GET …/api/v1/?profile=standard_profile&…`)
//! can ask stx instead, offline on the field: the same parameters, the same answer
//! (`request` echoed with `dataset` and `version`, `prediction` as an `ascent` and a
//! `descent` stage of `{altitude, datetime, latitude, longitude}` points, `metadata`,
//! `warnings`), the same errors (`{error: {type, description}, metadata}` with Tawhiri's
//! types and statuses).
//!
//! What is flown is stx's own: the station's forecast wind — with GFS files configured
//! (`[forecast_file] gfs`) the wind over the launch site at the launch time, otherwise the
//! station's forecast rows, the same everywhere and at every time (a warning says so) — and
//! stx's flight path (`stx_gnc::flight_path::vertical_leg`), deterministic: no samples. The
//! profile is Tawhiri's standard one: a constant ascent rate to the burst altitude, then a
//! fall whose speed is `descent_rate` at sea level and grows as `1/√ρ` (a round chute at its
//! terminal speed, stx's [`RoundChute`]), down to the launch site's ground (no elevation
//! model: the ground is taken at the launch altitude everywhere). The parafoil is not flown:
//! Tawhiri's callers ask where an unsteered payload comes down. `float_profile` is answered
//! `NotYetImplementedException` (501). Longitudes are 0–360 both ways, as Tawhiri's.
//!
//! Pure: the query's pairs and the wind in, the answer out; the adapter (`http::tawhiri`)
//! adds the metadata's wall-clock times.

use std::collections::BTreeMap;

use nalgebra::Vector3;
use schemars::JsonSchema;
use serde::Serialize;
use stx_gnc::flight_path::{Air, ForecastRow, RoundChute, vertical_leg};
use stx_gnc::geo::LocalFrame;
use stx_types::atmosphere::{Atmosphere, StandardAtmosphere};
use stx_types::wind::{WindField, WindProfile};
use stx_weather::{GfsField, OffsetDateTime, format_time};

/// Tawhiri's API version.
pub const VERSION: u32 = 1;
/// A trajectory point every this many seconds of flight (Tawhiri's solver step), with the
/// start, burst and landing besides.
pub const POINT_EVERY_S: f64 = 60.0;
/// Altitude step of the integration, m (the planner's).
const STEP_M: f64 = 10.0;

/// The wind the station flies.
pub enum StationWind<'a> {
    /// A GFS run: the wind over the launch site at the launch time.
    Gfs(&'a GfsField),
    /// Forecast rows (altitudes above mean sea level), one profile everywhere and always.
    Rows(&'a [ForecastRow]),
}

/// The answer to a prediction.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct TawhiriAnswer {
    /// When the prediction started and completed.
    pub metadata: TawhiriMetadata,
    /// The stages, `ascent` then `descent`.
    pub prediction: Vec<TawhiriStage>,
    /// The request with its defaults filled in.
    pub request: TawhiriRequest,
    /// Warnings by name (Tawhiri's `altitude_too_high`; stx's `station_profile`), each with
    /// how many times it fired and what it means; empty: none.
    pub warnings: BTreeMap<String, TawhiriWarning>,
}

/// Start and end of the computation, RFC 3339.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct TawhiriMetadata {
    /// When the request arrived.
    pub start_datetime: String,
    /// When the answer was ready.
    pub complete_datetime: String,
}

/// One stage of the flight.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct TawhiriStage {
    /// `ascent` or `descent`.
    pub stage: String,
    /// Its points, in time order; a stage starts where the one before ended.
    pub trajectory: Vec<TawhiriPoint>,
}

/// A point of a trajectory.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct TawhiriPoint {
    /// Altitude above mean sea level, m.
    pub altitude: f64,
    /// When, RFC 3339.
    pub datetime: String,
    /// Latitude, degrees north.
    pub latitude: f64,
    /// Longitude, degrees east, 0–360.
    pub longitude: f64,
}

/// The request as flown (Tawhiri's names and units).
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct TawhiriRequest {
    /// Ascent rate, m/s.
    pub ascent_rate: f64,
    /// Burst altitude above mean sea level, m.
    pub burst_altitude: f64,
    /// The forecast flown: the GFS run's time (hour), or with forecast rows the launch's
    /// hour (the rows carry no time; `warnings.station_profile` says so).
    pub dataset: String,
    /// Descent rate at sea level, m/s.
    pub descent_rate: f64,
    /// Launch altitude above mean sea level, m (given, or the station's launch site's).
    pub launch_altitude: f64,
    /// Launch time, RFC 3339.
    pub launch_datetime: String,
    /// Launch latitude, degrees north.
    pub launch_latitude: f64,
    /// Launch longitude, degrees east, 0–360.
    pub launch_longitude: f64,
    /// `standard_profile`.
    pub profile: String,
    /// The API version, 1.
    pub version: u32,
}

/// A warning that fired.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct TawhiriWarning {
    /// How many times.
    pub count: u32,
    /// What it means.
    pub description: String,
}

/// An error answer: `{error: {type, description}, metadata}`.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct TawhiriErrorAnswer {
    /// What went wrong.
    pub error: TawhiriErrorDetail,
    /// When the request arrived and was answered.
    pub metadata: TawhiriMetadata,
}

/// Tawhiri's error fragment.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct TawhiriErrorDetail {
    /// `RequestException` (400), `InvalidDatasetException` (404), `PredictionException`
    /// (500) or `NotYetImplementedException` (501).
    #[serde(rename = "type")]
    pub kind: String,
    /// Why, in Tawhiri's words where it has them.
    pub description: String,
}

/// Why a prediction was refused, as Tawhiri's exception types.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TawhiriError {
    /// The request is invalid (400).
    #[error("{0}")]
    Request(String),
    /// The dataset asked for is not the station's (404).
    #[error("{0}")]
    InvalidDataset(String),
    /// The flight could not be flown (500).
    #[error("{0}")]
    Prediction(String),
    /// A profile stx does not fly (501).
    #[error("{0}")]
    NotYetImplemented(String),
}

impl TawhiriError {
    /// Tawhiri's HTTP status.
    pub fn status(&self) -> u16 {
        match self {
            TawhiriError::Request(_) => 400,
            TawhiriError::InvalidDataset(_) => 404,
            TawhiriError::Prediction(_) => 500,
            TawhiriError::NotYetImplemented(_) => 501,
        }
    }

    /// Tawhiri's exception name.
    pub fn kind(&self) -> &'static str {
        match self {
            TawhiriError::Request(_) => "RequestException",
            TawhiriError::InvalidDataset(_) => "InvalidDatasetException",
            TawhiriError::Prediction(_) => "PredictionException",
            TawhiriError::NotYetImplemented(_) => "NotYetImplementedException",
        }
    }

    /// The error answer, with `metadata`.
    pub fn answer(&self, metadata: TawhiriMetadata) -> TawhiriErrorAnswer {
        TawhiriErrorAnswer {
            error: TawhiriErrorDetail {
                kind: self.kind().to_string(),
                description: self.to_string(),
            },
            metadata,
        }
    }
}

/// The query's value of `name`, parsed by `cast` and held to `valid`, in Tawhiri's words.
fn parameter<T>(
    query: &[(String, String)],
    name: &str,
    cast: impl Fn(&str) -> Option<T>,
    valid: impl Fn(&T) -> bool,
) -> Result<Option<T>, TawhiriError> {
    let Some((_, text)) = query.iter().find(|(k, _)| k == name) else {
        return Ok(None);
    };
    let value = cast(text.trim()).ok_or_else(|| {
        TawhiriError::Request(format!("Unable to parse parameter '{name}': {text}."))
    })?;
    if !valid(&value) {
        return Err(TawhiriError::Request(format!(
            "Invalid value for parameter '{name}': {text}."
        )));
    }
    Ok(Some(value))
}

fn required<T>(value: Option<T>, name: &str) -> Result<T, TawhiriError> {
    value.ok_or_else(|| {
        TawhiriError::Request(format!("Parameter '{name}' not provided in request."))
    })
}

fn number(text: &str) -> Option<f64> {
    text.parse::<f64>().ok().filter(|x| x.is_finite())
}

fn time(text: &str) -> Option<OffsetDateTime> {
    stx_weather::parse_time(text).ok()
}

/// `t` as Tawhiri names a dataset: its hour, `YYYY-MM-DDTHH:00:00Z`.
fn hour_of(t: OffsetDateTime) -> String {
    let utc = t.to_offset(stx_weather::UtcOffset::UTC);
    format!(
        "{:04}-{:02}-{:02}T{:02}:00:00Z",
        utc.year(),
        u8::from(utc.month()),
        utc.day(),
        utc.hour()
    )
}

/// A prediction before its metadata.
#[derive(Debug, Clone, PartialEq)]
pub struct Prediction {
    /// The stages.
    pub stages: Vec<TawhiriStage>,
    /// The request as flown.
    pub request: TawhiriRequest,
    /// The warnings that fired.
    pub warnings: BTreeMap<String, TawhiriWarning>,
}

impl Prediction {
    /// The answer, with `metadata`.
    pub fn answer(self, metadata: TawhiriMetadata) -> TawhiriAnswer {
        TawhiriAnswer {
            metadata,
            prediction: self.stages,
            request: self.request,
            warnings: self.warnings,
        }
    }
}

/// `t` in UTC, RFC 3339 (Tawhiri answers in UTC whatever offset it was given).
pub fn utc(t: OffsetDateTime) -> String {
    format_time(t.to_offset(stx_weather::UtcOffset::UTC))
}

/// The prediction the query asks for, over `wind`; `default_altitude_m` (the station's
/// launch site's ground) where the query gives no `launch_altitude`.
pub fn predict(
    query: &[(String, String)],
    wind: &StationWind<'_>,
    default_altitude_m: f64,
) -> Result<Prediction, TawhiriError> {
    let any = |_: &f64| true;
    let lat = required(
        parameter(query, "launch_latitude", number, |x| x.abs() <= 90.0)?,
        "launch_latitude",
    )?;
    let lon = required(
        parameter(query, "launch_longitude", number, |x| {
            (0.0..360.0).contains(x)
        })?,
        "launch_longitude",
    )?;
    let launch = required(
        parameter(query, "launch_datetime", time, |_| true)?,
        "launch_datetime",
    )?;
    let alt = parameter(query, "launch_altitude", number, any)?.unwrap_or(default_altitude_m);
    let profile = parameter(query, "profile", |s| Some(s.to_string()), |_| true)?
        .unwrap_or_else(|| "standard_profile".into());
    match profile.as_str() {
        "standard_profile" => {}
        "float_profile" => {
            return Err(TawhiriError::NotYetImplemented(
                "stx flies the standard profile only: float_profile is not implemented".into(),
            ));
        }
        other => return Err(TawhiriError::Request(format!("Unknown profile '{other}'."))),
    }
    let ascent = required(
        parameter(query, "ascent_rate", number, |x| *x > 0.0)?,
        "ascent_rate",
    )?;
    let burst = required(
        parameter(query, "burst_altitude", number, |x| *x > alt)?,
        "burst_altitude",
    )?;
    let descent = required(
        parameter(query, "descent_rate", number, |x| *x > 0.0)?,
        "descent_rate",
    )?;
    let dataset = parameter(query, "dataset", time, |_| true)?;
    // What stx's flight path accepts beyond Tawhiri's own rules.
    if lat.abs() > 89.0 || !(-500.0..=9000.0).contains(&alt) || burst >= 60_000.0 {
        return Err(TawhiriError::Request(
            "stx flies launches within ±89° of latitude, from −500…9000 m, with bursts \
             below 60 000 m"
                .into(),
        ));
    }
    let lon_east = if lon > 180.0 { lon - 360.0 } else { lon };
    let mut warnings = BTreeMap::new();
    let (rows, dataset_name) = match wind {
        StationWind::Gfs(field) => {
            let run = hour_of(field.reference_time());
            if let Some(asked) = dataset
                && hour_of(asked) != run
            {
                return Err(TawhiriError::InvalidDataset(format!(
                    "No matching dataset found: the station holds the GFS run {run} only."
                )));
            }
            let levels = field
                .profile(lat, lon_east, launch)
                .map_err(|e| TawhiriError::Request(format!("The station's GFS forecast: {e}")))?;
            (crate::forecast_file::rows(&levels), run)
        }
        StationWind::Rows(rows) => {
            if dataset.is_some() {
                return Err(TawhiriError::InvalidDataset(
                    "No matching dataset found: the station flies its configured forecast \
                     rows, which have no dataset time (leave out 'dataset')."
                        .into(),
                ));
            }
            warnings.insert(
                "station_profile".to_string(),
                TawhiriWarning {
                    count: 1,
                    description: "The wind is the station's forecast profile over its launch \
                                  site, taken the same everywhere and at every time."
                        .into(),
                },
            );
            (rows.to_vec(), hour_of(launch))
        }
    };
    let top = rows.last().map(|r| r.alt_msl_m);
    if top.is_some_and(|top| burst > top) {
        warnings.insert(
            "altitude_too_high".to_string(),
            TawhiriWarning {
                count: 1,
                description: "The altitude went too high, above the max forecast wind. Wind \
                              data will be unreliable"
                    .into(),
            },
        );
    }
    let profile_wind = stx_gnc::flight_path::Forecast::new(rows)
        .and_then(|f| f.profile(alt).map_err(Into::into))
        .map_err(|e| TawhiriError::Prediction(format!("Prediction did not complete: '{e}'.")))?;
    let frame = LocalFrame {
        lat_deg: lat,
        lon_deg: lon_east,
        alt_msl_m: alt,
    };
    let stages = fly(&frame, launch, &profile_wind, ascent, burst, descent);
    let request = TawhiriRequest {
        ascent_rate: ascent,
        burst_altitude: burst,
        dataset: dataset_name,
        descent_rate: descent,
        launch_altitude: alt,
        launch_datetime: utc(launch),
        launch_latitude: lat,
        launch_longitude: lon,
        profile,
        version: VERSION,
    };
    Ok(Prediction {
        stages,
        request,
        warnings,
    })
}

/// The ascent and descent stages from `frame`'s origin at `launch`.
fn fly(
    frame: &LocalFrame,
    launch: OffsetDateTime,
    wind: &WindProfile,
    ascent_rate: f64,
    burst_msl_m: f64,
    descent_rate: f64,
) -> Vec<TawhiriStage> {
    let air = Air {
        wind: wind as &dyn WindField,
        atmosphere: &StandardAtmosphere,
        ground_msl_m: frame.alt_msl_m,
    };
    let sea_level = StandardAtmosphere.air_at(0.0).density_kg_per_m3;
    // The chute whose terminal speed at sea level is the descent rate (per kilogram).
    let chute = RoundChute {
        drag_area_m2: 2.0 * 9.80665 / (sea_level * descent_rate * descent_rate),
        mass_kg: 1.0,
        gravity_mps2: 9.80665,
    };
    let point = |p: &Vector3<f64>, t: f64| {
        let (lat, lon, alt) = frame.to_geodetic(p);
        TawhiriPoint {
            altitude: alt,
            // To the millisecond: the sum of the steps' times is not exact to the nanosecond.
            datetime: utc(
                launch + std::time::Duration::from_millis((t.max(0.0) * 1e3).round() as u64)
            ),
            latitude: lat,
            longitude: lon.rem_euclid(360.0),
        }
    };
    let leg = |from: (Vector3<f64>, f64), to_height_m: f64, speed: &dyn Fn(f64) -> f64| {
        let mut trajectory = vec![point(&from.0, from.1)];
        let mut next = from.1 + POINT_EVERY_S;
        let end = vertical_leg(air, STEP_M, from.0, from.1, to_height_m, speed, |p, t| {
            if t >= next {
                trajectory.push(point(p, t));
                next += POINT_EVERY_S;
            }
        });
        if trajectory.last().map(|q| &q.datetime) != Some(&point(&end.0, end.1).datetime) {
            trajectory.push(point(&end.0, end.1));
        }
        (trajectory, end)
    };
    let (up, burst) = leg(
        (Vector3::zeros(), 0.0),
        burst_msl_m - frame.alt_msl_m,
        &|_| ascent_rate,
    );
    let (down, _) = leg(burst, 0.0, &|rho| chute.terminal_speed_mps(rho));
    vec![
        TawhiriStage {
            stage: "ascent".into(),
            trajectory: up,
        },
        TawhiriStage {
            stage: "descent".into(),
            trajectory: down,
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn query(pairs: &[(&str, &str)]) -> Vec<(String, String)> {
        pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    }

    const STANDARD: [(&str, &str); 8] = [
        ("profile", "standard_profile"),
        ("launch_latitude", "38.5"),
        ("launch_longitude", "352.1"),
        ("launch_datetime", "2026-11-30T08:00:00Z"),
        ("launch_altitude", "200"),
        ("ascent_rate", "5"),
        ("burst_altitude", "20000"),
        ("descent_rate", "6"),
    ];

    fn west_wind() -> Vec<ForecastRow> {
        vec![ForecastRow {
            alt_msl_m: 0.0,
            speed_mps: 10.0,
            from_deg: 270.0,
            sigma_mps: None,
        }]
    }

    #[test]
    fn a_uniform_wind_carries_the_burst_east_by_wind_times_climb_time() {
        let rows = west_wind();
        let Prediction {
            stages,
            request,
            warnings,
        } = predict(&query(&STANDARD), &StationWind::Rows(&rows), 0.0).unwrap();
        let up = &stages[0].trajectory;
        let burst = up.last().unwrap();
        assert_eq!(burst.altitude.round(), 20_000.0);
        let climb_s = 19_800.0 / 5.0;
        let frame = LocalFrame {
            lat_deg: 38.5,
            lon_deg: -7.9,
            alt_msl_m: 200.0,
        };
        let ned = frame.to_ned(burst.latitude, burst.longitude - 360.0, burst.altitude);
        assert!((ned.y - 10.0 * climb_s).abs() < 1.0, "{ned:?}");
        assert_eq!(burst.datetime, "2026-11-30T09:06:00Z");
        assert_eq!(stages[1].trajectory[0], *burst);
        let landing = stages[1].trajectory.last().unwrap();
        assert!((landing.altitude - 200.0).abs() < 1e-6, "{landing:?}");
        assert!(landing.longitude > burst.longitude);
        // Near the ground the fall is the sea-level rate, a little faster for the altitude.
        let n = stages[1].trajectory.len();
        assert!(n > 10);
        assert_eq!(request.launch_longitude, 352.1);
        assert_eq!(request.dataset, "2026-11-30T08:00:00Z");
        assert!(warnings.contains_key("station_profile"));
        assert!(warnings.contains_key("altitude_too_high"));
    }

    #[test]
    fn bad_parameters_are_named_in_tawhiris_words() {
        let rows = west_wind();
        let wind = StationWind::Rows(&rows);
        let without = |name: &str| {
            let q: Vec<(&str, &str)> = STANDARD
                .iter()
                .copied()
                .filter(|(k, _)| *k != name)
                .collect();
            predict(&query(&q), &wind, 0.0).unwrap_err()
        };
        let with = |name: &str, value: &str| {
            let mut q: Vec<(&str, &str)> = STANDARD
                .iter()
                .copied()
                .filter(|(k, _)| *k != name)
                .collect();
            q.push((name, value));
            predict(&query(&q), &wind, 0.0).unwrap_err()
        };
        let e = without("launch_datetime");
        assert_eq!(
            (e.status(), e.kind(), e.to_string().as_str()),
            (
                400,
                "RequestException",
                "Parameter 'launch_datetime' not provided in request."
            )
        );
        assert_eq!(
            with("launch_longitude", "-7.9").to_string(),
            "Invalid value for parameter 'launch_longitude': -7.9."
        );
        assert_eq!(
            with("ascent_rate", "fast").to_string(),
            "Unable to parse parameter 'ascent_rate': fast."
        );
        assert_eq!(
            with("burst_altitude", "150").to_string(),
            "Invalid value for parameter 'burst_altitude': 150."
        );
        assert_eq!(
            with("profile", "kite").to_string(),
            "Unknown profile 'kite'."
        );
        let float = with("profile", "float_profile");
        assert_eq!(
            (float.status(), float.kind()),
            (501, "NotYetImplementedException")
        );
        let dataset = with("dataset", "2026-11-30T06:00:00Z");
        assert_eq!(
            (dataset.status(), dataset.kind()),
            (404, "InvalidDatasetException")
        );
        // Missing launch altitude: the station's ground.
        let q: Vec<(&str, &str)> = STANDARD
            .iter()
            .copied()
            .filter(|(k, _)| *k != "launch_altitude")
            .collect();
        let Prediction {
            stages, request, ..
        } = predict(&query(&q), &wind, 245.0).unwrap();
        assert_eq!(request.launch_altitude, 245.0);
        assert_eq!(stages[0].trajectory[0].altitude, 245.0);
    }

    #[test]
    fn a_gfs_forecast_is_taken_at_the_launch_site_and_time_and_names_its_run() {
        let file = format!(
            "{}/../stx-weather/testdata/gfs_0p25_subset.grib2",
            env!("CARGO_MANIFEST_DIR")
        );
        let field = crate::forecast_file::read_gfs(&[file.into()]).unwrap();
        let wind = StationWind::Gfs(&field);
        let Prediction {
            stages,
            request,
            warnings,
        } = predict(&query(&STANDARD), &wind, 0.0).unwrap();
        assert_eq!(request.dataset, "2026-11-30T06:00:00Z");
        assert!(warnings.is_empty(), "{warnings:?}");
        assert_eq!(stages.len(), 2);
        let mut q = query(&STANDARD);
        q.push(("dataset".into(), "2026-11-30T06:00:00Z".into()));
        assert!(predict(&q, &wind, 0.0).is_ok());
        let mut late = query(&STANDARD);
        late[3].1 = "2026-12-01T08:00:00Z".into();
        let e = predict(&late, &wind, 0.0).unwrap_err();
        assert_eq!(e.kind(), "RequestException");
        assert!(e.to_string().contains("outside the forecast"), "{e}");
    }
}
