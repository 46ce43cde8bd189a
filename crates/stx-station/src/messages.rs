//! The JSON messages of the API (`API.md`): what the dashboard reads. Plain serde structs; the
//! station's core fills them.

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use stx_gnc::mission::{FlightMode, FlightStage, GuidancePhase};
use stx_gnc::params::ParamGroup;

use crate::config::{ForecastRow, Role};

pub use crate::ascent_wind_msg::{AscentBandView, AscentWindMsg};
mod flight_path;
mod footprint;
mod mission;
mod readiness;
mod stack;
mod vehicle;
pub use flight_path::{FlightPathView, PathPointView};
pub use footprint::{FootprintContourView, FootprintView, FootprintZoneHit};
pub use mission::{DisagreementView, LandingView};
pub use readiness::{CheckStatus, CheckView, ReadinessView, TickBody};
pub use stack::{BodySource, StackBody, StackBodyView, StackLine, StackLineView, StackView};
pub use vehicle::{
    AirView, AttitudeView, GpsView, OnboardLandingView, PowerView, ServosView, VehicleView,
};

/// `GET /api/session` and the WebSocket's `hello`.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct Session {
    /// The caller's role.
    pub role: Role,
    /// The caller's name.
    pub name: String,
    /// The station.
    pub station: StationInfo,
}

/// What the dashboard needs to know about the station.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct StationInfo {
    /// Display name.
    pub name: String,
    /// Origin of the local frame.
    pub origin: LatLonAlt,
    /// Tile URL template, if any.
    pub tile_url: Option<String>,
    /// Tile attribution.
    pub tile_attribution: String,
    /// Tiles are served by the station itself (no internet needed).
    pub offline_tiles: bool,
    /// Why the configured tile pack gives no map (missing, unreadable, vector tiles): the map
    /// shows this over its metric grid.
    pub offline_tiles_error: Option<String>,
    /// Deepest zoom the tile pack has; deeper, the map enlarges these tiles.
    pub tile_max_zoom: Option<u8>,
    /// The tile pack's extent: west, south, east, north, degrees (no tiles asked outside).
    pub tile_bounds: Option<[f64; 4]>,
    /// Modes the operator may select.
    #[schemars(with = "Vec<FlightMode>")]
    pub modes: Vec<String>,
    /// The station is replaying a recording (`stx replay`): nothing can be commanded.
    pub replay: bool,
}

/// A geodetic position.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct LatLonAlt {
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Longitude, degrees.
    pub lon_deg: f64,
    /// Altitude above mean sea level, m.
    pub alt_msl_m: f64,
}

/// Link quality.
#[derive(Debug, Clone, Default, Serialize, JsonSchema)]
pub struct LinkView {
    /// Heartbeats arriving.
    pub connected: bool,
    /// The vehicle's data are old: show them as stale.
    pub stale: bool,
    /// Seconds since the last message from the vehicle.
    pub age_s: Option<f64>,
    /// Messages per second.
    pub rate_hz: f64,
    /// Packet loss from sequence numbers, %.
    pub loss_percent: f64,
    /// Checksum failures.
    pub crc_errors: u64,
    /// Parse failures.
    pub parse_errors: u64,
    /// Signature failures.
    pub signature_errors: u64,
    /// Age of the last message of each kind, s.
    pub ages_s: BTreeMap<String, f64>,
    /// Each radio of the link (`link.address`, then `link.more_addresses`).
    pub radios: Vec<RadioView>,
}

/// One radio of the drone link.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct RadioView {
    /// Its address in the config.
    pub address: String,
    /// Commands go out on it now.
    pub transmitting: bool,
    /// Nothing heard on it for the stale time.
    pub stale: bool,
    /// Seconds since it last carried a frame.
    pub age_s: Option<f64>,
    /// Frames per second it carries (copies of the other radio's included).
    pub rate_hz: f64,
    /// Its own packet loss from sequence numbers, %.
    pub loss_percent: f64,
    /// Frames it carried that the other radio had already delivered.
    pub duplicates: u64,
}

