// The Plan page's launch window, its pure parts: the window boxes (from, to, every hours) to a
// `POST /api/plan/window` body (the station's `stx_station::launch_window`), and each launch
// of the answer as a row of the strip: its time, the share of samples from which steering
// reaches the target (as a bar's width), the unsteered landing and the burst, and whether it is
// among the best (marked ★) with its rank.

import type * as Wire from "../generated/api";

export type WindowBuilt = { ok: true; body: Wire.WindowBody } | { ok: false; error: string };

/** A datetime-local box's value (`2026-11-30T06:00`, read as UTC) or RFC 3339 text, as RFC 3339. */
export function utcText(box: string): string | null {
  const t = box.trim();
  if (t === "") return null;
  const full = /Z$|[+-]\d\d:\d\d$/.test(t) ? t : `${t.length === 16 ? `${t}:00` : t}Z`;
  return Number.isNaN(Date.parse(full)) ? null : full;
}

/** The body of a window over `forecast` for `request` (a plan request the form built). */
export function buildWindow(request: Wire.PlanRequestInput, from: string, to: string, everyHours: string, forecast: Wire.WindowForecast): WindowBuilt {
  const f = utcText(from);
  const t = utcText(to);
  if (f === null) return { ok: false, error: `window from: not a time: "${from}"` };
  if (t === null) return { ok: false, error: `window to: not a time: "${to}"` };
  const hours = Number(everyHours);
  if (!(Number.isFinite(hours) && hours > 0)) return { ok: false, error: `window every: a number of hours > 0, got "${everyHours}"` };
  if (!request.target_lat_lon_deg) return { ok: false, error: "a launch window needs a target: fill in the target's latitude and longitude" };
  return { ok: true, body: { request: { ...request, forecast: [] }, window: { from: f, to: t, every_s: Math.round(hours * 3600) }, forecast } };
}

export interface StripRow {
  time: string;
  /** 0…100. */
  sharePct: number;
  rank: number;
  best: boolean;
  text: string;
}

/** The strip's rows, in time order. */
export function stripRows(report: Wire.WindowReport): StripRow[] {
  return report.launches.map((l) => {
    const g = l.landing_unsteered;
    const b = l.burst;
    const pct = 100 * l.reach_share;
    return {
      time: l.launch_time,
      sharePct: pct,
      rank: l.rank,
      best: l.best,
      text: `${l.launch_time.replace("T", " ").replace(/:00Z$/, "Z")} · reach ${pct.toFixed(0)} % · landing ${g.lat_deg.toFixed(4)}, ${g.lon_deg.toFixed(4)} (${(l.target_from_landing_m / 1000).toFixed(1)} km from target) · burst ${b.lat_deg.toFixed(4)}, ${b.lon_deg.toFixed(4)} at ${(b.alt_msl_m / 1000).toFixed(1)} km · #${l.rank}${l.best ? " ★" : ""}`,
    };
  });
}
