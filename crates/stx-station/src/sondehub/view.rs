//! The upload as the pages show it (`GET /api/sharing`'s `sondehub`) and the chase car's
//! position a recovery phone gives (`POST /api/sondehub/chase`).

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Something the server said or a try that failed, with when.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct SondehubNote {
    /// When, Unix ms.
    pub wall_ms: u64,
    /// What.
    pub text: String,
}

/// The chase car as last uploaded.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct ChaseCarView {
    /// Its callsign on the map.
    pub callsign: String,
    /// Where it was, `[lat °, lon °, alt m]`.
    pub position: [f64; 3],
    /// When the position was uploaded, Unix ms; `null` while it waits.
    pub uploaded_wall_ms: Option<u64>,
}

/// The SondeHub-Amateur upload as the pages show it.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct SondehubView {
    /// The API's address.
    pub url: String,
    /// The station's callsign.
    pub uploader_callsign: String,
    /// The payload's callsign.
    pub payload_callsign: String,
    /// Time between two points, s.
    pub period_s: f64,
    /// Points made since the station started.
    pub made: u64,
    /// Points the server took.
    pub sent: u64,
    /// Of them, sent as `historical` (older than the server's window when sent).
    pub historical: u64,
    /// Points the server refused (its 202's errors, or a 400 for the whole batch): never
    /// sent again.
    pub refused: u64,
    /// Points waiting for the server (on disk with a queue directory).
    pub queued: u64,
    /// Points the queue holds at most.
    pub queue_max: u64,
    /// Points dropped as the oldest of a full queue.
    pub dropped: u64,
    /// Points found waiting on disk at start.
    pub restored: u64,
    /// The queue is kept on disk (survives a restart).
    pub on_disk: bool,
    /// When the server last took an upload, Unix ms; `null` before the first.
    pub last_upload_wall_ms: Option<u64>,
    /// The last answer or failure, in words; `null` before the first try.
    pub last_result: Option<String>,
    /// The server cannot be reached or fails: uploads wait and are tried again.
    pub failing: bool,
    /// When the next try is due while failing, Unix ms.
    pub retry_wall_ms: Option<u64>,
    /// The server's latest errors (points refused) and the failed tries, newest last.
    pub errors: Vec<SondehubNote>,
    /// The server's latest warnings (points taken but hidden), newest last.
    pub warnings: Vec<SondehubNote>,
    /// When the station's position was last uploaded, Unix ms; `null` without
    /// `station_position` or before it was.
    pub station_uploaded_wall_ms: Option<u64>,
    /// The chase car (a recovery phone's position); `null` before one was given.
    pub chase_car: Option<ChaseCarView>,
}

/// `POST /api/sondehub/chase`: where the recovery phone is.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ChaseCarBody {
    /// Latitude, ° (−90…90).
    pub lat_deg: f64,
    /// Longitude, ° (−180…180).
    pub lon_deg: f64,
    /// Altitude above mean sea level, m, if the phone gives one (else the station's
    /// origin's).
    #[serde(default)]
    pub alt_m: Option<f64>,
}

impl ChaseCarBody {
    /// Why the position cannot be used, if it cannot.
    pub fn invalid(&self) -> Option<&'static str> {
        let ok = self.lat_deg.is_finite()
            && self.lon_deg.is_finite()
            && self.lat_deg.abs() <= 90.0
            && self.lon_deg.abs() <= 180.0
            && (self.lat_deg != 0.0 || self.lon_deg != 0.0)
            && self
                .alt_m
                .is_none_or(|a| a.is_finite() && (-500.0..=10_000.0).contains(&a));
        (!ok).then_some("lat_deg −90…90 °, lon_deg −180…180 ° (not 0, 0), alt_m −500…10,000 m")
    }
}