/// The station's own estimate.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct EstimateView {
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Longitude, degrees.
    pub lon_deg: f64,
    /// Altitude MSL, m.
    pub alt_msl_m: f64,
    /// Height above the launch site's ground, m.
    pub height_m: f64,
    /// Velocity NED, m/s.
    pub velocity_ned_mps: [f64; 3],
    /// Ground speed, m/s.
    pub ground_speed_mps: f64,
    /// Course, degrees.
    pub course_deg: f64,
    /// Vehicle heading (air track), degrees.
    pub heading_deg: f64,
    /// Heading rate, degrees/s.
    pub heading_rate_dps: f64,
    /// Airspeed, m/s.
    pub airspeed_mps: f64,
    /// Sink rate, m/s.
    pub sink_rate_mps: f64,
    /// Glide through the air.
    pub glide_ratio_air: Option<f64>,
    /// Glide over the ground.
    pub glide_ratio_ground: Option<f64>,
    /// Wind NED, m/s.
    pub wind_ned_mps: [f64; 3],
    /// Wind speed, m/s.
    pub wind_speed_mps: f64,
    /// Direction the wind blows from, degrees.
    pub wind_from_deg: f64,
    /// 1-σ of the wind (largest component), m/s.
    pub wind_sigma_mps: f64,
    /// 1-σ of the horizontal position, m.
    pub position_sigma_m: f64,
    /// GPS in use.
    pub gps_ok: bool,
    /// Seconds since the newest GPS, attitude or air data the estimate used arrived.
    pub age_s: f64,
    /// Old: show it as stale.
    pub stale: bool,
}

/// The spiral's plan on the map.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct PatternView {
    /// Corners `[lat, lon]`.
    pub corners: Vec<[f64; 2]>,
    /// Where the base leg meets the final line `[lat, lon]`.
    pub final_entry: [f64; 2],
    /// Final-approach course, degrees.
    pub final_course_deg: f64,
    /// Height needed to turn base and glide in, m.
    pub final_approach_height_m: f64,
    /// The target is within the glide's reach.
    pub target_reachable: bool,
    /// Drift distance over reach.
    pub reach_ratio: f64,
}

/// What the replica has learned in flight of the stack's glide and turn (the drone's guidance
/// learns the same from the same data): scales on the polar guidance was given, which every
/// plan of the spiral is made with.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct LearnedView {
    /// The brake settings the scales are shown at, 0…1 (released, half, full).
    pub brake: [f64; 3],
    /// Horizontal airspeed flown over the polar's, at each brake setting.
    pub airspeed_scale: [f64; 3],
    /// Sink rate flown over the polar's, at each brake setting.
    pub sink_scale: [f64; 3],
    /// 1-σ of the airspeed scales (at the mean brake flown): their samples' scatter over the
    /// independent samples behind them; `null` before any.
    pub airspeed_sigma: Option<f64>,
    /// 1-σ of the sink-rate scales, as `airspeed_sigma`.
    pub sink_sigma: Option<f64>,
    /// Seconds of straight, settled flight the glide was learned from, s.
    pub learned_s: f64,
    /// Turn rate flown over the polar's for the same main-line commands.
    pub turn_scale: f64,
    /// 1-σ of the turn factor; `null` before any turn was learned from.
    pub turn_sigma: Option<f64>,
    /// Seconds of turning the turn rate was learned from, s.
    pub turn_learned_s: f64,
    /// The replica still flies under the parafoil; `false` once the drone has landed (or left
    /// the parafoil stage): these are then the values it last learned, kept for the debrief.
    pub flying: bool,
}

/// The localizer line the replica follows.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct LocalizerView {
    /// The line's point `[lat, lon]`.
    pub point: [f64; 2],
    /// The line's course, degrees.
    pub course_deg: f64,
    /// Glide slope (sink over ground speed) down the line to its point, if any.
    pub glide_slope: Option<f64>,
}

