//! A forecast file sent from the Plan page (`POST /api/plan/forecast`): GFS GRIB2 bytes or a
//! sounding's text, read as `[forecast_file]` reads them ([`crate::forecast_file`]), kept by
//! the station for the page's launch windows (`POST /api/plan/window` names it by id), and
//! answered with its rows over the launch site, which the page plans with as any forecast.
//!
//! Kept: the last [`KEPT`] uploads, in memory only (a GFS field of a field day's subset is a
//! few megabytes). An id no longer kept is refused naming it, so a page whose upload was
//! pushed out by others' sends its file again.
//!
//! Pure: bytes in, a forecast or the reason out; the adapter (`http::plan`) reads the body.

use std::collections::VecDeque;
use std::sync::Arc;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use stx_gnc::flight_path::{ForecastRow, PlanRequest};
use stx_weather::{GfsField, OffsetDateTime, Sounding, format_time};

use crate::launch_window::WindowTimes;

/// Uploads kept at once.
pub const KEPT: usize = 4;
/// Largest file taken, bytes.
pub const MAX_BYTES: usize = 32 * 1024 * 1024;

/// What a file held.
#[derive(Debug, Clone)]
pub enum Uploaded {
    /// A GFS run's winds.
    Gfs(Arc<GfsField>),
    /// A sounding's rows (one instant, one place).
    Sounding(Vec<ForecastRow>),
}

/// Reads a file's `bytes`: GRIB2 if it starts as one (`GRIB`), else a sounding's text. The
/// message says what is wrong or missing, as `stx plan --gfs`/`--sounding` does.
pub fn read(bytes: &[u8]) -> Result<Uploaded, String> {
    if bytes.starts_with(b"GRIB") {
        return GfsField::from_files([("the uploaded file", bytes)])
            .map(|f| Uploaded::Gfs(Arc::new(f)))
            .map_err(|e| e.to_string());
    }
    let text = std::str::from_utf8(bytes).map_err(|_| {
        "the file is neither GRIB2 (it would start with `GRIB`) nor a sounding's text".to_string()
    })?;
    let sounding = Sounding::parse(text).map_err(|e| format!("the uploaded sounding: {e}"))?;
    Ok(Uploaded::Sounding(crate::forecast_file::rows(
        &sounding.levels,
    )))
}

/// Where the launch site is and when the wind is wanted, for an upload's rows
/// (`POST /api/plan/forecast?lat=…&lon=…&time=…`).
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UploadQuery {
    /// Launch site latitude, degrees north (a GFS file needs it).
    #[serde(default)]
    pub lat: Option<f64>,
    /// Launch site longitude, degrees east (a GFS file needs it).
    #[serde(default)]
    pub lon: Option<f64>,
    /// The instant of a GFS file's wind, RFC 3339; absent: its first forecast time.
    #[serde(default)]
    pub time: Option<String>,
    /// The caller's token, when given in the address.
    #[serde(default)]
    pub token: Option<String>,
}

/// The answer to an upload.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct ForecastUploadReport {
    /// The upload's id, for `POST /api/plan/window`.
    pub id: u64,
    /// `gfs` or `sounding`.
    pub kind: String,
    /// A GFS file's run, RFC 3339; `null` for a sounding.
    pub gfs_run: Option<String>,
    /// A GFS file's forecast times, RFC 3339, earliest first; empty for a sounding.
    pub valid_times: Vec<String>,
    /// The instant the rows are taken at, RFC 3339; `null` for a sounding.
    pub at: Option<String>,
    /// The wind over the launch site, lowest first, to plan with.
    pub rows: Vec<ForecastRow>,
}

/// The rows of `upload` for `query`, and the answer naming it `id`.
pub fn report(
    id: u64,
    upload: &Uploaded,
    query: &UploadQuery,
) -> Result<ForecastUploadReport, String> {
    match upload {
        Uploaded::Sounding(rows) => Ok(ForecastUploadReport {
            id,
            kind: "sounding".into(),
            gfs_run: None,
            valid_times: Vec::new(),
            at: None,
            rows: rows.clone(),
        }),
        Uploaded::Gfs(field) => {
            let (Some(lat), Some(lon)) = (query.lat, query.lon) else {
                return Err("lat, lon: a GFS file needs the launch site whose wind to take".into());
            };
            let at = query
                .time
                .as_deref()
                .map(|t| {
                    stx_weather::parse_time(t)
                        .map_err(|_| format!("time: not an RFC 3339 time: {t:?}"))
                })
                .transpose()?;
            let at: OffsetDateTime = at.unwrap_or_else(|| field.valid_times()[0]);
            let rows = crate::forecast_file::gfs_rows(field, lat, lon, Some(at))?;
            Ok(ForecastUploadReport {
                id,
                kind: "gfs".into(),
                gfs_run: Some(format_time(field.reference_time())),
                valid_times: field.valid_times().into_iter().map(format_time).collect(),
                at: Some(format_time(at)),
                rows,
            })
        }
    }
}

