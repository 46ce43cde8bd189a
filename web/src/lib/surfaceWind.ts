// The wind at the ground by the landing target (`state.surface_wind`): a mast anemometer's mean
// or a value the operator typed, which the station uplinks to the drone every few seconds for
// the final approach. This module reads the block leniently (a station or a recording older
// than the surface wind has none: null, shown "—"), says what the Wind panel shows of it, and
// checks what the operator types before it is sent.
//
// What is shown must say whether the drone has the wind, not only what the station holds: a
// wind the drone never accepted does not steer the final, so the drone's copy has its own line,
// and a failed uplink or a sick anemometer is a warning, not a detail in a tooltip.

import { fmt, fmtDir } from "./format";
import { parseNumber } from "./inputs";
import { isObj, num, oneOf, str, sub, type Obj } from "./parseFields";
import type { DroneCopy, SurfaceWindBody, SurfaceWindSource } from "../generated/api";
import type { Anemometer, N, SurfaceWind, SurfaceWindReading } from "./types";

export type { SurfaceWind };

const SOURCES = { anemometer: true, operator: true } as const satisfies Record<SurfaceWindSource, true>;
const COPIES = { none: true, sending: true, held: true, failed: true } as const satisfies Record<DroneCopy, true>;

/** The station's bounds on a typed value (`POST /api/surface_wind` refuses beyond them). */
export const MAX_SPEED_MPS = 60;

function parseReading(o: Obj): SurfaceWindReading | null {
  const speed_mps = num(o, "speed_mps");
  const from_deg = num(o, "from_deg");
  const source = oneOf(o, "source", SOURCES);
  // A negative speed is not a wind: better none shown than a wrong one.
  if (speed_mps === null || speed_mps < 0 || from_deg === null || source === null) return null;
  return { speed_mps, from_deg, source, age_s: num(o, "age_s") };
}

const parseAnemometer = (o: Obj): Anemometer => ({
  address: str(o, "address") ?? "?",
  sentences: num(o, "sentences"),
  rejected: num(o, "rejected"),
  last_error: str(o, "last_error"),
  heard_age_s: num(o, "heard_age_s"),
  in_mean: num(o, "in_mean"),
});

/** `state.surface_wind`; null when it is not an object (absent from an older station's states). */
export function parseSurfaceWind(v: unknown): SurfaceWind | null {
  if (!isObj(v)) return null;
  return {
    wind: sub(v, "wind", parseReading),
    operator: sub(v, "operator", parseReading),
    drone: oneOf(v, "drone", COPIES),
    held: sub(v, "held", parseReading),
    drone_accepted_age_s: num(v, "drone_accepted_age_s"),
    last_error: str(v, "last_error"),
    anemometer: sub(v, "anemometer", parseAnemometer),
  };
}

/**
 * One line of the readout: what matters (bold), a detail after it (plain), whether it warns, and
 * the whole story for its tooltip.
 */
export interface ShownLine {
  text: string;
  detail: string;
  warn: boolean;
  title: string;
}

export interface SurfaceWindShown {
  /** The wind in force: speed and from-direction, then its source and age; "none" when there is none. */
  wind: ShownLine;
  /** The drone's copy. */
  drone: ShownLine;
  /** The anemometer's intake; null when none is configured (or the station does not say). */
  anemometer: ShownLine | null;
}

/** An age in whole units, short: "4 s", "12 min", "2.5 h" (the readouts share a narrow column). */
export function fmtAge(s: N | undefined): string {
  if (s === null || s === undefined || !Number.isFinite(s)) return "— s";
  const a = Math.max(0, s);
  if (a < 90) return `${a.toFixed(0)} s`;
  if (a < 90 * 60) return `${(a / 60).toFixed(0)} min`;
  return `${(a / 3600).toFixed(1)} h`;
}

const reading = (r: SurfaceWindReading): string => `${fmt(r.speed_mps, "m/s")} from ${fmtDir(r.from_deg)}`;
const count = (n: N): string => fmt(n, "", 0);