/// The guidance replica's view.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct GuidanceView {
    /// Mode.
    #[schemars(with = "FlightMode")]
    pub mode: String,
    /// Phase.
    #[schemars(with = "GuidancePhase")]
    pub phase: String,
    /// Landing target; `null` while the drone's target is not known.
    pub target: Option<LatLonAlt>,
    /// Where the target comes from: `drone_plan` (read from the drone), `drone_telemetry`
    /// (from its bearing and distance to the target, about 1 % of the distance), `operator`
    /// (a command the drone acknowledged, until it is read back); `null`: unknown.
    #[schemars(extend("enum" = ["drone_plan", "drone_telemetry", "operator", null]))]
    pub target_source: Option<&'static str>,
    /// The localizer line, once known.
    pub localizer: Option<LocalizerView>,
    /// Spiral plan, in spiral landing.
    pub pattern: Option<PatternView>,
    /// What the spiral has learned of the glide and the turn, once it has flown (kept after
    /// the landing until the next parafoil flight starts the replica afresh).
    pub learned: Option<LearnedView>,
    /// What the replica would command.
    pub commands: CommandsView,
    /// Seconds since the navigation data the replica ran on arrived; `null` without an
    /// estimate.
    pub age_s: Option<f64>,
    /// Old: show it as stale.
    pub stale: bool,
    /// The replica disagrees with the drone (or did, a few seconds ago): an alarm for every
    /// page; `null` while they agree.
    pub disagreement: Option<DisagreementView>,
}

/// Servo commands of the replica.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct CommandsView {
    /// Main line, −1…1 of its travel.
    pub main_line: f64,
    /// Symmetric brake, 0…1.
    pub brake: f64,
}

/// A predicted touchdown.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct TouchdownView {
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Longitude, degrees.
    pub lon_deg: f64,
    /// Seconds to touchdown.
    pub time_to_land_s: f64,
    /// 1-σ ellipse semi-major axis, m.
    pub semi_major_m: f64,
    /// 1-σ ellipse semi-minor axis, m.
    pub semi_minor_m: f64,
    /// Direction of the major axis, degrees clockwise from north.
    pub major_axis_deg: f64,
}

/// Both predictions of the station.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct PredictionView {
    /// Flying the plan; `null` while the plan of the drone's mode is not known.
    pub planned: Option<TouchdownView>,
    /// Servos neutral.
    pub uncontrolled: TouchdownView,
    /// Seconds since the navigation data the prediction started from arrived.
    pub age_s: Option<f64>,
    /// Old: show it as stale.
    pub stale: bool,
}

/// Mission state.
#[derive(Debug, Clone, Default, Serialize, JsonSchema)]
pub struct MissionView {
    /// Stage.
    #[schemars(with = "Option<FlightStage>")]
    pub stage: Option<String>,
    /// When an armed cutdown expires, s of the station's clock.
    pub cutdown_armed_until_s: Option<f64>,
    /// Where the drone landed and how far from its target, once it has.
    pub landing: Option<LandingView>,
}

