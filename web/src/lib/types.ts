// The API's messages as the page holds them. Their shapes are not written here: they come from the
// station's contract, ../generated/api.ts (generated from api.schema.json, itself generated from
// the daemon's Rust types; see crates/stx-station/API.md). What this file adds is the page's
// reading of them (parse.ts): a leaf the wire omits or garbles becomes null and the UI shows "—";
// the parser never invents a value. Each type below is the wire's, with its leaves made nullable
// except those the page requires (without them the block, or the message, is refused), so a
// field added, renamed or retyped in Rust shows up here as a compile error in parse.ts.

import type * as Wire from "../generated/api";

export type {
  FlightMode,
  FlightStage,
  GpsFix,
  GuidancePhase,
  Level,
  Outcome,
  BandMethod,
  ParamGroup,
  PlanBody,
  PlanItemBody,
  Role,
} from "../generated/api";

export type N = number | null;
export type Vec3 = [number, number, number];

export interface LatLon {
  lat_deg: number;
  lon_deg: number;
}

/** A field as the page reads it: a leaf or a list of leaves as on the wire, a sub-block (or a list of them) leniently. */
type Read<T> = T extends readonly (infer U)[]
  ? [U] extends [readonly unknown[]]
    ? T
    : [U] extends [object]
      ? Lenient<U>[]
      : T
  : T extends object
    ? Lenient<T>
    : T;

/**
 * A wire block `T` as the page reads it: every field may be null (missing or garbled on the wire),
 * except the `Kept` ones, which the parser always fills (it requires them or supplies a default).
 */
export type Lenient<T, Kept extends keyof T = never> = {
  [K in keyof T]: K extends Kept ? Read<T[K]> : Read<NonNullable<T[K]>> | null;
};

/** A position the page requires (latitude and longitude in range), with an optional altitude. */
export type Position = Lenient<Wire.LatLonAlt, "lat_deg" | "lon_deg">;

export type Station = Omit<Lenient<Wire.StationInfo, "name" | "tile_attribution" | "offline_tiles" | "modes" | "replay">, "origin"> & {
  origin: Position;
};

export type Session = Omit<Lenient<Wire.Session, "role" | "name">, "station"> & { station: Station };

/** One radio of the drone link (the station may hold a primary and backups). */
export type Radio = Lenient<Wire.RadioView, "address" | "transmitting" | "stale">;

export type Link = Omit<Lenient<Wire.LinkView, "connected" | "stale">, "ages_s" | "radios"> & {
  /** Age of the last message of each MAVLink type, seconds (the ones that arrived as numbers). */
  ages_s: Record<string, number>;
  /** Each radio of the link, the primary first. */
  radios: Radio[];
};

export type Gps = Lenient<Wire.GpsView>;

/** The drone's own predicted touchdown. */
export type OnboardLanding = Lenient<Wire.OnboardLandingView, "lat_deg" | "lon_deg">;

export type Vehicle = Omit<Lenient<Wire.VehicleView>, "predicted_landing"> & {
  predicted_landing: OnboardLanding | null;
};

export type Estimate = Lenient<Wire.EstimateView>;

export type Pattern = Lenient<Wire.PatternView, "corners">;

export type Localizer = Lenient<Wire.LocalizerView, "point">;

/** The guidance replica and the drone disagree (or did a few seconds ago). */
export type Disagreement = Lenient<Wire.DisagreementView, "what" | "replica" | "drone">;

/** What the spiral has learned in flight of the stack's glide and turn. */
export type Learned = Lenient<Wire.LearnedView>;

export type Guidance = Omit<Lenient<Wire.GuidanceView>, "target" | "localizer" | "pattern" | "disagreement" | "learned"> & {
  target: Position | null;
  localizer: Localizer | null;
  pattern: Pattern | null;
  disagreement: Disagreement | null;
  learned: Learned | null;
};

export type LandingPrediction = Lenient<Wire.TouchdownView, "lat_deg" | "lon_deg">;

export type Prediction = Omit<Lenient<Wire.PredictionView>, "planned" | "uncontrolled"> & {
  planned: LandingPrediction | null;
  uncontrolled: LandingPrediction | null;
};

