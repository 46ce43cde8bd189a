// Geodesy the page needs: great-circle distance and bearing (recovery page), a local flat frame
// around the session origin (3-D view, grid), and points at a distance/bearing (ellipses, arrows).
// A spherical Earth is enough: landing areas span a few km, where its error is below 0.5 %.

import type { LatLon } from "./types";

/** Mean Earth radius, m (IUGG). */
export const EARTH_RADIUS_M = 6_371_008.8;

const RAD = Math.PI / 180;

/** Great-circle (haversine) distance, m. */
export function distanceM(a: LatLon, b: LatLon): number {
  const dLat = (b.lat_deg - a.lat_deg) * RAD;
  const dLon = (b.lon_deg - a.lon_deg) * RAD;
  const h = Math.sin(dLat / 2) ** 2 + Math.cos(a.lat_deg * RAD) * Math.cos(b.lat_deg * RAD) * Math.sin(dLon / 2) ** 2;
  return 2 * EARTH_RADIUS_M * Math.asin(Math.min(1, Math.sqrt(h)));
}

/** Initial great-circle bearing from a to b, degrees clockwise from true north in [0, 360). */
export function bearingDeg(a: LatLon, b: LatLon): number {
  const φ1 = a.lat_deg * RAD;
  const φ2 = b.lat_deg * RAD;
  const dλ = (b.lon_deg - a.lon_deg) * RAD;
  const y = Math.sin(dλ) * Math.cos(φ2);
  const x = Math.cos(φ1) * Math.sin(φ2) - Math.sin(φ1) * Math.cos(φ2) * Math.cos(dλ);
  const deg = Math.atan2(y, x) / RAD;
  return (deg + 360) % 360;
}

/** The point at `distance_m` along the great circle leaving `from` on `bearing_deg`. */
export function destination(from: LatLon, bearing_deg: number, distance_m: number): LatLon {
  const δ = distance_m / EARTH_RADIUS_M;
  const θ = bearing_deg * RAD;
  const φ1 = from.lat_deg * RAD;
  const λ1 = from.lon_deg * RAD;
  const φ2 = Math.asin(Math.sin(φ1) * Math.cos(δ) + Math.cos(φ1) * Math.sin(δ) * Math.cos(θ));
  const λ2 = λ1 + Math.atan2(Math.sin(θ) * Math.sin(δ) * Math.cos(φ1), Math.cos(δ) - Math.sin(φ1) * Math.sin(φ2));
  return { lat_deg: φ2 / RAD, lon_deg: ((λ2 / RAD + 540) % 360) - 180 };
}

/** East/north offsets in metres from an origin, local tangent plane (equirectangular). */
export interface EastNorth {
  east_m: number;
  north_m: number;
}

export function toLocal(origin: LatLon, p: LatLon): EastNorth {
  return {
    east_m: (p.lon_deg - origin.lon_deg) * RAD * EARTH_RADIUS_M * Math.cos(origin.lat_deg * RAD),
    north_m: (p.lat_deg - origin.lat_deg) * RAD * EARTH_RADIUS_M,
  };
}

export function fromLocal(origin: LatLon, en: EastNorth): LatLon {
  return {
    lat_deg: origin.lat_deg + en.north_m / EARTH_RADIUS_M / RAD,
    lon_deg: origin.lon_deg + en.east_m / (EARTH_RADIUS_M * Math.cos(origin.lat_deg * RAD)) / RAD,
  };
}

/**
 * Outline of a 1-σ ellipse as `n` lat/lon points. `major_axis_deg` is the direction of the major
 * axis, degrees clockwise from true north (the API's convention for `major_axis_deg`, assumed).
 * The first point lies on the major axis, `semi_major_m` away in that direction.
 */
export function ellipsePoints(
  centre: LatLon,
  semi_major_m: number,
  semi_minor_m: number,
  major_axis_deg: number,
  n = 48,
): LatLon[] {
  const θ = major_axis_deg * RAD;
  // Unit vectors (east, north) of the major and minor axes.
  const ma = { e: Math.sin(θ), n: Math.cos(θ) };
  const mi = { e: Math.cos(θ), n: -Math.sin(θ) };
  const out: LatLon[] = [];
  for (let i = 0; i < n; i++) {
    const t = (2 * Math.PI * i) / n;
    const a = semi_major_m * Math.cos(t);
    const b = semi_minor_m * Math.sin(t);
    out.push(fromLocal(centre, { east_m: a * ma.e + b * mi.e, north_m: a * ma.n + b * mi.n }));
  }
  return out;
}

/** A "nice" grid step (1, 2 or 5 × 10^k m) giving about `target` lines across `span_m`. */
export function niceStep(span_m: number, target = 8): number {
  if (!(span_m > 0)) return 1;
  const raw = span_m / target;
  const p = 10 ** Math.floor(Math.log10(raw));
  const f = raw / p;
  return (f < 1.5 ? 1 : f < 3.5 ? 2 : f < 7.5 ? 5 : 10) * p;
}

/** Grid line positions (multiples of `step`) covering [lo, hi]. */
export function gridValues(lo: number, hi: number, step: number): number[] {
  const out: number[] = [];
  if (!(step > 0) || !(hi >= lo)) return out;
  for (let v = Math.ceil(lo / step) * step; v <= hi + 1e-9; v += step) out.push(Math.round(v / step) * step);
  return out;
}
