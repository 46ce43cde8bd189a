// The API's messages as the page uses them, after parsing (see parse.ts and crates/stx-station/API.md).
// Every leaf the wire may omit or garble is `number | null` (etc.): the parser never invents a value,
// and the UI shows "—" for null. Units are in the field names, as on the wire.

export type Role = "operator" | "viewer";
export type Vec3 = [number, number, number];
export type N = number | null;

export interface LatLon {
  lat_deg: number;
  lon_deg: number;
}

export interface Station {
  name: string;
  origin: LatLon & { alt_msl_m: N };
  tile_url: string | null;
  tile_attribution: string;
  offline_tiles: boolean;
  modes: string[];
}

export interface Session {
  role: Role;
  name: string;
  station: Station;
}

export interface Link {
  connected: boolean;
  stale: boolean;
  age_s: N;
  rate_hz: N;
  loss_percent: N;
  crc_errors: N;
  parse_errors: N;
  signature_errors: N;
  /** Age of the last message of each MAVLink type, seconds. */
  ages_s: Record<string, number>;
  /** Each radio of the link, the primary first. */
  radios: Radio[];
}

/** One radio of the drone link (the station may hold a primary and backups). */
export interface Radio {
  address: string;
  /** Commands go out on this radio now. */
  transmitting: boolean;
  stale: boolean;
  age_s: N;
  rate_hz: N;
  loss_percent: N;
  /** Frames it carried that another radio had already delivered. */
  duplicates: N;
}

export interface Gps {
  fix: string | null;
  satellites: N;
  lat_deg: N;
  lon_deg: N;
  alt_msl_m: N;
  velocity_ned_mps: Vec3 | null;
  h_acc_m: N;
}

export interface Vehicle {
  mode: string | null;
  stage: string | null;
  phase: string | null;
  gps: Gps | null;
  attitude: { roll_deg: N; pitch_deg: N; yaw_deg: N } | null;
  air: { static_pressure_pa: N; differential_pressure_pa: N; temperature_c: N; airspeed_mps: N } | null;
  servos: { main_line: N; brake_right: N; brake_left: N } | null;
  power: { voltage_v: N; current_a: N; remaining_percent: N } | null;
  onboard_wind_ned_mps: Vec3 | null;
}

export interface Estimate {
  lat_deg: N;
  lon_deg: N;
  alt_msl_m: N;
  height_m: N;
  velocity_ned_mps: Vec3 | null;
  ground_speed_mps: N;
  course_deg: N;
  heading_deg: N;
  heading_rate_dps: N;
  airspeed_mps: N;
  sink_rate_mps: N;
  glide_ratio_air: N;
  glide_ratio_ground: N;
  wind_ned_mps: Vec3 | null;
  wind_speed_mps: N;
  wind_from_deg: N;
  wind_sigma_mps: N;
  position_sigma_m: N;
  gps_ok: boolean | null;
}

export interface Pattern {
  corners: LatLon[];
  final_entry: LatLon | null;
  final_course_deg: N;
  final_approach_height_m: N;
  target_reachable: boolean | null;
  reach_ratio: N;
}

export interface Guidance {
  mode: string | null;
  phase: string | null;
  target: (LatLon & { alt_msl_m: N }) | null;
  pattern: Pattern | null;
  commands: { main_line: N; brake: N } | null;
}

export interface LandingPrediction extends LatLon {
  time_to_land_s: N;
  semi_major_m: N;
  semi_minor_m: N;
  /** Direction of the major axis, degrees clockwise from true north. */
  major_axis_deg: N;
}

export interface Prediction {
  planned: LandingPrediction | null;
  uncontrolled: LandingPrediction | null;
}

export interface ForecastWind {
  alt_msl_m: number;
  speed_mps: number;
  from_deg: N;
}

export interface Mission {
  stage: string | null;
  cutdown_armed_until_s: N;
}

export interface State {
  type: "state";
  time_s: number;
  wall_ms: N;
  link: Link;
  vehicle: Vehicle | null;
  estimate: Estimate | null;
  guidance: Guidance | null;
  prediction: Prediction | null;
  forecast_wind: ForecastWind[];
  mission: Mission;
}

export type Level = "info" | "warning" | "error";

export interface EventMsg {
  type: "event";
  time_s: N;
  wall_ms: N;
  level: Level;
  source: string;
  text: string;
}

export type Outcome = "accepted" | "denied" | "failed" | "unsupported" | "timed_out" | "in_progress";

export interface CommandResult {
  type: "command_result";
  request_id: string;
  command: string;
  outcome: Outcome;
  attempts: N;
  detail: string;
  /** Value read back from the drone, for parameter writes (assumed field; see README). */
  value: N;
}

export interface Param {
  name: string;
  value: N;
  min: N;
  max: N;
  units: string;
  description: string;
}

export interface ParamsMsg {
  type: "params";
  params: Param[];
  complete: boolean;
  time_s: N;
}

export interface TrackPoint {
  time_s: number;
  lat_deg: number;
  lon_deg: number;
  alt_msl_m: N;
}

export interface History {
  type: "history";
  track: TrackPoint[];
  events: EventMsg[];
  states: State[];
}

export interface Hello {
  type: "hello";
  session: Session;
}

export type ServerMessage =
  | Hello
  | State
  | EventMsg
  | CommandResult
  | ParamsMsg
  | History
  | { type: "pong" }
  | { type: "unknown"; raw_type: string };

/** The manual-control message the page sends while the dead-man is held (API.md, client → server). */
export interface ManualMsg {
  type: "manual";
  x: number;
  y: number;
  z: number;
  r: number;
  buttons: number;
}

/**
 * Sent once when a manual stream ends on the operator's side (dead-man released, focus or
 * visibility lost, gamepad gone): the station stops uplinking MANUAL_CONTROL at once instead of
 * waiting out its 0.5 s silence timeout.
 */
export interface ManualReleaseMsg {
  type: "manual_release";
}