/// The last [`KEPT`] uploads, by id.
#[derive(Debug, Default)]
pub struct Uploads {
    next: u64,
    kept: VecDeque<(u64, Uploaded)>,
}

impl Uploads {
    /// Keeps `upload` (forgetting the oldest beyond [`KEPT`]) and gives its id.
    pub fn keep(&mut self, upload: Uploaded) -> u64 {
        self.next += 1;
        self.kept.push_back((self.next, upload));
        while self.kept.len() > KEPT {
            self.kept.pop_front();
        }
        self.next
    }

    /// The upload `id`, if still kept.
    pub fn get(&self, id: u64) -> Option<&Uploaded> {
        self.kept.iter().find(|(i, _)| *i == id).map(|(_, u)| u)
    }
}

/// Which GFS forecast a window flies.
#[derive(Debug, Clone, PartialEq, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum WindowForecast {
    /// The station's `[forecast_file] gfs`.
    Configured,
    /// A file sent to `POST /api/plan/forecast`, by its id.
    Upload(u64),
}

/// `POST /api/plan/window`.
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct WindowBody {
    /// What each launch plans (its `forecast` is ignored: each launch flies the GFS wind at
    /// its time); it needs a target.
    pub request: PlanRequest,
    /// The launch times.
    pub window: WindowTimes,
    /// The GFS forecast to fly.
    pub forecast: WindowForecast,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn testdata(name: &str) -> Vec<u8> {
        let path = format!(
            "{}/../stx-weather/testdata/{name}",
            env!("CARGO_MANIFEST_DIR")
        );
        std::fs::read(path).unwrap()
    }

    #[test]
    fn a_gfs_upload_gives_the_rows_stx_plan_gives() {
        let bytes = testdata("gfs_0p25_subset.grib2");
        let upload = read(&bytes).unwrap();
        let query = UploadQuery {
            lat: Some(38.0),
            lon: Some(-8.0),
            time: Some("2026-11-30T07:30:00Z".into()),
            token: None,
        };
        let r = report(7, &upload, &query).unwrap();
        let field = GfsField::from_files([("f", bytes.as_slice())]).unwrap();
        let at = stx_weather::parse_time("2026-11-30T07:30:00Z").unwrap();
        let rows = crate::forecast_file::gfs_rows(&field, 38.0, -8.0, Some(at)).unwrap();
        assert_eq!((r.id, r.kind.as_str(), r.rows), (7, "gfs", rows));
        assert_eq!(r.valid_times.len(), 3);
        assert_eq!(r.gfs_run.as_deref(), Some("2026-11-30T06:00:00Z"));
        let e = report(7, &upload, &UploadQuery::default()).unwrap_err();
        assert!(e.starts_with("lat, lon"), "{e}");
    }

    #[test]
    fn a_sounding_upload_is_its_rows_and_bad_files_say_what_is_missing() {
        let text = testdata("72520_sounding.txt");
        let r = report(1, &read(&text).unwrap(), &UploadQuery::default()).unwrap();
        assert_eq!(r.kind, "sounding");
        assert!(r.rows.len() > 10);
        let e = read(&testdata("no_hgt.grib2")).unwrap_err();
        assert!(e.contains("no HGT"), "{e}");
        let e = read(&[0xff, 0xfe, 0x00]).unwrap_err();
        assert!(e.contains("neither GRIB2"), "{e}");
        let e = read(b"hello").unwrap_err();
        assert!(e.starts_with("the uploaded sounding"), "{e}");
    }

    #[test]
    fn only_the_last_uploads_are_kept() {
        let mut uploads = Uploads::default();
        let ids: Vec<u64> = (0..KEPT + 1)
            .map(|_| uploads.keep(Uploaded::Sounding(Vec::new())))
            .collect();
        assert!(uploads.get(ids[0]).is_none());
        assert!(ids[1..].iter().all(|&id| uploads.get(id).is_some()));
    }
}
