// Parses what the station sends into the typed shapes of types.ts (the generated contract, read
// leniently), defensively: the wire is outside our control (a daemon version skew, a proxy
// truncating a frame), and a bad message must never crash the page or be shown as data. Leaves
// that are missing or of the wrong type become null, and so do positions out of range and names
// the contract does not list; a message without what makes it meaningful (a state without time_s,
// an event without text) is rejected with a reason, so the caller can count and show it.

import { parseFlightPath } from "./flightPath";
import type {
  AscentBand,
  AscentWindMsg,
  BandMethod,
  CommandResult,
  Estimate,
  EventMsg,
  FlightMode,
  FlightStage,
  Footprint,
  KeepOutAlarm,
  KeepOutArea,
  KeepOutMsg,
  ForecastWind,
  Gps,
  GpsFix,
  Disagreement,
  Guidance,
  Landing,
  GuidancePhase,
  History,
  Lagged,
  LatLon,
  LandingPrediction,
  Level,
  Link,
  Localizer,
  Mission,
  Recording,
  Ring,
  Replay,
  N,
  OnboardLanding,
  Outcome,
  Param,
  ParamGroup,
  ParamsMsg,
  Pattern,
  Position,
  Prediction,
  Radio,
  Role,
  ServerMessage,
  Session,
  State,
  Station,
  TrackPoint,
  Vec3,
  Vehicle,
} from "./types";
import type { ServerMessage as WireServerMessage } from "../generated/api";
import { zonesOf } from "./zones";

type WireServerType = WireServerMessage["type"];
type WireServerMessageOf<T extends WireServerType> = Extract<WireServerMessage, { type: T }>;

type Obj = Record<string, unknown>;

export type Parsed<T> = { ok: true; value: T } | { ok: false; error: string };

const ok = <T>(value: T): Parsed<T> => ({ ok: true, value });
const bad = <T>(error: string): Parsed<T> => ({ ok: false, error });

export const isObj = (v: unknown): v is Obj => typeof v === "object" && v !== null && !Array.isArray(v);

const num = (o: Obj, k: string): N => {
  const v = o[k];
  return typeof v === "number" && Number.isFinite(v) ? v : null;
};
const str = (o: Obj, k: string): string | null => (typeof o[k] === "string" ? (o[k] as string) : null);
const bool = (o: Obj, k: string): boolean | null => (typeof o[k] === "boolean" ? (o[k] as boolean) : null);
const obj = (o: Obj, k: string): Obj | null => {
  const v = o[k];
  return isObj(v) ? v : null;
};

const vec3 = (o: Obj, k: string): Vec3 | null => {
  const v = o[k];
  if (!Array.isArray(v) || v.length !== 3) return null;
  return v.every((x) => typeof x === "number" && Number.isFinite(x)) ? (v as Vec3) : null;
};

const isLat = (x: unknown): x is number => typeof x === "number" && Number.isFinite(x) && Math.abs(x) <= 90;
const isLon = (x: unknown): x is number => typeof x === "number" && Number.isFinite(x) && Math.abs(x) <= 180;

/** `{lat_deg, lon_deg}` object, or null when either is missing or out of range. */
const latLonObj = (v: unknown): LatLon | null =>
  isObj(v) && isLat(v.lat_deg) && isLon(v.lon_deg) ? { lat_deg: v.lat_deg, lon_deg: v.lon_deg } : null;

/** `[lat, lon]` pair as the pattern's corners are sent. */
const latLonPair = (v: unknown): LatLon | null =>
  Array.isArray(v) && v.length === 2 && isLat(v[0]) && isLon(v[1]) ? { lat_deg: v[0], lon_deg: v[1] } : null;

/** Applies `f` to an optional sub-object: null when absent or not an object. */
const sub = <T>(o: Obj, k: string, f: (x: Obj) => T): T | null => {
  const v = obj(o, k);
  return v === null ? null : f(v);
};

