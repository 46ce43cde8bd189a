// The plan being edited: waypoints, then exactly one land item, as POST /api/commands/plan wants.

import type { LatLon, PlanBody, PlanItemBody } from "./types";

export interface PlanItem extends LatLon {
  kind: "waypoint" | "land";
  alt_msl_m: number;
  /** Land item only: null means "into the wind". */
  approach_course_deg?: number | null;
}

/** Body for POST /api/commands/plan, or why it cannot be sent. */
export function planBody(waypoints: readonly PlanItem[], land: PlanItem | null): { ok: true; body: PlanBody } | { ok: false; error: string } {
  if (land === null) return { ok: false, error: "the plan needs a land item" };
  for (const [i, w] of waypoints.entries()) {
    if (!Number.isFinite(w.lat_deg) || !Number.isFinite(w.lon_deg) || !Number.isFinite(w.alt_msl_m)) return { ok: false, error: `waypoint ${i + 1}: bad number` };
  }
  const items: PlanItemBody[] = [
    ...waypoints.map((w) => ({ kind: "waypoint" as const, lat_deg: w.lat_deg, lon_deg: w.lon_deg, alt_msl_m: w.alt_msl_m })),
    { kind: "land", lat_deg: land.lat_deg, lon_deg: land.lon_deg, alt_msl_m: land.alt_msl_m, approach_course_deg: land.approach_course_deg ?? null },
  ];
  return { ok: true, body: { items } };
}