/// The `state` message.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct StateMsg {
    /// Always `state`.
    #[serde(rename = "type")]
    #[schemars(extend("const" = "state"))]
    pub kind: &'static str,
    /// The station's clock: s since it started (its timers and ages run on it).
    pub time_s: f64,
    /// The mission clock: the drone's (s since its boot) at its newest time-stamped telemetry,
    /// carried forward at the rate it has been running against the station's clock (1 in a
    /// real flight, 20 in a rehearsal at 20×), so it runs on through a silent link. Plots, the
    /// T+ clock, countdowns and the log show it, at any speed. `null` before the drone is
    /// heard.
    pub mission_time_s: Option<f64>,
    /// Unix time, ms.
    pub wall_ms: u64,
    /// Link.
    pub link: LinkView,
    /// Vehicle.
    pub vehicle: Option<VehicleView>,
    /// Estimate.
    pub estimate: Option<EstimateView>,
    /// The four bodies and their lines around the drone; `null` before the drone's
    /// attitude is heard.
    pub stack: Option<StackView>,
    /// Guidance.
    pub guidance: Option<GuidanceView>,
    /// Prediction.
    pub prediction: Option<PredictionView>,
    /// The ground still reachable under the parafoil; `null` before the first footprint.
    pub footprint: Option<FootprintView>,
    /// The unsteered flight path from the balloon or the round chute (burst, deploy and
    /// landing points, in the ascent's measured winds); `null` under the parafoil, on the
    /// ground, and without a 3-D fix or any wind (no band, no forecast).
    pub flight_path: Option<FlightPathView>,
    /// Forecast wind.
    pub forecast_wind: Vec<ForecastRow>,
    /// Mission.
    pub mission: MissionView,
    /// Predicted landings inside a keep-out zone, one per prediction at most.
    pub keep_out_alarms: Vec<crate::keep_out::KeepOutAlarmView>,
    /// The station's recording of this run; `null` where no daemon records (tests of the
    /// core, replays).
    pub recording: Option<RecordingView>,
    /// The go/no-go board.
    pub readiness: ReadinessView,
    /// The replay this station is showing (`stx replay`); `null` when live.
    pub replay: Option<ReplayView>,
    /// The wind at the target (a ground anemometer's mean or the operator's value) and the
    /// drone's copy of it.
    pub surface_wind: crate::surface_wind::SurfaceWindView,
}

/// A replay of a recording, for the dashboard's REPLAY bar.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct ReplayView {
    /// The recording.
    pub file: String,
    /// Re-run through this station, or as recorded.
    pub mode: crate::replay::ReplayMode,
    /// Unix time of the recording's first message, ms.
    pub start_ms: u64,
    /// The recording's length, ms.
    pub duration_ms: u64,
    /// Where the replay is, ms after the start.
    pub position_ms: u64,
    /// × real time.
    pub speed: f64,
    /// Paused by request.
    pub paused: bool,
    /// At the end of the recording.
    pub finished: bool,
    /// The seek what is shown belongs to (0 from the start, +1 each seek): when it changes,
    /// the flight is shown as it was at the new position and a page starts its track, plots
    /// and event log over from the `history` of that epoch (sent to every page after the
    /// seek), never mixing what it had from before.
    pub epoch: u64,
    /// The station is being rebuilt at the position just sought (the recording run through
    /// it from the start): no `state` is sent until it is done.
    pub seeking: bool,
}

/// Whether the station is recording.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum RecordingState {
    /// Writing a file.
    On,
    /// Switched off in the configuration.
    Off,
    /// Wanted but nothing is being written (no directory, disk full, unwritable): see
    /// `problem`.
    Failing,
}

/// The station's recording, for the dashboard.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct RecordingView {
    /// Recording, off, or failing.
    pub state: RecordingState,
    /// The file being written.
    pub file: Option<String>,
    /// Bytes written to recording files, B.
    pub bytes_written: u64,
    /// Messages written.
    pub messages_written: u64,
    /// Messages that could not be written (queue full, disk full, unwritable).
    pub messages_lost: u64,
    /// The last problem, if any (it stays after recording resumes: see `resumed_ms`).
    pub problem: Option<String>,
    /// While the disk refuses the recording: when it began, Unix ms.
    pub failing_since_ms: Option<u64>,
    /// While the disk refuses the recording: seconds until the next try (0: under way). The
    /// wait doubles after each failed try, from 5 s up to 2 min.
    pub next_try_in_s: Option<f64>,
    /// While the disk refuses the recording: tries that failed, the first failure included;
    /// 0 otherwise.
    pub failed_tries: u32,
    /// When recording last resumed after the disk refused it, Unix ms; `null` if it never
    /// did.
    pub resumed_ms: Option<u64>,
    /// How long the disk had refused the recording before it resumed, s.
    pub resumed_after_s: Option<f64>,
}

/// Event levels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Level {
    /// Information.
    Info,
    /// Needs attention.
    Warning,
    /// Something failed.
    Error,
}

