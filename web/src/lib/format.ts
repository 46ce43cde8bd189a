// Number formatting for people: every number leaves here with its unit, and a missing value is an
// em dash with the unit still shown, so a blank never reads as zero.

import type { N } from "./types";

export const DASH = "—";

/** `12.3 m/s`; null or non-finite → `— m/s`. */
export function fmt(v: N | undefined, unit: string, digits = 1): string {
  const u = unit === "" ? "" : unit === "°" ? "°" : ` ${unit}`;
  if (v === null || v === undefined || !Number.isFinite(v)) return `${DASH}${u}`;
  // Avoid "-0.0": a value that rounds to zero is shown unsigned.
  const s = v.toFixed(digits);
  return `${Number(s) === 0 ? (0).toFixed(digits) : s}${u}`;
}

/** Wraps an angle into [0, 360). */
export function wrap360(deg: number): number {
  const w = deg % 360;
  return w < 0 ? w + 360 : w;
}

/** Wraps an angle into (-180, 180]. */
export function wrap180(deg: number): number {
  const w = wrap360(deg);
  return w > 180 ? w - 360 : w;
}

/** Compass directions (heading, course, bearing) as `005°`, always 0…359. */
export function fmtDir(v: N | undefined): string {
  if (v === null || v === undefined || !Number.isFinite(v)) return `${DASH}°`;
  const d = Math.round(wrap360(v)) % 360;
  return `${String(d).padStart(3, "0")}°`;
}

const CARDINALS = ["N", "NNE", "NE", "ENE", "E", "ESE", "SE", "SSE", "S", "SSW", "SW", "WSW", "W", "WNW", "NW", "NNW"];

/** 16-point compass name of a direction, for a quick read in the field. */
export function cardinal(deg: number): string {
  return CARDINALS[Math.round(wrap360(deg) / 22.5) % 16] ?? "N";
}

/** Distances: metres below 1 km, kilometres above. */
export function fmtDistance(m: N | undefined): string {
  if (m === null || m === undefined || !Number.isFinite(m)) return `${DASH} m`;
  if (Math.abs(m) < 1000) return `${Math.round(m)} m`;
  return `${(m / 1000).toFixed(Math.abs(m) < 10000 ? 2 : 1)} km`;
}

/** Durations: `45 s`, `3 min 07 s`, `1 h 02 min`. */
export function fmtDuration(s: N | undefined): string {
  if (s === null || s === undefined || !Number.isFinite(s)) return `${DASH} s`;
  const neg = s < 0 ? "−" : "";
  const a = Math.abs(s);
  if (a < 60) return `${neg}${a.toFixed(a < 10 ? 1 : 0)} s`;
  const tot = Math.round(a);
  if (tot < 3600) return `${neg}${Math.floor(tot / 60)} min ${String(tot % 60).padStart(2, "0")} s`;
  return `${neg}${Math.floor(tot / 3600)} h ${String(Math.floor((tot % 3600) / 60)).padStart(2, "0")} min`;
}

/** Mission clock `T+00:02:03.5`. */
export function fmtMissionTime(s: N | undefined): string {
  if (s === null || s === undefined || !Number.isFinite(s)) return `T+${DASH}`;
  const sign = s < 0 ? "−" : "+";
  const a = Math.abs(s);
  const h = Math.floor(a / 3600);
  const m = Math.floor((a % 3600) / 60);
  const sec = a % 60;
  return `T${sign}${String(h).padStart(2, "0")}:${String(m).padStart(2, "0")}:${sec.toFixed(1).padStart(4, "0")}`;
}

/** Wall clock in UTC, `14:03:07Z`: the field team and the station may be in different zones. */
export function fmtWallUtc(ms: N | undefined): string {
  if (ms === null || ms === undefined || !Number.isFinite(ms)) return `${DASH}`;
  return `${new Date(ms).toISOString().slice(11, 19)}Z`;
}

/** Latitude/longitude with hemisphere, 5 decimals (≈1 m). */
export function fmtLatLon(lat: N | undefined, lon: N | undefined): string {
  if (lat == null || lon == null || !Number.isFinite(lat) || !Number.isFinite(lon)) return `${DASH}`;
  return `${Math.abs(lat).toFixed(5)}° ${lat >= 0 ? "N" : "S"}, ${Math.abs(lon).toFixed(5)}° ${lon >= 0 ? "E" : "W"}`;
}

/** Human label of an API identifier: `spiral_landing` → `spiral landing`. */
export const label = (id: string | null | undefined): string => (id == null || id === "" ? DASH : id.replace(/_/g, " "));

/**
 * Parameter values: the drone stores float32, so a read-back of 0.0155 arrives as
 * 0.01549999974668026. Seven significant digits is what float32 holds; show no more.
 */
export function fmtParam(v: N | undefined): string {
  if (v === null || v === undefined || !Number.isFinite(v)) return DASH;
  return String(Number(v.toPrecision(7)));
}
