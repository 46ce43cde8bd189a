// Automatic map framing: which points the operator must see (vehicle, target, pattern, predicted
// landings with their ellipses), and when the view has to move to show them. The view moves only
// when something key is at the edge or out of view, or when everything has shrunk to a corner of
// it — not at every 4 Hz state, which would make the map jitter and fight the eye.

import { fromLocal, toLocal } from "./geo";
import { vehiclePosition } from "./fix";
import { isLanded } from "./recovery";
import type { LatLon, State } from "./types";

/** A lat/lon box, degrees. */
export interface Box {
  south: number;
  west: number;
  north: number;
  east: number;
}

/** The smallest span framed, m: a lone vehicle is shown with some ground around it. */
export const MIN_SPAN_M = 400;
/** Key points closer than this share of the view's size to its edge trigger a new framing. */
export const EDGE_MARGIN = 0.06;
/** Everything smaller than this share of the view (both ways): zoom in by framing again. */
export const SHRUNK_BELOW = 0.3;

/** The points to keep in view: vehicle, target, pattern, final entry, predictions ±1σ. */
export function keyPoints(s: State): LatLon[] {
  const out: LatLon[] = [];
  const at = vehiclePosition(s);
  if (at !== null) out.push({ lat_deg: at.lat_deg, lon_deg: at.lon_deg });
  const g = s.guidance;
  if (g?.target) out.push(g.target);
  // On the ground the plan and the predictions are history: frame where it is and where it aimed.
  if (isLanded(s)) return out;
  if (g?.pattern) {
    for (const [lat_deg, lon_deg] of g.pattern.corners) out.push({ lat_deg, lon_deg });
    if (g.pattern.final_entry) out.push({ lat_deg: g.pattern.final_entry[0], lon_deg: g.pattern.final_entry[1] });
  }
  for (const p of [s.prediction?.planned, s.prediction?.uncontrolled]) {
    if (!p) continue;
    // The ellipse's extent: its semi-major axis in every direction bounds it.
    const r = p.semi_major_m ?? 0;
    out.push(fromLocal(p, { east_m: -r, north_m: -r }), fromLocal(p, { east_m: r, north_m: r }));
  }
  return out.filter((p) => Number.isFinite(p.lat_deg) && Number.isFinite(p.lon_deg));
}

/** The box around `points`, widened to at least `MIN_SPAN_M` each way; null if none. */
export function boxAround(points: readonly LatLon[], minSpanM = MIN_SPAN_M): Box | null {
  if (points.length === 0) return null;
  let b: Box = { south: Infinity, west: Infinity, north: -Infinity, east: -Infinity };
  for (const p of points) {
    b = { south: Math.min(b.south, p.lat_deg), west: Math.min(b.west, p.lon_deg), north: Math.max(b.north, p.lat_deg), east: Math.max(b.east, p.lon_deg) };
  }
  const mid = { lat_deg: (b.south + b.north) / 2, lon_deg: (b.west + b.east) / 2 };
  const sw = fromLocal(mid, { east_m: -minSpanM / 2, north_m: -minSpanM / 2 });
  const ne = fromLocal(mid, { east_m: minSpanM / 2, north_m: minSpanM / 2 });
  return { south: Math.min(b.south, sw.lat_deg), north: Math.max(b.north, ne.lat_deg), west: Math.min(b.west, sw.lon_deg), east: Math.max(b.east, ne.lon_deg) };
}

function sizeM(b: Box): { w: number; h: number } {
  const sw = { lat_deg: b.south, lon_deg: b.west };
  const ne = toLocal(sw, { lat_deg: b.north, lon_deg: b.east });
  return { w: Math.abs(ne.east_m), h: Math.abs(ne.north_m) };
}

/** How much of the view `want` spans, the larger of its two shares (1: it just fills the view). */
export function shareOfView(view: Box, want: Box): number {
  const v = sizeM(view);
  const w = sizeM(want);
  return Math.max(w.w / v.w, w.h / v.h);
}

/**
 * Whether the view must be framed again to show `want` (the box of the key points): when a key
 * point is within `EDGE_MARGIN` of the view's edge or outside it, or when `want` has shrunk below
 * `SHRUNK_BELOW` of the view both ways (a framing shows it at about 85 %, so this cannot flap).
 */
export function needsFraming(view: Box, want: Box): boolean {
  const mLat = (view.north - view.south) * EDGE_MARGIN;
  const mLon = (view.east - view.west) * EDGE_MARGIN;
  const inside = want.south >= view.south + mLat && want.north <= view.north - mLat && want.west >= view.west + mLon && want.east <= view.east - mLon;
  if (!inside) return true;
  const v = sizeM(view);
  const w = sizeM(want);
  return w.w < SHRUNK_BELOW * v.w && w.h < SHRUNK_BELOW * v.h;
}
