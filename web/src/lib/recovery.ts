// Which point the recovery team should drive to: once landed, where the vehicle is; before, the
// landing predicted for the way it is flying (guided modes → planned; uncontrolled → uncontrolled).

import { fmt, fmtDistance, fmtDuration } from "./format";
import { distanceM } from "./geo";
import type { LatLon, N, State } from "./types";

export type RecoveryKind = "actual" | "planned" | "uncontrolled";

export interface RecoveryPoint extends LatLon {
  kind: RecoveryKind;
  time_to_land_s: N;
  semi_major_m: N;
}

/** On the ground: the mission's stage (else the drone's) is `landed`. */
export function isLanded(s: State): boolean {
  return (s.mission.stage ?? s.vehicle?.stage ?? null) === "landed";
}

export function recoveryPoint(s: State): RecoveryPoint | null {
  if (isLanded(s)) {
    const lat = s.estimate?.lat_deg ?? s.vehicle?.gps?.lat_deg ?? null;
    const lon = s.estimate?.lon_deg ?? s.vehicle?.gps?.lon_deg ?? null;
    if (lat !== null && lon !== null) return { kind: "actual", lat_deg: lat, lon_deg: lon, time_to_land_s: 0, semi_major_m: s.estimate?.position_sigma_m ?? null };
  }
  const p = s.prediction;
  if (p === null) return null;
  const mode = s.guidance?.mode ?? s.vehicle?.mode ?? null;
  const unguided = mode === "uncontrolled" || mode === "manual";
  const order = unguided ? [["uncontrolled", p.uncontrolled], ["planned", p.planned]] as const : [["planned", p.planned], ["uncontrolled", p.uncontrolled]] as const;
  for (const [kind, lp] of order) {
    if (lp !== null) return { kind, lat_deg: lp.lat_deg, lon_deg: lp.lon_deg, time_to_land_s: lp.time_to_land_s, semi_major_m: lp.semi_major_m };
  }
  return null;
}

/** The header's landing badge: live countdown, the same marked stale, or where it landed. */
export interface LandingBadge {
  state: "none" | "live" | "stale" | "landed";
  text: string;
}

/**
 * `stale`/`age_s`: the page's verdict on the data (staleness.ts). A stale countdown is not
 * counted down by the page — the drone may have done anything since — but says how old it is.
 */
export function landingBadge(s: State | null, stale: boolean, age_s: N): LandingBadge {
  if (s === null) return { state: "none", text: "landing —" };
  const pt = recoveryPoint(s);
  if (pt?.kind === "actual") {
    const t = s.guidance?.target ?? null;
    const miss = t === null ? "" : ` · ${fmtDistance(distanceM(pt, t))} from the target`;
    return { state: "landed", text: `LANDED${miss}${stale ? " (link stale)" : ""}` };
  }
  if (pt === null || pt.time_to_land_s === null) return { state: stale ? "stale" : "none", text: "landing —" };
  const n = `landing in ${fmt(pt.time_to_land_s, "s", 0)}${pt.kind === "uncontrolled" ? " (uncontrolled)" : ""}`;
  if (!stale) return { state: "live", text: n };
  return { state: "stale", text: `${n} as of ${age_s === null ? "an unknown time" : fmtDuration(age_s)} ago — STALE` };
}

/** The phase to show: the drone's own (the station's replica may disagree), or `landed`. */
export function phaseLabel(s: State): string | null {
  if (isLanded(s)) return "landed";
  return s.vehicle?.phase ?? s.guidance?.phase ?? null;
}