// The names each enumeration of the contract takes. `satisfies` makes the compiler hold each list
// to the generated type: a name added or removed in the daemon's Rust fails the build here.
const ROLES = { operator: true, viewer: true } as const satisfies Record<Role, true>;
const LEVELS = { info: true, warning: true, error: true } as const satisfies Record<Level, true>;
const OUTCOMES = { accepted: true, denied: true, failed: true, unsupported: true, timed_out: true, in_progress: true } as const satisfies Record<Outcome, true>;
const MODES = { uncontrolled: true, manual: true, heading: true, course: true, localizer: true, spiral_landing: true } as const satisfies Record<FlightMode, true>;
const STAGES = { pre_launch: true, ascent: true, round_chute: true, parafoil_deploy: true, parafoil: true, landed: true } as const satisfies Record<FlightStage, true>;
const PHASES = {
  idle: true, approximation: true, branch1: true, branch2: true, branch3: true, branch4: true, final_approach: true, flare: true, best_reachable: true, landed: true,
} as const satisfies Record<GuidancePhase, true>;
const FIXES = { no_gps: true, no_fix: true, fix2d: true, fix3d: true, dgps: true, rtk_float: true, rtk_fixed: true, static: true, ppp: true } as const satisfies Record<GpsFix, true>;
const GROUPS = { gains: true, spiral: true, failsafe: true, mission: true } as const satisfies Record<ParamGroup, true>;
const SOURCES = { guidance: true, link: true, command: true, station: true, vehicle: true, keep_out: true } as const satisfies Record<WireServerMessageOf<"event">["source"], true>;
const METHODS = { gps_velocity: true, position_differences: true } as const satisfies Record<BandMethod, true>;
const TARGET_SOURCES = { drone_plan: true, drone_telemetry: true, operator: true } as const satisfies Record<NonNullable<Guidance["target_source"]>, true>;

/** The value of `o[k]` if it is one of the names of `names`, else null. */
const oneOf = <T extends string>(o: Obj, k: string, names: Record<T, true>): T | null => {
  const v = o[k];
  return typeof v === "string" && Object.hasOwn(names, v) ? (v as T) : null;
};

/** A position the page can place: latitude and longitude in range (else null), altitude if a number. */
const position = (v: unknown): Position | null => {
  const ll = latLonObj(v);
  return ll === null || !isObj(v) ? null : { ...ll, alt_msl_m: num(v, "alt_msl_m") };
};

/** West, south, east, north in range with west < east and south < north, else null. */
const bounds = (v: unknown): [number, number, number, number] | null => {
  if (!Array.isArray(v) || v.length !== 4) return null;
  const [w, s, e, n] = v as unknown[];
  return isLon(w) && isLat(s) && isLon(e) && isLat(n) && w < e && s < n ? [w, s, e, n] : null;
};

export function parseStation(o: Obj): Station | null {
  const origin = position(o.origin);
  if (origin === null) return null;
  const modes = Array.isArray(o.modes) ? o.modes.filter((m): m is FlightMode => typeof m === "string" && Object.hasOwn(MODES, m)) : [];
  return {
    name: str(o, "name") ?? "station",
    origin,
    tile_url: str(o, "tile_url"),
    tile_attribution: str(o, "tile_attribution") ?? "",
    offline_tiles: bool(o, "offline_tiles") ?? false,
    offline_tiles_error: str(o, "offline_tiles_error"),
    tile_max_zoom: num(o, "tile_max_zoom"),
    tile_bounds: bounds(o.tile_bounds),
    modes,
    replay: bool(o, "replay") ?? false,
  };
}

export function parseSession(v: unknown): Parsed<Session> {
  if (!isObj(v)) return bad("session is not an object");
  const role = oneOf(v, "role", ROLES);
  if (role === null) return bad(`unknown role ${String(v.role)}`);
  const station = sub(v, "station", parseStation);
  if (station === null) return bad("session has no valid station (name, origin)");
  return ok({ role, name: str(v, "name") ?? "", station });
}