function windLine(sw: SurfaceWind): ShownLine {
  const w = sw.wind;
  const op = sw.operator;
  if (w === null) {
    const why = sw.anemometer === null ? "no operator value (and no anemometer configured)" : "no anemometer mean heard lately and no operator value";
    return { text: "none", detail: "", warn: false, title: `no surface wind is sent to the drone: ${why}` };
  }
  // The operator's value stays in the tooltip while a fresh anemometer mean wins over it.
  const beside = w.source === "anemometer" && op !== null ? `; the operator's ${reading(op)} (${fmtAge(op.age_s)} old) is not used while the anemometer is heard` : "";
  // The station sends a typed value as measured now (its `wind.age_s` stays 0): how long ago it
  // was typed is the operator block's age, which says when it lapses.
  const age = w.source === "operator" ? (op?.age_s ?? w.age_s) : w.age_s;
  return {
    text: reading(w),
    // An anemometer's age is its line's "heard … ago", just below: not said twice in a narrow column.
    detail: w.source === "anemometer" ? "· anemometer" : `· operator ${fmtAge(age)}`,
    warn: false,
    title: `surface wind sent to the drone: ${fmt(w.speed_mps, "m/s", 2)} from ${fmt(w.from_deg, "°")} true, ${w.source === "anemometer" ? "the anemometer's mean" : "typed by the operator"}, ${fmtAge(age)} old${beside}`,
  };
}

function droneLine(sw: SurfaceWind): ShownLine {
  const ago = sw.drone_accepted_age_s;
  const last = ago === null ? "never accepted one" : `last accepted one ${fmtAge(ago)} ago`;
  switch (sw.drone) {
    case "held": {
      // What the drone has, not what the station would send: they differ until the next uplink.
      const held = sw.held === null ? "" : ` ${reading(sw.held)}`;
      // Nothing in force any more (withdrawn, lapsed): the drone keeps its copy until it is too old.
      const lapsing = sw.wind === null ? "; the station sends none now, and guidance drops it 2 min after it was measured" : "";
      return { text: `held${held}`, detail: `${fmtAge(ago)} ago`, warn: false, title: `the drone accepted the surface wind${held} ${fmtAge(ago)} ago${lapsing}` };
    }
    case "sending":
      return { text: "sending", detail: "", warn: false, title: `sent, not yet acknowledged; the drone ${last}` };
    case "failed": {
      const why = sw.last_error ?? "no reason given";
      return { text: "FAILED:", detail: why, warn: true, title: `the last uplink failed (${why}); tried again at the next period; the drone ${last}` };
    }
    case "none":
      return { text: "not sent", detail: "", warn: false, title: sw.wind === null ? "no surface wind to send" : "not sent yet (no drone heard)" };
    default:
      return { text: "—", detail: "", warn: false, title: "the station does not say" };
  }
}

function anemometerLine(a: Anemometer, inForce: boolean): ShownLine {
  const heard = a.heard_age_s === null ? "not heard" : `heard ${fmtAge(a.heard_age_s)} ago`;
  const counts = `${count(a.sentences)} ok · ${count(a.rejected)} bad`;
  // Configured but not the wind in force: silent too long, or never heard. Where it listens is
  // then the first thing to check; otherwise the address is in the tooltip, the line is short.
  const detail = [
    ...(inForce ? [] : [a.heard_age_s === null ? `on ${a.address}` : "stale, not used"]),
    counts,
    ...(a.last_error === null ? [] : [a.last_error]),
  ];
  return {
    text: heard,
    detail: `· ${detail.join(" · ")}`,
    warn: !inForce || a.last_error !== null,
    title: `anemometer on ${a.address}: ${heard}, ${count(a.sentences)} wind sentences taken, ${count(a.rejected)} lines refused, ${count(a.in_mean)} in the mean${inForce ? "" : "; its wind is NOT in use (stale or never heard)"}${a.last_error === null ? "" : `; last error: ${a.last_error}`}`,
  };
}

/** What the Wind panel shows of `state.surface_wind`. */
export function surfaceWindShown(sw: SurfaceWind | null): SurfaceWindShown {
  if (sw === null) {
    const none = { text: "—", detail: "", warn: false, title: "this station (or recording) reports no surface wind" };
    return { wind: none, drone: none, anemometer: null };
  }
  return {
    wind: windLine(sw),
    drone: droneLine(sw),
    anemometer: sw.anemometer === null ? null : anemometerLine(sw.anemometer, sw.wind?.source === "anemometer"),
  };
}

/** The operator's typed speed (m/s) and from-direction (° true) as the body to POST, or why not. */
export function surfaceWindBody(speed: string, from: string): { ok: true; body: SurfaceWindBody } | { ok: false; error: string } {
  const s = parseNumber(speed, "speed (m/s)", 0, MAX_SPEED_MPS);
  if (!s.ok) return s;
  const d = parseNumber(from, "from (°)", -360, 360);
  if (!d.ok) return d;
  return { ok: true, body: { speed_mps: s.value, from_deg: d.value } };
}
