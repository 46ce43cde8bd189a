// Keep-out zones as the map edits them (ui/zoneEditor.ts): read from the station's GeoJSON
// FeatureCollection into named zones, written back as one after an operator's edit, and checked
// before they are sent. The station checks them again (crates/stx-station/src/core/keep_out.rs)
// and its refusal is shown as it said it; the check here catches what an operator can do with
// the mouse (a zone left unnamed, a ring pulled through itself, vertices deleted down to a line)
// while the edit is still on the map, and says which zone it is.
//
// Rings here are `[lat, lon]` without the closing point, as Leaflet holds them; GeoJSON's are
// `[lon, lat]` and closed (RFC 7946). Properties other than `name` and `kind` are kept as read.

import type { Ring, Zone } from "./types";

/** Kinds offered for a zone (the issue's list; the sample zones use these words). */
export const ZONE_KINDS = ["water", "border", "forest", "road", "people"] as const;

/** Decimal places of degrees written: 1e-7° is about a centimetre, finer than any click. */
const DECIMALS = 7;

const isObj = (v: unknown): v is Record<string, unknown> => typeof v === "object" && v !== null && !Array.isArray(v);

/** `[lon, lat]` positions as an open `[lat, lon]` ring; `null` when any position is not two numbers. */
function ringFromGeo(v: unknown): Ring | null {
  if (!Array.isArray(v)) return null;
  const ring: Ring = [];
  for (const p of v) {
    if (!Array.isArray(p) || typeof p[0] !== "number" || typeof p[1] !== "number") return null;
    ring.push([p[1], p[0]]);
  }
  return openRing(ring);
}

/** The ring without repeated consecutive points and without its closing point. */
export function openRing(ring: readonly (readonly [number, number])[]): Ring {
  const out: Ring = [];
  for (const [lat, lon] of ring) {
    const last = out[out.length - 1];
    if (last === undefined || last[0] !== lat || last[1] !== lon) out.push([lat, lon]);
  }
  const first = out[0];
  const last = out[out.length - 1];
  if (out.length > 1 && first && last && first[0] === last[0] && first[1] === last[1]) out.pop();
  return out;
}

/** The features of a FeatureCollection as zones; features that are not areas are left out. */
export function zonesOf(collection: unknown): Zone[] {
  const features = isObj(collection) && Array.isArray(collection.features) ? collection.features : [];
  const zones: Zone[] = [];
  features.forEach((f, i) => {
    if (!isObj(f) || !isObj(f.geometry) || !Array.isArray(f.geometry.coordinates)) return;
    const g = f.geometry;
    const raw = g.type === "Polygon" ? [g.coordinates] : g.type === "MultiPolygon" ? (g.coordinates as unknown[]) : [];
    const polygons: Ring[][] = [];
    for (const p of raw) {
      const rings = Array.isArray(p) ? p.map(ringFromGeo) : [];
      if (rings.length > 0 && rings.every((r): r is Ring => r !== null)) polygons.push(rings);
    }
    if (polygons.length === 0) return;
    const { name, kind, ...extra } = isObj(f.properties) ? f.properties : {};
    zones.push({ name: typeof name === "string" ? name : `zone ${i}`, kind: typeof kind === "string" ? kind : "", extra, polygons });
  });
  return zones;
}

const round = (x: number): number => Number(x.toFixed(DECIMALS));
/** An open `[lat, lon]` ring as a closed GeoJSON ring. */
const geoRing = (ring: Ring): [number, number][] => {
  const closed = ring.map(([lat, lon]): [number, number] => [round(lon), round(lat)]);
  if (closed[0]) closed.push([closed[0][0], closed[0][1]]);
  return closed;
};

/** The zones as the FeatureCollection `PUT /api/keep-out` takes: a Polygon per one-polygon zone. */
export function collectionOf(zones: readonly Zone[]): { type: "FeatureCollection"; features: unknown[] } {
  return {
    type: "FeatureCollection",
    features: zones.map((z) => ({
      type: "Feature",
      properties: { ...z.extra, name: z.name.trim(), ...(z.kind ? { kind: z.kind } : {}) },
      geometry:
        z.polygons.length === 1
          ? { type: "Polygon", coordinates: (z.polygons[0] ?? []).map(geoRing) }
          : { type: "MultiPolygon", coordinates: z.polygons.map((p) => p.map(geoRing)) },
    })),
  };
}

type LatLngLike = { lat: number; lng: number };
const isLatLng = (v: unknown): v is LatLngLike => isObj(v) && typeof v.lat === "number" && typeof v.lng === "number";