function parseLink(o: Obj | null): Link {
  // A state without a link block tells us nothing about freshness: treat it as stale.
  if (o === null) {
    return {
      connected: false, stale: true, age_s: null, rate_hz: null, loss_percent: null,
      crc_errors: null, parse_errors: null, signature_errors: null, ages_s: {}, radios: [],
    };
  }
  const ages: Record<string, number> = {};
  const rawAges = obj(o, "ages_s");
  if (rawAges !== null) {
    for (const [k, a] of Object.entries(rawAges)) if (typeof a === "number" && Number.isFinite(a)) ages[k] = a;
  }
  return {
    connected: bool(o, "connected") ?? false,
    stale: bool(o, "stale") ?? true,
    age_s: num(o, "age_s"),
    rate_hz: num(o, "rate_hz"),
    loss_percent: num(o, "loss_percent"),
    crc_errors: num(o, "crc_errors"),
    parse_errors: num(o, "parse_errors"),
    signature_errors: num(o, "signature_errors"),
    ages_s: ages,
    radios: Array.isArray(o.radios) ? o.radios.filter(isObj).map(parseRadio) : [],
  };
}

const parseRadio = (o: Obj): Radio => ({
  address: str(o, "address") ?? "?",
  transmitting: bool(o, "transmitting") ?? false,
  stale: bool(o, "stale") ?? true,
  age_s: num(o, "age_s"),
  rate_hz: num(o, "rate_hz"),
  loss_percent: num(o, "loss_percent"),
  duplicates: num(o, "duplicates"),
});

const parseGps = (o: Obj): Gps => ({
  fix: oneOf(o, "fix", FIXES),
  satellites: num(o, "satellites"),
  lat_deg: isLat(o.lat_deg) ? o.lat_deg : null,
  lon_deg: isLon(o.lon_deg) ? o.lon_deg : null,
  alt_msl_m: num(o, "alt_msl_m"),
  velocity_ned_mps: vec3(o, "velocity_ned_mps"),
  h_acc_m: num(o, "h_acc_m"),
});

function parseOnboardLanding(v: unknown): OnboardLanding | null {
  const p = position(v);
  if (p === null || !isObj(v)) return null;
  return { ...p, age_s: num(v, "age_s"), stale: bool(v, "stale") };
}

const parseVehicle = (o: Obj): Vehicle => ({
  mode: oneOf(o, "mode", MODES),
  stage: oneOf(o, "stage", STAGES),
  phase: oneOf(o, "phase", PHASES),
  gps: sub(o, "gps", parseGps),
  attitude: sub(o, "attitude", (a) => ({ time_boot_ms: num(a, "time_boot_ms"), roll_deg: num(a, "roll_deg"), pitch_deg: num(a, "pitch_deg"), yaw_deg: num(a, "yaw_deg") })),
  air: sub(o, "air", (a) => ({
    static_pressure_pa: num(a, "static_pressure_pa"),
    differential_pressure_pa: num(a, "differential_pressure_pa"),
    temperature_c: num(a, "temperature_c"),
    airspeed_mps: num(a, "airspeed_mps"),
  })),
  servos: sub(o, "servos", (s) => ({ main_line: num(s, "main_line"), brake_right: num(s, "brake_right"), brake_left: num(s, "brake_left") })),
  power: sub(o, "power", (p) => ({ voltage_v: num(p, "voltage_v"), current_a: num(p, "current_a"), remaining_percent: num(p, "remaining_percent") })),
  onboard_wind_ned_mps: vec3(o, "onboard_wind_ned_mps"),
  predicted_landing: parseOnboardLanding(o.predicted_landing),
  age_s: num(o, "age_s"),
  stale: bool(o, "stale"),
});

