// Parses what the station sends into the typed shapes of types.ts, defensively: the wire is
// outside our control (a daemon version skew, a proxy truncating a frame), and a bad message must
// never crash the page or be shown as data. Optional leaves that are missing or of the wrong type
// become null; a message without what makes it meaningful (a state without time_s, an event
// without text) is rejected with a reason, so the caller can count and show it.

import type {
  CommandResult,
  Estimate,
  EventMsg,
  ForecastWind,
  Gps,
  Guidance,
  History,
  LandingPrediction,
  LatLon,
  Level,
  Link,
  Radio,
  Mission,
  N,
  Outcome,
  Param,
  ParamsMsg,
  Pattern,
  Prediction,
  Role,
  ServerMessage,
  Session,
  State,
  Station,
  TrackPoint,
  Vec3,
  Vehicle,
} from "./types";

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

const ROLES: readonly Role[] = ["operator", "viewer"];
const LEVELS: readonly Level[] = ["info", "warning", "error"];
const OUTCOMES: readonly Outcome[] = ["accepted", "denied", "failed", "unsupported", "timed_out", "in_progress"];

function parseStation(o: Obj): Station | null {
  const origin = obj(o, "origin");
  const ll = latLonObj(origin);
  if (ll === null || origin === null) return null;
  const modes = Array.isArray(o.modes) ? o.modes.filter((m): m is string => typeof m === "string") : [];
  return {
    name: str(o, "name") ?? "station",
    origin: { ...ll, alt_msl_m: num(origin, "alt_msl_m") },
    tile_url: str(o, "tile_url"),
    tile_attribution: str(o, "tile_attribution") ?? "",
    offline_tiles: bool(o, "offline_tiles") ?? false,
    modes,
  };
}

export function parseSession(v: unknown): Parsed<Session> {
  if (!isObj(v)) return bad("session is not an object");
  const role = str(v, "role");
  if (role === null || !(ROLES as readonly string[]).includes(role)) return bad(`unknown role ${String(v.role)}`);
  const station = sub(v, "station", parseStation);
  if (station === null) return bad("session has no valid station (name, origin)");
  return ok({ role: role as Role, name: str(v, "name") ?? "", station });
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
  fix: str(o, "fix"),
  satellites: num(o, "satellites"),
  lat_deg: isLat(o.lat_deg) ? o.lat_deg : null,
  lon_deg: isLon(o.lon_deg) ? o.lon_deg : null,
  alt_msl_m: num(o, "alt_msl_m"),
  velocity_ned_mps: vec3(o, "velocity_ned_mps"),
  h_acc_m: num(o, "h_acc_m"),
});

const parseVehicle = (o: Obj): Vehicle => ({
  mode: str(o, "mode"),
  stage: str(o, "stage"),
  phase: str(o, "phase"),
  gps: sub(o, "gps", parseGps),
  attitude: sub(o, "attitude", (a) => ({ roll_deg: num(a, "roll_deg"), pitch_deg: num(a, "pitch_deg"), yaw_deg: num(a, "yaw_deg") })),
  air: sub(o, "air", (a) => ({
    static_pressure_pa: num(a, "static_pressure_pa"),
    differential_pressure_pa: num(a, "differential_pressure_pa"),
    temperature_c: num(a, "temperature_c"),
    airspeed_mps: num(a, "airspeed_mps"),
  })),
  servos: sub(o, "servos", (s) => ({ main_line: num(s, "main_line"), brake_right: num(s, "brake_right"), brake_left: num(s, "brake_left") })),
  power: sub(o, "power", (p) => ({ voltage_v: num(p, "voltage_v"), current_a: num(p, "current_a"), remaining_percent: num(p, "remaining_percent") })),
  onboard_wind_ned_mps: vec3(o, "onboard_wind_ned_mps"),
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
});

function parsePattern(o: Obj): Pattern {
  const corners = Array.isArray(o.corners) ? o.corners.map(latLonPair).filter((c): c is LatLon => c !== null) : [];
  return {
    corners,
    final_entry: latLonPair(o.final_entry),
    final_course_deg: num(o, "final_course_deg"),
    final_approach_height_m: num(o, "final_approach_height_m"),
    target_reachable: bool(o, "target_reachable"),
    reach_ratio: num(o, "reach_ratio"),
  };
}

