// What a relay's viewers are sent (`public_state`, `public_history`: no token, nothing of the
// operators'), parsed leniently like the rest of the wire, and the sentences the public page
// shows about how fresh and how exact it is.

import { isObj, num, str, type Obj } from "./parseFields";
import type { PublicPoint, PublicPosition, PublicStateMsg, PublicTrackPoint } from "../generated/api";

export type { PublicStateMsg, PublicTrackPoint };

const point = (v: unknown): PublicPoint | null => {
  if (!isObj(v)) return null;
  const lat_deg = num(v, "lat_deg");
  const lon_deg = num(v, "lon_deg");
  return lat_deg === null || lon_deg === null ? null : { lat_deg, lon_deg };
};

const position = (v: unknown): PublicPosition | null => {
  const p = point(v);
  if (p === null || !isObj(v)) return null;
  const f = (k: string): number => num(v as Obj, k) ?? 0;
  return { ...p, alt_msl_m: f("alt_msl_m"), ground_speed_mps: f("ground_speed_mps"), course_deg: f("course_deg"), climb_mps: f("climb_mps") };
};

/** A `public_state`, or `null` if it is not one. */
export function parsePublicState(v: unknown): PublicStateMsg | null {
  if (!isObj(v) || v.type !== "public_state") return null;
  const wall_ms = num(v, "wall_ms");
  if (wall_ms === null) return null;
  return {
    type: "public_state", wall_ms, mission_time_s: num(v, "mission_time_s"), stage: str(v, "stage"),
    link_stale: v.link_stale === true, position: position(v.position), landing: point(v.landing), target: point(v.target),
    delay_s: Math.max(0, num(v, "delay_s") ?? 0), coarsen_m: Math.max(0, num(v, "coarsen_m") ?? 0),
  };
}

/** The track of a `public_history` (points that do not parse are dropped), or `null`. */
export function parsePublicHistory(v: unknown): PublicTrackPoint[] | null {
  if (!isObj(v) || v.type !== "public_history" || !Array.isArray(v.track)) return null;
  const out: PublicTrackPoint[] = [];
  for (const p of v.track) {
    if (!isObj(p)) continue;
    const t = num(p, "mission_time_s");
    const q = point(p);
    if (t !== null && q !== null) out.push({ mission_time_s: t, ...q, alt_msl_m: num(p, "alt_msl_m") ?? 0 });
  }
  return out;
}

/** How exact and how late the page is, in words ("" when live and exact). */
export function caveat(s: PublicStateMsg): string {
  const parts: string[] = [];
  if (s.delay_s > 0) parts.push(`shown ${fmtSeconds(s.delay_s)} after the station`);
  if (s.coarsen_m > 0) parts.push(`positions rounded to ${Math.round(s.coarsen_m)} m`);
  return parts.join("; ");
}

/** How old what is shown is, in words, from the station's send time and the viewer's clock. */
export function freshness(s: PublicStateMsg, nowMs: number): { stale: boolean; text: string } {
  const age_s = Math.max(0, (nowMs - s.wall_ms) / 1000 - s.delay_s);
  if (s.link_stale) return { stale: true, text: "the station hears the payload no more: last known position" };
  if (age_s > 10) return { stale: true, text: `nothing new for ${fmtSeconds(age_s)}` };
  return { stale: false, text: "live" };
}

function fmtSeconds(s: number): string {
  if (s < 90) return `${Math.round(s)} s`;
  if (s < 5400) return `${Math.round(s / 60)} min`;
  return `${(s / 3600).toFixed(1)} h`;
}