export type ForecastWind = Lenient<Wire.ForecastRow, "alt_msl_m" | "speed_mps">;

/** The landing as the station measured it: the one figure every page shows. */
export type Landing = Omit<Lenient<Wire.LandingView, "body">, "position" | "target"> & {
  position: Position;
  target: Position | null;
};

export type Mission = Omit<Lenient<Wire.MissionView>, "landing"> & { landing: Landing | null };

/** The station's recording of this run. */
export type Recording = Lenient<Wire.RecordingView, "state">;

/** The replay this station shows (`stx replay`). */
export type Replay = Lenient<Wire.ReplayView, "file" | "mode">;

/** A line of the go/no-go board (`state.readiness`, lib/readiness.ts reads it). */
export type Check = Pick<Wire.CheckView, "id" | "label" | "manual" | "status" | "detail"> & { ticked_by: string | null; ticked_wall_ms: number | null };
export type Readiness = Omit<Wire.ReadinessView, "checks" | "checklist_error"> & { checks: Check[]; checklist_error: string | null };

/** A surface wind: one without its speed, direction or source says nothing and is dropped. */
export type SurfaceWindReading = Lenient<Wire.SurfaceWindReadingView, "speed_mps" | "from_deg" | "source">;
/** The ground anemometer's intake, as configured (its address) and heard. */
export type Anemometer = Lenient<Wire.AnemometerView, "address">;
/** The wind at the ground by the target (`state.surface_wind`, lib/surfaceWind.ts reads it). */
export type SurfaceWind = Omit<Lenient<Wire.SurfaceWindView>, "wind" | "operator" | "held" | "anemometer"> & {
  wind: SurfaceWindReading | null;
  operator: SurfaceWindReading | null;
  held: SurfaceWindReading | null;
  anemometer: Anemometer | null;
};

export type State = Omit<
  Lenient<Wire.StateMsg, "type" | "time_s" | "link" | "forecast_wind" | "mission">,
  "link" | "vehicle" | "guidance" | "prediction" | "forecast_wind" | "recording" | "replay" | "footprint" | "keep_out_alarms" | "flight_path" | "mission" | "readiness" | "stack" | "surface_wind"
> & {
  stack: Stack | null;
  /** Null from a station (or a recording) older than the surface wind, or a block that does not parse. */
  surface_wind: SurfaceWind | null;
  mission: Mission;
  readiness: Readiness;
  recording: Recording | null;
  replay: Replay | null;
  link: Link;
  vehicle: Vehicle | null;
  guidance: Guidance | null;
  prediction: Prediction | null;
  footprint: Footprint | null;
  flight_path: FlightPath | null;
  keep_out_alarms: KeepOutAlarm[];
  forecast_wind: ForecastWind[];
};

/** One body of the stack as the 3-D view draws it (`state.stack`, lib/stack.ts parses it). */
export interface StackBody {
  body: Wire.StackBody;
  roll_deg: number;
  pitch_deg: number;
  yaw_deg: number;
  /** From the drone's centre of mass, east/north/up, m. */
  position_enu_m: Vec3;
  /** Along its own forward, right, down axes, m. */
  size_m: Vec3;
  source: Wire.BodySource;
  age_s: N;
}
/** A line of the rigging between two attachment points, east/north/up from the drone, m. */
export interface StackLine {
  line: Wire.StackLine;
  top_enu_m: Vec3;
  bottom_enu_m: Vec3;
}
/** The four bodies (canopy, drone, capsule, transponder) and their lines. */
export interface Stack {
  bodies: StackBody[];
  lines: StackLine[];
}

/** `state.flight_path` as the page reads it (flightPath.ts parses and summarises it). */
/** A point of the path: where, how high and in how long. */
export interface PathPoint extends LatLon {
  alt_msl_m: number;
  in_s: number;
}

/** The flight path as the map draws it. */
export interface FlightPath {
  stage: string;
  burst: PathPoint | null;
  deploy: PathPoint;
  landing: PathPoint;
  round_chute_landing: PathPoint;
  reach_centre: LatLon;
  reach_radius_m: number;
  measured_bands: number;
  measured_to_msl_m: number | null;
  /** Where the burst altitude comes from: "drone", "station_config", or null if not said. */
  burst_source: string | null;
  /** The mission clock (the drone's) its `in_s` count from, s; null from an older station. */
  computed_mission_s: number | null;
}