function parseGuidance(o: Obj): Guidance {
  const t = obj(o, "target");
  const tll = latLonObj(t);
  return {
    mode: str(o, "mode"),
    phase: str(o, "phase"),
    target: tll === null || t === null ? null : { ...tll, alt_msl_m: num(t, "alt_msl_m") },
    pattern: sub(o, "pattern", parsePattern),
    commands: sub(o, "commands", (c) => ({ main_line: num(c, "main_line"), brake: num(c, "brake") })),
  };
}

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

const parsePrediction = (o: Obj): Prediction => ({ planned: parseLanding(o.planned), uncontrolled: parseLanding(o.uncontrolled) });

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
  const m: Mission = { stage: mission ? str(mission, "stage") : null, cutdown_armed_until_s: mission ? num(mission, "cutdown_armed_until_s") : null };
  return ok({
    type: "state",
    time_s,
    wall_ms: num(v, "wall_ms"),
    link: parseLink(obj(v, "link")),
    vehicle: sub(v, "vehicle", parseVehicle),
    estimate: sub(v, "estimate", parseEstimate),
    guidance: sub(v, "guidance", parseGuidance),
    prediction: sub(v, "prediction", parsePrediction),
    forecast_wind: parseForecast(v.forecast_wind),
    mission: m,
  });
}

export function parseEvent(v: Obj): Parsed<EventMsg> {
  const text = str(v, "text");
  if (text === null) return bad("event without text");
  const level = str(v, "level");
  return ok({
    type: "event",
    time_s: num(v, "time_s"),
    wall_ms: num(v, "wall_ms"),
    // An unknown level is shown as a warning rather than dropped: the text may matter.
    level: level !== null && (LEVELS as readonly string[]).includes(level) ? (level as Level) : "warning",
    source: str(v, "source") ?? "?",
    text,
  });
}

export function parseCommandResult(v: Obj): Parsed<CommandResult> {
  const request_id = str(v, "request_id");
  const outcome = str(v, "outcome");
  if (request_id === null) return bad("command_result without request_id");
  if (outcome === null || !(OUTCOMES as readonly string[]).includes(outcome)) return bad(`command_result with unknown outcome ${String(v.outcome)}`);
  return ok({
    type: "command_result",
    request_id,
    command: str(v, "command") ?? "?",
    outcome: outcome as Outcome,
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
    });
  }
  return ok({ type: "params", params, complete: bool(v, "complete") ?? false, time_s: num(v, "time_s") });
}

export function parseTrackPoint(v: unknown): TrackPoint | null {
  if (!isObj(v)) return null;
  const t = num(v, "time_s");
  if (t === null || !isLat(v.lat_deg) || !isLon(v.lon_deg)) return null;
  return { time_s: t, lat_deg: v.lat_deg, lon_deg: v.lon_deg, alt_msl_m: num(v, "alt_msl_m") };
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
    dropped: track.dropped + events.dropped + states.dropped,
  });
}

function parseHello(v: Obj): Parsed<ServerMessage> {
  // API.md says hello carries "session, as above": accept it either flattened into the message
  // (our reading) or nested under "session".
  const s = parseSession(obj(v, "session") ?? v);
  return s.ok ? ok({ type: "hello", session: s.value }) : bad(`hello: ${s.error}`);
}

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
  switch (type) {
    case "hello":
      return wrap(parseHello(v));
    case "state":
      return wrap(parseState(v));
    case "event":
      return wrap(parseEvent(v));
    case "command_result":
      return wrap(parseCommandResult(v));
    case "params":
      return wrap(parseParams(v));
    case "history": {
      const h = parseHistory(v);
      if (!h.ok) return { ok: false, error: h.error };
      const { dropped, ...history } = h.value;
      return { ok: true, msg: history, dropped };
    }
    case "pong":
      return { ok: true, msg: { type: "pong" }, dropped: 0 };
    default:
      return { ok: true, msg: { type: "unknown", raw_type: type }, dropped: 0 };
  }
}

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