/// The `event` message.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct EventMsg {
    /// Always `event`.
    #[serde(rename = "type")]
    #[schemars(extend("const" = "event"))]
    pub kind: &'static str,
    /// The station's clock, s since it started.
    pub time_s: f64,
    /// The mission clock (the drone's, s) when it happened; `null` before the drone is heard.
    pub mission_time_s: Option<f64>,
    /// Unix time, ms.
    pub wall_ms: u64,
    /// Level.
    pub level: Level,
    /// Where it comes from: guidance, link, command, station, vehicle, keep_out (the keep-out
    /// zones: loaded, edited, a landing predicted in one), readiness (the go/no-go board: its
    /// checklist read, an item ticked, a launch with checks open), anemometer (the surface
    /// wind: the ground anemometer heard or silent, a line refused, the drone's copy).
    #[schemars(extend("enum" = ["guidance", "link", "command", "station", "vehicle", "keep_out", "readiness", "anemometer"]))]
    pub source: &'static str,
    /// Text.
    pub text: String,
}

/// Outcomes of commands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// Still waiting.
    InProgress,
    /// Done.
    Accepted,
    /// Refused.
    Denied,
    /// Tried and failed.
    Failed,
    /// Not supported.
    Unsupported,
    /// No answer.
    TimedOut,
}

/// The `command_result` message (and `GET /api/commands/{id}`).
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct CommandResultMsg {
    /// Always `command_result`.
    #[serde(rename = "type")]
    #[schemars(extend("const" = "command_result"))]
    pub kind: &'static str,
    /// The request.
    pub request_id: String,
    /// Which command.
    pub command: String,
    /// Outcome.
    pub outcome: Outcome,
    /// Transmissions.
    pub attempts: u32,
    /// Details for people.
    pub detail: String,
    /// Value read back, for parameter writes.
    pub value: Option<f64>,
}

/// A parameter as the dashboard shows it.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct ParamView {
    /// Name.
    pub name: String,
    /// Value.
    pub value: f64,
    /// Smallest allowed, if known.
    pub min: Option<f64>,
    /// Largest allowed, if known.
    pub max: Option<f64>,
    /// Units.
    pub units: String,
    /// What it does.
    pub description: String,
    /// Part of the onboard software (`gains`, `spiral`, `failsafe`, `mission`), if known.
    #[schemars(with = "Option<ParamGroup>")]
    pub group: Option<String>,
    /// For flags and choices, the name of each whole value from 0 up; empty for numbers.
    pub choices: Vec<&'static str>,
}

/// The `params` message and `GET /api/params`.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct ParamsMsg {
    /// Always `params`.
    #[serde(rename = "type")]
    #[schemars(extend("const" = "params"))]
    pub kind: &'static str,
    /// The table.
    pub params: Vec<ParamView>,
    /// Every parameter arrived.
    pub complete: bool,
    /// The station's clock, s.
    pub time_s: f64,
}

/// A point of the track.
#[derive(Debug, Clone, Copy, Serialize, JsonSchema)]
pub struct TrackPoint {
    /// The station's clock, s.
    pub time_s: f64,
    /// The mission clock (the drone's), s.
    pub mission_time_s: f64,
    /// Latitude, degrees.
    pub lat_deg: f64,
    /// Longitude, degrees.
    pub lon_deg: f64,
    /// Altitude MSL, m.
    pub alt_msl_m: f64,
}

/// Error bodies.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct ErrorBody {
    /// Machine-readable kind; every kind the station answers is listed (a new one must be).
    #[schemars(extend("enum" = ["unauthorized", "forbidden", "bad_request", "not_found", "not_armed", "too_many_requests", "replay", "replay_failed", "unreadable", "unavailable", "busy", "internal", "io",
        "tile_pack", "not_saved", "lab_unavailable", "invalid_job", "invalid_vehicle", "invalid_gains", "no_job", "no_thread", "bad_name", "exists", "write_failed", "confirmation_required",
        "unknown_recording", "no_flight", "unknown_item"]))]
    pub error: &'static str,
    /// For people: what is wrong.
    pub reason: String,
}
