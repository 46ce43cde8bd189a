// Parses the station's `state` message (and the station, session and footprint it carries, and
// the keep-out zones) into the shapes of types.ts; see parse.ts for the rules.

import { parseReadiness } from "./readiness";
import { parseFlightPath } from "./flightPath";
import { zonesOf } from "./zones";
import { parseStack } from "./stack";
import { parseSurfaceWind } from "./surfaceWind";
import type {
  Estimate,
  FlightMode,
  Footprint,
  KeepOutAlarm,
  KeepOutArea,
  KeepOutMsg,
  ForecastWind,
  Gps,
  Disagreement,
  Guidance,
  Learned,
  Landing,
  LandingPrediction,
  Link,
  Localizer,
  Mission,
  Recording,
  Ring,
  Replay,
  OnboardLanding,
  Pattern,
  Prediction,
  Radio,
  Session,
  State,
  Station,
  Vehicle,
} from "./types";
import { FIXES, MODES, type Obj, PHASES, type Parsed, ROLES, STAGES, TARGET_SOURCES, bad, bool, bounds, isLat, isLon, isObj, latLonObj, num, obj, ok, oneOf, pair, position, str, sub, vec3 } from "./parseFields";

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
  final_approaches: num(o, "final_approaches"),
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

const parseLearned = (o: Obj): Learned => ({
  brake: vec3(o, "brake"),
  airspeed_scale: vec3(o, "airspeed_scale"),
  sink_scale: vec3(o, "sink_scale"),
  learned_s: num(o, "learned_s"),
  turn_scale: num(o, "turn_scale"),
  turn_learned_s: num(o, "turn_learned_s"),
  flying: bool(o, "flying"),
  airspeed_sigma: num(o, "airspeed_sigma"),
  sink_sigma: num(o, "sink_sigma"),
  turn_sigma: num(o, "turn_sigma"),
});

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
  learned: sub(o, "learned", parseLearned),
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
    stack: sub(v, "stack", parseStack),
    guidance: sub(v, "guidance", parseGuidance),
    prediction: sub(v, "prediction", parsePrediction),
    footprint: sub(v, "footprint", parseFootprint),
    flight_path: sub(v, "flight_path", parseFlightPath),
    keep_out_alarms: parseAlarms(v.keep_out_alarms),
    forecast_wind: parseForecast(v.forecast_wind),
    mission: m,
    recording: sub(v, "recording", parseRecording),
    readiness: parseReadiness(v.readiness),
    replay: sub(v, "replay", parseReplay),
    surface_wind: parseSurfaceWind(v.surface_wind),
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