const parseEstimate = (o: Obj): Estimate => ({
  lat_deg: isLat(o.lat_deg) ? o.lat_deg : null,
  lon_deg: isLon(o.lon_deg) ? o.lon_deg : null,
  alt_msl_m: num(o, "alt_msl_m"),
  height_m: num(o, "height_m"),
  velocity_ned_mps: vec3(o, "velocity_ned_mps"),
  ground_speed_mps: num(o, "ground_speed_mps"),
  course_deg: num(o, "course_deg"),
  heading_deg: num(o, "heading_deg"),
  heading_rate_dps: num(o, "heading_rate_dps"),
  airspeed_mps: num(o, "airspeed_mps"),
  sink_rate_mps: num(o, "sink_rate_mps"),
  glide_ratio_air: num(o, "glide_ratio_air"),
  glide_ratio_ground: num(o, "glide_ratio_ground"),
  wind_ned_mps: vec3(o, "wind_ned_mps"),
  wind_speed_mps: num(o, "wind_speed_mps"),
  wind_from_deg: num(o, "wind_from_deg"),
  wind_sigma_mps: num(o, "wind_sigma_mps"),
  position_sigma_m: num(o, "position_sigma_m"),
  gps_ok: bool(o, "gps_ok"),
  age_s: num(o, "age_s"),
  stale: bool(o, "stale"),
});

/** A `[lat, lon]` pair in range, as the pattern and the localizer send points. */
const pair = (v: unknown): [number, number] | null => (Array.isArray(v) && v.length === 2 && isLat(v[0]) && isLon(v[1]) ? [v[0], v[1]] : null);

function parsePattern(o: Obj): Pattern {
  const corners = Array.isArray(o.corners) ? o.corners.map(pair).filter((c): c is [number, number] => c !== null) : [];
  return {
    corners,
    final_entry: pair(o.final_entry),
    final_course_deg: num(o, "final_course_deg"),
    final_approach_height_m: num(o, "final_approach_height_m"),
    target_reachable: bool(o, "target_reachable"),
    reach_ratio: num(o, "reach_ratio"),
  };
}

function parseLocalizer(o: Obj): Localizer | null {
  const point = pair(o.point);
  return point === null ? null : { point, course_deg: num(o, "course_deg"), glide_slope: num(o, "glide_slope") };
}

function parseDisagreement(o: Obj): Disagreement | null {
  const replica = str(o, "replica");
  const drone = str(o, "drone");
  if (o.what !== "phase" || replica === null || drone === null) return null;
  return { what: "phase", replica, drone, since_s: num(o, "since_s"), for_s: num(o, "for_s"), resolved: bool(o, "resolved"), adopted: bool(o, "adopted") };
}

function parseMissionLanding(o: Obj): Landing | null {
  const p = position(o.position);
  if (p === null) return null;
  return { time_s: num(o, "time_s"), body: str(o, "body") ?? "drone", position: p, target: position(o.target), miss_m: num(o, "miss_m") };
}

const parseGuidance = (o: Obj): Guidance => ({
  mode: oneOf(o, "mode", MODES),
  phase: oneOf(o, "phase", PHASES),
  target: position(o.target),
  target_source: oneOf(o, "target_source", TARGET_SOURCES),
  localizer: obj(o, "localizer") === null ? null : parseLocalizer(obj(o, "localizer") as Obj),
  pattern: sub(o, "pattern", parsePattern),
  commands: sub(o, "commands", (c) => ({ main_line: num(c, "main_line"), brake: num(c, "brake") })),
  age_s: num(o, "age_s"),
  stale: bool(o, "stale"),
  disagreement: sub(o, "disagreement", parseDisagreement),
});

function parseLanding(v: unknown): LandingPrediction | null {
  const ll = latLonObj(v);
  if (ll === null || !isObj(v)) return null;
  return {
    ...ll,
    time_to_land_s: num(v, "time_to_land_s"),
    semi_major_m: num(v, "semi_major_m"),
    semi_minor_m: num(v, "semi_minor_m"),
    major_axis_deg: num(v, "major_axis_deg"),
  };
}

const parsePrediction = (o: Obj): Prediction => ({
  planned: parseLanding(o.planned),
  uncontrolled: parseLanding(o.uncontrolled),
  age_s: num(o, "age_s"),
  stale: bool(o, "stale"),
});

