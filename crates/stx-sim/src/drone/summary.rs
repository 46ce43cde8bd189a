//! A mission in figures ([`MissionSummary`]): what a run of the simulated drone is judged by
//! and what `stx drone --summary-json` prints, from the simulator's truth.

use stx_gnc::mission::FlightStage;

/// Where and how the mission ended.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Landing {
    /// Mission time of ground contact, s.
    pub time_s: f64,
    /// Where (north, east of the launch site), m.
    pub position_ne_m: [f64; 2],
    /// Distance from the landing target, m, if there is one.
    pub miss_m: Option<f64>,
    /// Vertical speed at contact, m/s.
    pub vertical_speed_mps: f64,
    /// Stage it landed from (parafoil, or round chute if the parafoil never deployed).
    pub under_parafoil: bool,
    /// Where, latitude, degrees.
    pub lat_deg: f64,
    /// Where, longitude, degrees.
    pub lon_deg: f64,
}

/// How the balloon stage ended.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BalloonEnd {
    /// It burst by itself.
    Burst,
    /// It was cut away (operator's command or `MIS_CUTDOWN_M`).
    Cutdown,
}

/// A stage and when it began.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct StageStart {
    /// The stage (snake case).
    pub stage: String,
    /// Mission time it began, s.
    pub start_s: f64,
}

/// A mission in figures, from the simulator's truth: what a run is judged by and what
/// `stx drone --summary-json` prints.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MissionSummary {
    /// Mission name.
    pub mission: String,
    /// Seed flown.
    pub seed: u64,
    /// Mission time reached, s.
    pub mission_time_s: f64,
    /// Every stage entered, in order.
    pub stages: Vec<StageStart>,
    /// How the balloon stage ended, when, and how high (m MSL).
    pub balloon_end: Option<(BalloonEnd, f64, f64)>,
    /// Highest altitude reached, m MSL.
    pub max_altitude_msl_m: f64,
    /// Fastest fall (under the round chute in a whole mission), m/s.
    pub peak_descent_mps: f64,
    /// When and how high above the site the parafoil deployed, s and m.
    pub deployment: Option<(f64, f64)>,
    /// The landing target, latitude and longitude, degrees.
    pub target_lat_lon_deg: Option<[f64; 2]>,
    /// Where and how it landed.
    pub landing: Option<Landing>,
    /// Guidance phases entered, with their mission time.
    pub phases: Vec<StageStart>,
    /// The course of the final approach the onboard guidance last planned, degrees from north
    /// (`None`: no spiral flew).
    pub final_course_deg: Option<f64>,
    /// Status texts sent.
    pub texts: u64,
    /// Outputs dropped because nobody drained them.
    pub outputs_dropped: u64,
}

/// Snake-case name of a stage, as the operator reads it.
pub fn stage_name(stage: FlightStage) -> String {
    serde_json::to_value(stage)
        .ok()
        .and_then(|v| v.as_str().map(String::from))
        .unwrap_or_else(|| format!("{stage:?}"))
}