/**
 * Leaflet's `Polygon.getLatLngs()` as polygons of open rings: `LatLng[]` (a ring),
 * `LatLng[][]` (a polygon with holes) or `LatLng[][][]` (a multi-polygon) alike.
 */
export function polygonsOfLatLngs(v: unknown): Ring[][] {
  if (!Array.isArray(v) || v.length === 0) return [];
  if (isLatLng(v[0])) return [[openRing(v.filter(isLatLng).map((p): [number, number] => [p.lat, p.lng]))]];
  if (Array.isArray(v[0]) && isLatLng(v[0][0])) return [v.flatMap((r) => polygonsOfLatLngs(r).flat())];
  return v.flatMap((p) => polygonsOfLatLngs(p));
}

/** Whether segments ab and cd cross or touch (points `[lat, lon]`; an affine map keeps crossings). */
function segmentsMeet(a: [number, number], b: [number, number], c: [number, number], d: [number, number]): boolean {
  const side = (p: [number, number], q: [number, number], r: [number, number]): number => Math.sign((q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]));
  const within = (p: [number, number], q: [number, number], r: [number, number]): boolean =>
    Math.min(p[0], q[0]) <= r[0] && r[0] <= Math.max(p[0], q[0]) && Math.min(p[1], q[1]) <= r[1] && r[1] <= Math.max(p[1], q[1]);
  const [d1, d2, d3, d4] = [side(c, d, a), side(c, d, b), side(a, b, c), side(a, b, d)];
  if (d1 !== d2 && d3 !== d4 && d1 !== 0 && d2 !== 0 && d3 !== 0 && d4 !== 0) return true;
  return (d1 === 0 && within(c, d, a)) || (d2 === 0 && within(c, d, b)) || (d3 === 0 && within(a, b, c)) || (d4 === 0 && within(a, b, d));
}

/** Why an open ring is not the boundary of an area, or `null`. */
export function ringProblem(ring: Ring): string | null {
  if (ring.some(([lat, lon]) => !Number.isFinite(lat) || !Number.isFinite(lon) || Math.abs(lat) > 90 || Math.abs(lon) > 180)) return "has a point off the globe";
  if (ring.length < 3) return `has ${ring.length} point${ring.length === 1 ? "" : "s"}: an area needs at least 3`;
  const n = ring.length;
  for (let i = 0; i < n; i++) {
    // Edges i and j that share no vertex (neighbours meet at their common vertex by design).
    for (let j = i + 2; j < n; j++) {
      if (i === 0 && j === n - 1) continue;
      const p = (k: number): [number, number] => ring[k % n] as [number, number];
      if (segmentsMeet(p(i), p(i + 1), p(j), p(j + 1))) return "crosses itself";
    }
  }
  let twiceArea = 0;
  for (let i = 0; i < n; i++) {
    const [a, b] = [ring[i] as [number, number], ring[(i + 1) % n] as [number, number]];
    twiceArea += a[1] * b[0] - b[1] * a[0];
  }
  if (Math.abs(twiceArea) < 1e-14) return "has no area (its points lie on one line)";
  return null;
}

/** The first reason the zones may not be sent, naming the zone; `null` when they may. */
export function zonesProblem(zones: readonly Zone[]): string | null {
  for (const [i, z] of zones.entries()) {
    const called = z.name.trim() ? `zone "${z.name.trim()}"` : `zone ${i + 1}`;
    if (!z.name.trim()) return `${called} needs a name`;
    if (z.polygons.length === 0) return `${called} has no area`;
    for (const [p, rings] of z.polygons.entries()) {
      for (const [r, ring] of rings.entries()) {
        const why = ringProblem(ring);
        if (why === null) continue;
        const which = r === 0 ? "boundary" : `hole ${r}`;
        return `${called}: its ${which}${z.polygons.length > 1 ? ` of part ${p + 1}` : ""} ${why}`;
      }
    }
  }
  return null;
}

/**
 * The station's reason with the zone named where it counts features (`keep-out feature 3: …`,
 * from 0 in the order sent): the operator knows zones by their names.
 */
export function withZoneNames(reason: string, sent: readonly Zone[]): string {
  return reason.replace(/\bfeature (\d+)\b/g, (all, i: string) => {
    const z = sent[Number(i)];
    return z ? `${all} ("${z.name.trim()}")` : all;
  });
}

/** A name for a new zone that no zone has yet: "Zone 1", "Zone 2", … */
export function newZoneName(names: readonly string[]): string {
  const taken = new Set(names.map((n) => n.trim().toLowerCase()));
  for (let i = 1; ; i++) if (!taken.has(`zone ${i}`)) return `Zone ${i}`;
}