/** A predicted landing inside a keep-out zone. */
export type KeepOutAlarm = Wire.KeepOutAlarmView;
/** One keep-out area as the map draws it: its outer ring then its holes, `[lat, lon]`. */
export interface KeepOutArea {
  name: string;
  rings: Ring[];
}
/**
 * One keep-out feature as the map edits it: its name, its kind (`""`: none), its other GeoJSON
 * properties kept as they came, and its polygons (outer ring then holes), each ring `[lat, lon]`
 * without the closing point.
 */
export interface Zone {
  name: string;
  kind: string;
  extra: Record<string, unknown>;
  polygons: Ring[][];
}
/** The keep-out zones in force: each area as the map draws it, each feature as it edits it. */
export type KeepOutMsg = Pick<Wire.KeepOutMsg, "type" | "time_s" | "load_error" | "changed_by" | "file"> & { areas: KeepOutArea[]; zones: Zone[] };

/** A ring of `[lat_deg, lon_deg]` points, Leaflet's own order. */
export type Ring = [number, number][];
/** The ground still reachable under the parafoil: per probability level, polygons (outer ring, then holes). */
export type Footprint = Omit<Wire.FootprintView, "contours"> & {
  contours: { level: number; polygons: Ring[][] }[];
};

export type EventMsg = Omit<Lenient<Wire.EventMsg, "type" | "level" | "text">, "source"> & {
  /** The station's sources, or `page` for what the page itself logs (a command refused, cutdown armed). */
  source: Wire.EventMsg["source"] | "page" | null;
};

export type CommandResult = Lenient<Wire.CommandResultMsg, "type" | "request_id" | "command" | "outcome" | "detail">;

export type Param = Lenient<Wire.ParamView, "name" | "units" | "description" | "choices">;

export type ParamsMsg = Omit<Lenient<Wire.ParamsMsg, "type" | "complete">, "params"> & { params: Param[] };

/** One altitude band of the wind measured during the ascent: a band without its wind and σ is dropped. */
export type AscentBand = Lenient<Wire.AscentBandView, "alt_msl_m" | "wind_north_mps" | "wind_east_mps" | "sigma_north_mps" | "sigma_east_mps">;

export type AscentWindMsg = Omit<Lenient<Wire.AscentWindMsg, "type" | "ascent_over">, "bands"> & { bands: AscentBand[] };

export type TrackPoint = Lenient<Wire.TrackPoint, "time_s" | "lat_deg" | "lon_deg">;

export type History = Omit<Lenient<Wire.HistoryMsg, "type">, "track" | "events" | "states"> & {
  track: TrackPoint[];
  events: EventMsg[];
  states: State[];
};

/** `hello` as the page keeps it: the session (the role and name beside it repeat the session's). */
export type Hello = Pick<Wire.HelloMsg, "type"> & { session: Session };

export type Lagged = Lenient<Wire.LaggedMsg, "type">;

/** Every message of the station, and what the page does not know (a newer station). */
export type ServerMessage =
  | Hello
  | State
  | EventMsg
  | CommandResult
  | ParamsMsg
  | AscentWindMsg
  | KeepOutMsg
  | History
  | Lagged
  | Wire.PongMsg
  | { type: "unknown"; raw_type: string };

/** The manual-control message the page sends while the dead-man is held (every stick, always). */
export type ManualMsg = Required<Extract<Wire.ClientMessage, { type: "manual" }>>;

/**
 * Sent once when a manual stream ends on the operator's side (dead-man released, focus or
 * visibility lost, gamepad gone): the station stops uplinking MANUAL_CONTROL at once instead of
 * waiting out its 0.5 s silence timeout.
 */
export type ManualReleaseMsg = Extract<Wire.ClientMessage, { type: "manual_release" }>;

/** Every message the page sends on the WebSocket. */
export type ClientMessage = Wire.ClientMessage;