/** A ring of finite `[lat, lon]` pairs in range; `null` when any point is not one. */
function parseRing(v: unknown): Ring | null {
  if (!Array.isArray(v) || v.length < 3) return null;
  const out: Ring = [];
  for (const p of v) {
    if (!Array.isArray(p) || p.length !== 2) return null;
    const [lat, lon] = p as unknown[];
    if (typeof lat !== "number" || typeof lon !== "number" || !(Math.abs(lat) <= 90) || !(Math.abs(lon) <= 180)) return null;
    out.push([lat, lon]);
  }
  return out;
}

/** The footprint; a level or polygon that does not parse is left out rather than drawn wrong. */
export function parseFootprint(o: Obj): Footprint | null {
  const computed_s = num(o, "computed_s");
  if (computed_s === null || !Array.isArray(o.contours)) return null;
  const contours: Footprint["contours"] = [];
  for (const c of o.contours) {
    if (!isObj(c)) continue;
    const level = num(c, "level");
    if (level === null || !Array.isArray(c.polygons)) continue;
    const polygons: Ring[][] = [];
    for (const poly of c.polygons) {
      if (!Array.isArray(poly)) continue;
      const rings = poly.map(parseRing);
      if (rings.length > 0 && rings.every((r): r is Ring => r !== null)) polygons.push(rings);
    }
    contours.push({ level, polygons });
  }
  const zone_hits: Footprint["zone_hits"] = [];
  for (const h of Array.isArray(o.zone_hits) ? o.zone_hits : []) {
    const zone = isObj(h) ? str(h, "zone") : null;
    const level = isObj(h) ? num(h, "level") : null;
    if (zone !== null && level !== null) zone_hits.push({ zone, level });
  }
  return {
    computed_s,
    zone_hits,
    age_s: num(o, "age_s") ?? 0,
    stale: bool(o, "stale") ?? false,
    height_m: num(o, "height_m") ?? 0,
    draws: num(o, "draws") ?? 0,
    contours,
  };
}

/** GeoJSON `[lon, lat]` rings as the map's `[lat, lon]`; `null` when any is not a ring. */
function geoRings(v: unknown): Ring[] | null {
  if (!Array.isArray(v) || v.length === 0) return null;
  const rings = v.map((r) => (Array.isArray(r) ? parseRing(r.map((p) => (Array.isArray(p) ? [p[1], p[0]] : p))) : null));
  return rings.every((r): r is Ring => r !== null) ? rings : null;
}

/** The zones of a `keep_out` message (a GeoJSON FeatureCollection of named Polygons and MultiPolygons). */
export function parseKeepOut(v: Obj): Parsed<KeepOutMsg> {
  const time_s = num(v, "time_s");
  if (time_s === null) return bad("keep_out without a numeric time_s");
  const zones = obj(v, "zones");
  const areas: KeepOutArea[] = [];
  const features = zones !== null && Array.isArray(zones.features) ? zones.features : [];
  for (const f of features) {
    if (!isObj(f)) continue;
    const props = obj(f, "properties");
    const name = (props && str(props, "name")) ?? "unnamed zone";
    const g = obj(f, "geometry");
    if (g === null || !Array.isArray(g.coordinates)) continue;
    const polygons = g.type === "Polygon" ? [g.coordinates] : g.type === "MultiPolygon" ? g.coordinates : [];
    for (const p of polygons) {
      const rings = geoRings(p);
      if (rings !== null) areas.push({ name, rings });
    }
  }
  return ok({ type: "keep_out", time_s, load_error: str(v, "load_error"), changed_by: str(v, "changed_by"), file: str(v, "file"), areas, zones: zonesOf(zones) });
}

const PREDICTION_KINDS = { planned: true, uncontrolled: true } as const satisfies Record<KeepOutAlarm["prediction"], true>;

function parseAlarms(v: unknown): KeepOutAlarm[] {
  if (!Array.isArray(v)) return [];
  const out: KeepOutAlarm[] = [];
  for (const a of v) {
    if (!isObj(a)) continue;
    const prediction = oneOf(a, "prediction", PREDICTION_KINDS);
    const zone = str(a, "zone");
    if (prediction !== null && zone !== null) out.push({ prediction, zone, since_s: num(a, "since_s") ?? 0 });
  }
  return out;
}

