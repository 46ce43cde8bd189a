// Which point the recovery team should drive to: once landed, where the vehicle is; before, the
// landing predicted for the way it is flying (guided modes → planned; uncontrolled → uncontrolled).

import type { LatLon, N, State } from "./types";

export type RecoveryKind = "actual" | "planned" | "uncontrolled";

export interface RecoveryPoint extends LatLon {
  kind: RecoveryKind;
  time_to_land_s: N;
  semi_major_m: N;
}

/** Stage names that mean the payload is on the ground (API.md does not list stages; assumed). */
const LANDED = new Set(["landed", "ground", "on_ground"]);

export function isLanded(s: State): boolean {
  const st = s.mission.stage ?? s.vehicle?.stage ?? null;
  return st !== null && LANDED.has(st);
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
