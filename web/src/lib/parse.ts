// Parses what the station sends into the typed shapes of types.ts (the generated contract, read
// leniently), defensively: the wire is outside our control (a daemon version skew, a proxy
// truncating a frame), and a bad message must never crash the page or be shown as data. Leaves
// that are missing or of the wrong type become null, and so do positions out of range and names
// the contract does not list; a message without what makes it meaningful (a state without time_s,
// an event without text) is rejected with a reason, so the caller can count and show it.

import type {
  AscentBand,
  AscentWindMsg,
  CommandResult,
  EventMsg,
  History,
  Lagged,
  Param,
  ParamsMsg,
  ServerMessage,
  TrackPoint,
} from "./types";
import { GROUPS, LEVELS, METHODS, OUTCOMES, type Obj, type Parsed, SOURCES, type WireServerType, bad, bool, isLat, isLon, isObj, num, obj, ok, oneOf, str } from "./parseFields";
import { parseSession, parseKeepOut, parseState } from "./parseState";

// What the pages import from here, wherever it is written.
export { isObj, type Parsed } from "./parseFields";
export { parseStation, parseSession, parseFootprint, parseKeepOut, parseState } from "./parseState";

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
