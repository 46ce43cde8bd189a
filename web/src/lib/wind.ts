// The forecast wind profile at a given altitude, to compare with the onboard estimate, and the
// ascent's measured bands with their uncertainty, as the wind panel draws them.

import type { AscentBand, ForecastWind } from "./types";
import { wrap360 } from "./format";

export interface WindAt {
  speed_mps: number;
  from_deg: number | null;
}

/**
 * Linear interpolation in altitude; direction interpolated the short way round. Outside the
 * profile the nearest level is used (no extrapolation). `profile` is sorted by altitude.
 */
export function forecastAt(profile: readonly ForecastWind[], alt_msl_m: number): WindAt | null {
  if (profile.length === 0 || !Number.isFinite(alt_msl_m)) return null;
  const first = profile[0]!;
  const last = profile[profile.length - 1]!;
  if (alt_msl_m <= first.alt_msl_m) return { speed_mps: first.speed_mps, from_deg: first.from_deg };
  if (alt_msl_m >= last.alt_msl_m) return { speed_mps: last.speed_mps, from_deg: last.from_deg };
  for (let i = 1; i < profile.length; i++) {
    const a = profile[i - 1]!;
    const b = profile[i]!;
    if (alt_msl_m <= b.alt_msl_m) {
      const f = b.alt_msl_m === a.alt_msl_m ? 0 : (alt_msl_m - a.alt_msl_m) / (b.alt_msl_m - a.alt_msl_m);
      let from: number | null = null;
      if (a.from_deg !== null && b.from_deg !== null) {
        const d = ((b.from_deg - a.from_deg + 540) % 360) - 180;
        from = wrap360(a.from_deg + f * d);
      }
      return { speed_mps: a.speed_mps + f * (b.speed_mps - a.speed_mps), from_deg: from };
    }
  }
  return null;
}

/** Height of one level of the measured profile, m. */
export const PROFILE_BIN_M = 25;

export interface ProfilePoint {
  alt_msl_m: number;
  speed_mps: number;
  from_deg: number;
}

/**
 * The wind the drone has measured on its way down, one averaged point per `PROFILE_BIN_M`: what
 * the forecast profile is compared with. Directions are averaged as vectors (350° and 10° give
 * 0°, not 180°). Fed only with current (not stale) estimates.
 */
export class MeasuredProfile {
  private readonly bins = new Map<number, { n: number; speed: number; e: number; n_: number }>();

  constructor(readonly binM = PROFILE_BIN_M) {}

  add(alt_msl_m: number, speed_mps: number, from_deg: number): void {
    if (![alt_msl_m, speed_mps, from_deg].every(Number.isFinite)) return;
    const k = Math.round(alt_msl_m / this.binM);
    const b = this.bins.get(k) ?? { n: 0, speed: 0, e: 0, n_: 0 };
    const r = (from_deg * Math.PI) / 180;
    b.n += 1;
    b.speed += speed_mps;
    b.e += Math.sin(r);
    b.n_ += Math.cos(r);
    this.bins.set(k, b);
  }

  clear(): void {
    this.bins.clear();
  }

  /** The levels, lowest first. */
  points(): ProfilePoint[] {
    return [...this.bins.entries()]
      .sort((a, b) => a[0] - b[0])
      .map(([k, b]) => ({ alt_msl_m: k * this.binM, speed_mps: b.speed / b.n, from_deg: wrap360((Math.atan2(b.e, b.n_) * 180) / Math.PI) }));
  }
}

/**
 * A direction profile as polyline pieces on a 0…360 axis: a piece ends where the direction
 * crosses north (350° → 10°), where a straight line would sweep across the whole chart.
 */
export function directionPieces(points: readonly { alt_msl_m: number; from_deg: number | null }[]): { alt_msl_m: number; from_deg: number }[][] {
  const out: { alt_msl_m: number; from_deg: number }[][] = [];
  let cur: { alt_msl_m: number; from_deg: number }[] = [];
  for (const p of points) {
    if (p.from_deg === null || !Number.isFinite(p.from_deg)) {
      if (cur.length > 0) out.push(cur);
      cur = [];
      continue;
    }
    const d = wrap360(p.from_deg);
    const prev = cur[cur.length - 1];
    if (prev !== undefined && Math.abs(d - prev.from_deg) > 180) {
      out.push(cur);
      cur = [];
    }
    cur.push({ alt_msl_m: p.alt_msl_m, from_deg: d });
  }
  if (cur.length > 0) out.push(cur);
  return out;
}

/** A band of the ascent's measured wind as the wind panel draws it. */
export interface AscentPoint {
  alt_msl_m: number;
  /** Altitudes the band's fixes span, m MSL (the band's own altitude when unknown). */
  alt_min_msl_m: number;
  alt_max_msl_m: number;
  speed_mps: number;
  from_deg: number;
  /** 2-σ interval of the speed, m/s (never below 0). */
  speed_lo_mps: number;
  speed_hi_mps: number;
  /** 2-σ half-width of the direction, degrees; null when the band's wind is too weak to have one (2σ ≥ 180°). */
  dir_half_deg: number | null;
  samples: number | null;
}

/**
 * A band's speed and from-direction with their 2-σ intervals, from the wind's components and
 * their 1-σ (first-order propagation: speed σ = √((n·σn)² + (e·σe)²)/s, direction σ =
 * √((e·σn)² + (n·σe)²)/s² rad). At a speed within the noise the direction is undetermined.
 */
export function ascentPoint(b: AscentBand): AscentPoint {
  const n = b.wind_north_mps;
  const e = b.wind_east_mps;
  const sn = b.sigma_north_mps;
  const se = b.sigma_east_mps;
  const speed = Math.hypot(n, e);
  const from = wrap360((Math.atan2(-e, -n) * 180) / Math.PI);
  const sigmaSpeed = speed > 1e-9 ? Math.hypot(n * sn, e * se) / speed : Math.max(sn, se);
  const sigmaDir = speed > 1e-9 ? Math.hypot(e * sn, n * se) / (speed * speed) : Infinity;
  const half = (2 * sigmaDir * 180) / Math.PI;
  return {
    alt_msl_m: b.alt_msl_m,
    alt_min_msl_m: b.alt_min_msl_m ?? b.alt_msl_m,
    alt_max_msl_m: b.alt_max_msl_m ?? b.alt_msl_m,
    speed_mps: speed,
    from_deg: from,
    speed_lo_mps: Math.max(0, speed - 2 * sigmaSpeed),
    speed_hi_mps: speed + 2 * sigmaSpeed,
    dir_half_deg: half < 180 ? half : null,
    samples: b.samples,
  };
}

/**
 * An interval of directions `centre ± half` (degrees) as pieces on the 0…360 axis: one piece,
 * or two where it crosses north; the whole axis for an undetermined direction (`half` null).
 */
export function directionSpans(centre_deg: number, half_deg: number | null): [number, number][] {
  if (half_deg === null || half_deg >= 180) return [[0, 360]];
  const c = wrap360(centre_deg);
  const lo = c - half_deg;
  const hi = c + half_deg;
  if (lo < 0) return [[0, hi], [lo + 360, 360]];
  if (hi > 360) return [[lo, 360], [0, hi - 360]];
  return [[lo, hi]];
}

/** The band whose fixes span `alt_msl_m`, else null. */
export function ascentBandAt(points: readonly AscentPoint[], alt_msl_m: number): AscentPoint | null {
  return points.find((p) => alt_msl_m >= p.alt_min_msl_m && alt_msl_m <= p.alt_max_msl_m) ?? null;
}