function parseForecast(v: unknown): ForecastWind[] {
  if (!Array.isArray(v)) return [];
  const out: ForecastWind[] = [];
  for (const e of v) {
    if (!isObj(e)) continue;
    const alt = num(e, "alt_msl_m");
    const speed = num(e, "speed_mps");
    if (alt !== null && speed !== null) out.push({ alt_msl_m: alt, speed_mps: speed, from_deg: num(e, "from_deg") });
  }
  return out.sort((a, b) => a.alt_msl_m - b.alt_msl_m);
}

export function parseState(v: Obj): Parsed<State> {
  const time_s = num(v, "time_s");
  if (time_s === null) return bad("state without a numeric time_s");
  const mission = obj(v, "mission");
  const m: Mission = {
    stage: mission ? oneOf(mission, "stage", STAGES) : null,
    cutdown_armed_until_s: mission ? num(mission, "cutdown_armed_until_s") : null,
    landing: mission ? sub(mission, "landing", parseMissionLanding) : null,
  };
  return ok({
    type: "state",
    time_s,
    mission_time_s: num(v, "mission_time_s"),
    wall_ms: num(v, "wall_ms"),
    link: parseLink(obj(v, "link")),
    vehicle: sub(v, "vehicle", parseVehicle),
    estimate: sub(v, "estimate", parseEstimate),
    guidance: sub(v, "guidance", parseGuidance),
    prediction: sub(v, "prediction", parsePrediction),
    footprint: sub(v, "footprint", parseFootprint),
    flight_path: sub(v, "flight_path", parseFlightPath),
    keep_out_alarms: parseAlarms(v.keep_out_alarms),
    forecast_wind: parseForecast(v.forecast_wind),
    mission: m,
    recording: sub(v, "recording", parseRecording),
    replay: sub(v, "replay", parseReplay),
  });
}

const REPLAY_MODES = { rerun: true, recorded: true } as const satisfies Record<Replay["mode"], true>;

function parseReplay(o: Obj): Replay | null {
  const mode = oneOf(o, "mode", REPLAY_MODES);
  const file = str(o, "file");
  if (mode === null || file === null) return null;
  return {
    file,
    mode,
    start_ms: num(o, "start_ms"),
    duration_ms: num(o, "duration_ms"),
    position_ms: num(o, "position_ms"),
    speed: num(o, "speed"),
    paused: bool(o, "paused"),
    finished: bool(o, "finished"),
    epoch: num(o, "epoch"),
    seeking: bool(o, "seeking"),
  };
}

const RECORDING_STATES = { on: true, off: true, failing: true } as const satisfies Record<Recording["state"], true>;

function parseRecording(o: Obj): Recording | null {
  const state = oneOf(o, "state", RECORDING_STATES);
  if (state === null) return null;
  return {
    state,
    file: str(o, "file"),
    bytes_written: num(o, "bytes_written"),
    messages_written: num(o, "messages_written"),
    messages_lost: num(o, "messages_lost"),
    problem: str(o, "problem"),
    failing_since_ms: num(o, "failing_since_ms"),
    next_try_in_s: num(o, "next_try_in_s"),
    failed_tries: num(o, "failed_tries"),
    resumed_ms: num(o, "resumed_ms"),
    resumed_after_s: num(o, "resumed_after_s"),
  };
}

export function parseEvent(v: Obj): Parsed<EventMsg> {
  const text = str(v, "text");
  if (text === null) return bad("event without text");
  return ok({
    type: "event",
    time_s: num(v, "time_s"),
    mission_time_s: num(v, "mission_time_s"),
    wall_ms: num(v, "wall_ms"),
    // An unknown level is shown as a warning rather than dropped: the text may matter.
    level: oneOf(v, "level", LEVELS) ?? "warning",
    source: oneOf(v, "source", SOURCES),
    text,
  });
}

