// The leaf readers every parser of the station's messages shares (a number, a string, a
// position in range, one of the contract's names), and the names each enumeration of the
// contract takes. Each returns null for what it cannot read; the parsers decide what is fatal.

import type {
  BandMethod,
  FlightMode,
  FlightStage,
  GpsFix,
  Guidance,
  GuidancePhase,
  LatLon,
  Level,
  N,
  Outcome,
  ParamGroup,
  Position,
  Role,
  Vec3,
} from "./types";
import type { ServerMessage as WireServerMessage } from "../generated/api";

export type WireServerType = WireServerMessage["type"];
export type WireServerMessageOf<T extends WireServerType> = Extract<WireServerMessage, { type: T }>;

export type Obj = Record<string, unknown>;

export type Parsed<T> = { ok: true; value: T } | { ok: false; error: string };

export const ok = <T>(value: T): Parsed<T> => ({ ok: true, value });
export const bad = <T>(error: string): Parsed<T> => ({ ok: false, error });

export const isObj = (v: unknown): v is Obj => typeof v === "object" && v !== null && !Array.isArray(v);

export const num = (o: Obj, k: string): N => {
  const v = o[k];
  return typeof v === "number" && Number.isFinite(v) ? v : null;
};
export const str = (o: Obj, k: string): string | null => (typeof o[k] === "string" ? (o[k] as string) : null);
export const bool = (o: Obj, k: string): boolean | null => (typeof o[k] === "boolean" ? (o[k] as boolean) : null);
export const obj = (o: Obj, k: string): Obj | null => {
  const v = o[k];
  return isObj(v) ? v : null;
};

export const vec3 = (o: Obj, k: string): Vec3 | null => {
  const v = o[k];
  if (!Array.isArray(v) || v.length !== 3) return null;
  return v.every((x) => typeof x === "number" && Number.isFinite(x)) ? (v as Vec3) : null;
};

export const isLat = (x: unknown): x is number => typeof x === "number" && Number.isFinite(x) && Math.abs(x) <= 90;
export const isLon = (x: unknown): x is number => typeof x === "number" && Number.isFinite(x) && Math.abs(x) <= 180;

/** `{lat_deg, lon_deg}` object, or null when either is missing or out of range. */
export const latLonObj = (v: unknown): LatLon | null =>
  isObj(v) && isLat(v.lat_deg) && isLon(v.lon_deg) ? { lat_deg: v.lat_deg, lon_deg: v.lon_deg } : null;

/** `[lat, lon]` pair as the pattern's corners are sent. */
export const latLonPair = (v: unknown): LatLon | null =>
  Array.isArray(v) && v.length === 2 && isLat(v[0]) && isLon(v[1]) ? { lat_deg: v[0], lon_deg: v[1] } : null;

/** Applies `f` to an optional sub-object: null when absent or not an object. */
export const sub = <T>(o: Obj, k: string, f: (x: Obj) => T): T | null => {
  const v = obj(o, k);
  return v === null ? null : f(v);
};

// The names each enumeration of the contract takes. `satisfies` makes the compiler hold each list
// to the generated type: a name added or removed in the daemon's Rust fails the build here.
export const ROLES = { operator: true, viewer: true } as const satisfies Record<Role, true>;
export const LEVELS = { info: true, warning: true, error: true } as const satisfies Record<Level, true>;
export const OUTCOMES = { accepted: true, denied: true, failed: true, unsupported: true, timed_out: true, in_progress: true } as const satisfies Record<Outcome, true>;
export const MODES = { uncontrolled: true, manual: true, heading: true, course: true, localizer: true, spiral_landing: true } as const satisfies Record<FlightMode, true>;
export const STAGES = { pre_launch: true, ascent: true, round_chute: true, parafoil_deploy: true, parafoil: true, landed: true } as const satisfies Record<FlightStage, true>;
export const PHASES = {
  idle: true, approximation: true, branch1: true, branch2: true, branch3: true, branch4: true, final_approach: true, flare: true, best_reachable: true, landed: true,
} as const satisfies Record<GuidancePhase, true>;
export const FIXES = { no_gps: true, no_fix: true, fix2d: true, fix3d: true, dgps: true, rtk_float: true, rtk_fixed: true, static: true, ppp: true } as const satisfies Record<GpsFix, true>;
export const GROUPS = { gains: true, spiral: true, failsafe: true, mission: true, polar: true } as const satisfies Record<ParamGroup, true>;
export const SOURCES = { guidance: true, link: true, command: true, station: true, vehicle: true, keep_out: true, readiness: true, anemometer: true } as const satisfies Record<WireServerMessageOf<"event">["source"], true>;
export const METHODS = { gps_velocity: true, position_differences: true } as const satisfies Record<BandMethod, true>;
export const TARGET_SOURCES = { drone_plan: true, drone_telemetry: true, operator: true } as const satisfies Record<NonNullable<Guidance["target_source"]>, true>;

/** The value of `o[k]` if it is one of the names of `names`, else null. */
export const oneOf = <T extends string>(o: Obj, k: string, names: Record<T, true>): T | null => {
  const v = o[k];
  return typeof v === "string" && Object.hasOwn(names, v) ? (v as T) : null;
};

/** A position the page can place: latitude and longitude in range (else null), altitude if a number. */
export const position = (v: unknown): Position | null => {
  const ll = latLonObj(v);
  return ll === null || !isObj(v) ? null : { ...ll, alt_msl_m: num(v, "alt_msl_m") };
};

/** West, south, east, north in range with west < east and south < north, else null. */
export const bounds = (v: unknown): [number, number, number, number] | null => {
  if (!Array.isArray(v) || v.length !== 4) return null;
  const [w, s, e, n] = v as unknown[];
  return isLon(w) && isLat(s) && isLon(e) && isLat(n) && w < e && s < n ? [w, s, e, n] : null;
};


/** A `[lat, lon]` pair in range, as the pattern and the localizer send points. */
export const pair = (v: unknown): [number, number] | null => (Array.isArray(v) && v.length === 2 && isLat(v[0]) && isLon(v[1]) ? [v[0], v[1]] : null);