export function parseCommandResult(v: Obj): Parsed<CommandResult> {
  const request_id = str(v, "request_id");
  const outcome = oneOf(v, "outcome", OUTCOMES);
  if (request_id === null) return bad("command_result without request_id");
  if (outcome === null) return bad(`command_result with unknown outcome ${String(v.outcome)}`);
  return ok({
    type: "command_result",
    request_id,
    command: str(v, "command") ?? "?",
    outcome,
    attempts: num(v, "attempts"),
    detail: str(v, "detail") ?? "",
    value: num(v, "value"),
  });
}

export function parseParams(v: Obj): Parsed<ParamsMsg> {
  if (!Array.isArray(v.params)) return bad("params without a params array");
  const params: Param[] = [];
  for (const p of v.params) {
    if (!isObj(p)) continue;
    const name = str(p, "name");
    if (name === null) continue;
    params.push({
      name,
      value: num(p, "value"),
      min: num(p, "min"),
      max: num(p, "max"),
      units: str(p, "units") ?? "",
      description: str(p, "description") ?? "",
      group: oneOf(p, "group", GROUPS),
      choices: Array.isArray(p.choices) ? p.choices.filter((c): c is string => typeof c === "string") : [],
    });
  }
  return ok({ type: "params", params, complete: bool(v, "complete") ?? false, time_s: num(v, "time_s") });
}

/** A band needs its altitude, wind and σ (finite, σ ≥ 0) to be drawn; one without is dropped. */
function parseAscentBand(v: unknown): AscentBand | null {
  if (!isObj(v)) return null;
  const [alt, n, e, sn, se] = ["alt_msl_m", "wind_north_mps", "wind_east_mps", "sigma_north_mps", "sigma_east_mps"].map((k) => num(v, k));
  if (alt == null || n == null || e == null || sn == null || se == null || sn < 0 || se < 0) return null;
  return {
    alt_msl_m: alt,
    alt_min_msl_m: num(v, "alt_min_msl_m"),
    alt_max_msl_m: num(v, "alt_max_msl_m"),
    speed_mps: num(v, "speed_mps"),
    from_deg: num(v, "from_deg"),
    wind_north_mps: n,
    wind_east_mps: e,
    sigma_north_mps: sn,
    sigma_east_mps: se,
    samples: num(v, "samples"),
    method: oneOf(v, "method", METHODS),
    time_start_s: num(v, "time_start_s"),
    time_end_s: num(v, "time_end_s"),
    refused: str(v, "refused"),
  };
}

export function parseAscentWind(v: Obj): Parsed<AscentWindMsg & { dropped: number }> {
  if (!Array.isArray(v.bands)) return bad("ascent_wind without a bands array");
  const bands = parseList(v.bands, parseAscentBand);
  return ok({
    type: "ascent_wind",
    time_s: num(v, "time_s"),
    band_height_m: num(v, "band_height_m"),
    ascent_over: bool(v, "ascent_over") ?? false,
    fixes_used: num(v, "fixes_used"),
    bands: bands.items,
    dropped: bands.dropped,
  });
}

export function parseTrackPoint(v: unknown): TrackPoint | null {
  if (!isObj(v)) return null;
  const t = num(v, "time_s");
  if (t === null || !isLat(v.lat_deg) || !isLon(v.lon_deg)) return null;
  return { time_s: t, mission_time_s: num(v, "mission_time_s"), lat_deg: v.lat_deg, lon_deg: v.lon_deg, alt_msl_m: num(v, "alt_msl_m") };
}

/** Parses each element with `f`, keeping the good ones; returns how many were dropped. */
function parseList<T>(v: unknown, f: (x: unknown) => T | null): { items: T[]; dropped: number } {
  if (!Array.isArray(v)) return { items: [], dropped: 0 };
  const items: T[] = [];
  for (const x of v) {
    const p = f(x);
    if (p !== null) items.push(p);
  }
  return { items, dropped: v.length - items.length };
}

const orNull = <T>(p: Parsed<T>): T | null => (p.ok ? p.value : null);

function parseHistory(v: Obj): Parsed<History & { dropped: number }> {
  if (!Array.isArray(v.track) && !Array.isArray(v.events) && !Array.isArray(v.states)) return bad("history without track, events or states");
  const track = parseList(v.track, parseTrackPoint);
  const events = parseList(v.events, (e) => (isObj(e) ? orNull(parseEvent(e)) : null));
  const states = parseList(v.states, (s) => (isObj(s) ? orNull(parseState(s)) : null));
  return ok({
    type: "history",
    track: track.items,
    events: events.items,
    states: states.items,
    replay_epoch: num(v, "replay_epoch"),
    dropped: track.dropped + events.dropped + states.dropped,
  });
}

function parseHello(v: Obj): Parsed<ServerMessage> {
  // The session is under "session" (with role and name repeated beside it); a session flattened
  // into the message is read too.
  const s = parseSession(obj(v, "session") ?? v);
  return s.ok ? ok({ type: "hello", session: s.value }) : bad(`hello: ${s.error}`);
}

const parseLagged = (v: Obj): Parsed<Lagged> =>
  ok({ type: "lagged", missed: num(v, "missed"), missed_total: num(v, "missed_total"), time_s: num(v, "time_s"), refetch: str(v, "refetch") === "/api/events" ? "/api/events" : null });

/** Result of decoding one WebSocket frame. `dropped` counts bad elements inside a good message. */
export type Decoded = { ok: true; msg: ServerMessage; dropped: number } | { ok: false; error: string };

export function decodeMessage(raw: unknown): Decoded {
  if (typeof raw !== "string") return { ok: false, error: "binary frame" };
  let v: unknown;
  try {
    v = JSON.parse(raw);
  } catch {
    return { ok: false, error: `not JSON: ${raw.slice(0, 40)}` };
  }
  if (!isObj(v)) return { ok: false, error: "not a JSON object" };
  const type = str(v, "type");
  if (type === null) return { ok: false, error: "no type" };
  const wrap = (p: Parsed<ServerMessage>, dropped = 0): Decoded => (p.ok ? { ok: true, msg: p.value, dropped } : { ok: false, error: p.error });
  return Object.hasOwn(DECODERS, type) ? DECODERS[type as WireServerType](v, wrap) : { ok: true, msg: { type: "unknown", raw_type: type }, dropped: 0 };
}

type Wrap = (p: Parsed<ServerMessage>, dropped?: number) => Decoded;

// One decoder for each message type of the contract: the compiler holds this table to the
// generated ServerMessage, so a message added to the daemon must be added here.
const DECODERS = {
  hello: (v, wrap) => wrap(parseHello(v)),
  state: (v, wrap) => wrap(parseState(v)),
  event: (v, wrap) => wrap(parseEvent(v)),
  command_result: (v, wrap) => wrap(parseCommandResult(v)),
  params: (v, wrap) => wrap(parseParams(v)),
  ascent_wind: (v) => {
    const a = parseAscentWind(v);
    if (!a.ok) return { ok: false, error: a.error };
    const { dropped, ...msg } = a.value;
    return { ok: true, msg, dropped };
  },
  history: (v) => {
    const h = parseHistory(v);
    if (!h.ok) return { ok: false, error: h.error };
    const { dropped, ...history } = h.value;
    return { ok: true, msg: history, dropped };
  },
  lagged: (v, wrap) => wrap(parseLagged(v)),
  pong: () => ({ ok: true, msg: { type: "pong" }, dropped: 0 }),
  keep_out: (v, wrap) => wrap(parseKeepOut(v)),
} satisfies Record<WireServerType, (v: Obj, wrap: Wrap) => Decoded>;

/** Counts what arrived, so loss and garbage are shown rather than hidden (style.md, lesson 9). */
export class MessageStats {
  received = 0;
  bad = 0;
  ignored = 0;
  lastError: string | null = null;

  record(d: Decoded): void {
    this.received += 1;
    if (!d.ok) {
      this.bad += 1;
      this.lastError = d.error;
      return;
    }
    if (d.dropped > 0) {
      this.bad += d.dropped;
      this.lastError = `${d.msg.type}: ${d.dropped} malformed item(s) dropped`;
    }
    if (d.msg.type === "unknown") this.ignored += 1;
  }
}
